"""Per-sample cost of our estimators: one `step` call per sample in a Python loop."""

from __future__ import annotations

from collections.abc import Callable

import fusion_core


def step_pass(key: str, data: list[tuple[list[float], list[float], float]]) -> Callable[[], int]:
    """A fresh estimator (set-up, not timed) and the loop that steps it over every sample."""
    step = fusion_core.ESTIMATORS[key]().step

    def run() -> int:
        for acc, gyro, dt in data:
            step(acc, gyro, dt)
        return len(data)

    return run


def fmu_core_pass(key: str, data: list[tuple[list[float], list[float], float]]
                  ) -> Callable[[], int]:
    """What a pythonfmu FMU's doStep runs per sample: the twin's step through
    fusion_core.native.Stepper where the twin loads, else the Python step."""
    from fusion_core import native

    st = native.stepper(fusion_core.ESTIMATORS[key]())
    if st is None:
        return step_pass(key, data)
    step, last = st.step, st.last

    def run() -> int:
        for acc, gyro, dt in data:
            step(acc, gyro, dt)
            last()
        return len(data)

    return run


def stream_pass(key: str, data: list[tuple[list[float], list[float], float]]
                ) -> Callable[[], int]:
    """The same loop through Estimator.stream(): the per-sample step at the C twin's speed."""
    step = fusion_core.ESTIMATORS[key]().stream().step

    def run() -> int:
        for acc, gyro, dt in data:
            step(acc, gyro, dt)
        return len(data)

    return run


STREAM = " (stream)"
"""The suffix of the stream passes' names in the per-sample timing."""


def stream_factories(
    keys: tuple[str, ...], data: list[tuple[list[float], list[float], float]]
) -> dict[str, Callable[[], Callable[[], int]]]:
    """Pass factories of our estimators' streams where the C twin is available, else none."""
    from fusion_core import native

    if not native.available():
        return {}
    return {key + STREAM: (lambda key=key: stream_pass(key, data)) for key in keys}


def step_factories(
    keys: tuple[str, ...], data: list[tuple[list[float], list[float], float]]
) -> dict[str, Callable[[], Callable[[], int]]]:
    """Pass factories (see common.time_interleaved) of our estimators."""
    return {key: (lambda key=key: step_pass(key, data)) for key in keys}

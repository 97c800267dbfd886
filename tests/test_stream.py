"""Estimator.stream(): step() at the C twin's speed, its results and states to the bit, and a
clear error where the twin cannot serve."""

from __future__ import annotations

import pytest
from helpers import KEYS, make, noisy_two_axis_recording, paper

from fusion_core import InvalidSample, native
from fusion_core.kalman import AngleBiasKalmanFilter

needs_twin = pytest.mark.skipif(not native.available(),
                                reason=f"the C twin is unavailable: {native.reason()}")


@pytest.fixture(params=["compiled", "cffi"])
def entry(request, monkeypatch) -> str:
    """Both ways a stream steps: the compiled entry point, and the cffi call it falls back to
    where that is not built."""
    from fusion_core.native import stream

    if request.param == "cffi":
        monkeypatch.setattr(stream, "stream_extension", lambda: None)
    elif native.library.stream_extension() is None:
        pytest.skip(f"no compiled entry point: {native.library.stream_reason()}")
    return request.param


@needs_twin
@pytest.mark.parametrize("preset", ["recommended", "paper"])
@pytest.mark.parametrize("key", KEYS)
def test_the_stream_gives_steps_results_and_state_to_the_bit(key: str, preset: str,
                                                              entry: str) -> None:
    params = paper(key) if preset == "paper" else {}
    rec = noisy_two_axis_recording(4.0)
    samples = list(zip(rec["acc_meas"].tolist(), rec["gyro_meas"].tolist(),
                       rec["dt"].tolist(), strict=True))
    python, stream = make(key, **params), make(key, **params).stream()
    for k, (acc, gyro, dt) in enumerate(samples):
        assert stream.step(acc, gyro, dt) == python.step(acc, gyro, dt), k
        if k == 200:  # a state taken from the stream continues in Python, and back
            snapshot = stream.get_state()
            assert snapshot == python.get_state()
            stream.set_state(snapshot)
    assert stream.get_state() == python.get_state()
    assert stream.last == python.last


@needs_twin
def test_arrays_and_numpy_numbers_step_as_lists_do(entry: str) -> None:
    import numpy as np

    rec = noisy_two_axis_recording(1.0)
    a, b = make("ukf").stream(), make("ukf").stream()
    for acc, gyro, dt in zip(rec["acc_meas"], rec["gyro_meas"], rec["dt"], strict=True):
        assert a.step(acc, gyro, dt) == b.step(acc.tolist(), gyro.tolist(), float(dt))
    assert a.step(np.float32([0.0, 0.0, 9.8]), (0, 0, 0), np.float64(0.01)) == \
        b.step([0.0, 0.0, float(np.float32(9.8))], [0.0, 0.0, 0.0], 0.01)


@needs_twin
def test_a_rejected_sample_says_why_and_leaves_the_state(entry: str) -> None:
    stream = make("kf").stream()
    stream.step((0.0, 0.0, 9.8), (0.0, 0.0, 0.0), 0.01)
    before = stream.get_state()
    with pytest.raises(InvalidSample, match="is not finite"):
        stream.step((float("nan"), 0.0, 9.8), (0.0, 0.0, 0.0), 0.01)
    with pytest.raises(InvalidSample, match="outside the allowed range"):
        stream.step((0.0, 0.0, 9.8), (0.0, 0.0, 0.0), -0.01)
    with pytest.raises(InvalidSample, match="three accelerations"):
        stream.step((0.0, 9.8), (0.0, 0.0, 0.0), 0.01)
    assert stream.get_state() == before


@needs_twin
def test_a_parameter_change_goes_through_the_stream() -> None:
    rec = noisy_two_axis_recording(2.0)
    python, stream = make("cf"), make("cf").stream()
    for i, (acc, gyro, dt) in enumerate(zip(rec["acc_meas"].tolist(), rec["gyro_meas"].tolist(),
                                            rec["dt"].tolist(), strict=True)):
        if i == 50:
            python.set_param("tau", 0.4)
            stream.set_param("tau", 0.4)
        assert stream.step(acc, gyro, dt) == python.step(acc, gyro, dt)


def test_a_class_without_a_twin_of_its_own_is_refused_with_the_reason() -> None:
    class Mine(AngleBiasKalmanFilter):
        pass

    with pytest.raises(ValueError, match="no C twin of its own"):
        Mine().stream()


@needs_twin
def test_a_step_taken_before_set_state_stays_safe_to_call(entry: str) -> None:
    """A step bound before set_state, called after it and a garbage collection, steps a twin
    that is still alive (the compiled entry point keeps the one it was bound to): finite
    estimates, no crash; the stream itself continues from the state it was given."""
    import gc
    import math

    stream = make("kf").stream()
    old = stream.step
    old((0.0, 0.0, 9.8), (0.0, 0.0, 0.0), 0.01)
    stream.set_state(make("kf").get_state())
    gc.collect()
    for _ in range(200):
        e = old((0.0, 0.1, 9.8), (0.01, 0.0, 0.0), 0.01)
        assert math.isfinite(e.roll) and math.isfinite(e.pitch)
    fresh = make("kf")
    stream.set_state(fresh.get_state())
    assert stream.step((0.0, 0.0, 9.8), (0.0, 0.0, 0.0), 0.01) == fresh.step(
        (0.0, 0.0, 9.8), (0.0, 0.0, 0.0), 0.01)

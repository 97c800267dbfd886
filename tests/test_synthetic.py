"""The trajectory's two evaluation paths: numpy on an array of times (Trajectory.truth) and plain
floats at one time (Trajectory.truth_at, the plant FMU's per-step path) give the same truth."""

from __future__ import annotations

import numpy as np
import pytest

from fusion_core import synthetic
from fusion_core.scenarios import SCENARIOS
from fusion_core.synthetic import SCALAR, TRUTH_NAMES


def _times(duration: float) -> np.ndarray:
    """A 1 kHz grid over the scenario, random times, and the whole and half seconds (where the
    minimum-jerk moves start and stop, so both sides of every clip are hit exactly)."""
    rng = np.random.default_rng(11)
    edges = np.arange(0.0, duration + 0.25, 0.5)
    return np.concatenate([np.arange(0.0, duration, 1e-3), rng.uniform(0.0, duration, 500), edges])


def _stacked(d: dict[str, np.ndarray]) -> np.ndarray:
    """truth()'s arrays as columns in the order of TRUTH_NAMES."""
    return np.column_stack([d["roll"], d["pitch"], d["yaw"], d["omega"], d["f"], d["pos"],
                            d["vel"]])


@pytest.mark.heavy  # every scenario's truth sample by sample: seconds
@pytest.mark.parametrize("name", list(SCENARIOS))
def test_truth_at_equals_the_vectorised_truth(name: str) -> None:
    scenario = SCENARIOS[name]
    trajectory = scenario.trajectory()
    t = _times(scenario.duration)
    vector = _stacked(trajectory.truth(t))
    scalar = np.array([trajectory.truth_at(x) for x in t.tolist()])
    assert scalar.shape == (len(t), len(TRUTH_NAMES))
    np.testing.assert_allclose(scalar, vector, rtol=0.0, atol=1e-12)


def test_truth_at_is_plain_python_floats() -> None:
    """No numpy scalar comes out (or is made) on the per-step path."""
    for scenario in SCENARIOS.values():
        values = scenario.trajectory().truth_at(1.25)
        assert all(type(v) is float for v in values), scenario.name


def test_every_signal_gives_the_same_values_on_a_float_and_on_an_array() -> None:
    t = _times(8.0)
    signals = [
        synthetic.constant(0.3),
        synthetic.sine(0.4, 1.3, 0.2, 0.1),
        synthetic.add(synthetic.sine(0.2, 0.5), synthetic.sine(0.1, 2.0, 1.0),
                      synthetic.constant(1)),
        synthetic.min_jerk(-1.0, 2.5, 2.0, 3.0),
    ]
    for s in signals:
        vector = np.column_stack(np.broadcast_arrays(*s(t)))
        scalar = np.array([s(x, SCALAR) for x in t.tolist()])
        np.testing.assert_allclose(scalar, vector, rtol=0.0, atol=1e-12)


def test_min_jerk_is_the_minimum_jerk_polynomial_and_rests_outside_the_move() -> None:
    start, end, t0, duration = 0.5, 2.5, 2.0, 3.0
    move = synthetic.min_jerk(start, end, t0, duration)
    t = np.linspace(0.0, 7.0, 7001)
    pos, vel, acc = move(t)
    s = np.clip((t - t0) / duration, 0.0, 1.0)
    d = end - start
    inside = (t > t0) & (t < t0 + duration)
    np.testing.assert_allclose(pos, start + d * (10 * s**3 - 15 * s**4 + 6 * s**5), atol=1e-14)
    np.testing.assert_allclose(vel, inside * d * (30 * s**2 - 60 * s**3 + 30 * s**4) / duration,
                               atol=1e-14)
    np.testing.assert_allclose(
        acc, inside * d * (60 * s - 180 * s**2 + 120 * s**3) / duration**2, atol=1e-14)
    assert np.all(pos[t <= t0] == start) and np.all(pos[t >= t0 + duration] == end)
    assert np.all(vel[~inside] == 0.0) and np.all(acc[~inside] == 0.0)

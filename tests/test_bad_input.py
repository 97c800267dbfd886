"""Bad samples are refused with InvalidSample and leave the filter exactly as it was; an
untrusted accelerometer (norm near zero or far from g) is not a bad sample (interface v2)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import KEYS, estimator_class, make, noisy_two_axis_recording
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fusion_core import G, InvalidSample
from fusion_core.base import Estimator

NAN = math.nan
INF = math.inf
LEVEL = (0.0, 0.0, G)
STILL = (0.0, 0.0, 0.0)
DT = 0.01

# kind -> (acc, gyro, dt, estimator parameters)
INVALID_SAMPLES: dict[str, tuple[tuple[float, ...], tuple[float, ...], float, dict]] = {
    "acc_nan": ((NAN, 0.0, G), STILL, DT, {}),
    "acc_inf": ((0.0, INF, G), STILL, DT, {}),
    "acc_minus_inf": ((0.0, 0.0, -INF), STILL, DT, {}),
    "gyro_nan": (LEVEL, (0.0, NAN, 0.0), DT, {}),
    "gyro_inf": (LEVEL, (INF, 0.0, 0.0), DT, {}),
    "gyro_minus_inf": (LEVEL, (0.0, 0.0, -INF), DT, {}),
    "dt_nan": (LEVEL, STILL, NAN, {}),
    "dt_inf": (LEVEL, STILL, INF, {}),
    "dt_zero": (LEVEL, STILL, 0.0, {}),
    "dt_negative": (LEVEL, STILL, -DT, {}),
    "dt_above_default_max_dt": (LEVEL, STILL, 1.001, {}),
    "dt_above_max_dt_0p05": (LEVEL, STILL, 0.0501, {"max_dt": 0.05}),
    "gyro_above_default_max_rate": (LEVEL, (1000.001, 0.0, 0.0), DT, {}),
    "gyro_norm_above_max_rate_10": (LEVEL, (6.0, 6.0, 6.0), DT, {"max_rate": 10.0}),
    "gyro_1e300": (LEVEL, (0.0, -1e300, 0.0), DT, {}),
}


def busy_estimator(key: str, **params: object) -> Estimator:
    """An estimator that has processed 200 samples of noisy, biased two-axis motion."""
    est = make(key, **params)
    rec = noisy_two_axis_recording(2.0)
    out = est.run(rec["acc_meas"][:200], rec["gyro_meas"][:200], rec["dt"][:200])
    assert not out["rejected"].any(), f"{out['rejected'].sum()} of 200 valid samples rejected"
    return est


@pytest.mark.parametrize("kind", list(INVALID_SAMPLES))
@pytest.mark.parametrize("key", KEYS)
def test_invalid_sample_raises_and_leaves_state_unchanged(key: str, kind: str) -> None:
    acc, gyro, dt, params = INVALID_SAMPLES[kind]
    est = busy_estimator(key, **params)
    before = est.get_state()
    with pytest.raises(InvalidSample):
        est.step(acc, gyro, dt)
    assert est.get_state() == before


@pytest.mark.parametrize("kind", list(INVALID_SAMPLES))
@pytest.mark.parametrize("key", KEYS)
def test_invalid_first_sample_leaves_filter_uninitialised(key: str, kind: str) -> None:
    acc, gyro, dt, params = INVALID_SAMPLES[kind]
    est = make(key, **params)
    before = est.get_state()
    with pytest.raises(InvalidSample):
        est.step(acc, gyro, dt)
    assert est.get_state() == before
    assert est.get_state()["state"]["initialized"] is False


@pytest.mark.parametrize("key", KEYS)
def test_samples_at_the_limits_are_accepted(key: str) -> None:
    """dt = max_dt and a rate of exactly max_rate are valid, and so is any finite accelerometer
    reading: only dt > max_dt and a rate above max_rate are refused."""
    est = busy_estimator(key, max_dt=0.05, max_rate=10.0)
    est.step(LEVEL, STILL, 0.05)
    est.step(LEVEL, (6.0, 8.0, 0.0), DT)
    for acc in ((0.0, 0.0, 0.0), (0.0, 0.0, 0.099 * G), (1e300, -1e300, 1e-320), (0, 0, 50 * G)):
        est.step(acc, STILL, DT)
    assert est.get_state()["state"]["n_samples"] == 206


@pytest.mark.parametrize("acc", [(0.0, 0.0, 0.0), (0.01 * G, 0.0, 0.02 * G), (0.0, 0.0, 1e-320),
                                 (3e5, 1e300, -2e300)], ids=["zero", "0.02g", "subnormal", "1e300"])
@pytest.mark.parametrize("key", KEYS)
def test_untrusted_accelerometer_integrates_the_gyro_and_skips_the_correction(
    key: str, acc: tuple[float, float, float]
) -> None:
    """Free fall or an absurd reading: the sample is processed, not rejected; the gyro turns the
    attitude as it would with the accelerometer's correction off, and nothing becomes
    non-finite. 20 such samples turning about x at 1 rad/s: roll moves by 0.2 rad."""
    est = busy_estimator(key, gyro_sampling="mean")
    roll0 = est.last.roll
    for _ in range(20):
        e = est.step(acc, (1.0, 0.0, 0.0), DT)
        assert all(math.isfinite(v) for v in (e.roll, e.pitch, *e.bias))
    assert est.n_rejected == 0
    assert abs((est.last.roll - roll0) - 0.2) < 0.02


@pytest.mark.parametrize("key", KEYS)
def test_first_samples_without_gravity_wait_for_one_that_has_it(key: str) -> None:
    """An accelerometer below 0.1 g cannot initialise roll and pitch: the filter waits (the
    sample is skipped, not rejected) and starts from the first sample that has gravity."""
    est = make(key)
    est.step((0.0, 0.0, 0.05 * G), STILL, DT)
    assert est.get_state()["state"]["initialized"] is False and est.n_rejected == 0
    est.step((0.0, G * math.sin(0.3), G * math.cos(0.3)), STILL, DT)
    assert est.get_state()["state"]["initialized"] is True
    assert est.last.roll == pytest.approx(0.3, abs=1e-12)


@pytest.mark.parametrize("key", KEYS)
def test_run_flags_rejected_samples_and_repeats_the_previous_estimate(key: str) -> None:
    rec = noisy_two_axis_recording(1.0)
    acc, gyro, dt = rec["acc_meas"].copy(), rec["gyro_meas"].copy(), rec["dt"].copy()
    bad = [0, 10, 11, 50]
    acc[0, 1] = NAN
    gyro[10, 2] = INF
    dt[11] = 0.0
    gyro[50] = 2000.0
    acc[60] = 0.0  # free fall: processed
    out = make(key).run(acc, gyro, dt)
    assert np.flatnonzero(out["rejected"]).tolist() == bad
    fields = [f for f in ("roll", "pitch", "bias", "pos", "vel") if f in out]
    for i in bad[1:]:
        for f in fields:
            assert np.array_equal(out[f][i], out[f][i - 1]), (f, i)


# ---- property: whatever mix of valid and invalid samples, the estimate stays finite ----------

MAX_DT = 1.0  # the default max_dt


@st.composite
def valid_sample(draw: st.DrawFn) -> tuple[list[float], list[float], float]:
    """Anything a real IMU can send: |acc| from 0 to 16 g in any direction (upside down and
    pitch +-90 deg included), rates within +-2000 deg/s, 0 < dt <= max_dt."""
    direction = draw(
        st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: sum(x * x for x in v) > 1e-6)
    )
    norm = draw(st.floats(0.0, 16.0 * G) | st.just(G))
    length = math.sqrt(sum(x * x for x in direction))
    acc = [norm * x / length for x in direction]
    gyro = [draw(st.floats(-35.0, 35.0)) for _ in range(3)]
    dt = draw(st.floats(1e-4, MAX_DT) | st.just(0.01))
    return acc, gyro, dt


@st.composite
def invalid_sample(draw: st.DrawFn) -> tuple[list[float], list[float], float]:
    acc, gyro, dt = draw(valid_sample())
    kind = draw(
        st.sampled_from(
            ["acc", "gyro", "dt_nonfinite", "dt_nonpositive", "dt_large", "gyro_large"]
        )
    )
    bad = st.sampled_from([NAN, INF, -INF])
    if kind == "acc":
        acc[draw(st.integers(0, 2))] = draw(bad)
    elif kind == "gyro":
        gyro[draw(st.integers(0, 2))] = draw(bad)
    elif kind == "dt_nonfinite":
        dt = draw(bad)
    elif kind == "dt_nonpositive":
        dt = draw(st.floats(-10.0, 0.0))
    elif kind == "dt_large":
        dt = draw(st.floats(MAX_DT, 1e6, exclude_min=True))
    else:
        gyro[draw(st.integers(0, 2))] = draw(st.floats(1000.001, 1e308) | st.floats(-1e308, -1001))
    return acc, gyro, dt


samples = st.lists(st.one_of(valid_sample(), invalid_sample()), min_size=1, max_size=40)


@pytest.mark.heavy  # hypothesis: many recordings per estimator
@pytest.mark.parametrize("key", KEYS)
def test_mixed_valid_and_invalid_samples_never_give_a_non_finite_estimate(key: str) -> None:
    cls = estimator_class(key)
    examples = 0

    @settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
    @given(sequence=samples)
    def check(sequence: list[tuple[list[float], list[float], float]]) -> None:
        nonlocal examples
        examples += 1
        acc = np.array([s[0] for s in sequence])
        gyro = np.array([s[1] for s in sequence])
        dt = np.array([s[2] for s in sequence])
        out = cls().run(acc, gyro, dt)
        for name in ("roll", "pitch", "bias", "pos", "vel"):
            if name in out:
                assert np.all(np.isfinite(out[name])), (name, out[name])

    check()
    print(f"\n{key}: {examples} hypothesis examples")

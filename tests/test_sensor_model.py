"""The realistic sensor model's parts, each against a known answer, and the ideal setting."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from fusion_core import DEG, G
from fusion_core.sensor import DLPF_TABLE, SENSOR_PRESETS, ImuSensorModel

QUIET = {**SENSOR_PRESETS["ideal"], "gyro_psd": 0.0, "acc_psd": 0.0, "bits": 0}
"""A sensor with every error off, to switch one on at a time."""


def samples(model: ImuSensorModel, omega, f, h: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    out = [model.sample(omega(k * h) if callable(omega) else omega,
                        f(k * h) if callable(f) else f, h) for k in range(1, n + 1)]
    return np.array([o[0] for o in out]), np.array([o[1] for o in out])


def test_the_per_run_bias_appears_as_a_constant_offset_drawn_from_the_seed() -> None:
    model = ImuSensorModel(**{**QUIET, "calibration": "startup"}, seed=3)
    _acc, gyro = samples(model, (0.1, -0.2, 0.3), (0.0, 0.0, G), 0.01, 200)
    offset = gyro - np.array([0.1, -0.2, 0.3])
    assert np.ptp(offset, axis=0).max() < 1e-15  # constant
    assert np.allclose(offset[0], model.gyro_turn_on, atol=1e-15)
    assert 0.0 < np.abs(offset[0]).max() < 5 * 0.16 * DEG
    other = ImuSensorModel(**{**QUIET, "calibration": "startup"}, seed=4)
    assert other.gyro_turn_on != model.gyro_turn_on
    assert ImuSensorModel(**{**QUIET, "calibration": "startup"}, seed=3).gyro_turn_on == \
        model.gyro_turn_on


def test_uncalibrated_turn_on_bias_reaches_the_datasheet_tolerance() -> None:
    biases = np.array([ImuSensorModel(calibration="none", seed=s).gyro_turn_on
                       for s in range(300)])
    assert biases.std() == pytest.approx(20.0 / 3.0 * DEG, rel=0.1)


@pytest.mark.heavy
@pytest.mark.parametrize("cfg", [3, 4, 5])
def test_the_dlpf_corner_frequency_from_a_sine_sweep_is_the_datasheets(cfg: int) -> None:
    """At 1 kHz the gyro's DLPF passes a sine at its datasheet bandwidth at -3 dB (1/sqrt 2)."""
    rate, bandwidth = 1000.0, DLPF_TABLE[cfg][2]
    h = 1.0 / rate

    def gain(freq: float) -> float:
        model = ImuSensorModel(**{**QUIET, "dlpf_cfg": cfg})
        _, gyro = samples(model, lambda t: (math.sin(2 * math.pi * freq * t), 0.0, 0.0),
                          (0.0, 0.0, G), h, 4000)
        return float(np.abs(gyro[2000:, 0]).max())

    lo, hi = 0.5 * bandwidth, 1.5 * bandwidth  # the -3 dB frequency, bisected to 1/128 of it
    assert gain(lo) > 1 / math.sqrt(2) > gain(hi)
    for _ in range(7):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gain(mid) > 1 / math.sqrt(2) else (lo, mid)
    corner = 0.5 * (lo + hi)
    assert corner == pytest.approx(bandwidth, rel=0.03)
    assert gain(0.1 * bandwidth) == pytest.approx(1.0, abs=0.01)


def test_a_dlpf_above_the_nyquist_frequency_keeps_the_datasheet_delay() -> None:
    """At 100 Hz, DLPF_CFG 0 (256 Hz) cannot show its magnitude response; its 0.98 ms of gyro
    delay stays: a ramp reads 0.98 ms late."""
    model = ImuSensorModel(**{**QUIET, "dlpf_cfg": 0})
    _, gyro = samples(model, lambda t: (t, 0.0, 0.0), (0.0, 0.0, G), 0.01, 50)
    t = np.arange(1, 51) * 0.01
    assert np.allclose(gyro[5:, 0], t[5:] - 0.98e-3, atol=1e-12)


def test_quantisation_step_is_two_full_scales_over_two_to_the_bits() -> None:
    model = ImuSensorModel(**{**QUIET, "bits": 16})
    lsb = 2 * 2000.0 * DEG / 2**16
    _, gyro = samples(model, (0.3 * lsb, 1.6 * lsb, 1000.3 * lsb), (0.0, 0.0, G), 0.01, 3)
    assert np.array_equal(gyro[0], [0.0, 2 * lsb, 1000 * lsb])


def test_saturation_at_the_full_scale_range() -> None:
    model = ImuSensorModel(**QUIET)
    acc, gyro = samples(model, (50.0, -50.0, 1.0), (0.0, 0.0, 30 * G), 0.01, 2)
    assert gyro[0].tolist() == [2000.0 * DEG, -2000.0 * DEG, 1.0]
    assert acc[0].tolist() == [0.0, 0.0, 16.0 * G]


def test_mean_sampling_delivers_the_rate_averaged_over_the_interval() -> None:
    """A rate ramp w = t: the point sample at t_k is t_k, the interval mean t_k - h/2."""
    h = 0.01
    for sampling, lag in (("point", 0.0), ("mean", h / 2)):
        model = ImuSensorModel(**{**QUIET, "gyro_sampling": sampling})
        _, gyro = samples(model, lambda t: (t, 0.0, 0.0), (0.0, 0.0, G), h, 20)
        t = np.arange(1, 21) * h
        assert np.allclose(gyro[1:, 0], t[1:] - lag, atol=1e-15)


def test_scale_and_cross_axis_errors_are_a_fixed_matrix_per_seed() -> None:
    model = ImuSensorModel(**{**QUIET, "gyro_scale_std": 0.01, "gyro_cross_axis_std": 0.0067},
                           seed=5)
    _, gyro = samples(model, (1.0, 0.0, 0.0), (0.0, 0.0, G), 0.01, 3)
    column = np.array(model.gyro_matrix)[:, 0]
    assert np.allclose(gyro[0], column, atol=1e-15)
    assert abs(column[0] - 1.0) < 0.05 and 0.0 < np.abs(column[1:]).max() < 0.04


@pytest.mark.heavy  # statistics over long recordings
def test_bias_instability_wanders_with_its_standard_deviation() -> None:
    model = ImuSensorModel(**{**QUIET, "gyro_bias_instability": 0.003 * DEG,
                              "bias_time_constant": 1.0})
    _, gyro = samples(model, (0.0, 0.0, 0.0), (0.0, 0.0, G), 0.01, 60000)
    assert gyro.std() == pytest.approx(0.003 * DEG, rel=0.15)


def test_the_ideal_sensor_has_white_noise_only() -> None:
    model = ImuSensorModel(**{**SENSOR_PRESETS["ideal"], "bits": 0}, seed=1)
    _acc, gyro = samples(model, (0.0, 0.0, 0.0), (0.0, 0.0, G), 0.01, 20000)
    assert np.abs(gyro.mean(axis=0)).max() < 4 * 0.005 * DEG * 10 / math.sqrt(20000)
    assert gyro.std() == pytest.approx(0.005 * DEG * 10, rel=0.03)


def test_state_round_trip_continues_bit_identically() -> None:
    a = ImuSensorModel(seed=9)
    samples(a, (0.2, 0.1, -0.3), (0.5, -0.2, G), 0.01, 50)
    b = ImuSensorModel(seed=1)
    b.set_state(a.get_state())
    ra = samples(a, (0.2, 0.1, -0.3), (0.5, -0.2, G), 0.01, 50)
    rb = samples(b, (0.2, 0.1, -0.3), (0.5, -0.2, G), 0.01, 50)
    assert np.array_equal(ra[0], rb[0]) and np.array_equal(ra[1], rb[1])


def test_the_noise_of_sample_k_depends_on_the_seed_and_k_only() -> None:
    """Counter-based noise (fusion_core.noise): a model restored from a snapshot taken at any
    sample, even by a fresh process, draws exactly the samples the uninterrupted one draws."""
    omega, f, h = (0.1, -0.2, 0.05), (0.3, 0.1, 9.7), 0.01
    whole = ImuSensorModel(seed=11)
    first = [whole.sample(omega, f, h) for _ in range(1500)]
    part = ImuSensorModel(seed=11)
    for _ in range(700):
        part.sample(omega, f, h)
    snapshot = json.loads(json.dumps(part.get_state()))  # through JSON, as an FMU stores it
    resumed = ImuSensorModel(seed=0)
    resumed.set_state(snapshot)
    assert [resumed.sample(omega, f, h) for _ in range(800)] == first[700:]
    assert ImuSensorModel(seed=12).sample(omega, f, h) != first[0]


def test_without_jitter_the_sample_dt_is_the_step_to_the_picosecond():
    """A host's step carries its time grid's rounding (0.01 as 0.009999999999999787); the
    sample's dt is the period itself, in both twins, so that results compare exactly."""
    from fusion_core.sensor import ImuSensorModel

    for h in (0.009999999999999787, 0.01000000000000156):
        _, _, dt = ImuSensorModel(seed=1).sample((0.0, 0.0, 0.0), (0.0, 0.0, 9.8), h)
        assert dt == 0.01
    out = ImuSensorModel(seed=1).run(np.zeros((3, 3)), np.tile([0.0, 0.0, 9.8], (3, 1)),
                                     np.array([0.009999999999999787, 0.01, 0.01000000000000156]))
    assert np.all(out["dt"] == 0.01)

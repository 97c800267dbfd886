"""Named parameter sets of the estimators: `create(key, preset_params(name, key))`.

Two sets, as the interface contract names them:

- "recommended": values for real MEMS IMUs. They are the classes' own defaults (so the dicts
  here are empty) and the start values of every FMU; each value's derivation is in the
  docstring of its estimator class, in this order of sources: sensor physics (noise densities,
  sampling, scale-factor class, range, the accelerometer's trust), then, only where physics
  fixes nothing, a coarse scan checked by cross-validation across groups of recordings
  (`python -m testbenches broad DIR --cv`: each scanned value chosen again without each group
  and scored on it), never an in-sample minimum.
- "paper": the seed papers' own filters (fusion_core.papers, chosen by "filter": "paper"), at
  their values and rules, to reproduce their results. The papers tune for one calibrated sensor
  at one loop rate and integrate the gyro with the rectangle rule; on a real IMU at another rate
  their gains are far off (docs, "Presets"). None of them turns its output ahead over the
  sensor's delay: sensor_delay 0 in each, also where a recording states the delay of its
  sensor.

A preset may also be a JSON file with the same shape, {"kf": {"R_measure": 1e-4, ...}, ...},
for any subset of the estimators, a paper's filter chosen by "filter": "paper" in its entry
(load_preset); `python -m testbenches tune` and `noise` write
such files.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from .base import SensorNoise
from .registry import FILTER, KEYS, REGISTRY, create
from .types import GYRO_RANGE_DEFAULT, read_json

PAPER_RULES: dict[str, Any] = {"gyro_sampling": "mean", "sensor_delay": 0.0}
"""What every paper's filter keeps whatever the recording's sensor says: the rectangle rule, and
outputs not turned ahead over the sensor's delay (a recording's sensor properties fill in only
what a parameter set leaves open: testbenches.broad)."""
PAPER: dict[str, dict[str, Any]] = {k: {FILTER: "paper", **PAPER_RULES} for k in KEYS}
"""The papers' filters (fusion_core.papers), each at its paper's values (their defaults)."""

PRESETS: dict[str, dict[str, dict[str, Any]]] = {
    "recommended": {k: {} for k in KEYS},
    "paper": PAPER,
}
"""Preset name -> estimator key -> parameters (see the module docstring)."""

RENAMED_PRESETS = {"default": "paper", "broad": "recommended"}
"""Preset names of version 0.2, and what each became."""


def _unknown(name: str) -> ValueError:
    hint = (f" ('{name}' is now '{RENAMED_PRESETS[name]}')" if name in RENAMED_PRESETS else "")
    return ValueError(f"unknown preset {name!r}{hint}: allowed {', '.join(PRESETS)} or a JSON "
                      "file of parameters per estimator")


REFERENCE_ACC_SAMPLE_STD = 0.05
"""Standard deviation of one accelerometer sample at rest [m/s^2] on the real MEMS IMU the
recommended values are derived for (BROAD's myon aktos-t: 0.045-0.07 m/s^2 per axis)."""


def noise_preset(gyro_density: float, acc_density: float, acc_sample_std: float,
                 gyro_range: float = GYRO_RANGE_DEFAULT, gyro_bias_std: float = 0.0
                 ) -> dict[str, dict[str, float]]:
    """The recommended values that follow from a sensor's noise, per estimator: each class's
    noise_params (base.SensorNoise; the derivations are theirs), which `imu-fusion noise`
    applies to a user's own sensor. gyro_density [rad/s/sqrt(Hz)] and acc_density
    [m/s^2/sqrt(Hz)] are the white-noise densities (the Allan deviation at tau = 1 s),
    acc_sample_std [m/s^2] the standard deviation of one accelerometer sample at rest at the
    rate the filter will run, gyro_bias_std [rad/s] the spread of the gyro bias a part starts
    a run with. gyro_range [rad/s], the gyro's full-scale setting (a datasheet value no static
    recording shows), goes to every estimator: a sample at it is clipped (base.Estimator).

    The recommended defaults are this function at the reference sensor,
    building_blocks.REAL_GYRO_DENSITY, position.REAL_ACC_DENSITY and REFERENCE_ACC_SAMPLE_STD
    (tests/test_presets.py holds them to it; the acc_noise of cf, mgcf and ukf is rounded to
    0.005)."""
    noise = SensorNoise(gyro_density, acc_density, acc_sample_std, gyro_bias_std)
    return {e.key: {**e.cls.noise_params(noise), "gyro_range": gyro_range} for e in REGISTRY}


def preset_params(preset: str, key: str) -> dict[str, Any]:
    """A copy of a named preset's parameters for estimator `key` (ValueError for an unknown
    name)."""
    if preset not in PRESETS:
        raise _unknown(preset)
    if key not in PRESETS[preset]:
        raise ValueError(f"preset {preset!r} has no estimator {key!r}: it has "
                         f"{', '.join(PRESETS[preset])}")
    return dict(PRESETS[preset][key])


def load_preset(spec: str | Path) -> dict[str, dict[str, Any]]:
    """Every estimator's parameters of a preset given by name ("recommended", "paper") or as a
    JSON file {"kf": {...}, ...} (estimators it leaves out get {}: their recommended values).
    Each parameter set is checked by building its estimator: a ValueError names what is wrong."""
    text = str(spec)
    if text in PRESETS:
        return {k: dict(v) for k, v in PRESETS[text].items()}
    path = Path(text)
    if not path.suffix == ".json":
        raise _unknown(text)
    data = read_json(path, "preset file")
    if not isinstance(data, dict) or not all(isinstance(v, dict) for v in data.values()):
        raise ValueError(f"preset file {path}: expected an object of parameter objects per "
                         f"estimator, e.g. {{\"kf\": {{\"R_measure\": 0.0001}}}}")
    unknown = sorted(set(data) - set(KEYS))
    if unknown:
        raise ValueError(f"preset file {path}: unknown estimator(s) {', '.join(unknown)}: "
                         f"allowed {', '.join(KEYS)}")
    out = {k: dict(data.get(k, {})) for k in KEYS}
    for key, params in out.items():
        try:
            create(key, params)
        except ValueError as err:
            raise ValueError(f"preset file {path}, {key}: {err}") from None
    return out


__all__ = ["KEYS", "PAPER", "PRESETS", "load_preset", "preset_params"]

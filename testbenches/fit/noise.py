"""`python -m testbenches noise`: a static recording in; noise densities, a preset for every
estimator and the sensor FMU's parameters for that sensor out.

From the Allan deviation of each axis (allan.py): the white-noise densities (gyro_psd, acc_psd:
their squares, the units of the sensor FMU's parameters), the rate random walk (gyro_bias_psd,
acc_bias_psd) and the bias instability, per axis and their mean; beside them the static biases,
the accelerometer's norm and one sample's standard deviation. The preset is
fusion_core.presets.noise_preset of those numbers (the derivation the recommended defaults come
from), so the command and the defaults cannot drift apart.
"""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.presets import noise_preset
from fusion_core.registry import create
from fusion_core.types import DEG, GYRO_RANGE_DEFAULT, G

from ..gyro_unit import UNITS
from .allan import AllanFit, allan_deviation, fit
from .recording import PER_SAMPLE, Recording, RecordingError

MIN_DURATION_S = 20.0
"""The white-noise fit needs taus up to a few seconds, each averaged over ten clusters at least."""
LONG_DURATION_S = 2 * 3600.0
"""Bias instability and rate random walk of a MEMS IMU show from minutes to an hour: record this
long to resolve them (the usual 2 h static recording)."""
MAX_GYRO_SWING = 1.0 * DEG
"""Peak-to-peak of the gyro's 1 s means [rad/s] beyond which the recording is not static."""
QUIETEST_MEMS_GYRO = 2e-4 * DEG
"""Gyro white-noise density [rad/s/sqrt(Hz)] below the quietest MEMS parts' (high-end MEMS
IMUs reach about 3e-4 deg/s/sqrt(Hz), an angle random walk of 0.02 deg/sqrt(h); consumer parts
5e-3 to 1e-2): a figure below it is a fibre-optic or ring-laser gyro's, or a MEMS gyro's read in
a unit 57 times too large (rad/s data read as deg/s)."""
MAX_TILT_CHANGE = 1.0 * DEG
"""Change of the accelerometer's direction (1 s means) beyond which the sensor moved."""
STILL_SHARE = 0.5
"""A recording the sensor moved in, its gyro unit not confirmed by its data, is analysed on its
longest still stretch where that holds at least this share of it (a bump or two on the table):
a gyro read in a unit 57 times too large makes noise look like rotation with still flukes
between. Where its turns confirmed the unit (testbenches.gyro_unit), any still stretch of
MIN_DURATION_S serves (a log that rests before it moves)."""
STRETCH_MARGIN = 0.5
"""A stretch taken out of a recording the sensor moved in keeps within this share of the
bounds above: still, not just within them (a recording whose gyro noise reads as rotation, its
unit wrong, holds stretches just within them by chance)."""
AXES = ("x", "y", "z")


def check_static(rec: Recording) -> None:
    """RecordingError unless rec is long enough and static (see the constants)."""
    if rec.duration < MIN_DURATION_S:
        raise RecordingError(
            f"{rec.name}: {rec.duration:.1f} s is too short: the white-noise fit needs at least "
            f"{MIN_DURATION_S:.0f} s at rest ({LONG_DURATION_S / 3600:.0f} h to resolve the bias "
            "instability and the random walk)")
    if (moved := _moved(rec)) is not None:
        raise RecordingError("".join(moved))


def _moved(rec: Recording) -> tuple[str, str] | None:
    """Why rec is not static, and where a wrong gyro unit would explain it, the unit that
    would (else ""); None where it is static."""
    block = max(1, round(rec.rate))
    n = len(rec.dt) // block * block
    g_means = rec.gyro[:n].reshape(-1, block, 3).mean(axis=1)
    swing = float(np.max(np.ptp(g_means, axis=0)))
    if swing > MAX_GYRO_SWING:
        other = _other_unit(rec, swing, lambda v: v <= MAX_GYRO_SWING)
        return (f"{rec.name}: not static: rotation seen in the gyro (its 1 s means move by "
                f"{np.degrees(swing):.2f} deg/s, allowed {np.degrees(MAX_GYRO_SWING):.1f}); "
                "record with the sensor at rest", "" if other is None else
                f". Or it was at rest and its gyro is not in {rec.gyro_unit}, which a still "
                f"recording cannot confirm: in {other[0]} its 1 s means move by "
                f"{np.degrees(other[1]):.3g} deg/s (--gyro-unit {other[0]})")
    a_means = rec.acc[:n].reshape(-1, block, 3).mean(axis=1)
    u = a_means / np.linalg.norm(a_means, axis=1, keepdims=True)
    tilt = float(np.max(np.arccos(np.clip(u @ u[0], -1.0, 1.0))))
    if tilt > MAX_TILT_CHANGE:
        return (f"{rec.name}: not static: the accelerometer's direction changed by "
                f"{np.degrees(tilt):.2f} deg (allowed {np.degrees(MAX_TILT_CHANGE):.1f}): the "
                "sensor moved", "")
    return None


def numbers_only(rec: Recording) -> tuple[Recording, str]:
    """rec without its samples that lack a number in a column (a logger's empty cell, NaN),
    the rest taken as one series at its rate, and a note counting them ("" where none): the
    Allan deviation needs every sample, and a few taken out move a static recording's noise
    figures by nothing a fit resolves (as the estimators reject and count such samples)."""
    valid = rec.valid
    if valid.all():
        return rec, ""
    kept = replace(rec, **{name: None if (v := getattr(rec, name)) is None else v[valid]
                           for name in PER_SAMPLE})
    return kept, (f"{int((~valid).sum())} of {len(valid)} samples without a number in every "
                  "column left out, the others taken as one series")


def still_part(rec: Recording) -> tuple[Recording, str]:
    """rec where it is static throughout (check_static), else its longest stretch of whole
    seconds that is, and a note saying which: a bump on the table an hour into a two-hour
    recording costs the hour, not the recording. RecordingError where rec is too short, or its
    longest still stretch is shorter than MIN_DURATION_S or, its gyro unit unconfirmed by its
    data, STILL_SHARE of it (check_static's refusal, with the stretch): such a recording that
    moves that much may have its gyro unit wrong, whose noise then reads as rotation with still
    flukes between."""
    if rec.duration < MIN_DURATION_S or (moved := _moved(rec)) is None:
        check_static(rec)
        return rec, ""
    lo, hi = _longest_still(rec)
    part = rec.slice(lo, hi)
    share = 0.0 if rec.gyro_unit_checked else STILL_SHARE
    if part.duration < max(MIN_DURATION_S, share * rec.duration):
        why, unit = moved
        raise RecordingError(
            f"{why}. Its longest still stretch, {part.duration:.0f} s of {rec.duration:.0f} s, "
            f"is too short to be used instead (at least {MIN_DURATION_S:.0f} s"
            + (f" and {STILL_SHARE * 100:.0f} % of the recording, its gyro unit unconfirmed "
               "by its data" if share else "") + f"){unit}")
    check_static(part)
    t = np.cumsum(rec.dt) - rec.dt[0]
    return part, (f"the sensor moved: its longest still stretch used, {t[lo]:.0f}-{t[hi - 1]:.0f}"
                  f" s of {rec.duration:.0f} s")


def _longest_still(rec: Recording) -> tuple[int, int]:
    """The samples [lo, hi) of rec's longest run of whole seconds within which the gyro's 1 s
    means move by at most STRETCH_MARGIN of MAX_GYRO_SWING per axis and the accelerometer's
    direction's by at most that of MAX_TILT_CHANGE per component (a window's subwindows keep
    both: a sliding window finds it)."""
    import collections

    block = max(1, round(rec.rate))
    n = len(rec.dt) // block
    g = rec.gyro[:n * block].reshape(n, block, 3).mean(axis=1)
    a = rec.acc[:n * block].reshape(n, block, 3).mean(axis=1)
    u = a / np.linalg.norm(a, axis=1, keepdims=True)
    features = np.column_stack([g, u])
    limits = [STRETCH_MARGIN * MAX_GYRO_SWING] * 3 + [STRETCH_MARGIN * MAX_TILT_CHANGE] * 3
    highs: list[collections.deque[int]] = [collections.deque() for _ in limits]
    lows: list[collections.deque[int]] = [collections.deque() for _ in limits]
    best, left = (0, 0), 0
    for right in range(n):
        row = features[right]
        if not np.all(np.isfinite(row)):  # a second with a missing value ends a stretch
            left = right + 1
            for q in (*highs, *lows):
                q.clear()
            continue
        for k, value in enumerate(row):
            while highs[k] and features[highs[k][-1], k] <= value:
                highs[k].pop()
            highs[k].append(right)
            while lows[k] and features[lows[k][-1], k] >= value:
                lows[k].pop()
            lows[k].append(right)
        while any(features[highs[k][0], k] - features[lows[k][0], k] > limit
                  for k, limit in enumerate(limits)):
            left += 1
            for q in (*highs, *lows):
                while q and q[0] < left:
                    q.popleft()
        if right + 1 - left > best[1] - best[0]:
            best = (left, right + 1)
    return best[0] * block, best[1] * block


def _other_unit(rec: Recording, value: float, passes: Any) -> tuple[str, float] | None:
    """Where rec's gyro unit is unconfirmed by the data: the unit nearest to it in which a gyro
    figure (`value`, proportional to the gyro's readings) would pass (`passes(value)`), and the
    figure in that unit; None where none would or the data confirmed the unit."""
    if rec.gyro_unit_checked:
        return None
    ratios = sorted(((f / UNITS[rec.gyro_unit], u) for u, f in UNITS.items()
                     if u != rec.gyro_unit), key=lambda ru: abs(math.log(ru[0])))
    return next(((u, value * r) for r, u in ratios if passes(value * r)), None)


def _axes(values: list[float | None]) -> dict[str, float | None]:
    out: dict[str, float | None] = dict(zip(AXES, values, strict=True))
    known = [v for v in values if v is not None]
    out["mean"] = float(np.mean(known)) if len(known) == len(values) else None
    return out


def _squared(d: dict[str, float | None]) -> dict[str, float | None]:
    return {k: (None if v is None else v * v) for k, v in d.items()}


def analyse(rec: Recording) -> tuple[dict[str, Any], dict[str, list[AllanFit]]]:
    """noise.json's content for a static recording (its longest still stretch where the sensor
    moved: still_part), and the fits per signal (for the plot)."""
    rec, missing = numbers_only(rec)
    rec, moved = still_part(rec)
    fits = {
        "gyro": [fit(*allan_deviation(rec.gyro[:, i], rec.rate)) for i in range(3)],
        "acc": [fit(*allan_deviation(rec.acc[:, i], rec.rate)) for i in range(3)],
    }
    out: dict[str, Any] = {
        "recording": {"name": rec.name, "samples": len(rec.dt), "duration_s": rec.duration,
                      "rate_hz": rec.rate},
        "units": {"gyro_density": "rad/s/sqrt(Hz)", "gyro_psd": "rad2/s (= (rad/s)^2/Hz)",
                  "acc_density": "m/s2/sqrt(Hz)", "acc_psd": "m2/s3 (= (m/s^2)^2/Hz)",
                  "gyro_bias_psd": "rad2/s3", "acc_bias_psd": "m2/s5",
                  "gyro_bias_instability": "rad/s", "acc_bias_instability": "m/s2"},
    }
    for sig in ("gyro", "acc"):
        f = fits[sig]
        density = _axes([x.white for x in f])
        walk = _axes([x.random_walk for x in f])
        out[f"{sig}_density"] = density
        out[f"{sig}_psd"] = _squared(density)
        out[f"{sig}_bias_psd"] = _squared(walk)
        out[f"{sig}_bias_instability"] = _axes([x.instability for x in f])
        out[f"{sig}_white_fit_taus_s"] = [list(x.white_taus) for x in f]
    out["gyro_density_deg_s_sqrt_hz"] = float(np.degrees(out["gyro_density"]["mean"]))
    out["acc_density_ug_sqrt_hz"] = float(out["acc_density"]["mean"] / G * 1e6)
    out["gyro_static_bias"] = dict(zip(AXES, rec.gyro.mean(axis=0).tolist(), strict=True))
    out["acc_mean"] = dict(zip(AXES, rec.acc.mean(axis=0).tolist(), strict=True))
    norm = float(np.linalg.norm(rec.acc.mean(axis=0)))
    out["acc_norm"] = norm
    out["acc_norm_g"] = norm / G
    out["acc_sample_std"] = float(np.mean(np.std(rec.acc, axis=0)))
    notes = [n for n in (missing, moved) if n]
    if rec.duration < LONG_DURATION_S:
        notes.append(f"{rec.duration:.0f} s of data: bias instability and random walk need "
                     f"about {LONG_DURATION_S / 3600:.0f} h at rest to be resolved; null in "
                     "noise.json where this recording does not reach them")
    density = out["gyro_density"]["mean"]
    if density < QUIETEST_MEMS_GYRO:
        other = _other_unit(rec, density, lambda v: v >= QUIETEST_MEMS_GYRO)
        notes.append(
            f"a gyro white noise of {np.degrees(density):.3g} deg/s/sqrt(Hz) is a "
            "navigation-grade gyro's (fibre-optic or ring laser), below any MEMS part's "
            f"({np.degrees(QUIETEST_MEMS_GYRO):.1g} and more)" + ("" if other is None else
            f": if the part is MEMS, its gyro is not in {rec.gyro_unit}, which a still "
            f"recording cannot confirm: in {other[0]} the noise is {np.degrees(other[1]):.3g} "
            f"deg/s/sqrt(Hz) (--gyro-unit {other[0]})"))
    if notes:
        out["note"] = "; ".join(notes)
    return out, fits


def preset_for(noise: dict[str, Any]) -> dict[str, dict[str, float]]:
    """The recommended-style preset for every estimator (fusion_core.presets.noise_preset)."""
    return noise_preset(noise["gyro_density"]["mean"], noise["acc_density"]["mean"],
                        noise["acc_sample_std"], noise.get("gyro_range", GYRO_RANGE_DEFAULT),
                        noise.get("gyro_bias_std", 0.0))


def sensor_params(noise: dict[str, Any]) -> dict[str, float]:
    """The sensor FMU's (ImuSensor's) parameters for this sensor: its white noise, and its bias
    instability and random walk where the recording resolved them (the per-run calibration
    residual, scale and cross-axis errors keep the model's defaults)."""
    out = {"gyro_psd": noise["gyro_psd"]["mean"], "acc_psd": noise["acc_psd"]["mean"],
           "gyro_range": noise.get("gyro_range", GYRO_RANGE_DEFAULT)}
    for sig in ("gyro", "acc"):
        b = noise[f"{sig}_bias_instability"]["mean"]
        if b is not None:
            out[f"{sig}_bias_instability"] = b
        k = noise[f"{sig}_bias_psd"]["mean"]
        if k is not None:
            out[f"{sig}_bias_psd"] = k
    return out


def plot(fits: dict[str, list[AllanFit]], path: Path, title: str) -> None:
    """allan.png: the Allan deviation of each axis with the fitted lines, as datasheets show it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    scale = {"gyro": (np.degrees(1.0) * 3600.0, "Allan deviation [deg/h]"),
             "acc": (1e6 / G, "Allan deviation [ug]")}
    for ax, (sig, f) in zip(axes, fits.items(), strict=True):
        k, label = scale[sig]
        for axis, x in zip(AXES, f, strict=True):
            line = ax.loglog(x.taus, x.adev * k, label=f"{sig} {axis}")[0]
            t = x.taus
            ax.loglog(t, x.white / np.sqrt(t) * k, "--", color=line.get_color(), lw=0.8)
            if x.random_walk is not None:
                ax.loglog(t, x.random_walk * np.sqrt(t / 3.0) * k, ":", color=line.get_color(),
                          lw=0.8)
            if x.instability is not None:
                ax.plot(x.instability_tau, x.instability * 0.664 * k, "o",
                        color=line.get_color())
        ax.set_xlabel("tau [s]")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(f"{sig}: -- white noise (-1/2), : random walk (+1/2), o floor")
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run_noise(rec: Recording, out_dir: Path, plots: bool = True,
              gyro_range: float = GYRO_RANGE_DEFAULT, gyro_bias_std: float = 0.0
              ) -> dict[str, Any]:
    """Write noise.json, preset.json, sensor.json (and allan.png) into out_dir; return the
    noise.json content. gyro_range [rad/s]: the gyro's full-scale setting, which goes to every
    estimator and to the sensor model; gyro_bias_std [rad/s]: the spread of the bias a part
    starts with where it is not calibrated at start-up (presets.noise_preset), from its
    datasheet."""
    noise, fits = analyse(rec)
    noise["gyro_range"] = gyro_range
    noise["units"]["gyro_range"] = "rad/s"
    noise["gyro_bias_std"] = gyro_bias_std
    noise["units"]["gyro_bias_std"] = "rad/s"
    preset = preset_for(noise)
    for key, params in preset.items():  # a preset no estimator takes is refused, not written
        try:
            create(key, params)
        except ValueError as err:
            raise ValueError(f"{rec.name}: the preset for {key} would not load ({err}): check "
                             "--gyro-range and --gyro-bias-std") from None
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / "noise.json").write_text(json.dumps(noise, indent=1))
    (out_dir / "preset.json").write_text(json.dumps(preset, indent=1))
    (out_dir / "sensor.json").write_text(json.dumps(sensor_params(noise), indent=1))
    if plots:
        plot(fits, out_dir / "allan.png",
             f"{rec.name}: {noise['recording']['duration_s']:.0f} s at {rec.rate:g} Hz")
    return noise

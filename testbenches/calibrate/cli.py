"""`imu-fusion calibrate RECORDING`: a part's calibration from a session of static poses and the
turns between them, written as calibration.json for every estimator's input.

    imu-fusion calibrate session.csv [--rate HZ] [--gyro-unit rad/s|deg/s] [--acc-unit m/s2|g]
                         [--sections FILE.json] [--gyro-range DEG_PER_S] [--out DIR]

Finds the static intervals itself (Tedaldi's detector, its threshold chosen by Tedaldi's
criterion), fits the accelerometer (|a| = g at every pose) and the gyro (the turns between poses
take one pose's gravity direction to the next one's), and writes DIR/calibration.json
(`acc_cal` and `gyro_cal`, each {"matrix": 3x3, "offset": 3} in SI units, calibrated = matrix
(raw - offset), with the units, the poses, the residual per pose and each term's standard
uncertainty) and DIR/calibration.png (the static intervals over the signals; the residual per
pose before and after). With --sections (imucal's section list) it also computes Ferraris's
calibration from those sections and from the session's own intervals, and imucal's where imucal
is installed, beside it; a session of Ferraris's six poses alone is calibrated by Ferraris's
method. A session that cannot determine the model is refused with what to record instead.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from fusion_core.calibration import Calibration
from fusion_core.types import G

from ..options import (
    RECORDING_HELP,
    add_no_plots,
    add_recording_options,
    out_folder,
    positive_float,
)
from . import ferraris as fer
from .detect import MULTIPLES, WINDOW_S, noise_floor, static_intervals, variance_magnitude
from .heldout import HeldOut, ferraris_held_out, tedaldi_held_out
from .level import level_pose, levelled
from .tedaldi import CalibrationRefused, Fit, Session, calibrate_session


def add_calibrate_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    """The calibrate subcommand."""
    p = sub.add_parser("calibrate", help="a part's calibration from a session of static poses "
                       "and turns (calibration.json for --calibration)",
                       description=__doc__.split("\n\n")[0])
    p.add_argument("recording", type=Path, help=f"the session: {RECORDING_HELP}; with a time "
                   "column (or --rate)")
    add_recording_options(p)
    p.add_argument("--sections", type=Path, default=None, metavar="FILE.json",
                   help="imucal's section list (x_p ... z_a, x_rot ... z_rot): Ferraris's "
                   "calibration beside")
    p.add_argument("--gyro-range", type=positive_float, default=2000.0, metavar="DEG_PER_S",
                   help="the gyro's full-scale range [deg/s] (2000)")
    p.add_argument("--gravity", type=positive_float, default=G,
                   help=f"local gravity [m/s^2] ({G})")
    p.add_argument("--level", action="store_true",
                   help="the session's still pose nearest z up was held with the housing "
                   "level (on a level surface): the calibrated axes are turned so that it reads "
                   "level, a tilt of the sensor in its housing that poses and turns alone cannot "
                   "show")
    p.add_argument("--out", type=out_folder, default=Path("calibration"),
                   help="output folder (calibration)")
    add_no_plots(p, "calibration.png")
    p.set_defaults(func=run)


def _fit_json(fit: Fit, unit: str, held: np.ndarray, spans: list[tuple[int, int]]
              ) -> dict[str, Any]:
    std = {"matrix_std": fit.matrix_std.tolist(), "offset_std": fit.offset_std.tolist()} \
        if np.all(np.isfinite(fit.matrix_std)) else {}
    return {**std, "residual_before": fit.before.tolist(), "residual_after": fit.after.tolist(),
            "residual_unit": unit, "residual_held_out": held.tolist(),
            "held_out_samples": [list(s) for s in spans], **fit.extra}


def _calibration(acc: Fit, gyro: Fit, extra: dict[str, Any]) -> Calibration:
    return Calibration(tuple(acc.matrix.ravel()), tuple(acc.offset),  # type: ignore[arg-type]
                       tuple(gyro.matrix.ravel()), tuple(gyro.offset),  # type: ignore[arg-type]
                       extra=extra)


def _own_sections(acc: np.ndarray, gyro: np.ndarray, dt: np.ndarray, g: float
                  ) -> tuple[dict[str, tuple[int, int]], Fit, Fit] | None:
    """Ferraris on the session's own intervals: of the detector's thresholds that find all
    nine sections, the one whose poses Ferraris's accelerometer fits best."""
    rate = 1.0 / float(np.median(dt))
    varsigma = variance_magnitude(acc, rate)
    floor = noise_floor(varsigma)
    best = None
    for k in MULTIPLES:
        statics = static_intervals(acc, gyro, rate, k * floor, varsigma)
        if len(statics) < len(fer.POSES):
            continue
        bias = np.mean([s.gyro for s in statics], axis=0)
        try:
            sections = fer.sections_from_session(statics, gyro, dt, bias)
            acc_fit, gyro_fit = fer.ferraris(acc, gyro, dt, sections, g)
        except (CalibrationRefused, np.linalg.LinAlgError):
            continue
        score = float(np.mean(acc_fit.after ** 2))
        if best is None or score < best[0]:
            best = (score, sections, acc_fit, gyro_fit)
    return None if best is None else best[1:]


def _imucal(acc: np.ndarray, gyro: np.ndarray, rate: float,
            sections: dict[str, tuple[int, int]]) -> tuple[np.ndarray, np.ndarray] | None:
    """imucal's Ferraris matrices (accelerometer, gyro) on the same sections, where installed."""
    try:
        import pandas as pd
        from imucal import FerrarisCalibration, ferraris_regions_from_section_list
    except ImportError:
        return None
    data = pd.DataFrame(np.column_stack([acc, np.degrees(gyro)]),
                        columns=["acc_x", "acc_y", "acc_z", "gyr_x", "gyr_y", "gyr_z"])
    section_list = pd.DataFrame({name: {"start": s, "end": e} for name, (s, e)
                                 in sections.items()}).T
    regions = ferraris_regions_from_section_list(data, section_list)
    info = FerrarisCalibration().compute(regions, sampling_rate_hz=rate, from_acc_unit="m/s^2",
                                         from_gyr_unit="deg/s")
    return (np.linalg.inv(info.R_a) @ np.linalg.inv(info.K_a),
            np.linalg.inv(info.R_g) @ np.linalg.inv(info.K_g))


def _matrix_rows(label: str, m: np.ndarray) -> str:
    return f"  {label:<28}" + "  ".join(" ".join(f"{v:+.4f}" for v in row) for row in m)


MAX_FILLED_S = 0.1
"""The longest run of samples without a number [s] that a session's values are filled across
(linearly in time): a pose holds still and a turn's rate changes little over it; a longer one
would make up part of a turn, which the gyro's fit integrates."""


def _filled(rec: Any, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """acc, gyro and dt of the session with its samples that lack a number filled linearly in
    time from their neighbours, and a note counting them ("" where none). A session's samples
    are numbered by --sections and its fits integrate every turn, so none is left out; a run
    of them longer than MAX_FILLED_S is refused."""
    from ..fit.recording import RecordingError

    valid = rec.valid & np.isfinite(t)
    if valid.all():
        return rec.acc, rec.gyro, rec.dt, ""
    if valid.sum() < 2:
        raise RecordingError(f"{rec.name}: no two samples have a number in every column")
    index = np.arange(len(t))
    times = np.interp(index, index[valid], t[valid])  # a missing time: between its neighbours
    starts = np.flatnonzero(np.diff(np.concatenate([[1], valid.astype(int)])) == -1)
    ends = np.flatnonzero(np.diff(np.concatenate([valid.astype(int), [1]])) == 1) + 1
    runs = [(times[min(e, len(t) - 1)] - times[max(b - 1, 0)], b, e)  # neighbour to neighbour
            for b, e in zip(starts, ends, strict=True)]
    longest, b, e = max(runs)
    if longest > MAX_FILLED_S:
        raise RecordingError(
            f"{rec.name}: samples {b} to {e - 1} (from 0, as --sections numbers them) lack a "
            f"number ({longest:.2f} s from {times[b]:.2f} s): a session is filled across at "
            f"most {MAX_FILLED_S:g} s, as its turns are integrated sample by sample; record the "
            "session again")
    acc, gyro = rec.acc.copy(), rec.gyro.copy()
    for values in (acc, gyro):
        for k in range(3):
            ok = np.isfinite(values[:, k])  # a row's other numbers are kept
            values[~ok, k] = np.interp(times[~ok], times[ok], values[ok, k])
    dt = np.concatenate([[rec.dt[0]], np.diff(times)])
    return acc, gyro, dt, (f"{int((~valid).sum())} sample(s) without a number in every "
                           "column filled from their neighbours (linearly in time)")


def run(args: argparse.Namespace) -> int:
    """Calibrate, write calibration.json and calibration.png, print the result."""
    from ..fit.recording import recording_from_args

    rec, t = recording_from_args(args.recording, args)
    acc, gyro, dt, filled = _filled(rec, t)
    g = args.gravity
    rate = 1.0 / float(np.median(dt))
    gyro_range = math.radians(args.gyro_range)
    session: Session | None = None
    refused: str | None = None
    try:
        session = calibrate_session(acc, gyro, dt, gyro_range, g)
    except CalibrationRefused as err:
        refused = str(err)
    comparisons: dict[str, Any] = {}
    given = fer.read_sections(args.sections) if args.sections else None
    lines: list[str] = [filled] if filled else []
    own = None
    if given is not None or session is None:
        own = _own_sections(acc, gyro, dt, g)
    sections: dict[str, tuple[int, int]] | None = None
    if given is not None:
        f_acc, f_gyro = fer.ferraris(acc, gyro, dt, given, g)
        comparisons["ferraris"] = {"acc_matrix": f_acc.matrix.tolist(),
                                   "gyro_matrix": f_gyro.matrix.tolist(),
                                   **fer.summary(f_acc, f_gyro)}
        if own is not None:
            comparisons["ferraris_own_sections"] = {
                "sections": {k: list(v) for k, v in own[0].items()},
                "acc_matrix": own[1].matrix.tolist(), "gyro_matrix": own[2].matrix.tolist(),
                **fer.summary(own[1], own[2])}
        peer = _imucal(acc, gyro, rate, given)
        if peer is not None:
            comparisons["imucal"] = {"acc_matrix": peer[0].tolist(),
                                     "gyro_matrix": peer[1].tolist()}
    if session is not None:
        acc_fit, gyro_fit, method = session.acc, session.gyro, "tedaldi"
        held = tedaldi_held_out(session, g)
    elif given is not None:
        acc_fit, gyro_fit, method, sections = f_acc, f_gyro, "ferraris", given
        lines.append(f"Tedaldi's method refused ({refused}); Ferraris's on the sections given")
    elif own is not None:
        sections, acc_fit, gyro_fit = own
        method = "ferraris"
        lines.append(f"Tedaldi's method refused ({refused}); Ferraris's on the six poses and "
                     "three full turns found in the session")
    else:
        print(f"error: {args.recording}: {refused}; nor does it hold Ferraris's six poses (each "
              "axis held up and down, still) with a full turn about each axis between two of "
              "them (give their samples with --sections FILE.json where the session has them)",
              file=sys.stderr)
        return 2
    if sections is not None:
        held = ferraris_held_out(acc, gyro, dt, sections, acc_fit, gyro_fit, g)
    level: dict[str, Any] | None = None
    if args.level:  # after the held-out fits, which a turn of both frames leaves as they are
        means = ([s.acc for s in session.statics] if session is not None
                 else [acc[slice(*sections[p])].mean(axis=0) for p in fer.POSES])
        try:
            acc_fit, gyro_fit, level = levelled(acc_fit, gyro_fit, level_pose(means))
        except ValueError as err:
            print(f"error: {args.recording}: --level: {err}", file=sys.stderr)
            return 2
        lines.append(f"levelled (--level): the still pose nearest z up read roll "
                     f"{level['roll_deg']:+.3f} deg, pitch {level['pitch_deg']:+.3f} deg; the "
                     "calibrated axes turned so that it reads level")
    extra: dict[str, Any] = {
        "method": method,
        "units": {"acc": "m/s2", "gyro": "rad/s", "matrix": "1"},
        "input_units": {"acc": args.acc_unit, "gyro": args.gyro_unit} if args.counts is None
        else {"acc": f"counts ({args.counts[0]:g} per g)",
              "gyro": f"counts ({args.counts[1]:g} per deg/s)"},
        "gravity": g,
        "recording": str(args.recording),
        "acc": _fit_json(acc_fit, "m/s2 (| |a| - g | per pose)", held.acc, held.acc_spans),
        "gyro": _fit_json(gyro_fit, "rad (gravity direction per turn)" if method == "tedaldi"
                          else "rad (| turn - 2 pi | per turn)", held.gyro, held.gyro_spans),
        "held_out": ("each pose and turn under a fit without it (leave one out)"
                     if method == "tedaldi" else "the session's other poses and the moves "
                     "between them, under the calibration fitted to Ferraris's sections"),
    }
    if filled:
        extra["filled"] = filled
    if level is not None:
        extra["level"] = {"pose": "the still pose nearest z up, held level (--level)", **level}
    if sections is not None:
        extra["sections"] = {k: list(v) for k, v in sections.items()}
    if session is not None:
        extra["poses"] = len(session.statics)
        extra["static_intervals"] = [[s.start, s.stop] for s in session.statics]
        extra["detector"] = {"window_s": WINDOW_S, "floor": session.floor,
                             "multiple": session.multiple, "threshold": session.threshold}
        extra["turn_degrees"] = session.turn_degrees.tolist()
    if comparisons:
        extra["comparisons"] = comparisons
    cal = _calibration(acc_fit, gyro_fit, extra)
    args.out.mkdir(parents=True, exist_ok=True)
    cal.write(args.out / "calibration.json")
    if not args.no_plots:
        if session is not None:
            spans = [(s.start, s.stop, "static") for s in session.statics]
        else:
            assert sections is not None
            spans = [(lo, hi, "static" if name in fer.POSES else "turn")
                     for name, (lo, hi) in sections.items()]
        _plot(args.out / "calibration.png", t, acc, gyro, spans, acc_fit, gyro_fit, held, method)
    lines += _report(method, session, acc_fit, gyro_fit, held, comparisons)
    lines.append(f"wrote {args.out / 'calibration.json'}" + (
        "" if args.no_plots else f" and {args.out / 'calibration.png'}"))
    print("\n".join(lines))
    return 0


def _report(method: str, session: Session | None, acc_fit: Fit, gyro_fit: Fit, held: HeldOut,
            comparisons: dict[str, Any]) -> list[str]:
    lines = []
    if session is not None:
        lines.append(f"{len(session.statics)} static poses (threshold {session.multiple:g} x "
                     f"the noise floor), {int(np.sum(session.turn_degrees >= 20))} turns")
    lines.append(f"method: {method}; calibrated = matrix (raw - offset)")
    for sensor, fit, unit in (("acc", acc_fit, "m/s2"), ("gyro", gyro_fit, "rad/s")):
        lines.append(_matrix_rows(f"{sensor} matrix", fit.matrix))
        lines.append(f"  {sensor + ' offset [' + unit + ']':<28}"
                     + " ".join(f"{v:+.5f}" for v in fit.offset))
        if np.all(np.isfinite(fit.matrix_std)):
            lines.append(f"  {'  standard uncertainty':<28}"
                         + f"matrix up to {np.max(fit.matrix_std):.2g}, offset up to "
                         f"{np.max(fit.offset_std):.2g}")
    lines.append(f"  acc residual per pose: before {_rms(acc_fit.before):.4f}, after "
                 f"{_rms(acc_fit.after):.4f}, held out {_rms(held.acc):.4f} m/s2 (RMS; "
                 f"{len(held.acc)} poses held out)")
    lines.append(f"  gyro residual per turn: before {math.degrees(_rms(gyro_fit.before)):.3f}, "
                 f"after {math.degrees(_rms(gyro_fit.after)):.3f}, held out "
                 f"{math.degrees(_rms(held.gyro)):.3f} deg (RMS; {len(held.gyro)} moves held "
                 "out)")
    for name, comp in comparisons.items():
        lines.append(f"{name}:")
        lines.append(_matrix_rows("acc matrix", np.array(comp["acc_matrix"])))
        lines.append(_matrix_rows("gyro matrix", np.array(comp["gyro_matrix"])))
    return lines


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if len(x) else math.nan


def _plot(path: Path, t: np.ndarray, acc: np.ndarray, gyro: np.ndarray,
          spans: list[tuple[int, int, str]], acc_fit: Fit, gyro_fit: Fit, held: HeldOut,
          method: str) -> None:
    """The session with the fit's intervals shaded; per pose and per turn the residual of the
    raw data, of the fit on its own data, and held out (heldout.py), against time."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    g = float(np.median(np.linalg.norm(acc, axis=1)))
    fig, axes = plt.subplots(3, 1, figsize=(10, 9), sharex=True)
    ax = axes[0]
    ax.plot(t, np.linalg.norm(acc, axis=1) / g, lw=0.7, label="|acc| [g]")
    ax.plot(t, np.degrees(np.linalg.norm(gyro, axis=1)) / 100.0, lw=0.7,
            label="|gyro| [100 deg/s]")
    for lo, hi, kind in spans:
        ax.axvspan(t[lo], t[hi - 1], color="tab:green" if kind == "static" else "tab:orange",
                   alpha=0.2, lw=0)
    ax.set_title(f"the session; what {method}'s fit used shaded (poses green, turns orange)")
    ax.legend(loc="upper right")
    fitted = [(lo, hi) for lo, hi, kind in spans if kind == "static"]
    for ax, fit, held_res, held_spans, unit, scale, what in (
            (axes[1], acc_fit, held.acc, held.acc_spans, "| |a| - g | [m/s2]", 1.0, "pose"),
            (axes[2], gyro_fit, held.gyro, held.gyro_spans, "[deg]", math.degrees(1.0),
             "turn")):
        mid = lambda s: 0.5 * (t[s[0]] + t[min(s[1], len(t)) - 1])  # noqa: E731
        if what == "pose":
            at = [mid(s) for s in fitted]
        elif method == "tedaldi":
            at = [mid(s) for s in held_spans]
        else:
            at = [mid((lo, hi)) for lo, hi, kind in spans if kind == "turn"]
        if len(at) == len(fit.after):
            ax.semilogy(at, np.maximum(fit.before * scale, 1e-6), "v", color="0.6",
                        label="raw" if what == "pose" else "raw less the bias")
            ax.semilogy(at, np.maximum(fit.after * scale, 1e-6), "o", mfc="none",
                        color="tab:blue", label="fit, on its own data")
        if len(held_res):
            ax.semilogy([mid(s) for s in held_spans], np.maximum(held_res * scale, 1e-6), "s",
                        color="tab:red", label="held out (a fit without it)")
        ax.set_ylabel(unit)
        ax.set_title(f"accelerometer residual per {what}" if what == "pose" else
                     "gyro residual per turn: gravity's predicted against measured direction"
                     if method == "tedaldi" else
                     "gyro residual: full turn (fit) and moves between poses (held out)")
        ax.legend(loc="best", fontsize=8)
    axes[2].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def calibration_json(path: Path) -> dict[str, Any]:
    """calibration.json as written (for reports and tests)."""
    return json.loads(path.read_text())

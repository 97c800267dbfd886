"""`imu-fusion docs [--check | --write] [NAME ...]`: the figures, tables and pictures of the
README and the docs that a command makes, made again by that command.

A page holds a generated block between two marks:

    <!-- generated: NAME -->
    ...
    <!-- end generated: NAME -->

and a picture is a file the page shows. FIGURES names each one, the command a reader runs to
reproduce it, what it needs (built FMUs, a data set) and how it is made; everything is seeded,
so a text block must match to the character and a picture to its pixels (PICTURE_TOLERANCE of
them may differ, for font rendering between machines). `--check` (the default) says which no
longer match and exits 1; `--write` makes them again. tests/test_docs_figures.py runs the check
for every figure whose needs are met here.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import io
import os
import re
import sys
import tempfile
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]
PICTURE_TOLERANCE = 0.002
"""The share of a picture's pixels that may differ from the page's: fonts render a little
differently between machines; a changed curve moves far more pixels than this."""
IMUCAL_SESSION = "example_ferraris_session.csv"


@dataclass(frozen=True)
class Figure:
    """One generated figure: where it is (a page's block, or a picture file), the command that
    makes it, what that needs, and the function that makes it (text for a block; for a picture
    it writes the file it is given). `make` takes the context (fmu_dir, data folders)."""

    name: str
    page: str
    command: str
    make: Callable[[dict[str, Path]], str] | Callable[[dict[str, Path], Path], None]
    picture: str | None = None
    needs: tuple[str, ...] = ()


def _main(argv: list[str]) -> int:
    """`imu-fusion ARGV` for the commands whose output the docs show (estimate, calibrate,
    broad, campaign, run)."""
    from .broad.cli import add_broad_parser
    from .calibrate.cli import add_calibrate_parser
    from .estimate import add_estimate_parser
    from .montecarlo.cli import add_campaign_parser
    from .run_cli import add_run_parser

    parser = argparse.ArgumentParser(prog="imu-fusion")
    sub = parser.add_subparsers(required=True)
    add_estimate_parser(sub)
    add_calibrate_parser(sub)
    add_broad_parser(sub)
    add_campaign_parser(sub)
    add_run_parser(sub)
    args = parser.parse_args(argv)
    return int(args.func(args))


def _captured(argv: list[str], cwd: Path) -> str:
    """What `imu-fusion ARGV` prints, run in cwd."""
    out = io.StringIO()
    here = Path.cwd()
    try:
        os.chdir(cwd)
        with contextlib.redirect_stdout(out):
            status = _main(argv)
    finally:
        os.chdir(here)
    if status != 0:
        raise RuntimeError(f"imu-fusion {' '.join(argv)} exited with {status}")
    return out.getvalue()


# ----- the figures ------------------------------------------------------------------------------

ESTIMATE_ARGS = ["estimate", "examples/tilt_motion.csv", "--reference",
                 "examples/tilt_motion_truth.csv", "--no-vqf"]


def estimate_output(ctx: dict[str, Path]) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        text = _captured([*ESTIMATE_ARGS, "--no-plots", "--out", tmp], REPO)
        text = text.replace(tmp, "reports/estimate")
    return "```text\n" + text.rstrip() + "\n```"


def estimate_picture(ctx: dict[str, Path], path: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        _captured([*ESTIMATE_ARGS, "--out", tmp], REPO)
        Path(tmp, "tilt_motion.png").replace(path)


def calibrate_output(ctx: dict[str, Path]) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        text = _captured(["calibrate", IMUCAL_SESSION, "--rate", "102.4", "--gyro-unit",
                          "deg/s", "--gravity", "9.81", "--out", tmp], ctx["imucal"])
        text = text.replace(tmp, "calibration")
    return "```text\n" + text.rstrip() + "\n```"


def calibrate_picture(ctx: dict[str, Path], path: Path) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        _captured(["calibrate", IMUCAL_SESSION, "--rate", "102.4", "--gyro-unit", "deg/s",
                   "--gravity", "9.81", "--out", tmp], ctx["imucal"])
        Path(tmp, "calibration.png").replace(path)


IMUCAL_SECTIONS = "example_ferraris_session_list.json"


def imucal_table(ctx: dict[str, Path]) -> str:
    """docs/results/calibration.md: ours beside imucal's on imucal's session, with its section
    list and with the sections our detector finds."""
    import json

    from .calibrate.ferraris import scales_and_misalignment

    with tempfile.TemporaryDirectory() as tmp:
        _captured(["calibrate", IMUCAL_SESSION, "--rate", "102.4", "--gyro-unit", "deg/s",
                   "--acc-unit", "m/s2", "--sections", IMUCAL_SECTIONS, "--gravity", "9.81",
                   "--out", tmp], ctx["imucal"])
        comp = json.loads(Path(tmp, "calibration.json").read_text())["comparisons"]
    columns = ("imucal", "ferraris", "ferraris_own_sections")
    rows = ["| | imucal (Ferraris) | ours, Ferraris on the given sections | ours, Ferraris on "
            "the sections our detector finds |", "|---|---|---|---|"]
    for sensor, label in (("gyro", "gyro"), ("acc", "accelerometer")):
        found = [scales_and_misalignment(comp[c][f"{sensor}_matrix"]) for c in columns]
        rows.append(f"| {label} scale x / y / z | " + " | ".join(
            " / ".join(f"{v:.4f}" for v in sc) for sc, _ in found) + " |")
        rows.append(f"| {label} misalignment x / y / z [deg] | " + " | ".join(
            " / ".join(f"{v:.2f}" for v in an) for _, an in found) + " |")
    diffs = []
    for c in columns:
        d = [float(np.max(np.abs(np.asarray(comp[c][f"{s}_matrix"])
                                 - np.asarray(comp["imucal"][f"{s}_matrix"]))))
             for s in ("acc", "gyro")]
        diffs.append("0" if max(d) == 0.0 else f"{d[0]:.2g} / {d[1]:.2g}")
    rows.append("| largest difference from imucal's matrix entries, accelerometer / gyro | "
                + " | ".join(diffs) + " |")
    return "\n".join(rows)


def fmu_picture(ctx: dict[str, Path], path: Path) -> None:
    """The README's picture: the native FMI 3.0 AngleBiasKalmanFilter FMU in fmpy on the
    example, as examples/plot_example.py draws it."""
    import importlib.util

    from fmpy import simulate_fmu
    from fmpy.util import read_csv, write_csv

    fmu = ctx["fmus"] / "native" / "fmi3" / "AngleBiasKalmanFilter.fmu"
    spec = importlib.util.spec_from_file_location("plot_example",
                                                  REPO / "examples" / "plot_example.py")
    assert spec is not None and spec.loader is not None
    plot_example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(plot_example)
    with tempfile.TemporaryDirectory() as tmp:
        result = simulate_fmu(str(fmu), input=read_csv(str(REPO / "examples" /
                                                           "tilt_motion.csv")),
                              output_interval=0.01)
        out = Path(tmp) / "out.csv"
        write_csv(str(out), result)
        plot_example.plot(plot_example.read(out),
                          plot_example.read(REPO / "examples" / "tilt_motion_truth.csv"),
                          "AngleBiasKalmanFilter.fmu on examples/tilt_motion.csv", path)


def readme_contract(ctx: dict[str, Path]) -> str:
    """README.md: what `make run` states (`imu-fusion run` on the FMUs of ctx["fmus"], the
    defaults, the realistic sensor): its checks on one part and over PARTS parts, and each
    check over parts not met, by how and scenario."""
    import json
    import textwrap

    from .parts import HOW, PARTS

    with tempfile.TemporaryDirectory() as tmp:
        argv = ["run", "--fmu-dir", str(ctx["fmus"]), "--out", tmp, "--no-plots"]
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            _main(argv)  # exit status 1 where a check FAILs: the figure says which
        report = json.loads((Path(tmp) / "report.json").read_text(encoding="utf-8"))
    checks = report["checks"] + [c for r in report["runs"] for c in r["checks"]]
    over = [c for c in checks if c["name"].startswith(f"accuracy over {PARTS} parts")]
    one = [c for c in checks if c not in over]
    missed = []
    for how, share in HOW.values():
        scenarios: dict[str, list[str]] = {}
        for c in over:
            head, _, what = c["name"].partition(": ")
            if c["passed"] or not head.endswith(how):
                continue
            key, scenario = what.split(" ", 1)
            scenarios.setdefault(scenario, []).append(f"{key} {c['measured']:.0f} %")
        if scenarios:
            missed.append(f"{how} ({100 * share:.0f} % of parts asked): " + "; ".join(
                f"`{sc}` {', '.join(cells)}" for sc, cells in scenarios.items()))
    def count(cs: list[dict[str, Any]]) -> str:
        return f"{sum(c['passed'] for c in cs)} of {len(cs)}"

    text = (f"- **The contract**: `make run` states {len(checks)} checks with the defaults on "
            f"the realistic sensor: on one part (seed 0, through the FMUs) {count(one)} PASS; "
            f"over {PARTS} parts (the share of parts within each accuracy bound, as delivered "
            f"and calibrated first) {count(over)} PASS.")
    if missed:
        text += " Not met yet, the share of parts within: " + "; ".join(missed) + "."
    return "\n".join(textwrap.wrap(text, 96, subsequent_indent="  ", break_on_hyphens=False))


def parts_table(ctx: dict[str, Path]) -> str:
    """The contract's accuracy over 20 parts (testbenches.parts), the defaults, the realistic
    sensor."""
    from fusion_core.presets import load_preset
    from fusion_core.registry import KEYS
    from fusion_core.scenarios import ESTIMATION_SCENARIOS
    from fusion_core.sensor import sensor_preset

    from . import parts

    rmse = parts.part_rmse(list(KEYS), list(ESTIMATION_SCENARIOS), load_preset("recommended"),
                           sensor_preset("realistic"), bounded_only=True)
    return parts.parts_table(rmse)


CALIBRATED_PARTS = 200


@functools.lru_cache(maxsize=1)
def _calibrated_parts() -> dict[str, dict[bool, np.ndarray]]:
    """Roll and pitch RMSE [deg] of every estimator and of VQF on moderate_dynamics over
    CALIBRATED_PARTS parts of the realistic sensor, as delivered (False) and calibrated first
    (True): the runs of `imu-fusion campaign --scenario moderate_dynamics --seeds 200
    [--calibrate-first]` (testbenches.parts gives them through the same C twins) and of
    `imu-fusion run ... --peers vqf`."""
    from fusion_core.presets import load_preset
    from fusion_core.sensor import sensor_preset

    from .contract import PAPER_MODERATE
    from .parts import part_rmse, vqf_rmse

    sensor = sensor_preset("realistic")
    rmse = part_rmse(list(PAPER_MODERATE), ["moderate_dynamics"], load_preset("recommended"),
                     sensor, CALIBRATED_PARTS)  # the estimators with a paper row
    out: dict[str, dict[bool, np.ndarray]] = {}
    for (calibrated, key, _), values in rmse.items():
        out.setdefault(key, {})[calibrated] = values
    out["vqf"] = {calibrated: vqf_rmse("moderate_dynamics", sensor, CALIBRATED_PARTS, calibrated)
                  for calibrated in (False, True)}
    return out


def _half_row(key: str) -> tuple[float, float]:
    from .contract import DEFAULTS_MODERATE_SHARE, PAPER_MODERATE

    roll, pitch = PAPER_MODERATE[key]
    return DEFAULTS_MODERATE_SHARE * roll, DEFAULTS_MODERATE_SHARE * pitch


def _within(values: np.ndarray, bound: tuple[float, float]) -> float:
    from .parts import share_within

    return 100.0 * share_within(values, bound)


def _share(values: np.ndarray, bound: tuple[float, float] | None) -> str:
    """The share of parts within bound, "92 %", or "no bound" where the contract has none."""
    return "no bound" if bound is None else f"{_within(values, bound):.0f} %"


def calibrated_parts_table(ctx: dict[str, Path]) -> str:
    """docs/results/calibration.md: each estimator's half row, calibrated first and as
    delivered, over CALIBRATED_PARTS parts; VQF on the same samples beside."""
    runs = _calibrated_parts()
    pair = lambda v: f"{v[0]:.3f} / {v[1]:.3f}"  # noqa: E731
    rows = ["| roll / pitch RMSE [deg] | half the row | calibrated first: mean | median | "
            "within | as delivered: mean | within |", "|---|---|---|---|---|---|---|"]
    for key in runs:  # the estimators with a paper row, then VQF
        half = _half_row("ukf" if key == "vqf" else key)
        cal, raw = runs[key][True], runs[key][False]
        name = "VQF, the same samples calibrated alike" if key == "vqf" else key
        whose = " (UKF's half row)" if key == "vqf" else ""
        rows.append(f"| {name} | {'' if key == 'vqf' else pair(half)} | "
                    f"{pair(cal.mean(axis=0))} | {pair(np.median(cal, axis=0))} | "
                    f"{_within(cal, half):.1f} %{whose} | "
                    f"{pair(raw.mean(axis=0))} | {_within(raw, half):.1f} % |")
    return "\n".join(rows)


def readme_calibrated_part(ctx: dict[str, Path]) -> str:
    """The README's result line of the same runs."""
    runs = _calibrated_parts()
    ukf, vqf = runs["ukf"][True].mean(axis=0), runs["vqf"][True].mean(axis=0)
    half = _half_row("ukf")
    return (f"- **A calibrated part**: {CALIBRATED_PARTS} parts of the realistic sensor on "
            "`moderate_dynamics`, each calibrated\n  first on its own session by `imu-fusion "
            "calibrate`'s code: every estimator's mean RMSE within\n  half its row of the "
            f"paper's Table 1 (UKF {ukf[0]:.3f}/{ukf[1]:.3f} deg against {half[0]:.3f}/"
            f"{half[1]:.3f}; VQF on the same\n  calibrated samples {vqf[0]:.3f}/{vqf[1]:.3f}) "
            "(`imu-fusion campaign --scenario moderate_dynamics --seeds 200\n  "
            "--calibrate-first`; [docs/results/calibration.md](docs/results/calibration.md)).")


def _stats(v: np.ndarray) -> tuple[str, str, str]:
    mean, median, p95 = v.mean(axis=0), np.median(v, axis=0), np.percentile(v, 95, axis=0)
    return tuple(f"{a[0]:.2f} / {a[1]:.2f}" for a in (mean, median, p95))  # type: ignore[return-value]


def campaigns_parts_table(ctx: dict[str, Path]) -> str:
    """docs/guide/campaigns.md: moderate_dynamics over CALIBRATED_PARTS parts as delivered,
    each estimator beside VQF, and the share within its row and within the defaults' target
    (half the UKF's row)."""
    from fusion_core import registry

    from .contract import DEFAULTS_MODERATE_SHARE, PAPER_MODERATE

    runs = _calibrated_parts()
    rows = [f"| moderate_dynamics, {CALIBRATED_PARTS} parts | mean | median | p95 | within "
            "its row | within half the UKF's row |", "|---|---|---|---|---|---|"]
    share = DEFAULTS_MODERATE_SHARE  # the defaults' target (tests/test_paper_rows.py)
    half = (share * PAPER_MODERATE["ukf"][0], share * PAPER_MODERATE["ukf"][1])
    for key in (*registry.ATTITUDE_FILTERS, "vqf"):
        v = runs[key][False]
        if key == "vqf":
            rows.append("| VQF (peer) | " + " | ".join(_stats(v)) + f" | - | "
                        f"{_within(v, half):.1f} % |")
            continue
        row = PAPER_MODERATE[key]
        within = _within(v, row)
        note = f" (row {row[0]:.2f} / {row[1]:.2f})" if within < 100.0 else ""
        rows.append(f"| {key} | " + " | ".join(_stats(v)) + f" | {within:.0f} %{note} | "
                    f"{_within(v, half):.1f} % |")
    return "\n".join(rows)


def _bench_report() -> Any:
    """benchmarks.report of the source checkout (benchmarks/ is not part of the installed
    package: `imu-fusion` run from .venv/bin does not have it on its path)."""
    if str(REPO) not in sys.path:
        sys.path.append(str(REPO))
    import benchmarks.report

    return benchmarks.report


def speed_table(ctx: dict[str, Path]) -> str:
    """docs/results/speed.md: `make bench`'s table of the run kept in docs/results/speed.json
    (written by `python -m benchmarks --docs`); refused where that run lacks an estimator of
    the registry, so that a new estimator's speed cannot go unshown."""
    import json

    from fusion_core.registry import KEYS

    report = _bench_report()
    r = json.loads(report.DOCS_JSON.read_text(encoding="utf-8"))
    lacking = [k for k in KEYS if k not in r.get("per_sample_us_stream", {})]
    if lacking:
        raise ValueError(f"{report.DOCS_JSON} has no figures of {', '.join(lacking)}: measure "
                         "again with python -m benchmarks --docs")
    return "```text\n" + report.format_table(r) + "\n```"


def write_speed(results: dict[str, Any]) -> list[Path]:
    """Keep a full `make bench` run as benchmarks.report.DOCS_JSON and write speed.md's table
    of it (`python -m benchmarks --docs`)."""
    import json

    path = _bench_report().DOCS_JSON
    path.write_text(json.dumps(results, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    page = path.with_name("speed.md")
    replace_block(page, "speed-bench", speed_table({}))
    return [path, page]


def makefile_campaign() -> list[str]:
    """The arguments after `python -m testbenches` of the Makefile's `campaign` recipe: the
    docs' table runs exactly what `make campaign` runs."""
    import shlex

    text = (REPO / "Makefile").read_text(encoding="utf-8").replace("\\\n", " ")
    m = re.search(r"^campaign:.*\n\t(.*)$", text, re.M)
    if m is None:
        raise ValueError("Makefile: no campaign recipe")
    words = shlex.split(m.group(1))
    return words[words.index("testbenches") + 1:]


def campaigns_makefile_table(ctx: dict[str, Path]) -> str:
    """docs/guide/campaigns.md: `make campaign` (its own arguments, a LocalCluster, out in a
    temporary folder), roll / pitch RMSE mean and 95th percentile per estimator and scenario,
    and the share of parts within the contract's bound."""
    from fusion_core.registry import KEYS

    from .contract import accuracy_limits
    from .montecarlo.store import read_rows

    words = makefile_campaign()
    with tempfile.TemporaryDirectory() as tmp:
        argv = [*words[:words.index("--out")], "--out", tmp, "--no-plots"]
        with contextlib.redirect_stdout(io.StringIO()):
            if _main(argv) != 0:
                raise RuntimeError(f"python -m testbenches {' '.join(words)} failed")
        rows = [r for r in read_rows(Path(tmp)) if r["status"] == "ok"]
    cell: dict[tuple[str, str], list[list[float]]] = {}
    for r in rows:
        cell.setdefault((r["estimator"], r["scenario"]), []).append(
            [r["rmse_roll_deg"], r["rmse_pitch_deg"]])
    order = {k: i for i, k in enumerate(KEYS)}  # the registry's order, the Makefile's scenarios
    keys = sorted({k for k, _ in cell}, key=order.__getitem__)
    scenarios = words[words.index("--scenario") + 1].split(",")
    parts = {len(cell.get((k, s), [])) for k in keys for s in scenarios}
    lines = [f"Parts per cell: {', '.join(map(str, sorted(parts)))}. Cells: roll / pitch mean, "
             "roll / pitch 95th percentile [deg], share of parts within the contract's bound.",
             "", "| estimator | " + " | ".join(scenarios) + " |",
             "|---" * (len(scenarios) + 1) + "|"]
    for key in keys:
        cells = []
        for scenario in scenarios:
            v = np.array(cell[(key, scenario)])
            mean, p95 = v.mean(axis=0), np.percentile(v, 95, axis=0)
            cells.append(f"{mean[0]:.2f}/{mean[1]:.2f}, {p95[0]:.2f}/{p95[1]:.2f}, "
                         f"{_share(v, accuracy_limits(key, scenario))}")
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


SCENARIO_PARTS = 100
SCENARIO_TABLE = ("static_level", "roll_sweep", "pitch_sweep", "roll_pitch", "vibration",
                  "high_dynamics", "translation_2m")


def campaigns_scenarios_table(ctx: dict[str, Path]) -> str:
    """docs/guide/campaigns.md: kf, ukf and VQF on the contract's other scenarios over
    SCENARIO_PARTS parts as delivered: mean, 95th percentile, share within the bound."""
    from fusion_core.presets import load_preset
    from fusion_core.sensor import sensor_preset

    from .contract import bound
    from .parts import part_rmse, vqf_rmse

    sensor = sensor_preset("realistic")
    ours = part_rmse(["kf", "ukf"], list(SCENARIO_TABLE), load_preset("recommended"), sensor,
                     SCENARIO_PARTS, calibrated_first=(False,))
    rows = ["| scenario | kf | ukf | VQF (peer) |", "|---|---|---|---|"]
    for scenario in SCENARIO_TABLE:
        cells = []
        for v in (ours[(False, "kf", scenario)], ours[(False, "ukf", scenario)],
                  vqf_rmse(scenario, sensor, SCENARIO_PARTS)):
            lim = bound("kf", scenario)
            mean, p95 = v.mean(axis=0), np.percentile(v, 95, axis=0)
            cells.append(f"{mean[0]:.2f}/{mean[1]:.2f}, {p95[0]:.2f}/{p95[1]:.2f}, "
                         f"{_within(v, lim):.0f} %")
        rows.append(f"| {scenario} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


UNCALIBRATED_PARTS = 40


def uncalibrated_rest_table(ctx: dict[str, Path]) -> str:
    """docs/guide/own-sensor.md: static_tilted on UNCALIBRATED_PARTS parts whose gyro and
    accelerometer were not calibrated at start-up (the sensor's `calibration` none), each filter
    with VQF's rest rule (rest_bias_bound 0) and with the default; mean roll/pitch RMSE."""
    from fusion_core import registry
    from fusion_core.presets import load_preset
    from fusion_core.sensor import sensor_preset

    from .parts import part_rmse, vqf_rmse

    sensor = {**sensor_preset("realistic"), "calibration": "none"}
    keys = list(registry.ATTITUDE_FILTERS)
    preset = load_preset("recommended")
    pair = lambda v: f"{v[0]:.2g}/{v[1]:.2g}"  # noqa: E731
    vqf_rule = part_rmse(keys, ["static_tilted"], preset, sensor, UNCALIBRATED_PARTS,
                         {"rest_bias_bound": 0.0}, calibrated_first=(False,))
    default = part_rmse(keys, ["static_tilted"], preset, sensor, UNCALIBRATED_PARTS,
                        calibrated_first=(False,))
    before = "from the accelerometer until the first rest, aligning there; then at rest"
    how = {"cf": before, "mgcf": before, "kf": "also from the accelerometer",
           "ukf": "also from the accelerometer"}
    rows = ["| filter | `rest_bias_bound` 0 (VQF's rule) | default (20 deg/s) | how it learns "
            "its bias |", "|---|---|---|---|"]
    for key in keys:
        k = (False, key, "static_tilted")
        rows.append(f"| {key} | {pair(vqf_rule[k].mean(axis=0))} | "
                    f"{pair(default[k].mean(axis=0))} | {how[key]} |")
    vqf = vqf_rmse("static_tilted", sensor, UNCALIBRATED_PARTS).mean(axis=0)
    rows.append(f"| VQF | {pair(vqf)} | | |")
    return "\n".join(rows)


def broad_gyro_table(ctx: dict[str, Path]) -> str:
    """Each BROAD trial's gyro against its reference, no estimator involved
    (testbenches.broad.gyro, as `--gyro-fit` prints it): its lag, the fit's residual per window
    at no lag and at the lag, its bias, scale and largest cross-axis errors."""
    from .broad.gyro import fit_delay, fit_gyro
    from .mechanisms import load_trials

    trials, _ = load_trials([ctx["broad"]])
    rows = ["| trial | lag [ms] | residual per window, no lag -> lag [deg] | bias x/y/z [deg/s] "
            "| scale errors x/y/z [%] | largest cross-axis [%] |", "|---|---|---|---|---|---|"]
    for trial in trials:
        lag = fit_delay(trial).as_dict()
        fit = fit_gyro(trial).as_dict()
        bias = " / ".join(f"{v:+.2f}" for v in fit["bias_dps"])
        scale = " / ".join(f"{v:+.2f}" for v in fit["scale_error_pct"])
        rows.append(f"| {trial.name} | {lag['delay_ms']:.2f} | "
                    f"{lag['residual_deg_at_zero']:.3f} -> {lag['residual_deg_at_delay']:.3f} | "
                    f"{bias} | {scale} | {fit['max_abs_cross_axis_pct']:.2f} |")
    return "\n".join(rows)


CONSTANT_NOISE = {"gyro_scale_std": 0.0, "disturbance_time": 0.0}
"""The papers' constant measurement and process noise: no gyro scale uncertainty, no measured
disturbance."""


def constant_noise_table(ctx: dict[str, Path]) -> str:
    """docs/results/contract.md: the sweeps and high_dynamics on seed 0's part, each attitude
    filter with its defaults and with constant noise (CONSTANT_NOISE), against the bound."""
    from fusion_core.presets import load_preset
    from fusion_core.registry import ATTITUDE_FILTERS
    from fusion_core.sensor import sensor_preset

    from .contract import accuracy_limits
    from .parts import part_rmse

    keys, scenarios = list(ATTITUDE_FILTERS), ["roll_sweep", "pitch_sweep", "high_dynamics"]
    preset, sensor = load_preset("recommended"), sensor_preset("realistic")
    default = part_rmse(keys, scenarios, preset, sensor, 1, calibrated_first=(False,))
    constant = part_rmse(keys, scenarios, preset, sensor, 1, CONSTANT_NOISE,
                         calibrated_first=(False,))
    pair = lambda v: f"{v[0]:.2f}/{v[1]:.2f}"  # noqa: E731
    rows = ["| scenario (bound) | filter | defaults | constant noise |", "|---|---|---|---|"]
    for scenario in scenarios:
        bound = pair(accuracy_limits("kf", scenario))
        for key in keys:
            k = (False, key, scenario)
            rows.append(f"| {scenario} ({bound}) | {key} | {pair(default[k][0])} | "
                        f"{pair(constant[k][0])} |")
    return "\n".join(rows)


def broad_noise_table(ctx: dict[str, Path]) -> str:
    """docs/guide/own-sensor.md: `imu-fusion noise` on each BROAD trial's rest segment, over the
    13 trials, beside the reference sensor's values the recommended defaults are derived from
    (fusion_core.presets.noise_preset)."""
    from fusion_core import DEG
    from fusion_core.building_blocks.sampling import REAL_GYRO_DENSITY
    from fusion_core.position import REAL_ACC_DENSITY
    from fusion_core.presets import REFERENCE_ACC_SAMPLE_STD

    from .fit.noise import analyse
    from .fit.recording import rest, trial_recording
    from .mechanisms import load_trials

    trials, _ = load_trials([ctx["broad"]])
    found = [analyse(rest(trial_recording(t)))[0] for t in trials]
    rests = [f["recording"]["duration_s"] for f in found]
    rows = ["| quantity (rest segments of " + f"{rests and min(rests):.0f}-{max(rests):.0f} s) "
            "| lowest | median | highest | the recommended defaults' |", "|---|---|---|---|---|"]
    for label, values, default in (
            ("gyro density [deg/s/sqrt(Hz)]",
             [f["gyro_density"]["mean"] / DEG for f in found], REAL_GYRO_DENSITY / DEG),
            ("accelerometer density [m/s^2/sqrt(Hz)]",
             [f["acc_density"]["mean"] for f in found], REAL_ACC_DENSITY),
            ("one accelerometer sample's std [m/s^2]",
             [f["acc_sample_std"] for f in found], REFERENCE_ACC_SAMPLE_STD)):
        rows.append(f"| {label} | {min(values):.2g} | {float(np.median(values)):.2g} | "
                    f"{max(values):.2g} | {default:.2g} |")
    return "\n".join(rows)


def slow_roll_table(ctx: dict[str, Path]) -> str:
    from .slow_roll import table

    return table()


def estimators_table(ctx: dict[str, Path], pages: str = "") -> str:
    """README: every estimator of the registry, its classes (the FMU is named after the
    recommended one), its papers and equations and the gyro biases it learns; with pages (the
    folder of the estimators' pages, relative to the page), each key links to its page."""
    from fusion_core.base import NEVER_ESTIMATED
    from fusion_core.registry import REGISTRY

    rows = ["| key | class and FMU | the paper's filter (`--preset paper`) | paper, equations | "
            "gyro bias learned |", "|---|---|---|---|---|"]
    for e in REGISTRY:
        moving = [a for i, a in enumerate("xyz") if i in e.cls.BIAS_IN_MOTION]
        rest = [a for a in "xyz" if a not in moving
                and not e.cls.ZERO_BIAS.get(f"bias_{a}", "").startswith(NEVER_ESTIMATED)]
        learned = "; ".join(
            [*([", ".join(moving) + " in motion and at rest"] if moving else []),
             *([", ".join(rest) + " at rest only"] if rest else [])]) or "none"
        also = " (also position, velocity)" if e.cls.HAS_POSITION else ""
        paper = (f"`{e.reference.__name__}`" if e.reference is not None
                 else "the same class at its paper's values")
        key = f"[`{e.key}`]({pages}{e.key}.md)" if pages else f"`{e.key}`"
        rows.append(f"| {key} | `{e.fmu}`{also} | {paper} | {e.cites} | {learned} |")
    return "\n".join(rows)


def recovery_table(ctx: dict[str, Path]) -> str:
    from .recovery import table

    return table()


def uncalibrated_moving_table(ctx: dict[str, Path]) -> str:
    """docs/guide/own-sensor.md: roll_pitch (never at rest) on UNCALIBRATED_PARTS parts whose
    gyro and accelerometer were not calibrated at start-up, each filter with the default bias
    prior and the Kalman filters with one of the part class's turn-on bias (3 deg/s), beside
    VQF; mean roll/pitch RMSE."""
    from fusion_core import DEG
    from fusion_core.presets import load_preset
    from fusion_core.registry import ATTITUDE_FILTERS
    from fusion_core.sensor import sensor_preset

    from .parts import part_rmse, vqf_rmse

    sensor = {**sensor_preset("realistic"), "calibration": "none"}
    keys, preset = list(ATTITUDE_FILTERS), load_preset("recommended")
    pair = lambda v: f"{v[0]:.1f}/{v[1]:.1f}"  # noqa: E731
    default = part_rmse(keys, ["roll_pitch"], preset, sensor, UNCALIBRATED_PARTS,
                        calibrated_first=(False,))
    wide = part_rmse(["kf", "ukf"], ["roll_pitch"], preset, sensor, UNCALIBRATED_PARTS,
                     {"init_bias_std": 3.0 * DEG}, calibrated_first=(False,))
    rows = ["| filter | default `init_bias_std` | `init_bias_std` 3 deg/s |", "|---|---|---|"]
    for key in keys:
        k = (False, key, "roll_pitch")
        rows.append(f"| {key} | {pair(default[k].mean(axis=0))} | "
                    f"{pair(wide[k].mean(axis=0)) if k in wide else ''} |")
    rows.append(f"| VQF | {pair(vqf_rmse('roll_pitch', sensor, UNCALIBRATED_PARTS).mean(axis=0))}"
                " | |")
    return "\n".join(rows)


MEAN_OF_PARTS = ("shaking", "gyro_clipping")
"""Scenarios whose bound is VQF's mean over 20 parts: their rows are means over those parts."""


def vqf_contract_table(ctx: dict[str, Path]) -> str:
    """docs/results/contract.md: VQF on every contract scenario against the same bounds (seed
    0; the means of 20 parts where the bound is one), and our best estimators beside."""
    from fusion_core.presets import load_preset
    from fusion_core.registry import KEYS
    from fusion_core.scenarios import ESTIMATION_SCENARIOS
    from fusion_core.sensor import sensor_preset

    from .contract import ACCURACY
    from .parts import PARTS, part_rmse, vqf_rmse

    sensor, preset = sensor_preset("realistic"), load_preset("recommended")
    pair = lambda v: f"{v[0]:.2f}/{v[1]:.2f}"  # noqa: E731
    rows = ["| scenario | VQF roll/pitch RMSE [deg] | bound | VQF | ours, best three |",
            "|---|---|---|---|---|"]
    for scenario in ESTIMATION_SCENARIOS:
        parts = PARTS if scenario in MEAN_OF_PARTS else 1
        ours = part_rmse(list(KEYS), [scenario], preset, sensor, parts,
                         calibrated_first=(False,))
        vqf = vqf_rmse(scenario, sensor, parts).mean(axis=0)
        bound = ACCURACY.get(scenario)
        verdict = "-" if bound is None else (
            "PASS" if vqf[0] <= bound[0] and vqf[1] <= bound[1] else "FAIL")
        means = {key: ours[(False, key, scenario)].mean(axis=0) for key in KEYS}
        best = sorted(means, key=lambda k: max(means[k]))[:3]
        label = scenario + (f" (mean of {parts} parts)" if parts > 1 else " (seed 0)")
        shown = "per class" if bound is None else f"{bound[0]:.3g}/{bound[1]:.3g}"
        rows.append(f"| {label} | {pair(vqf)} | {shown} | {verdict} | "
                    + ", ".join(f"{k} {pair(means[k])}" for k in best) + " |")
    return "\n".join(rows)


BUDGET_EXCERPT = (("ukf", "roll_sweep", False), ("ukf", "roll_sweep", True),
                  ("cf", "pitch_sweep", False), ("ukf", "moderate_dynamics", False),
                  ("kf", "moderate_dynamics", False), ("ukf", "high_dynamics", False),
                  ("kf", "high_dynamics", False))
"""The error budget's excerpt in docs/results/contract.md: (estimator, scenario, with constant
noise: gyro_scale_std and disturbance_time 0, as the papers have it)."""


def budget_excerpt(ctx: dict[str, Path]) -> str:
    """`python -m testbenches budget`'s rows of BUDGET_EXCERPT (seeds 0-2, the recommended
    preset, the realistic sensor): full, three sources off, motion only."""
    from fusion_core.presets import load_preset
    from fusion_core.sensor import sensor_preset

    from .budget import error_budget

    sensor, preset = sensor_preset("realistic"), load_preset("recommended")
    pair = lambda v: f"{v[0]:.2f}/{v[1]:.2f}"  # noqa: E731
    rows = ["| estimator, scenario | bound | full | -gyro_scale | -gyro_cross | -calibration | "
            "motion only |", "|---|---|---|---|---|---|---|"]
    for key, scenario, constant in BUDGET_EXCERPT:
        params = {key: {**preset[key], **({"gyro_scale_std": 0.0, "disturbance_time": 0.0}
                                          if constant else {})}}
        (row,) = error_budget([key], [scenario], 3, sensor, params)
        label = f"{key} {scenario}" + (", constant noise" if constant else "")
        rows.append(f"| {label} | {row.limit[0]:g}/{row.limit[1]:g} | {pair(row.full)} | "
                    + " | ".join(pair(row.without[n]) for n in ("gyro_scale", "gyro_cross",
                                                                 "calibration"))
                    + f" | {pair(row.motion_only)} |")
    return "\n".join(rows)


def readme_broad(ctx: dict[str, Path]) -> str:
    """The README's BROAD line: `imu-fusion broad DIR --estimator cf,mgcf,kf,ukf --peers --cv`
    on the 13 shared trials, cross-validated and in sample, beside VQF with the same output
    prediction."""
    import json

    with tempfile.TemporaryDirectory() as tmp:
        _captured(["broad", str(ctx["broad"]), "--estimator", "cf,mgcf,kf,ukf", "--peers",
                   "--cv", "--no-plots", "--out", tmp], REPO)
        report = json.loads(Path(tmp, "report.json").read_text())
    cv, sample = report["cv_mean_inclination_rmse_deg"], report["mean_inclination_rmse_deg"]
    order = sorted(cv, key=cv.get)
    first, *middle, last = order
    return ("- **Real recordings** (BROAD, 13 trials with motion-capture truth): mean inclination "
            "RMSE,\n  cross-validated (each tuned parameter chosen without the fold of motion "
            "it is scored on,\n  among the values the contract allows, by its worst fold), "
            f"{first} {cv[first]:.3f} deg" + "".join(f", {k} {cv[k]:.3f}" for k in middle)
            + f",\n  {last} {cv[last]:.3f} (in sample "
            + ", ".join(f"{sample[k]:.3f}" for k in order)
            + "), against VQF with the same output\n  prediction at "
            f"{sample['vqf-ahead']:.3f}\n  (`imu-fusion broad DIR --estimator cf,mgcf,kf,ukf "
            "--peers --cv`;\n  [docs/results/broad.md](docs/results/broad.md)).")


BROAD_ALL = ["--estimator", "all", "--preset", "all", "--peers", "--cv"]
"""results/broad.md's command: every estimator with both presets, the peers and the
cross-validation on the 13 shared trials."""


@functools.lru_cache(maxsize=1)
def _broad_all(data: str) -> tuple[str, dict[str, Any]]:
    """What `imu-fusion broad DATA` with BROAD_ALL prints, and its report.json."""
    import json

    with tempfile.TemporaryDirectory() as tmp:
        printed = _captured(["broad", data, *BROAD_ALL, "--no-plots", "--out", tmp], REPO)
        return printed, json.loads(Path(tmp, "report.json").read_text())


def _between(text: str, first: str, stop: str | None) -> str:
    """The lines of text from the one starting with `first` to the one before the first after
    it starting with `stop` (None: to the end), trailing blank lines left out."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(first))
    end = next((i for i in range(start + 1, len(lines))
                if stop is not None and lines[i].startswith(stop)), len(lines))
    return "\n".join(lines[start:end]).rstrip()


def broad_groups(ctx: dict[str, Path]) -> str:
    """report.json's means of `imu-fusion broad` with BROAD_ALL: every estimator with both
    presets and the peers, mean inclination RMSE over all trials and per BROAD group."""
    report = _broad_all(str(ctx["broad"]))[1]
    means = report["mean_inclination_rmse_deg"]
    names = list(means)
    rows = ["| group (trials) | " + " | ".join(names) + " |", "|---|" + "---|" * len(names),
            f"| all ({report['trial_count']}) | "
            + " | ".join(f"{means[n]:.3f}" for n in names) + " |"]
    for group, g in report["groups"].items():
        m = g["mean_inclination_rmse_deg"]
        rows.append(f"| {group} ({len(g['trials'])}) | "
                    + " | ".join(f"{m[n]:.3f}" if m[n] is not None else "-" for n in names)
                    + " |")
    return "\n".join(rows)


def broad_cv(ctx: dict[str, Path]) -> str:
    """The cross-validation table and each fold's choice, as `broad --cv` prints them."""
    printed = _broad_all(str(ctx["broad"]))[0]
    return "```\n" + _between(printed, "estimator  figure", None) + "\n```"


def moderate_presets_table(ctx: dict[str, Path]) -> str:
    """Roll/pitch RMSE of every estimator on moderate_dynamics (seed 0) with both presets on
    both sensors, and the paper's Table 1 rows: the C twins of the plant, the sensor and the
    estimators, which give the FMUs' numbers to the bit."""
    from fusion_core.presets import load_preset
    from fusion_core.registry import ENTRY, KEYS
    from fusion_core.sensor import sensor_preset

    from .contract import PAPER_MODERATE
    from .parts import part_rmse

    rows = ["| preset / sensor | " + " | ".join(KEYS) + " |", "|---|" + "---|" * len(KEYS)]
    for preset in ("recommended", "paper"):
        for sensor in ("realistic", "ideal"):
            rmse = part_rmse(KEYS, ["moderate_dynamics"], load_preset(preset),
                             sensor_preset(sensor), parts=1, calibrated_first=(False,))
            cells = [f"{r[0, 0]:.2f}/{r[0, 1]:.2f}"
                     for r in (rmse[(False, key, "moderate_dynamics")] for key in KEYS)]
            rows.append(f"| {preset} / {sensor} | " + " | ".join(cells) + " |")
    rows.append("| Duong Quoc et al. Table 1 | " + " | ".join(
        "-" if ENTRY[k].paper_row is None else
        f"{PAPER_MODERATE[k][0]:.2f}/{PAPER_MODERATE[k][1]:.2f} ({ENTRY[k].paper_row.of})"
        for k in KEYS) + " |")
    return "\n".join(rows)


SCALE_CLASSES = ((0.01, 0.02 / 3.0), (0.005, 0.0033), (0.0025, 0.0025), (0.001, 0.001))
"""results/broad.md's gyro scale and cross-axis classes (1 sigma): the realistic sensor's, and
calibrated gyros."""


def scale_parts_table(ctx: dict[str, Path]) -> str:
    """The UKF and VQF over 40 parts of each gyro scale class on moderate_dynamics: seed 0, the
    mean, the median and the share within half the paper's row."""
    from .parts import part_rmse, share_within, vqf_rmse

    parts, half = 40, _half_row("ukf")
    rows = ["| gyro scale / cross-axis (1 sigma) | UKF seed 0 | UKF mean | UKF median | UKF "
            "within half its row | VQF mean | VQF within |", "|---|---|---|---|---|---|---|"]
    for scale, cross in SCALE_CLASSES:
        sensor = {"gyro_scale_std": scale, "gyro_cross_axis_std": cross}
        ukf = part_rmse(["ukf"], ["moderate_dynamics"], {}, sensor, parts,
                        calibrated_first=(False,))[(False, "ukf", "moderate_dynamics")]
        vqf = vqf_rmse("moderate_dynamics", sensor, parts)
        name = f"{100 * scale:g} % / {100 * cross:.2g} %"
        rows.append(
            f"| {name} | {ukf[0, 0]:.2f}/{ukf[0, 1]:.2f} | "
            f"{ukf[:, 0].mean():.2f}/{ukf[:, 1].mean():.2f} | "
            f"{np.median(ukf[:, 0]):.2f}/{np.median(ukf[:, 1]):.2f} | "
            f"{100 * share_within(ukf, half):.0f} % | "
            f"{vqf[:, 0].mean():.2f}/{vqf[:, 1].mean():.2f} | "
            f"{100 * share_within(vqf, half):.0f} % |")
    return "\n".join(rows)


def embedded_table(ctx: dict[str, Path]) -> str:
    """`make embedded`'s table: each twin on the Cortex-M7 (double) and the Cortex-M4F (float)
    under QEMU, on moderate_dynamics through the realistic sensor (BROAD_DIR unset)."""
    from .embedded.cli import report_without_broad

    report, _ = report_without_broad()
    double = report["cortex-m7-double"]["estimators"]
    single = report["cortex-m4f-float"]["estimators"]
    rows = ["| | Cortex-M7, double: largest difference from the desktop | instructions per "
            "sample | RAM per instance [B] | flash [B] | Cortex-M4F, float: largest difference "
            "from double | instructions per sample | RAM [B] |",
            "|---|---|---|---|---|---|---|---|"]
    for key, d in double.items():
        f = single[key]
        rows.append(f"| {key} | {d['max_abs_diff']:.2g} | {d['insns_per_sample']:.0f} | "
                    f"{d['ram_bytes']} | {d['flash_bytes']} | {f['max_abs_diff']:.2g} | "
                    f"{f['insns_per_sample']:.0f} | {f['ram_bytes']} |")
    return "\n".join(rows)


def engines_table(ctx: dict[str, Path]) -> str:
    from .engines import engine_rows, engine_table

    return engine_table(engine_rows(ctx["fmus"]), speed=False)


@functools.lru_cache(maxsize=3)
def _battery(known_scale: bool = False, calibrated_first: bool = False) -> Any:
    from .battery import MOTIONS, PARTS, SENSOR_CLASSES, Setup, run_battery

    return run_battery(list(MOTIONS), list(SENSOR_CLASSES), PARTS, scheduler=None,
                       setup=Setup(known_scale, calibrated_first))


def battery_classes() -> str:
    from .battery import classes_text

    return classes_text()


def battery_overview(ctx: dict[str, Path]) -> str:
    from .battery import overview_table

    return overview_table(_battery())


def _battery_versus(flag: str) -> Callable[[dict[str, Path]], str]:
    """The table of every cell as recommended beside the battery with one Setup flag on."""
    def make(ctx: dict[str, Path]) -> str:
        from .battery import Setup, setup_table

        return setup_table(_battery(), _battery(**{flag: True}), Setup(**{flag: True}))

    return make


def battery_picture(ctx: dict[str, Path], path: Path) -> None:
    from .battery import plot

    plot(_battery(), path)


RATE_SWEEP = (50.0, 100.0, 400.0, 1000.0)
"""The rates [Hz] of the battery page's sample-rate table: a slow logger's, the MPU-6050's
usual, the order of BROAD's (286 Hz) and a flight controller's."""


@functools.lru_cache(maxsize=1)
def _battery_rates() -> Any:
    from .battery import MOTIONS, PARTS, at_rate, run_battery

    sensors = [at_rate("mpu6050", hz) for hz in RATE_SWEEP]
    return run_battery(list(MOTIONS), sensors, PARTS, scheduler=None)


def battery_rates(ctx: dict[str, Path]) -> str:
    """docs/results/battery/index.md: the realistic MPU-6050 at each of RATE_SWEEP, every
    motion, beside VQF (battery.rate_table)."""
    from .battery import rate_table

    return rate_table(_battery_rates())


def readme_battery(ctx: dict[str, Path]) -> str:
    """The README's battery line: in how many cells (motion class x sensor class) the best of
    ours and kf, ukf are ahead of VQF, and where they are furthest behind; the same counts with
    each part calibrated first; and on how many motions the best of ours is ahead at each of
    RATE_SWEEP (the realistic MPU-6050 sampled at that rate)."""
    from .battery import PARTS, aims_met, aims_per_class, verdicts

    results = _battery()
    cells = {(m, s): verdicts(c) for m, by in results.items() for s, c in by.items()}
    ahead, level = aims_met(results)
    cal_ahead, cal_level = aims_met(_battery(calibrated_first=True))
    worst = max(cells, key=lambda k: cells[k]["kf_ukf_vs_vqf"])
    sensors = len(next(iter(results.values())))
    rates = _battery_rates()
    by_rate = [ahead for ahead, _ in aims_per_class(rates)]
    return (f"- **A battery of motions and parts**: {len(results)} motion classes x {sensors} "
            f"sensor classes x {PARTS} parts\n  beside VQF on the same samples: the best of ours "
            f"ahead of VQF in {ahead} of {len(cells)} cells,\n  kf and ukf within 5 % of it or "
            f"ahead in {level}; furthest behind on {worst[0]} / {worst[1]}\n  "
            f"({cells[worst]['kf_ukf_vs_vqf']:.2f} times VQF's RMSE). Each part calibrated "
            f"first, VQF given the same\n  calibration: {cal_ahead} and {cal_level}. The "
            "MPU-6050 sampled at " + ", ".join(f"{hz:g}" for hz in RATE_SWEEP)
            + " Hz:\n  the best of ours ahead on " + ", ".join(str(n) for n in by_rate)
            + f" of {len(rates)} motions "
            "(`imu-fusion battery\n  [--calibrated-first | --sensor mpu6050 --rate HZ,...]`;\n  "
            "[docs/results/battery](docs/results/battery/index.md)).")


def _battery_motion(name: str) -> Callable[[dict[str, Path]], str]:
    def make(ctx: dict[str, Path]) -> str:
        from .battery import motion_text

        return motion_text(_battery(), name)

    return make


def mechanisms_table(ctx: dict[str, Path]) -> str:
    from fusion_core.registry import ATTITUDE_FILTERS

    from .battery import PARTS
    from .mechanisms import MECHANISMS, load_trials, measure, worth_table

    trials, groups = load_trials([ctx["broad"]])
    return worth_table(measure(trials, groups, list(ATTITUDE_FILTERS), MECHANISMS, PARTS))


def mechanisms_count(ctx: dict[str, Path]) -> str:
    """docs/results/mechanisms.md: per attitude filter, the values its defaults take from data
    (broad.cv.CV_GRID's parameters it has, chosen by the cross-validation) and the mechanisms
    kept and dropped by `imu-fusion mechanisms` (each a keep-or-drop choice made on data)."""
    from fusion_core.registry import ATTITUDE_FILTERS, ESTIMATORS

    from .broad.cv import CV_GRID
    from .mechanisms import MECHANISMS

    rows = ["| estimator | scanned values (`broad --cv`) | mechanisms on | dropped |",
            "|---|---|---|---|"]
    for key in ATTITUDE_FILTERS:
        specs = ESTIMATORS[key].param_specs()
        grid = [name for name in CV_GRID if name in specs]
        on = [m.name for m in MECHANISMS if m.applies(key)]
        off = [m.name for m in MECHANISMS if m.dropped(key)]
        rows.append(f"| {key} | {len(grid)}: {', '.join(grid)} | {len(on)}: {', '.join(on)} | "
                    f"{len(off)}: {', '.join(off) or '-'} |")
    return "\n".join(rows)


RUNNING_SWITCHES = {"as recommended": {}, "acc_lowpass_stretch=1": {"acc_lowpass_stretch": 1.0},
                    "held_acceleration=0.1": {"held_acceleration": 0.1}}
"""The running page's switches (`imu-fusion battery --param NAME=VALUE`): the longer vector
off, and the slow band's statistic capped at 0.1 m/s2."""


def battery_running_switches(ctx: dict[str, Path]) -> str:
    """docs/results/battery/running.md: kf and ukf over VQF (mean RMSE over the parts) on the
    running torso and the pendulum, as recommended and with each of RUNNING_SWITCHES: what the
    slow band's statistic costs where it counts a fast bounce, and what a lower cap on it costs
    where the vector holds a slow swing."""
    from .battery import PARTS, filter_overrides, run_variants, stats

    motions, sensors = ("running", "pendulum"), ("mpu6050", "worse")
    variants = {name: filter_overrides(values) for name, values in RUNNING_SWITCHES.items()}
    results = run_variants(variants, motions, sensors, PARTS, scheduler=None,
                           filters=["kf", "ukf"], vqf=True)
    rows = ["| motion / sensor class | VQF [deg] | "
            + " | ".join(f"kf / ukf over VQF, {name}" for name in variants) + " |",
            "|---|---|" + "---|" * len(variants)]
    for m in motions:
        for s in sensors:
            vqf = stats(results["as recommended"][m][s]["vqf"])[0]
            cells = [" / ".join(f"{stats(results[v][m][s][k])[0] / vqf:.2f}" for k in ("kf", "ukf"))
                     for v in variants]
            rows.append(f"| {m} / {s} | {vqf:.3f} | " + " | ".join(cells) + " |")
    return "\n".join(rows)


def _battery_figures() -> tuple[Figure, ...]:
    from .battery import MOTIONS

    command = "imu-fusion battery"
    return (
        Figure("battery-classes", "docs/results/battery/index.md", command,
               lambda ctx: battery_classes()),
        Figure("readme-battery", "README.md", f"{command}; {command} --calibrated-first; "
               f"{command} --sensor mpu6050 --rate " + ",".join(f"{hz:g}" for hz in RATE_SWEEP),
               readme_battery, needs=("vqf",)),
        Figure("battery-overview", "docs/results/battery/index.md", command, battery_overview,
               needs=("vqf",)),
        *(Figure(f"battery-{flag.replace('_', '-')}", "docs/results/battery/index.md",
                 f"{command}; {command} --{flag.replace('_', '-')}", _battery_versus(flag),
                 needs=("vqf",)) for flag in ("known_scale", "calibrated_first")),
        Figure("battery-picture", "docs/results/battery/index.md", command, battery_picture,
               "docs/results/battery/battery.png", ("vqf",)),
        *(Figure(f"battery-{m}", f"docs/results/battery/{m}.md", f"{command} --motion {m}",
                 _battery_motion(m), needs=("vqf",)) for m in MOTIONS),
        Figure("battery-rates", "docs/results/battery/index.md",
               f"{command} --sensor mpu6050 --rate "
               + ",".join(f"{hz:g}" for hz in RATE_SWEEP), battery_rates, needs=("vqf",)),
        Figure("battery-running-switches", "docs/results/battery/running.md",
               f"{command} --motion running,pendulum --sensor mpu6050,worse --param "
               "acc_lowpass_stretch=1 (or held_acceleration=0.1)", battery_running_switches,
               needs=("vqf",)))


FIGURES: tuple[Figure, ...] = (
    Figure("fmu-example", "README.md",
           "fmpy simulate dist/native/fmi3/AngleBiasKalmanFilter.fmu --input-file "
           "examples/tilt_motion.csv --output-interval 0.01 --output-file out.csv; python "
           "examples/plot_example.py out.csv examples/tilt_motion_truth.csv "
           "docs/fmu_example.png", fmu_picture, "docs/fmu_example.png", ("fmus",)),
    Figure("estimate-example", "docs/guide/estimate.md", "imu-fusion " + " ".join(
        ESTIMATE_ARGS) + " --no-plots", estimate_output),
    Figure("estimate-picture", "docs/guide/estimate.md", "imu-fusion " + " ".join(
        ESTIMATE_ARGS), estimate_picture, "docs/estimate_example.png"),
    Figure("readme-estimators", "README.md", "fusion_core.registry (python -c 'from "
           "testbenches.docs_figures import estimators_table; print(estimators_table({}))')",
           estimators_table),
    Figure("estimators-index", "docs/estimators/index.md", "fusion_core.registry (as "
           "readme-estimators)", functools.partial(estimators_table, pages="./")),
    Figure("readme-contract", "README.md", "make run (imu-fusion run --fmu-dir dist)",
           readme_contract, needs=("fmus",)),
    Figure("contract-parts", "docs/results/contract.md", "imu-fusion run (its checks over 20 "
           "parts; testbenches.parts.parts_table)", parts_table),
    Figure("calibrated-parts", "docs/results/calibration.md",
           "imu-fusion campaign --estimator all --scenario moderate_dynamics --seeds 200 "
           "[--calibrate-first]; imu-fusion run --scenario moderate_dynamics --seeds 200 "
           "--peers vqf [--calibrate-first]", calibrated_parts_table, needs=("vqf",)),
    Figure("readme-calibrated-part", "README.md",
           "imu-fusion campaign --scenario moderate_dynamics --seeds 200 --calibrate-first",
           readme_calibrated_part, needs=("vqf",)),
    Figure("speed-bench", "docs/results/speed.md", "python -m benchmarks --docs (make bench)",
           speed_table, needs=("checkout",)),
    Figure("campaigns-makefile", "docs/guide/campaigns.md", "make campaign",
           campaigns_makefile_table),
    Figure("campaigns-parts", "docs/guide/campaigns.md",
           "python -m testbenches run --estimator cf,mgcf,kf,ukf --scenario moderate_dynamics "
           "--seeds 200 --peers vqf --no-contract --no-plots", campaigns_parts_table,
           needs=("vqf",)),
    Figure("campaigns-scenarios", "docs/guide/campaigns.md",
           "python -m testbenches run --estimator kf,ukf --scenario SCENARIO --seeds 100 "
           "--peers vqf --no-contract --no-plots", campaigns_scenarios_table, needs=("vqf",)),
    Figure("uncalibrated-rest", "docs/guide/own-sensor.md",
           "python -m testbenches run --scenario static_tilted --seeds 40 --sensor "
           "uncalibrated.json --peers vqf [--param rest_bias_bound=0] --no-contract",
           uncalibrated_rest_table, needs=("vqf",)),
    Figure("uncalibrated-moving", "docs/guide/own-sensor.md",
           "python -m testbenches run --scenario roll_pitch --seeds 40 --sensor "
           "uncalibrated.json --peers vqf [--param init_bias_std=0.0524] --no-contract",
           uncalibrated_moving_table, needs=("vqf",)),
    Figure("contract-vqf", "docs/results/contract.md",
           "python -m testbenches run --peers vqf (shaking, gyro_clipping: --seeds 20)",
           vqf_contract_table, needs=("vqf",)),
    Figure("robustness-recovery", "docs/results/robustness.md", "python -m testbenches.recovery",
           recovery_table),
    Figure("contract-constant-noise", "docs/results/contract.md",
           "python -m testbenches run --scenario roll_sweep,pitch_sweep,high_dynamics "
           "--no-contract [--param gyro_scale_std=0 --param disturbance_time=0]",
           constant_noise_table),
    Figure("broad-noise", "docs/guide/own-sensor.md",
           "imu-fusion noise TRIAL (each BROAD trial's rest segment)", broad_noise_table,
           needs=("broad",)),
    Figure("slow-roll", "docs/guide/own-sensor.md", "python -m testbenches.slow_roll",
           slow_roll_table, needs=("vqf",)),
    Figure("budget-excerpt", "docs/results/contract.md",
           "python -m testbenches budget --estimator ... --scenario ... (seeds 0-2)",
           budget_excerpt),
    Figure("readme-broad", "README.md",
           "imu-fusion broad DIR --estimator cf,mgcf,kf,ukf --peers --cv", readme_broad,
           needs=("broad", "vqf")),
    Figure("embedded-table", "docs/guide/backends.md", "make embedded", embedded_table,
           needs=("embedded",)),
    Figure("engines-table", "docs/guide/engines.md", "imu-fusion engines --fmu-dir dist",
           engines_table, needs=("fmus", "engines")),
    Figure("imucal-table", "docs/results/calibration.md",
           f"imu-fusion calibrate {IMUCAL_SESSION} --rate 102.4 --gyro-unit deg/s --acc-unit "
           f"m/s2 --sections {IMUCAL_SECTIONS} --gravity 9.81", imucal_table,
           needs=("imucal", "imucal-package")),
    Figure("calibrate-imucal", "docs/results/calibration.md",
           f"imu-fusion calibrate {IMUCAL_SESSION} --rate 102.4 --gyro-unit deg/s "
           "--gravity 9.81", calibrate_output, needs=("imucal",)),
    Figure("calibrate-picture", "docs/results/calibration.md",
           f"imu-fusion calibrate {IMUCAL_SESSION} --rate 102.4 --gyro-unit deg/s "
           "--gravity 9.81", calibrate_picture, "docs/calibration_example.png", ("imucal",)),
    *_battery_figures(),
    Figure("broad-groups", "docs/results/broad.md",
           "imu-fusion broad DIR " + " ".join(BROAD_ALL), broad_groups, needs=("broad", "vqf")),
    Figure("broad-cv", "docs/results/broad.md", "imu-fusion broad DIR " + " ".join(BROAD_ALL),
           broad_cv, needs=("broad", "vqf")),
    Figure("broad-moderate", "docs/results/broad.md",
           "imu-fusion run --scenario moderate_dynamics --no-contract --preset PRESET --sensor "
           "SENSOR", moderate_presets_table),
    Figure("broad-gyro", "docs/results/broad.md",
           "imu-fusion broad DIR --gyro-fit (the lag and fit of each trial's gyro)",
           broad_gyro_table, needs=("broad",)),
    Figure("broad-scale-parts", "docs/results/broad.md",
           "imu-fusion run --estimator ukf --scenario moderate_dynamics --seeds 40 --sensor "
           "SENSOR.json --peers vqf --no-contract", scale_parts_table, needs=("vqf",)),
    Figure("mechanisms-count", "docs/results/mechanisms.md", "imu-fusion mechanisms --help; "
           "imu-fusion broad --help (the grid)", mechanisms_count),
    Figure("mechanisms-table", "docs/results/mechanisms.md", "imu-fusion mechanisms DIR",
           mechanisms_table, needs=("broad",)),
)
"""Every generated figure of the README and the docs."""


# ----- blocks and pictures ----------------------------------------------------------------------

def block_pattern(name: str) -> re.Pattern[str]:
    return re.compile(rf"(<!-- generated: {re.escape(name)} -->\n)(.*?)(<!-- end generated: "
                      rf"{re.escape(name)} -->)", re.S)


def block(page: Path, name: str) -> str:
    """The text of a page's generated block; ValueError where the page has none of that name."""
    m = block_pattern(name).search(page.read_text(encoding="utf-8"))
    if m is None:
        raise ValueError(f"{page}: no generated block {name!r} (marks <!-- generated: {name} "
                         f"--> and <!-- end generated: {name} -->)")
    return m.group(2).removesuffix("\n")


def replace_block(page: Path, name: str, text: str) -> None:
    block(page, name)  # it is there
    new = block_pattern(name).sub(lambda m: m.group(1) + text + "\n" + m.group(3),
                                  page.read_text(encoding="utf-8"))
    page.write_text(new, encoding="utf-8")


def pixels_differ(a: Path, b: Path) -> float:
    """The share of pixels that differ between two pictures (1.0 where their sizes do)."""
    import matplotlib.image as mpimg

    x, y = mpimg.imread(a), mpimg.imread(b)
    if x.shape != y.shape:
        return 1.0
    return float(np.mean(np.any(np.abs(x - y) > 1.0 / 255.0, axis=-1)))


def context(fmu_dir: Path | None = None, imucal: Path | None = None) -> dict[str, Path]:
    """What the figures need that is here: the built FMUs, imucal's session."""
    ctx: dict[str, Path] = {}
    if (REPO / "benchmarks" / "report.py").is_file():  # a source checkout, not a wheel
        ctx["checkout"] = REPO
    fmus = fmu_dir or REPO / "dist"
    if (fmus / "native" / "fmi3" / "AngleBiasKalmanFilter.fmu").is_file():
        ctx["fmus"] = fmus
    from .embedded.build import missing_tools
    from .engines import ENGINES, engine_reason

    if not missing_tools():
        ctx["embedded"] = REPO
    for module, need in (("vqf", "vqf"), ("imucal", "imucal-package")):
        try:
            __import__(module)
        except ImportError:
            continue
        ctx[need] = REPO

    if all(engine_reason(e) is None for e in ENGINES):
        ctx["engines"] = REPO
    broad = REPO.parent / "shared" / "data" / "broad"
    if broad.is_dir() and any(broad.iterdir()):
        ctx["broad"] = broad
    data = imucal or REPO.parent / "shared" / "data" / "imucal"
    if (data / IMUCAL_SESSION).is_file():
        ctx["imucal"] = data
    return ctx


def missing(figure: Figure, ctx: dict[str, Path]) -> list[str]:
    """What a figure needs that is not here."""
    return [n for n in figure.needs if n not in ctx]


def check(figure: Figure, ctx: dict[str, Path], root: Path = REPO) -> str | None:
    """None where the figure in the pages under root matches its command, else what
    differs."""
    if figure.picture is None:
        want = figure.make(ctx)  # type: ignore[call-arg]
        have = block(root / figure.page, figure.name)
        if want == have:
            return None
        diff = next((i for i, (a, b) in enumerate(zip(want, have, strict=False)) if a != b),
                    min(len(want), len(have)))
        return (f"{figure.page}, block {figure.name}: differs from its command's output at "
                f"character {diff} (page: {have[diff:diff + 60]!r}; command: "
                f"{want[diff:diff + 60]!r})")
    with tempfile.TemporaryDirectory() as tmp:
        made = Path(tmp) / "made.png"
        figure.make(ctx, made)  # type: ignore[call-arg]
        shown = root / figure.picture
        if not shown.is_file():
            return f"{figure.picture}: missing"
        share = pixels_differ(made, shown)
    if share <= PICTURE_TOLERANCE:
        return None
    return (f"{figure.picture}: {100 * share:.2f} % of its pixels differ from what its command "
            f"draws (at most {100 * PICTURE_TOLERANCE:g} % may)")


def write(figure: Figure, ctx: dict[str, Path]) -> None:
    if figure.picture is None:
        replace_block(REPO / figure.page, figure.name, figure.make(ctx))  # type: ignore[call-arg]
    else:
        figure.make(ctx, REPO / figure.picture)  # type: ignore[call-arg]


def add_docs_parser(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    p = sub.add_parser("docs", help="check (or make again) the docs' generated figures",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("names", nargs="*", help="which figures (all)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--check", action="store_true",
                      help="say which no longer match and exit 1 if any (the default)")
    mode.add_argument("--write", action="store_true", help="make them again instead of checking")
    p.add_argument("--fmu-dir", type=Path, default=None, help="built FMUs (dist)")
    p.add_argument("--imucal", type=Path, default=None,
                   help=f"the folder of imucal's {IMUCAL_SESSION}")
    p.set_defaults(func=cmd_docs)


def cmd_docs(args: argparse.Namespace) -> int:
    from .options import choose

    names = choose(",".join(args.names) or "all", [f.name for f in FIGURES], "figure")
    ctx = context(args.fmu_dir, args.imucal)
    stale = 0
    for figure in (f for f in FIGURES if f.name in names):
        lacking = missing(figure, ctx)
        if lacking:
            print(f"{figure.name}: skipped, needs {', '.join(lacking)} (--fmu-dir, --imucal)")
            continue
        if args.write:
            write(figure, ctx)
            print(f"{figure.name}: made ({figure.picture or figure.page})")
            continue
        problem = check(figure, ctx)
        print(f"{figure.name}: {'matches' if problem is None else problem}")
        stale += problem is not None
    return 1 if stale else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit("use: imu-fusion docs")

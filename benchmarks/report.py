"""Targets of issue 6 beside the measurements, the terminal table and bench.json."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

UKF_VS_FILTERPY = 10.0
STREAM_VS_VQF = 3.0
"""Estimator.stream() per sample at most this many times VQF's update() in the same run."""
"""Our UKF must be at least this many times faster than filterpy's UKF in the same run."""
FMU_OVERHEAD_TARGET_US = 10.0
TESTBENCH_RTF_TARGET = 50.0
TESTBENCH_TARGET_RATE = "1000Hz"
NATIVE_FMU_SPEEDUP = 4.0
"""A native FMU step (fmpy low-level calls) at least this many times faster than pythonfmu's."""
C_HOST_VS_TWIN = 2.0
"""A native FMU step in a C host within this factor of the C twin's batch run per sample."""
TESTBENCH_NATIVE_RATIO = 3.0
TESTBENCH_NATIVE_RTF = 100.0
"""The native testbench at 1 kHz: this many times the pythonfmu one's real-time factor, and at
least this real-time factor on a quiet fast machine."""


def _target(name: str, measured: float | None, target: str, met: bool | None,
            limit: str = "") -> dict[str, Any]:
    return {"name": name, "measured": measured, "target": target, "met": met,
            "limited_by": "" if met else limit}


def evaluate_targets(r: dict[str, Any]) -> list[dict[str, Any]]:
    """Every target the measurements of r allow to judge: met or not, and what limits it."""
    out: list[dict[str, Any]] = []
    ps = r.get("per_sample_us")
    if ps:
        floor = r.get("step_floor_us")
        floor_text = (
            f"the step API alone (input conversion, checks, Estimate) costs {floor:.2f} us "
            "per call in this interpreter" if floor is not None else ""
        )
        vqf = ps.get("vqf")
        limit_text = (
            "CPython float arithmetic: step() is the Python reference, interpreted (the one "
            "compiled path is the C twin, behind run(), stream() and every FMU; see "
            "docs/results/speed.md)"
            + (f"; {floor_text}" if floor_text else "")
            + (f"; VQF (C++) costs {vqf:.2f} us in the same run" if vqf is not None else "")
        )
        from fusion_core.registry import REGISTRY  # not at import: __main__ pins its core first

        for key, limit in ((e.key, e.bench.step_us) for e in REGISTRY):
            v = ps.get(key)
            out.append(_target(
                f"per_sample_us.{key}", v, f"<= {limit:g} us",
                None if v is None else v <= limit, limit_text,
            ))
        ukf, peer = ps.get("ukf"), ps.get("filterpy_ukf")
        if ukf is not None and peer is not None:
            out.append(_target(
                "per_sample_us.ukf vs filterpy_ukf", peer / ukf,
                f">= {UKF_VS_FILTERPY:g}x faster", peer / ukf >= UKF_VS_FILTERPY,
                "13 sigma points through the exact rotation, 6x6 covariance in Python floats",
            ))
    stream, vqf = r.get("per_sample_us_stream") or {}, (ps or {}).get("vqf")
    for key, v in stream.items():
        if v is None or vqf is None:
            continue
        out.append(_target(
            f"per_sample_us_stream.{key} vs vqf", v / vqf, f"<= {STREAM_VS_VQF:g}x VQF update",
            v / vqf <= STREAM_VS_VQF,
            "the twin's own work plus Python's calling convention and the Estimate; without "
            "the compiled entry point (fusion_core.native.library.stream_reason()), one cffi "
            "call in ABI mode, packing the six numbers and building the Estimate in Python",
        ))
    overhead = r.get("fmu_overhead_us")
    if overhead:
        low = r.get("fmu_overhead_lowlevel_us", {})
        floors = r.get("fmu_floor_us", {})
        for key, v in overhead.items():
            lv = low.get(key)
            floor = floors.get(key, {})
            out.append(_target(
                f"fmu_overhead_us.{key}", v, f"<= {FMU_OVERHEAD_TARGET_US:g} us",
                v <= FMU_OVERHEAD_TARGET_US,
                "fmpy's list-to-ctypes conversion per call, pythonfmu's C++ wrapper and the "
                "slave's Python setters/getters"
                + (f" (with preallocated ctypes arrays the overhead is {lv:.1f} us)"
                   if lv is not None else "")
                + (f"; an FMU whose calls return at once already costs "
                   f"{floor['api']:.1f} us (fmpy API) / {floor['lowlevel']:.1f} us (low-level) "
                   "per step" if floor.get("api") is not None
                   and floor.get("lowlevel") is not None else ""),
            ))
    nat = r.get("native")
    if nat and nat.get("available"):
        from .native import NATIVE_TARGETS_US, VQF_RATIO_TARGETS

        vqf = nat.get("vqf_batch_us_per_sample")
        for key, limit in NATIVE_TARGETS_US.items():
            v = nat["run_us_per_sample"].get(key)
            out.append(_target(
                f"native.run_us_per_sample.{key}", v, f"<= {limit:g} us",
                v is not None and v <= limit,
                "no C twin yet" if v is None else
                "the filter's arithmetic, spread over its parts (docs/results/speed.md, where "
                "the batch time goes)",
            ))
            ratio = VQF_RATIO_TARGETS.get(key)
            if ratio is not None and v is not None and vqf is not None:
                out.append(_target(
                    f"native.{key} over vqf_batch", v / vqf, f"<= {ratio:g}x VQF's batch",
                    v <= ratio * vqf,
                    "one pass moves by up to 15 % on a busy machine: `python -m "
                    "benchmarks.batch_ratio` gives the median over rounds",
                ))
    if nat and nat.get("fmu_step_us"):
        floors = nat.get("fmu_floor_us", {})
        for key, v in nat.get("fmu_step_speedup_vs_pythonfmu", {}).items():
            out.append(_target(
                f"native.fmu_step_speedup_vs_pythonfmu.{key}", v,
                f">= {NATIVE_FMU_SPEEDUP:g}x", v >= NATIVE_FMU_SPEEDUP,
                "the host's side: fmpy's wrapped ctypes calls cost "
                f"{floors.get('fmi2', float('nan')):.1f} us per step even on a native FMU "
                "whose calls return at once (fmu_floor_us)",
            ))
        for key, v in nat.get("c_host_vs_twin", {}).items():
            out.append(_target(
                f"native.c_host_step_us.fmi2.{key} vs twin run", v,
                f"<= {C_HOST_VS_TWIN:g}x the twin's run per sample", v <= C_HOST_VS_TWIN,
                "three FMI calls per step with their state and value-reference checks",
            ))
        for key, t in nat.get("testbench_rtf_1khz", {}).items():
            out.append(_target(
                f"native.testbench_rtf_1khz.{key}", t["ratio"],
                f">= {TESTBENCH_NATIVE_RATIO:g}x the pythonfmu testbench",
                t["ratio"] >= TESTBENCH_NATIVE_RATIO,
                "fmpy's per-call cost in the Python master (eight FMI calls per step)",
            ))
            out.append(_target(
                f"native.testbench_rtf_1khz.{key}.native", t["native"],
                f">= {TESTBENCH_NATIVE_RTF:g} (on a quiet fast machine)",
                t["native"] >= TESTBENCH_NATIVE_RTF,
                "the Python master: fmpy's ctypes calls, eight per step",
            ))
    camp = r.get("campaign")
    if camp and camp.get("available"):
        from .campaign import SAMPLES_PER_S_TARGET, SCALING_TARGET, WORKERS

        per = camp["per_sample_us"]
        out.append(_target(
            "campaign.samples_per_s", camp["samples_per_s"], f">= {SAMPLES_PER_S_TARGET:.0e}",
            camp["samples_per_s"] >= SAMPLES_PER_S_TARGET,
            f"per sample on one worker: the estimators' batch runs {per['estimators']:.2f} us "
            f"(the UKF's 13 sigma-point rotations the dearest), the sensor's share "
            f"{per['sensor']:.2f} us, "
            f"the rest {per['rest']:.2f} us; the estimators alone on every core reach "
            f"{camp['estimator_ceiling_samples_per_s']:.3g} samples/s",
        ))
        out.append(_target(
            "campaign.scaling", camp["scaling"], f">= {SCALING_TARGET:g}",
            camp["scaling"] >= SCALING_TARGET,
            f"fixed costs that do not shrink with workers (the cluster's start and stop, the "
            f"workers' first imports, the last batches): {camp['overhead_seconds']:.1f} of "
            f"{camp['seconds']:.1f} s with {WORKERS} workers, "
            f"{camp['overhead_seconds_1_worker']:.1f} of {camp['seconds_1_worker']:.1f} s with "
            f"one; the runs alone scale by {camp['runs_scaling']:.2f}",
        ))
    tb = r.get("testbench")
    if tb:
        for key, rates in tb.items():
            at = rates.get(TESTBENCH_TARGET_RATE)
            if at is None:
                continue
            est = at["estimator_fmu_us_per_step"]
            out.append(_target(
                f"testbench.{key}.{TESTBENCH_TARGET_RATE}.real_time_factor",
                at["real_time_factor"], f">= {TESTBENCH_RTF_TARGET:g}",
                at["real_time_factor"] >= TESTBENCH_RTF_TARGET,
                f"{at['us_per_step']:.0f} us per testbench step, of which the estimator FMU "
                f"{est:.0f} us; the rest is the ImuPlant and ImuSensor FMUs and the master",
            ))
    long = r.get("estimate_2e6")
    if long:
        from .long_file import ESTIMATE_VS_READ, PEAK_MB

        for fmt, run in long["runs"].items():
            out.append(_target(
                f"estimate_2e6.{fmt}.vs_pyarrow_read", run["vs_pyarrow_read"],
                f"<= {ESTIMATE_VS_READ:g}", run["vs_pyarrow_read"] <= ESTIMATE_VS_READ,
                f"the estimators' C twins alone, summed over one core each, take "
                f"{long.get('estimators_alone_vs_pyarrow_read', float('nan')):.1f}x the read; "
                "they run in parallel on the machine's cores, while pyarrow's read uses every "
                "core"
                + ("; formatting every double as text" if fmt == "csv" else "")))
            out.append(_target(
                f"estimate_2e6.{fmt}.peak_mb", run["peak_mb"], f"<= {PEAK_MB:g}",
                run["peak_mb"] <= PEAK_MB, "blocks in flight and the libraries loaded"))
    sc = r.get("scaling")
    if sc:
        for key, s in sc.items():
            if s.get("flat") is None:
                continue
            out.append(_target(
                f"scaling.{key}.flat", s["excess_growth_bytes_per_sample"],
                f"growth beyond the outputs <= {s['allowed_growth_bytes_per_sample']:.1f} B "
                "per extra sample", s["flat"],
                "run() keeps Python objects per sample",
            ))
    return out


def _fmt(v: float | None, digits: int = 2) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.{digits}f}"


def _verdict(t: dict[str, Any] | None) -> str:
    if t is None or t["met"] is None:
        return ""
    return "met" if t["met"] else "NOT MET"


def _native_lines(r: dict[str, Any], targets: dict[str, Any]) -> list[str]:
    nat = r["native"]
    if not nat.get("available"):
        return ["", f"Native twin: unavailable ({nat.get('reason')})"]
    lines = ["", f"Native twin: batch run over {nat['samples']} samples [us per sample]",
             f"  {'filter':<15}{'native':>10}{'python':>10}{'speed-up':>10}{'over VQF':>10}   "
             f"{'target':<22}verdict"]
    vqf = nat.get("vqf_batch_us_per_sample")
    for key, v in nat["run_us_per_sample"].items():
        t = targets.get(f"native.run_us_per_sample.{key}")
        over = f"{_fmt(v / vqf)}x" if vqf else "-"
        lines.append(f"  {key:<15}{_fmt(v):>10}{_fmt(nat['python_run_us_per_sample'][key]):>10}"
                     f"{_fmt(nat['speedup_vs_python'][key], 1):>9}x{over:>10}   "
                     f"{(t['target'] if t else ''):<22}{_verdict(t)}")
        r_ = targets.get(f"native.{key} over vqf_batch")
        if r_:
            lines.append(f"  {'':<15}{'':>40}   {r_['target']:<22}{_verdict(r_)}")
    for key in nat.get("no_twin_yet", []):
        lines.append(f"  {key:<15}{'-':>10}   no C twin yet")
    lines.append("  vqf (C++ updateBatch): " + (f"{_fmt(vqf)} us" if vqf is not None
                                                 else f"unavailable: {nat.get('vqf_unavailable')}"))
    steps = nat.get("fmu_step_us")
    if not steps:
        return lines
    floors, host = nat.get("fmu_floor_us", {}), nat.get("c_host_step_us", {})
    rtf = nat.get("testbench_rtf_1khz", {})
    lines += ["", "Native FMUs: one set/doStep/get cycle as the testbench calls (the ctypes "
              "functions fmpy loaded), and in a C host's own loop [us]; testbench real-time "
              "factor at 1 kHz",
              f"  {'filter':<8}{'pythonfmu':>10}{'fmi2':>7}{'fmi3':>7}{'speed-up':>9}"
              f"{'C fmi2':>8}{'C fmi3':>8}{'C/twin':>7}{'RTF nat':>9}{'RTF py':>8}{'ratio':>7}"]
    for key in steps.get("fmi2", {}):
        r_ = rtf.get(key, {})
        lines.append(
            f"  {key:<8}{_fmt(steps['pythonfmu'][key]):>10}{_fmt(steps['fmi2'][key]):>7}"
            f"{_fmt(steps['fmi3'][key]):>7}"
            f"{_fmt(nat['fmu_step_speedup_vs_pythonfmu'][key], 1):>8}x"
            f"{_fmt(host.get('fmi2', {}).get(key)):>8}{_fmt(host.get('fmi3', {}).get(key)):>8}"
            f"{_fmt(nat.get('c_host_vs_twin', {}).get(key), 1):>6}x"
            f"{_fmt(r_.get('native'), 0):>9}{_fmt(r_.get('pythonfmu'), 0):>8}"
            f"{_fmt(r_.get('ratio'), 1):>6}x")
    lines.append("  floor (an FMU whose calls return at once): " + ", ".join(
        f"{k} {_fmt(v)} us" for k, v in floors.items()))
    return lines


def _campaign_lines(r: dict[str, Any], targets: dict[str, Any]) -> list[str]:
    c = r["campaign"]
    if not c.get("available"):
        return ["", f"Campaign: unavailable ({c.get('reason')})"]
    t, s = targets.get("campaign.samples_per_s"), targets.get("campaign.scaling")
    return ["", f"Campaign on a local Dask cluster: {c['runs']} runs",
            f"  2 workers: {c['samples_per_s']:.3g} samples/s ({c['seconds']:.1f} s), target "
            f"{t['target'] if t else ''}: {_verdict(t)}",
            f"  1 worker:  {c['samples_per_s_1_worker']:.3g} samples/s "
            f"({c['seconds_1_worker']:.1f} s); scaling {c['scaling']:.2f} (target "
            f"{s['target'] if s else ''}): {_verdict(s)}",
            f"  fixed costs {c['overhead_seconds']:.1f} s (2 workers), "
            f"{c['overhead_seconds_1_worker']:.1f} s (1 worker); the runs alone scale by "
            f"{c['runs_scaling']:.2f}",
            "  per sample on one worker [us]: " + ", ".join(
                f"{k} {v:.2f}" for k, v in c["per_sample_us"].items())
            + f"; the estimators alone on every core: "
            f"{c['estimator_ceiling_samples_per_s']:.3g} samples/s"]


def format_table(r: dict[str, Any]) -> str:
    """The results as a terminal table, every target beside its measurement."""
    targets = {t["name"]: t for t in r.get("targets", [])}
    lines: list[str] = []
    rec = r["recording"]
    m = r["machine"]
    lines.append(
        f"Machine: {m['cpu']} ({m['usable_cpus']} usable of {m['cpu_count']} CPUs), "
        f"Python {m['python']} (PGO/LTO build: {'yes' if m['python_pgo_lto'] else 'no'}); "
        f"load average {m.get('load_average_start')} -> {m.get('load_average_end')}"
    )
    lines.append(
        f"Recording: {rec['scenario']} at {rec['rate_hz']:g} Hz, {rec['samples']} samples; "
        f"medians of {r['repeats']} passes{' (--quick)' if r['quick'] else ''}"
    )
    if "core" in r:
        lines.append("fusion_core: the Python reference's step; run() and the pythonfmu FMUs' "
                     "steps " + ("through the C twin" if r["core"].get("native") else
                                 f"in Python too ({r['core'].get('native_reason')})"))
    if "per_sample_us" in r:
        lines += ["", "Per sample: one step/update call in a Python loop [us]",
                  f"  {'filter':<15}{'median':>10}{'min':>10}   {'target':<22}verdict"]
        detail = r["per_sample_detail"]
        for key, v in r["per_sample_us"].items():
            t = targets.get(f"per_sample_us.{key}")
            if v is None:
                reason = r["peers_unavailable"].get(key, "not measured")
                lines.append(f"  {key:<15}{'-':>10}{'':>10}   unavailable: {reason}")
                continue
            lines.append(
                f"  {key:<15}{_fmt(v):>10}{_fmt(detail[key]['min_us']):>10}   "
                f"{(t['target'] if t else ''):<22}{_verdict(t)}"
            )
        t = targets.get("per_sample_us.ukf vs filterpy_ukf")
        if t:
            lines.append(f"  ukf speed-up over filterpy_ukf: {_fmt(t['measured'], 1)}x "
                         f"(target {t['target']}): {_verdict(t)}")
        lines.append(f"  step API floor (an estimator whose update is a Python no-op): "
                     f"{_fmt(r.get('step_floor_us'))} us")
    stream = {k: v for k, v in r.get("per_sample_us_stream", {}).items() if v is not None}
    if stream:
        lines += ["", "Per sample through Estimator.stream(): the C twin's step [us]",
                  f"  {'estimator':<15}{'median':>10}{'x VQF':>10}   {'target':<22}verdict"]
        for key, v in stream.items():
            t = targets.get(f"per_sample_us_stream.{key} vs vqf")
            lines.append(f"  {key:<15}{_fmt(v):>10}{_fmt(t['measured'] if t else None, 1):>10}   "
                         f"{(t['target'] if t else ''):<22}{_verdict(t)}")
    if "fmu_step_us" in r:
        lines += ["", "FMU step: set inputs + doStep + get outputs through fmpy [us]; overhead = "
                  "FMU less fusion_core's step, timed in turn",
                  f"  {'estimator':<11}{'core':>8}{'fmpy API':>10}{'overhead':>10}"
                  f"{'low-level':>11}{'overhead':>10}   {'target':<18}verdict"]
        ov = r.get("fmu_overhead_us", {})
        lov = r.get("fmu_overhead_lowlevel_us", {})
        core = r.get("fmu_core_us", {})
        for key, v in r["fmu_step_us"].items():
            t = targets.get(f"fmu_overhead_us.{key}")
            lines.append(
                f"  {key:<11}{_fmt(core.get(key), 1):>8}{_fmt(v, 1):>10}{_fmt(ov.get(key), 1):>10}"
                f"{_fmt(r['fmu_step_lowlevel_us'][key], 1):>11}{_fmt(lov.get(key), 1):>10}   "
                f"{('overhead ' + t['target']) if t else '':<18}{_verdict(t)}"
            )
        floors = r.get("fmu_floor_us", {})
        for key, f in floors.items():
            if f.get("api") is not None and f.get("lowlevel") is not None:
                lines.append(f"  floor beside {key}: an FMU whose calls return at once: "
                             f"{_fmt(f['api'], 1)} us (fmpy API), {_fmt(f['lowlevel'], 1)} us "
                             "(low-level)")
    if "testbench" in r:
        lines += ["", "Testbench: ImuPlant -> ImuSensor -> estimator FMU (testbenches.master)",
                  f"  {'estimator':<11}{'rate':>8}{'steps/s':>10}{'RTF':>8}{'us/step':>9}"
                  f"{'est. us':>9}   {'target':<10}verdict"]
        for key, rates in r["testbench"].items():
            for rate, x in rates.items():
                t = targets.get(f"testbench.{key}.{rate}.real_time_factor")
                lines.append(
                    f"  {key:<11}{rate:>8}{_fmt(x['steps_per_s'], 0):>10}"
                    f"{_fmt(x['real_time_factor'], 1):>8}{_fmt(x['us_per_step'], 0):>9}"
                    f"{_fmt(x['estimator_fmu_us_per_step'], 0):>9}   "
                    f"{(t['target'] if t else ''):<10}{_verdict(t)}"
                )
    if "native" in r:
        lines += _native_lines(r, targets)
    if "campaign" in r:
        lines += _campaign_lines(r, targets)
    if "scaling" in r:
        lines += ["", "Scaling of run(): time per sample and peak memory growth",
                  f"  {'estimator':<11}{'N':>9}{'us/sample':>11}{'peak MB':>9}"
                  f"{'outputs MB':>12}{'excess MB':>11}"]
        for key, s in r["scaling"].items():
            for run in s["runs"]:
                lines.append(
                    f"  {key:<11}{run['n']:>9}{_fmt(run['us_per_sample']):>11}"
                    f"{run['peak_bytes'] / 1e6:>9.2f}{run['output_bytes'] / 1e6:>12.2f}"
                    f"{run['excess_bytes'] / 1e6:>11.2f}"
                )
            t = targets.get(f"scaling.{key}.flat")
            if t:
                lines.append(f"  {key:<11}memory growth beyond the outputs "
                             f"{_fmt(t['measured'], 2)} B per extra sample (target "
                             f"{t['target'].split('<= ')[1]}): {_verdict(t)}")
    if "estimate_2e6" in r:
        long = r["estimate_2e6"]
        each = all("pyarrow_read_s" in run for run in long["runs"].values())
        lines += ["", f"imu-fusion estimate, every estimator and the plot, on {long['rows']} "
                  f"rows ({long['file_mb']:.0f} MB of CSV); pyarrow reads it in "
                  f"{long['pyarrow_read_s']:.2f} s"
                  + (" at best, and again just before each run" if each else ""),
                  f"  {'format':<9}{'seconds':>9}{'read s':>8}{'x read':>8}{'peak MB':>9}"]
        for fmt, run in long["runs"].items():
            read = run.get("pyarrow_read_s", long["pyarrow_read_s"])
            lines.append(f"  {fmt:<9}{run['seconds']:>9.2f}{read:>8.2f}"
                         f"{run['vs_pyarrow_read']:>8.1f}{run['peak_mb']:>9.0f}  "
                         f"{_verdict(targets.get(f'estimate_2e6.{fmt}.vs_pyarrow_read'))}, "
                         f"{_verdict(targets.get(f'estimate_2e6.{fmt}.peak_mb'))}")
    missed = [t for t in r.get("targets", []) if t["met"] is False]
    if missed:
        lines += ["", "Targets not met, and what limits them:"]
        lines += [f"  {t['name']}: {_fmt(t['measured'])} (target {t['target']}): "
                  f"{t['limited_by']}" for t in missed]
    return "\n".join(lines)


def write_json(r: dict[str, Any], out_dir: Path) -> Path:
    """DIR/bench.json."""
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / "bench.json"
    path.write_text(json.dumps(r, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    return path


DOCS_JSON = Path(__file__).resolve().parents[1] / "docs" / "results" / "speed.json"
"""The full run docs/results/speed.md shows (its block `speed-bench` is format_table of it,
testbenches.docs_figures.speed_table, checked by tests/test_docs_figures.py)."""

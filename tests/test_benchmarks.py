"""The benchmark suite's code paths on tiny sizes (no timing is asserted), and the memory
behaviour of run() that its scaling section measures."""

from __future__ import annotations

import json
import subprocess
import sys
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import benchmarks.__main__ as cli
from benchmarks import BenchConfig, peers, report, scaling
from benchmarks.common import recording
from fusion_core import ComplementaryFilter
from fusion_core.registry import KEYS, keys_help

REPO = Path(__file__).resolve().parents[1]

TINY = dict(
    duration_s=0.5,
    repeats=1,
    testbench_s={100.0: 0.05, 1000.0: 0.01},
    testbench_repeats=1,
    testbench_estimators=("kf",),
    scaling_sizes=(300, 600),
    scaling_estimators=("cf",),
    campaign_seeds=4,  # 40 runs a campaign: the section's fields, not its figures
    campaign_passes=1,
    native_samples=2000,
    python_samples=200,
    long_rows=3000,
)


pytestmark = pytest.mark.xdist_group("bench")  # bench_json is made once, on one worker


@pytest.fixture(scope="module")
def bench_json(built_fmus, tmp_path_factory: pytest.TempPathFactory) -> dict:
    """`python -m benchmarks --quick` with the quick settings shrunk to TINY, through main()."""
    out = tmp_path_factory.mktemp("bench")
    original = BenchConfig.quick_config
    BenchConfig.quick_config = classmethod(  # type: ignore[method-assign]
        lambda cls, fmu_dir=None: cls(fmu_dir=fmu_dir, quick=True, **TINY))
    try:
        assert cli.main(["--quick", "--out", str(out), "--fmu-dir", str(built_fmus.directory)]) == 0
    finally:
        BenchConfig.quick_config = original  # type: ignore[method-assign]
    return json.loads((out / "bench.json").read_text())


def test_json_holds_every_section_of_the_issue(bench_json: dict) -> None:
    for key in ("per_sample_us", "fmu_step_us", "fmu_overhead_us", "testbench", "scaling",
                "machine", "repeats", "targets", "estimate_2e6"):
        assert key in bench_json, key
    assert bench_json["repeats"] == 1
    assert bench_json["machine"]["cpu_count"] >= 1


def test_the_long_file_is_timed_beside_pyarrows_read_in_every_format(bench_json: dict) -> None:
    long = bench_json["estimate_2e6"]
    assert long["rows"] == 3000 and long["pyarrow_read_s"] > 0
    assert set(long["runs"]) == {"csv", "parquet", "hdf5"}
    names = {t["name"] for t in bench_json["targets"]}
    for fmt, run in long["runs"].items():
        assert run["seconds"] > 0 and run["peak_mb"] > 0
        # each run beside a read timed just before it, on the machine as it then was
        assert run["vs_pyarrow_read"] == pytest.approx(run["seconds"] / run["pyarrow_read_s"])
        assert run["pyarrow_read_s"] >= long["pyarrow_read_s"]
        assert {f"estimate_2e6.{fmt}.vs_pyarrow_read", f"estimate_2e6.{fmt}.peak_mb"} <= names


def test_campaign_section_measures_both_worker_counts_or_says_why_not(bench_json: dict) -> None:
    c = bench_json["campaign"]
    if not c["available"]:
        assert c["reason"]
        return
    assert c["runs"] == 4 * len(KEYS) * 2  # seeds x estimators x scenarios
    assert c["samples_per_s"] > 0.0 and c["samples_per_s_1_worker"] > 0.0
    assert c["scaling"] == pytest.approx(c["samples_per_s"] / c["samples_per_s_1_worker"])
    names = {t["name"] for t in bench_json["targets"]}
    assert {"campaign.samples_per_s", "campaign.scaling"} <= names


def test_per_sample_has_every_estimator_and_every_peer_or_its_reason(bench_json: dict) -> None:
    ps = bench_json["per_sample_us"]
    assert set(ps) == {*KEYS, *peers.PEERS}
    assert all(ps[k] > 0.0 for k in KEYS)
    for name in peers.PEERS:
        assert (ps[name] is not None and ps[name] > 0.0) or name in bench_json["peers_unavailable"]


def test_the_stream_is_timed_per_estimator_where_the_twin_is(bench_json: dict) -> None:
    from fusion_core import native

    stream = bench_json["per_sample_us_stream"]
    assert set(stream) == set(KEYS)
    if not native.available():
        assert all(v is None for v in stream.values())
        return
    assert all(stream[k] > 0.0 for k in KEYS)
    if bench_json["per_sample_us"].get("vqf") is not None:
        names = {t["name"] for t in bench_json["targets"]}
        assert {f"per_sample_us_stream.{k} vs vqf" for k in KEYS} <= names


def test_the_stream_target_is_three_times_vqfs_update() -> None:
    results = {"per_sample_us": {"vqf": 0.5}, "per_sample_us_stream": {"cf": 1.4, "ukf": 1.6}}
    t = {x["name"]: x for x in report.evaluate_targets(results)}
    assert t["per_sample_us_stream.cf vs vqf"]["measured"] == pytest.approx(2.8)
    assert t["per_sample_us_stream.cf vs vqf"]["met"] is True
    assert t["per_sample_us_stream.ukf vs vqf"]["met"] is False


def test_each_twins_batch_has_its_ratio_to_vqfs_batch_as_a_target() -> None:
    from benchmarks.native import VQF_RATIO_TARGETS

    results = {"native": {"available": True, "vqf_batch_us_per_sample": 0.2,
                          "run_us_per_sample": {"kf": 0.16, "poskf": 0.32}}}
    t = {x["name"]: x for x in report.evaluate_targets(results)}
    assert VQF_RATIO_TARGETS["kf"] == 0.75 and VQF_RATIO_TARGETS["poskf"] == 1.5
    assert t["native.kf over vqf_batch"]["measured"] == pytest.approx(0.8)
    assert t["native.kf over vqf_batch"]["met"] is False
    assert t["native.poskf over vqf_batch"]["met"] is False
    results["native"]["run_us_per_sample"] = {"kf": 0.14, "poskf": 0.29}
    t = {x["name"]: x for x in report.evaluate_targets(results)}
    assert t["native.kf over vqf_batch"]["met"] and t["native.poskf over vqf_batch"]["met"]


def test_fmu_step_and_overhead_per_estimator(bench_json: dict) -> None:
    for key in KEYS:
        step = bench_json["fmu_step_us"][key]
        assert step > 0.0
        assert bench_json["fmu_overhead_us"][key] == pytest.approx(
            step - bench_json["fmu_core_us"][key])


def test_fmu_floor_is_timed_beside_every_estimator(bench_json: dict) -> None:
    """The floor FMU (FMI calls that return at once) is timed in turn with each estimator FMU,
    through both hosts."""
    for key in KEYS:
        detail = bench_json["fmu_step_detail"][key]
        for host in ("api", "lowlevel"):
            assert detail[f"floor_{host}"]["median_us"] > 0.0
            assert len(detail[f"floor_{host}"]["passes_us"]) == len(detail[host]["passes_us"])
            assert bench_json["fmu_floor_us"][key][host] == detail[f"floor_{host}"]["median_us"]


def test_testbench_at_100_hz_and_1_khz(bench_json: dict) -> None:
    for rate, hz in (("100Hz", 100.0), ("1000Hz", 1000.0)):
        x = bench_json["testbench"]["kf"][rate]
        assert x["steps_per_s"] > 0.0
        assert x["real_time_factor"] == pytest.approx(x["steps_per_s"] / hz)


def test_scaling_reports_time_and_memory_per_size(bench_json: dict) -> None:
    runs = bench_json["scaling"]["cf"]["runs"]
    assert [r["n"] for r in runs] == [300, 600]
    for r in runs:
        assert r["us_per_sample"] > 0.0
        assert r["output_bytes"] == r["n"] * (8 + 8 + 24 + 1)  # roll, pitch, bias, rejected
        assert r["peak_bytes"] >= 0


def test_every_target_is_judged_beside_its_measurement(bench_json: dict) -> None:
    names = {t["name"] for t in bench_json["targets"]}
    expected = {f"per_sample_us.{k}" for k in ("cf", "kf", "mgcf", "ukf", "poskf")}
    expected |= {f"fmu_overhead_us.{k}" for k in KEYS}
    expected |= {"testbench.kf.1000Hz.real_time_factor"}
    expected |= {"scaling.cf.flat"}
    assert expected <= names
    for t in bench_json["targets"]:
        assert isinstance(t["met"], bool)
        assert t["met"] or t["limited_by"], t["name"]


def test_ukf_target_needs_ten_times_filterpys_speed() -> None:
    results = {"per_sample_us": {"ukf": 20.0, "filterpy_ukf": 150.0}}
    t = {x["name"]: x for x in report.evaluate_targets(results)}
    assert t["per_sample_us.ukf"]["met"] is True
    assert t["per_sample_us.ukf vs filterpy_ukf"]["measured"] == pytest.approx(7.5)
    assert t["per_sample_us.ukf vs filterpy_ukf"]["met"] is False


def test_an_unavailable_peer_is_reported_with_its_reason(monkeypatch: pytest.MonkeyPatch) -> None:
    def missing(name: str, rec: dict) -> None:
        raise ImportError(f"No module named {name!r}")

    monkeypatch.setattr(peers, "peer_pass_factory", missing)
    timings, unavailable = peers.per_sample_peers(recording(0.1), 1, ("vqf",))
    assert timings == {}
    assert unavailable == {"vqf": "ImportError: No module named 'vqf'"}


def test_table_names_every_estimator_and_verdict(bench_json: dict) -> None:
    table = report.format_table(bench_json)
    for key in KEYS:
        assert f"\n  {key} " in table
    assert "met" in table


def test_flatness_tells_a_chunked_run_from_one_that_keeps_every_sample() -> None:
    def runs(excess_per_sample: float) -> list[dict]:
        return [{"n": n, "us_per_sample": 1.0, "output_bytes": 41 * n,
                 "excess_bytes": 2_000_000 + excess_per_sample * n} for n in (10_000, 100_000)]

    assert scaling.flatness(runs(0.0))["flat"] is True
    assert scaling.flatness(runs(500.0))["flat"] is False


def test_run_memory_beyond_the_outputs_does_not_grow_with_n(tmp_path: Path) -> None:
    rec = recording(10.0)

    def peak_beyond_outputs(n: int) -> int:
        idx = np.arange(n) % len(rec["dt"])
        acc, gyro, dt = rec["acc_meas"][idx], rec["gyro_meas"][idx], rec["dt"][idx]
        tracemalloc.start()
        try:
            out = ComplementaryFilter().run(acc, gyro, dt)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
        return peak - sum(v.nbytes for v in out.values())

    small, large = peak_beyond_outputs(2_000), peak_beyond_outputs(8_000)
    # Keeping one Python object per sample grows by about 12 times the extra outputs' bytes.
    assert large - small < 0.25 * 41 * 6_000


def test_the_benchmarks_list_the_registrys_estimators() -> None:
    from benchmarks.config import BenchConfig, estimator_keys

    assert estimator_keys(BenchConfig().scaling_estimators) == KEYS
    assert estimator_keys(("kf",)) == ("kf",)


def test_the_command_line_chooses_its_core_before_fusion_core_is_imported() -> None:
    """Importing the benchmarks package and its command line imports no fusion_core module (the
    suite imports it when it runs)."""
    code = ("import sys, benchmarks, benchmarks.__main__; "
            "print([m for m in sys.modules if m.split('.')[0] == 'fusion_core'])")
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                          text=True, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == "[]"


def test_bench_json_says_which_core_ran(bench_json: dict) -> None:
    """step() is the Python reference; run() and the FMUs' steps go through the C twin where it
    is loaded, which bench.json says."""
    from fusion_core import native

    assert bench_json["core"]["kind"] == "python"
    assert bench_json["core"]["native"] == native.available()


def test_batch_loop_runs_one_estimators_batch_for_a_profiler(
    capsys: pytest.CaptureFixture[str]
) -> None:
    from benchmarks import batch_loop
    from fusion_core import native

    if not native.available():
        pytest.skip(f"the C twin is not available: {native.reason()}")
    assert batch_loop.main(["kf", "--samples", "500", "--repeat", "2"]) == 0
    assert capsys.readouterr().out.startswith("kf: ")
    with pytest.raises(SystemExit):
        batch_loop.main(["no_such_filter"])
    assert f"allowed {keys_help()}" in capsys.readouterr().err


def test_batch_ratio_refuses_what_it_cannot_run() -> None:
    from benchmarks import batch_ratio

    with pytest.raises(SystemExit):
        batch_ratio.main(["--estimator", "nope"])
    with pytest.raises(SystemExit):
        batch_ratio.main(["--rounds", "0"])
    assert set(batch_ratio.VQF_RATIO_TARGETS) <= set(KEYS)


def test_batch_ratio_prints_each_twins_median_beside_its_target(
        capsys: pytest.CaptureFixture[str]) -> None:
    from benchmarks import batch_ratio
    from fusion_core import native

    pytest.importorskip("vqf", reason="the peer VQF is in the bench extra")
    if not native.available():
        pytest.skip(f"no C twin: {native.reason()}")
    assert batch_ratio.main(["--rounds", "1", "--repeats", "1", "--estimator", "cf,kf"]) == 0
    out = capsys.readouterr().out
    for key in ("cf", "kf"):
        line = next(ln for ln in out.splitlines() if ln.startswith(key + " "))
        assert "0.75x" in line and ("met" in line), line  # no timing asserted: the format only

"""`make embedded`: the C twin on a Cortex-M under QEMU gives the desktop's outputs (double) or
stays close to them (float), and the command says what to install where the tools are missing."""

from __future__ import annotations

import json
import shutil

import pytest

from testbenches.embedded import build, cli

TOOLS = build.missing_tools()


def test_missing_tools_are_named_with_their_packages(monkeypatch, capsys, tmp_path) -> None:
    monkeypatch.setattr(shutil, "which", lambda name: None)
    assert cli.main(out=tmp_path) == 0
    said = capsys.readouterr().out
    assert "arm-none-eabi-gcc" in said and build.PACKAGES in said
    assert not (tmp_path / "report.json").exists()


@pytest.mark.heavy
@pytest.mark.skipif(bool(TOOLS), reason=f"not installed: {', '.join(TOOLS)} "
                    f"(apt-get install {build.PACKAGES})")
def test_the_twins_on_a_microcontroller(tmp_path, capsys) -> None:
    assert cli.main(out=tmp_path) == 0
    report = json.loads((tmp_path / "report.json").read_text())
    double, single = report["cortex-m7-double"], report["cortex-m4f-float"]
    for key in build.ESTIMATORS:
        # newlib's libm against glibc's is the only difference a double build may have
        assert double["estimators"][key]["max_abs_diff"] <= 1e-12, key
        assert single["estimators"][key]["max_abs_diff"] <= 1e-3, key
        for r in (double, single):
            e = r["estimators"][key]
            assert 500 < e["insns_per_sample"] < 20000 and e["ram_bytes"] > 0
            assert e["flash_bytes"] > 1000
    assert set(double["libm"]) == set(build.LIBM)
    for name in ("exp", "log", "sqrt"):  # correctly rounded in both libraries here
        assert double["libm"][name]["differing"] == 0, name
    long_run = report["float_accuracy"]["long_run"]
    assert all(v["finite"] and v["last_tenth_max_diff_deg"] < 0.05 for v in long_run.values())
    assert "largest roll error after 5 s" in capsys.readouterr().out

"""The documentation: the site builds with warnings as errors, the README stays a page, and no
product file or page depends on the folder our CI keeps beside the project; commands the
pages give are the code's."""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PRODUCT = ("fusion_core", "fmu_src", "testbenches", "benchmarks", "docs", "examples")


@pytest.mark.heavy
@pytest.mark.skipif(importlib.util.find_spec("mkdocs") is None,
                    reason="mkdocs is not installed (the docs extra, which the test extra has)")
def test_the_site_builds_strict(tmp_path: Path) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path)],
        cwd=REPO, capture_output=True, text=True, check=False,
        env=os.environ | {"NO_MKDOCS_2_WARNING": "1"},
    )
    assert proc.returncode == 0, proc.stderr[-4000:]
    for page in ("index.html", "estimators/ukf/index.html", "interface/index.html"):
        assert (tmp_path / page).is_file(), page
    ukf = (tmp_path / "estimators/ukf/index.html").read_text()
    assert "bias_psd" in ukf and "PaperUnscentedKalmanFilter" in ukf  # the tables were made
    assert "gyro_range" not in ukf.split("The recommended filter")[0]  # the filter's own only
    shared = (tmp_path / "estimators/index.html").read_text()
    assert "gyro_range" in shared and "sensor_delay" in shared  # the input stage's, once
    home = (tmp_path / "index.html").read_text()
    assert 'id="quickstart"' in home and 'href="results/broad/"' in home  # the README, relinked


def test_the_home_page_is_the_readme_with_its_links_into_docs_relative() -> None:
    spec = importlib.util.spec_from_file_location("readme_hook", REPO / "docs/_hooks/readme.py")
    assert spec is not None and spec.loader is not None
    hook = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(hook)
    assert (REPO / "docs/index.md").read_text().strip() == hook.MARK
    page = hook.on_page_markdown(hook.MARK)
    readme = (REPO / "README.md").read_text()
    assert page == hook.readme_for_site(readme) and "## Quickstart" in page
    assert "](docs/" not in page and "](CHANGELOG.md)" not in page


def test_the_readme_is_a_page() -> None:
    lines = (REPO / "README.md").read_text().splitlines()
    assert len(lines) <= 250, len(lines)
    for heading in ("## Quickstart", "## Install", "## The estimators and FMUs", "## Read on"):
        assert heading in lines, heading


def test_no_product_file_points_at_the_ci_folder_beside_the_project() -> None:
    hits = []
    for top in (*PRODUCT, "README.md", "Makefile", "pyproject.toml", "mkdocs.yml", "setup.py"):
        paths = [REPO / top] if (REPO / top).is_file() else (REPO / top).rglob("*")
        for path in paths:
            if path.suffix in (".py", ".md", ".c", ".h", ".toml", ".yml", "") and path.is_file():
                text = path.read_text(errors="replace")
                if "../shared" in text or "shared/INTERFACE" in text:
                    hits.append(str(path.relative_to(REPO)))
    assert hits == []


def test_the_readmes_python_runs_as_written() -> None:
    """The README's Python block, executed: every name it uses exists and it computes what its
    comments say (a sensor at rest rolled 10 deg)."""
    text = (REPO / "README.md").read_text()
    block = text.split("```python\n", 1)[1].split("```", 1)[0]
    scope: dict[str, object] = {}
    exec(compile(block, "README.md", "exec"), scope)
    import numpy as np

    assert abs(np.degrees(scope["out"]["roll"][-1]) - 10.0) < 0.1  # type: ignore[index]
    assert scope["est"].roll == 0.0  # type: ignore[attr-defined]


def test_the_command_line_says_its_version_and_lists_each_command_once() -> None:
    from testbenches.cli import _parser, _version

    parser = _parser("imu-fusion")
    text = parser.format_help()
    assert text.count("estimate  ") == 1 and "--version" in text
    assert _version() != "(not installed)"


def test_a_named_command_imports_its_own_module_only() -> None:
    """testbenches.cli.COMMANDS is every command of the full parser, and the command line of
    one command builds that command's parser without importing the others'."""
    import argparse

    from testbenches.cli import COMMANDS, _parser

    full = _parser("imu-fusion")
    sub = next(a for a in full._actions if isinstance(a, argparse._SubParsersAction))
    assert list(sub.choices) == list(COMMANDS)
    code = ("import sys; from testbenches.cli import _parser; "
            "p = _parser('imu-fusion', 'estimate'); "
            "print(sorted(m for m in ('testbenches.run_cli', 'testbenches.broad.cli', "
            "'testbenches.docs_figures', 'fmu_src.cli') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                          text=True, check=True)
    assert proc.stdout.strip() == "[]", proc.stdout


def _by_hand_commands(text: str) -> list[list[str]]:
    """The `cc ... libfusion_core.so ...` commands in a text, continuation lines joined, split
    into words."""
    joined = re.sub(r"\\\\?\n\s*", " ", text)
    return [line.split() for line in re.findall(r"cc -std=c99[^\n`]*libfusion_core\.so[^\n`]*",
                                                 joined)]


def test_the_c_twins_by_hand_command_has_the_librarys_flags() -> None:
    """The guide's and the module's one command for the library by hand compiles as the cached
    build does (fusion_core.native.CFLAGS): where the flags change, so must they."""
    from fusion_core.native import CFLAGS

    for path in (REPO / "docs" / "guide" / "backends.md",
                 REPO / "fusion_core" / "native" / "__init__.py"):
        commands = _by_hand_commands(path.read_text())
        assert commands, f"{path}: no by-hand command found"
        for words in commands:
            assert tuple(words[1:1 + len(CFLAGS)]) == CFLAGS, (path, words)

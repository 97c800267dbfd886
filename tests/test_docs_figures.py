"""Documentation that cannot go stale: every generated figure, table and picture of the README
and the docs matches what its command gives (testbenches.docs_figures), and a figure changed
on purpose is caught."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from testbenches import docs_figures as figs

REPO = Path(__file__).resolve().parents[1]
BY_NAME = {f.name: f for f in figs.FIGURES}
WHERE = {"checkout": "the project's source checkout (benchmarks/)",
         "imucal": "imucal's session beside the project in ../shared/data/imucal",
         "engines": "libcosimpy and ecospy (pip install '.[engines]'; apt-get install libtbb12)",
         "vqf": "the peers (pip install -e '.[bench]')",
         "broad": "BROAD's trials beside the project in ../shared/data/broad",
         "imucal-package": "imucal (pip install -e '.[bench]')",
         "embedded": "arm-none-eabi-gcc and qemu-system-arm (apt-get install gcc-arm-none-eabi "
                     "libnewlib-arm-none-eabi qemu-system-arm)"}


def _context(figure: figs.Figure, request: pytest.FixtureRequest) -> dict[str, Path]:
    ctx = figs.context(imucal=None)
    ctx.pop("fmus", None)  # the FMUs of this checkout, built for the session, never dist/'s
    if "fmus" in figure.needs:
        built = request.getfixturevalue("built_fmus")
        built.native("fmi3", "AngleBiasKalmanFilter")
        ctx["fmus"] = built.directory
    lacking = figs.missing(figure, ctx)
    if lacking:
        pytest.skip(f"{figure.name} needs {', '.join(lacking)}: " + "; ".join(
            WHERE[n] for n in lacking))
    return ctx


HEAVY = ("engines-table", "contract-parts", "readme-contract", "embedded-table",
         "campaigns-scenarios", "broad-scale-parts", "readme-battery", "broad-gyro",
         "broad-noise", "contract-vqf", "uncalibrated-rest", "uncalibrated-moving",
         "calibrate-picture", "calibrate-imucal", "imucal-table", "budget-excerpt",
         *(f.name for f in figs.FIGURES if f.name.startswith("battery-")))
"""Figures whose command runs for tens of seconds (`make test-fast` leaves them out)."""
SLOW = ("calibrated-parts", "readme-calibrated-part", "campaigns-parts", "campaigns-makefile",
        "readme-broad", "mechanisms-table", "broad-groups", "broad-cv", "readme-battery",
        *(f.name for f in figs.FIGURES if f.name.startswith("battery-")
          and f.name != "battery-classes"))
"""Figures of 200 parts calibrated first, `make campaign`'s 17,500 runs, BROAD's trials, the
battery's campaign (every motion class x sensor class x 20 parts) or the battery ten times:
minutes (`make test-slow`)."""


SHARED_RUNS = {
    "battery": ("readme-battery", *(f.name for f in figs.FIGURES
                                    if f.name.startswith("battery-"))),
    "contract-parts": ("readme-contract", "contract-parts", "campaigns-scenarios"),
    "embedded": ("embedded-table",),
    "engines": ("engines-table",),
}
"""Figures made from runs their process keeps (docs_figures' cached battery, the parts' runs
of testbenches.parts, the embedded report of testbenches.embedded.cli, the engines' runs of
testbenches.engines), each set on one worker
(`--dist loadgroup`, with the tests of the same group) so that the runs are made once."""


def _marks(name: str) -> list[pytest.MarkDecorator]:
    marks = [pytest.mark.heavy] if name in HEAVY else []
    marks += [pytest.mark.slow] if name in SLOW else []
    marks += [pytest.mark.xdist_group(group) for group, names in SHARED_RUNS.items()
              if name in names]
    if "fmus" in BY_NAME[name].needs:  # built for the session: `make test-fast` leaves it out
        marks.append(pytest.mark.fmu)
    return marks


@pytest.mark.parametrize("name", [pytest.param(n, marks=_marks(n)) for n in BY_NAME])
def test_every_generated_figure_matches_its_command(name: str, request) -> None:
    figure = BY_NAME[name]
    problem = figs.check(figure, _context(figure, request))
    assert problem is None, f"{problem}; make it again with: imu-fusion docs --write {name}"


def test_every_page_mark_is_a_registered_figure_and_every_figure_is_shown() -> None:
    marks = set()
    for page in [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]:
        text = page.read_text(encoding="utf-8")
        marks |= set(re.findall(r"<!-- generated: ([\w-]+) -->", text))
    assert marks == {f.name for f in figs.FIGURES if f.picture is None}
    for figure in figs.FIGURES:
        if figure.picture is not None:
            shown = Path(figure.picture).name
            assert shown in (REPO / figure.page).read_text(encoding="utf-8"), figure.name


def test_a_block_changed_on_purpose_is_caught(tmp_path: Path) -> None:
    figure = BY_NAME["estimate-example"]
    page = tmp_path / figure.page
    page.parent.mkdir(parents=True)
    text = (REPO / figure.page).read_text(encoding="utf-8")
    page.write_text(text.replace("0.5996", "0.5997", 1), encoding="utf-8")
    problem = figs.check(figure, {}, root=tmp_path)
    assert problem is not None and "block estimate-example: differs" in problem
    assert "(page: '7  reports" in problem and "command: '6  reports" in problem


def test_a_picture_changed_on_purpose_is_caught(tmp_path: Path) -> None:
    """The estimate plot as the page shows it matches; drawn with two estimators fewer, it no
    longer does."""
    figure = BY_NAME["estimate-picture"]
    shown = tmp_path / figure.picture
    shown.parent.mkdir(parents=True)
    shutil.copy(REPO / figure.picture, shown)
    assert figs.check(figure, {}, root=tmp_path) is None
    out = tmp_path / "fewer"
    figs._captured([*figs.ESTIMATE_ARGS, "--estimator", "cf,kf,ukf", "--out", str(out)], REPO)
    shutil.copy(out / "tilt_motion.png", shown)
    problem = figs.check(figure, {}, root=tmp_path)
    assert problem is not None and "of its pixels differ" in problem


MEASURED = re.compile(r"\d+\.\d+/\d+\.\d+\s*deg(?!/)|\d+\.\d+\s*->\s*\d+\.\d+\s*deg(?!/)"
                      r"|\d\.\d{3,}\s*deg(?!/)")
"""What a measured accuracy looks like in prose: a roll/pitch pair in deg, a before -> after in
deg, a figure in deg to a thousandth. Such a figure belongs in a generated block."""


def _prose(text: str) -> str:
    """A page without its generated blocks and code blocks (blank lines in their place)."""
    blank = lambda m: "\n" * m.group(0).count("\n")  # noqa: E731
    text = re.sub(r"<!-- generated: ([\w-]+) -->.*?<!-- end generated: \1 -->", blank, text,
                  flags=re.S)
    return re.sub(r"```.*?```", blank, text, flags=re.S)


def test_no_page_quotes_a_measured_accuracy_outside_a_generated_block() -> None:
    """A measured figure typed into prose goes stale with the next change of a default; the
    pages refer to their generated tables instead."""
    found = []
    for page in [REPO / "README.md", *sorted((REPO / "docs").rglob("*.md"))]:
        for number, line in enumerate(_prose(page.read_text(encoding="utf-8")).splitlines(), 1):
            if MEASURED.search(line):
                found.append(f"{page.relative_to(REPO)}:{number}: {line.strip()}")
    assert not found, "measured figures in prose:\n" + "\n".join(found)


def test_the_prose_check_sees_a_typed_figure() -> None:
    page = ("kf 0.17/0.28 deg against 0.17/0.24\n<!-- generated: x -->\n0.50/0.40 deg\n"
            "<!-- end generated: x -->\nfrom 0.507 to 0.524 deg, 1.33 -> 0.40 deg, 0.005 deg/s\n")
    hits = [line for line in _prose(page).splitlines() if MEASURED.search(line)]
    assert hits == ["kf 0.17/0.28 deg against 0.17/0.24",
                    "from 0.507 to 0.524 deg, 1.33 -> 0.40 deg, 0.005 deg/s"]

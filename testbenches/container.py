"""An exported SSP as one FMU: fmu-manipulation-toolbox's fmucontainer around plant, sensor and
estimator, which any FMI 2.0 or 3.0 host (fmpy, a Modelica tool, Simulink) runs as one block.

`container_from_ssp` builds it with the toolbox's own Assembly from the SSP testbenches.ssp
writes. Its SSP reader (alpha in fmu-manipulation-toolbox 2.0) reads the components and their
connections but neither parameter bindings nor outputs that are not wired to the system, so
what the SSP binds becomes the container's start values here, and the estimator's outputs (and
the plant's truth, as true_*) its outputs. A sequential container steps the FMUs in the
chain's order on each other's newest outputs (Gauss-Seidel); a parallel one steps every FMU on
the others' outputs of the previous step (Jacobi, master.CHAIN_DELAY).
"""

from __future__ import annotations

import logging
import shutil
import tempfile
import zipfile
from pathlib import Path

from fmpy import read_model_description
from fmpy.ssp.ssd import read_ssv

from fusion_core.synthetic import TRUTH_NAMES

COMPONENTS = ("plant", "sensor", "estimator")


def container_from_ssp(ssp: Path | str, out: Path | str, *, sequential: bool,
                       step: float = 0.01, fmi: int = 2) -> Path:
    """Build the FMU `out` (FMI `fmi`) from an exported SSP: sequential (Gauss-Seidel) or
    parallel (Jacobi) stepping at `step` seconds, the SSP's parameters as start values, the
    estimator's outputs and the plant's truth (true_<name>) as outputs."""
    ssp, out = Path(ssp), Path(out)
    # its log says at INFO and WARNING what this function does on purpose (every output of
    # plant and sensor left unexposed); errors still show
    toolbox_log = logging.getLogger("fmu_manipulation_toolbox")
    level = toolbox_log.level
    toolbox_log.setLevel(logging.ERROR)
    try:
        return _build(ssp, out, sequential, step, fmi)
    finally:
        toolbox_log.setLevel(level)


def _build(ssp: Path, out: Path, sequential: bool, step: float, fmi: int) -> Path:
    from fmu_manipulation_toolbox.assembly import Assembly

    with tempfile.TemporaryDirectory(prefix="container_") as tmp:
        work = Path(tmp)
        # the container's model identifier is its file's stem: out's, so that two containers
        # loaded in one process do not share a library name
        shutil.copy(ssp, work / f"{out.stem}.ssp")
        assembly = Assembly(f"{out.stem}.ssp", fmu_directory=work, default_step_size=step,
                            default_sequential=sequential)
        root = assembly.root
        root.sequential = sequential
        root.step_size = step
        embedded = _embedded(ssp, root.fmu_names_list)
        for component in COMPONENTS:
            for p in _parameters(ssp, component):
                value = str(p.value).lower() if isinstance(p.value, bool) else str(p.value)
                root.add_start_value(embedded[component], p.name, value)
        # the sensor's inputs hold at a step's end where the container steps in order
        root.add_start_value(embedded["sensor"], "inputs_at", "1" if sequential else "2")
        with zipfile.ZipFile(ssp) as z:
            source = _sources(z)["estimator"]
            with z.open(source) as f, tempfile.NamedTemporaryFile(suffix=".fmu") as copy:
                copy.write(f.read())
                copy.flush()
                md = read_model_description(copy.name)
        for v in md.modelVariables:
            if v.causality == "output":
                root.add_output(embedded["estimator"], v.name, v.name)
        for name in TRUTH_NAMES:
            root.add_output(embedded["plant"], name, f"true_{name}")
        assembly.make_fmu(fmi_version=fmi, filename=f"{out.stem}.fmu")
        out.parent.mkdir(parents=True, exist_ok=True)
        shutil.move(work / f"{out.stem}.fmu", out)
    return out


def _sources(z: zipfile.ZipFile) -> dict[str, str]:
    """Each component's FMU inside the SSP (its resources/ entry), read off the .ssd."""
    import xml.etree.ElementTree as ET

    ns = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription"}
    root = ET.fromstring(z.read("SystemStructure.ssd"))
    return {c.get("name", ""): c.get("source", "")
            for c in root.iterfind(".//ssd:Component", ns)}


def _embedded(ssp: Path, names: list[str]) -> dict[str, str]:
    """The Assembly's name of each component's FMU (its file name under the extract folder)."""
    with zipfile.ZipFile(ssp) as z:
        sources = _sources(z)
    by_file = {Path(n).name: n for n in names}
    return {c: by_file[Path(s).name] for c, s in sources.items()}


def _parameters(ssp: Path, component: str) -> list:
    try:
        return list(read_ssv(str(ssp), resource=f"resources/{component}.ssv").parameters)
    except KeyError:
        return []

"""The project's FMUs by name. Every estimator of fusion_core.registry is one FMU, named after
its recommended class, whose slave module is generated from its registry entry
(`estimator_script`); the testbench's plant and sensor are the modules
fmu_src/models/<snake_name>_fmu.py, their model names the CamelCase of <snake_name>. Both
builders (fmu_src/build.py, fmu_src/native/build.py) find their models here."""

from __future__ import annotations

from pathlib import Path

MODELS_DIR = Path(__file__).resolve().parent / "models"
"""The testbench's FMUs (plant, sensor): one slave module each."""


def estimator_fmus() -> dict[str, str]:
    """FMU model name -> estimator key, for every estimator of the registry."""
    from fusion_core.registry import FMU_NAMES

    return {name: key for key, name in FMU_NAMES.items()}


def model_names() -> list[str]:
    """Every FMU of the project, by model name."""
    testbench = (_camel(p.name[: -len("_fmu.py")]) for p in MODELS_DIR.glob("*_fmu.py"))
    return sorted({*estimator_fmus(), *testbench})


def _camel(snake: str) -> str:
    return "".join(part.capitalize() for part in snake.split("_"))


def _snake(camel: str) -> str:
    return "".join("_" + c.lower() if c.isupper() else c for c in camel).lstrip("_")


def script_name(name: str) -> str:
    """The slave module's file name of the FMU called name: <snake_name>_fmu.py, a top-level
    module name unique among the FMUs of a process."""
    return f"{_snake(name)}_fmu.py"


def estimator_script(name: str) -> str:
    """The slave module of an estimator FMU, generated from its registry entry: a subclass of
    fmu_src.estimator.EstimatorSlave naming the key and the entry's text."""
    from fusion_core.registry import ENTRY

    entry = ENTRY[estimator_fmus()[name]]
    return (f'"""{name} FMU: the estimator {entry.key!r} of fusion_core.registry ({entry.title}) '
            "as a co-simulation FMU.\n\nGenerated from its registry entry by "
            'fmu_src.names.estimator_script."""\n\n'
            "from fmu_src.estimator import EstimatorSlave\n\n\n"
            f"class {name}(EstimatorSlave):\n"
            f"    key = {entry.key!r}\n"
            f"    description = {entry.fmu_text!r}\n")


def write_script(name: str, folder: Path) -> Path:
    """The slave module of the FMU called name, written into folder: generated for an
    estimator, copied for the plant and the sensor. ValueError for an unknown name."""
    target = folder / script_name(name)
    if name in estimator_fmus():
        target.write_text(estimator_script(name))
        return target
    source = MODELS_DIR / script_name(name)
    if not source.is_file():
        raise ValueError(f"no FMU called {name!r}: the FMUs are {', '.join(model_names())}")
    target.write_text(source.read_text())
    return target


PRESET_FILE = "preset.json"
"""The preset an FMU was built with, in its resources folder."""

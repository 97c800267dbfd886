"""The project's FMUs by name: every module fmu_src/models/<snake_name>_fmu.py is one model, its
model name the CamelCase of <snake_name>. Both builders (fmu_src/build.py, fmu_src/native/build.py)
find their models here."""

from __future__ import annotations

from pathlib import Path

MODELS_DIR = Path(__file__).resolve().parent / "models"


def model_names() -> list[str]:
    """Every FMU of the project, by model name."""
    return sorted(_camel(p.name[: -len("_fmu.py")]) for p in MODELS_DIR.glob("*_fmu.py"))


def _camel(snake: str) -> str:
    return "".join(part.capitalize() for part in snake.split("_"))


def _snake(camel: str) -> str:
    return "".join("_" + c.lower() if c.isupper() else c for c in camel).lstrip("_")


def script_path(name: str) -> Path:
    """The slave module of the FMU called name."""
    path = MODELS_DIR / f"{_snake(name)}_fmu.py"
    if not path.is_file():
        raise ValueError(f"no FMU called {name!r}: the FMUs are {', '.join(model_names())}")
    return path


PRESET_FILE = "preset.json"
"""The preset an FMU was built with, in its resources folder."""

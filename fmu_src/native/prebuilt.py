"""Native FMUs built when the wheel was: what `build-fmus --kind native` copies where no C
compiler exists.

A wheel built where a compiler exists (setup.py) holds, beside the C twin's library, every
model's native FMU for FMI 2.0 and 3.0 with the recommended and the paper presets, under
`prebuilt/<preset>/<version>/<Model>.fmu` in this folder. They are the FMUs `build_native` makes
from the same sources: a user without a compiler gets the same files. A JSON preset's start
values are compiled into the binary, so it needs a compiler.
"""

from __future__ import annotations

import shutil
from collections.abc import Iterator
from pathlib import Path

HERE = Path(__file__).resolve().parent
FOLDER = "prebuilt"
PRESETS = ("recommended", "paper")
"""The presets the wheel carries FMUs for (fusion_core.presets' named ones)."""


def prebuilt_fmu(name: str, version: str, preset: str) -> Path | None:
    """The wheel's FMU of model name for version ("fmi2", "fmi3") and preset, if it has one."""
    path = HERE / FOLDER / preset / version / f"{name}.fmu"
    return path if path.is_file() else None


def copy_prebuilt(name: str, version: str, preset: str, out_dir: Path) -> Path:
    """Copy the wheel's FMU to out_dir/<version>/<name>.fmu (as build_native writes it);
    RuntimeError saying what would build it where there is none."""
    source = prebuilt_fmu(name, version, preset)
    if source is None:
        why = (f"the wheel carries native FMUs for the presets {' and '.join(PRESETS)} only: a "
               "JSON preset's start values are compiled into the binary"
               if preset not in PRESETS else "this installation carries no prebuilt FMUs")
        raise RuntimeError(f"no C compiler found and {why}; install cc, gcc or clang (or set CC)")
    target = out_dir / version / f"{name}.fmu"
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(source, target)
    return target


def build_into(build_lib: Path) -> Iterator[str]:
    """Compile the C twin's library and every native FMU into a wheel's build folder; one line
    per artefact. RuntimeError where no compiler exists (setup.py then builds a pure wheel)."""
    from fusion_core import native
    from fusion_core.presets import load_preset

    from ..names import model_names
    from .build import VERSIONS, build_native, native_model

    if native.compiler() is None:
        raise RuntimeError("no C compiler found")
    library = build_lib / "fusion_core" / "native" / native.PREBUILT.name
    library.parent.mkdir(parents=True, exist_ok=True)
    shutil.copy2(native.build(), library)
    yield f"compiled {library.relative_to(build_lib)}"
    from fusion_core.native.library import write_declarations

    declared = write_declarations(library.parent)  # loaded without parsing the headers
    yield f"declared {declared.relative_to(build_lib)}"
    from fusion_core.native.library import STREAM_PREBUILT, build_stream

    try:  # stream()'s compiled entry point needs the Python headers too
        stream = library.parent / STREAM_PREBUILT.name
        shutil.copy2(build_stream(), stream)
        yield f"compiled {stream.relative_to(build_lib)}"
    except RuntimeError as err:
        yield f"no compiled entry point for stream(): {err}"
    for preset in PRESETS:
        entries = load_preset(preset)
        out = build_lib / "fmu_src" / "native" / FOLDER / preset
        for version in VERSIONS:
            for name in model_names():
                path = build_native(native_model(name, entries), version, out, windows=False)
                yield f"built {path.relative_to(build_lib)}"

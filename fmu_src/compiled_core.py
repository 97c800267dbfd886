"""The compiled fusion_core: the same Python sources, compiled to C extension modules by mypyc.

fusion_core is plain, typed Python (mypy-clean). mypyc (the compiler that ships with mypy and
compiles mypy itself and black) turns its estimator modules into C extensions in which the
floats of the hot paths are C doubles. The math stays in one place, the Python source; the
compiled modules compute the same IEEE operations in the same order, so their outputs are bit
for bit those of the pure-Python modules (tests/test_compiled_core.py checks it), at 3-7x the
speed (`make bench`).

Each FMU ships both: resources/fusion_core holds the .py sources and, beside them, the extension
modules built for the builder's CPython (their file names carry its ABI tag, for example
`.cpython-311-x86_64-linux-gnu.so`), plus mypyc's shared runtime module at the top of
resources/. Python prefers an extension module to a source file of the same name, so a host
with the same CPython runs the compiled core, and any other host ignores the .so files and runs
the pure-Python one.

The build takes about 40 s on two cores and is cached under build/compiled_core/<key>, the key
being a hash of the sources, the mypy version and the ABI tag.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import shutil
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path
from types import ModuleType

REPO = Path(__file__).resolve().parents[1]
DEFAULT_CACHE = REPO / "build" / "compiled_core"
COMPILED_MODULES = (
    "types", "kinematics", "base", "building_blocks", "complementary", "kalman", "mgcf", "ukf",
    "position",
)
"""The fusion_core modules that mypyc compiles: the estimators and what their hot paths call.
The rest (presets, scenarios, the sensor model, the synthetic recordings) stays Python."""
EXT_SUFFIX = sysconfig.get_config_var("EXT_SUFFIX") or ".so"
CORES = ("auto", "compiled", "python")
"""--core choices of the FMU build and the benchmarks: auto = compiled when it can be built."""


class CompiledCoreError(RuntimeError):
    """The compiled core could not be built here (no mypyc, no C compiler, a mypyc error)."""


def toolchain_missing() -> str | None:
    """Why the compiled core cannot be built here (no C compiler, no Python headers, no mypyc),
    or None when it can be tried."""
    cc = os.environ.get("CC") or sysconfig.get_config_var("CC") or "cc"
    if shutil.which(cc.split()[0]) is None:
        return f"no C compiler ({cc.split()[0]!r} not found)"
    include = Path(sysconfig.get_paths()["include"])
    if not (include / "Python.h").is_file():
        return f"no Python headers ({include / 'Python.h'} not found)"
    if importlib.util.find_spec("mypyc") is None:
        return "mypyc is not installed (it comes with mypy: pip install 'mypy>=1.11')"
    return None


def fusion_core_dir() -> Path:
    """The fusion_core package the build compiles (the importable one, without importing it)."""
    spec = importlib.util.find_spec("fusion_core")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError("fusion_core is not importable: run from the repository root")
    return Path(next(iter(spec.submodule_search_locations)))


def cache_key(core: Path) -> str:
    """A hash of the fusion_core sources, the modules compiled, the compiler version and the
    interpreter's ABI tag (call it once toolchain_missing() has found mypyc)."""
    from mypy.version import __version__ as mypy_version

    modules = ",".join(COMPILED_MODULES)
    digest = hashlib.sha256(f"{mypy_version}|{EXT_SUFFIX}|{sys.version}|{modules}".encode())
    for path in sorted(core.glob("*.py")):
        digest.update(path.name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def build_compiled_core(cache: Path = DEFAULT_CACHE) -> Path:
    """The folder of a compiled fusion_core, built unless cached: it holds fusion_core/ (every
    .py source plus the extension modules of COMPILED_MODULES) and mypyc's shared runtime module.
    Put it first on sys.path to import the compiled core. Raises CompiledCoreError saying why it
    cannot be built."""
    missing = toolchain_missing()
    if missing:
        raise CompiledCoreError(missing)
    core = fusion_core_dir()
    target = cache / cache_key(core)
    if (target / "COMPLETE").is_file():
        return target
    cache.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix="compile_", dir=cache))
    try:
        shutil.copytree(core, work / "fusion_core", ignore=shutil.ignore_patterns("__pycache__"))
        sources = [f"fusion_core/{name}.py" for name in COMPILED_MODULES]
        env = {**os.environ, "MYPYC_OPT_LEVEL": "3", "MYPYC_DEBUG_LEVEL": "0"}
        proc = subprocess.run(
            [sys.executable, "-m", "mypyc", *sources], cwd=work, env=env,
            capture_output=True, text=True, check=False,
        )
        if proc.returncode != 0:
            tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-15:])
            raise CompiledCoreError(f"mypyc failed (exit {proc.returncode}):\n{tail}")
        for name in COMPILED_MODULES:
            if not (work / "fusion_core" / f"{name}{EXT_SUFFIX}").is_file():
                raise CompiledCoreError(f"mypyc did not produce fusion_core/{name}{EXT_SUFFIX}")
        shutil.rmtree(work / "build", ignore_errors=True)
        shutil.rmtree(work / ".mypy_cache", ignore_errors=True)
        (work / "COMPLETE").write_text("".join(f"{p.name}\n" for p in shipped_files(work)))
        try:
            work.rename(target)
        except OSError:  # another process finished the same build first: use that one
            if not (target / "COMPLETE").is_file():
                raise
    finally:
        shutil.rmtree(work, ignore_errors=True)
    _prune(cache, keep=target)
    return target


def _prune(cache: Path, keep: Path, n: int = 3) -> None:
    """Remove all but the n newest builds of the cache (each source change makes a new one)."""
    builds = sorted((d for d in cache.iterdir() if (d / "COMPLETE").is_file()),
                    key=lambda d: d.stat().st_mtime, reverse=True)
    for old in builds[n:]:
        if old != keep:
            shutil.rmtree(old, ignore_errors=True)


def shipped_files(root: Path) -> list[Path]:
    """The top-level entries of a compiled-core folder that an FMU's resources/ receives:
    fusion_core/ and mypyc's shared runtime module(s)."""
    return [root / "fusion_core", *sorted(root.glob(f"*__mypyc{EXT_SUFFIX}"))]


def resolve_core(core: str, cache: Path = DEFAULT_CACHE) -> Path | None:
    """The compiled-core folder for a --core choice, or None for the pure-Python core. 'auto'
    falls back to Python (with a warning on stderr) where the compiled core cannot be built;
    'compiled' raises CompiledCoreError there."""
    if core not in CORES:
        raise ValueError(f"core={core!r}: choose one of {', '.join(CORES)}")
    if core == "python":
        return None
    try:
        return build_compiled_core(cache)
    except CompiledCoreError as err:
        if core == "compiled":
            raise
        print(f"warning: using the pure-Python fusion_core: {err}", file=sys.stderr)
        return None


def is_compiled(module: ModuleType) -> bool:
    """Whether an imported module is an extension module (the compiled core)."""
    return str(getattr(module, "__file__", "")).endswith(EXT_SUFFIX)

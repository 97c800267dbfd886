"""The C twin as a library: its sources, the compiler, the build (cached by content and flags)
and the cffi binding whose declarations are the headers' (fusion_core.native)."""

from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
import subprocess
import tempfile
import threading
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
DATA_HEADERS = ("fc_scenarios.h", "fc_real.h")
"""Headers the binding does not declare, compiled in: the scenarios' signal nodes, the real type."""
EXTENSION_SOURCES = ("fc_stream_ext.c",)
"""C sources of the directory that are not the library (the stream's CPython entry point)."""


def _sources() -> tuple[str, ...]:
    """Every fc_*.c of the twin's directory but the extension: a new twin (the prefix a class's
    TWIN names) joins the library by its files alone."""
    return tuple(sorted(p.name for p in HERE.glob("fc_*.c") if p.name not in EXTENSION_SOURCES))


def _headers() -> tuple[str, ...]:
    """Every fc_*.h but DATA_HEADERS, each after the headers it includes (the binding declares
    a type before its use), else by name."""
    names = sorted(p.name for p in HERE.glob("fc_*.h") if p.name not in DATA_HEADERS)
    includes = {n: [m for m in re.findall(r'#include "(fc_\w+\.h)"', (HERE / n).read_text())
                    if m in names] for n in names}
    order: list[str] = []

    def visit(name: str) -> None:
        if name not in order:
            for included in includes[name]:
                visit(included)
            order.append(name)

    for name in names:
        visit(name)
    return tuple(order)


SOURCES = _sources()
"""The library's C sources."""
HEADERS = _headers()
"""The headers, in the order the binding declares them."""
CFLAGS = ("-std=c99", "-O3", "-fno-semantic-interposition", "-fPIC", "-shared",
          "-ffp-contract=off", "-fno-fast-math")
"""No fused multiply-add (-ffp-contract=off) and no fast-math: each operation rounds as
Python's does, which is what makes the twins equal; -O3 inlines and unrolls more than -O2 (fewer
instructions per sample) and leaves every rounding as it is.
-fno-semantic-interposition lets the compiler inline the small shared functions of a source
into their callers in it (fc_core.c's angles and low-pass stages), as it does outside a shared
library: nothing outside interposes them."""
PREBUILT = HERE / "libfusion_core.so"
"""A library built beside the sources, as the pythonfmu FMUs ship it (fmu_src.build): loaded
first where it loads (same platform); elsewhere the library is built or Python runs."""

_lib: Any = None
_ffi: Any = None
_loading = threading.RLock()
"""Held while the library (or the stream's entry point) loads: a thread that asks meanwhile
waits for the outcome instead of reading a half-set one (and running in Python)."""
_reason: str | None = "not loaded yet"
_path: Path | None = None
_tried = False


def cache_dir() -> Path:
    """Where the built library is kept: FUSION_CORE_NATIVE_CACHE, else build/native in a source
    checkout, else the user's cache folder."""
    env = os.environ.get("FUSION_CORE_NATIVE_CACHE")
    if env:
        return Path(env)
    repo = HERE.parents[1]
    if (repo / "pyproject.toml").is_file():
        return repo / "build" / "native"
    return Path.home() / ".cache" / "imu-fusion-fmu" / "native"


def compiler() -> str | None:
    """The C compiler to build with: $CC, else cc, gcc or clang on the PATH."""
    cc = os.environ.get("CC")
    if cc:
        return shutil.which(cc)
    for name in ("cc", "gcc", "clang"):
        found = shutil.which(name)
        if found:
            return found
    return None


def _key(cc: str) -> str:
    h = hashlib.sha256()
    for name in (*SOURCES, *HEADERS, *DATA_HEADERS):
        h.update(name.encode() + b"\0" + (HERE / name).read_bytes())
    h.update(" ".join((cc, *CFLAGS)).encode())
    return h.hexdigest()[:16]


def build(force: bool = False) -> Path:
    """Compile the library (unless cached) and return its path; RuntimeError saying why not."""
    cc = compiler()
    if cc is None:
        raise RuntimeError("no C compiler found (set CC, or install cc, gcc or clang)")
    target = cache_dir() / _key(cc) / "libfusion_core.so"
    if target.is_file() and not force:
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".so", dir=target.parent)
    os.close(fd)
    cmd = [cc, *CFLAGS, "-o", tmp, *(str(HERE / s) for s in SOURCES), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        os.unlink(tmp)
        tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-10:])
        raise RuntimeError(f"building the C twin failed ({' '.join(cmd)}):\n{tail}")
    os.replace(tmp, target)  # atomic: a parallel build never sees half a library
    return target


STREAM_SOURCE = HERE / "fc_stream_ext.c"
"""Estimator.stream()'s compiled entry point: a CPython extension of the stable ABI that calls a
twin's step through its address (no arithmetic of its own)."""
STREAM_PREBUILT = HERE / "_fc_stream.abi3.so"
"""The entry point built with a wheel, loaded before any build."""
_stream: Any = None
_stream_reason: str | None = "not loaded yet"


def build_stream(force: bool = False) -> Path:
    """Compile the stream's entry point (unless cached) and return its path; RuntimeError
    saying why not (no compiler, no Python headers)."""
    import sysconfig

    cc = compiler()
    if cc is None:
        raise RuntimeError("no C compiler found")
    include = sysconfig.get_paths().get("include")
    if not include or not (Path(include) / "Python.h").is_file():
        raise RuntimeError(f"no Python.h in {include} (the Python development headers)")
    h = hashlib.sha256(STREAM_SOURCE.read_bytes() + f"{cc} {include}".encode()).hexdigest()[:16]
    target = cache_dir() / f"stream-{h}" / STREAM_PREBUILT.name
    if target.is_file() and not force:
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".so", dir=target.parent)
    os.close(fd)
    cmd = [cc, "-std=c99", "-O2", "-fPIC", "-shared", "-I", include, "-o", tmp,
           str(STREAM_SOURCE)]
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        os.unlink(tmp)
        tail = "\n".join((proc.stdout + proc.stderr).strip().splitlines()[-10:])
        raise RuntimeError(f"building the stream's entry point failed ({' '.join(cmd)}):\n{tail}")
    os.replace(tmp, target)
    return target


def stream_extension() -> Any:
    """The stream's compiled entry point (built on first use), or None where it cannot be had
    (stream_reason() says why: stream() then steps through the cffi call)."""
    if _stream is not None or _stream_reason != "not loaded yet":
        return _stream
    with _loading:
        if _stream is None and _stream_reason == "not loaded yet":
            _load_stream()
    return _stream


def _load_stream() -> None:
    global _stream, _stream_reason
    import importlib.machinery
    import importlib.util

    try:
        path = STREAM_PREBUILT if STREAM_PREBUILT.is_file() else build_stream()
        loader = importlib.machinery.ExtensionFileLoader("_fc_stream", str(path))
        spec = importlib.util.spec_from_file_location("_fc_stream", path, loader=loader)
        assert spec is not None
        module = importlib.util.module_from_spec(spec)
        loader.exec_module(module)
        _stream, _stream_reason = module, None
    except (RuntimeError, OSError, ImportError) as err:
        _stream_reason = str(err)


def stream_reason() -> str | None:
    """Why the stream's entry point is not available; None when it is."""
    stream_extension()
    return _stream_reason


def cdef(real: str = "double") -> str:
    """The headers as cffi declarations: comments, include guards, #includes, macros and the
    static inline default functions left out; integer #defines kept (lib.NAME), and written
    into the declarations that use them (array sizes); a declaring macro used at the top level
    of a header (FC_DECLARE_ESTIMATOR(fc_kf);) expanded into its declarations. real: the twins'
    real type (fc_real.h; the binding is the double build, testbenches.embedded also loads a
    float one)."""
    out: list[str] = [f"typedef {real} fc_real;"]
    defines: dict[str, str] = {}
    macros: dict[str, tuple[str, str]] = {}  # NAME -> (its parameter, its body)
    for name in HEADERS:
        text = re.sub(r"/\*.*?\*/", "", (HERE / name).read_text(), flags=re.S)
        text = text.replace("\\\n", " ")  # a macro's continued lines into one
        text = re.sub(r"static inline[^{]*\{.*?\n\}\n", "", text, flags=re.S)
        for line in text.splitlines():
            line = line.rstrip()
            define = re.match(r"#define (\w+) (-?\d+)(?:\s.*)?$", line)
            macro = re.match(r"#define (\w+)\((\w+)\)\s+(.*)$", line)
            use = re.match(r"(\w+)\((\w+)\);$", line)
            if define:  # a constant the binding reads too (lib.NAME)
                defines[define.group(1)] = define.group(2)
                out.append(f"#define {define.group(1)} {define.group(2)}")
                continue
            if macro:
                macros[macro.group(1)] = (macro.group(2), macro.group(3))
                continue
            if line.startswith("#"):
                continue
            if use and use.group(1) in macros:
                param, body = macros[use.group(1)]
                arg = use.group(2)
                line = re.sub(rf"\b{param}\b", arg, body.replace(f"{param}##", arg)) + ";"
            if defines:
                line = re.sub(r"\b(" + "|".join(defines) + r")\b",
                              lambda m: defines[m.group(1)], line)
            out.append(line)
    return "\n".join(out)


def declarations_name(text: str) -> str:
    """The module name of cdef() text's declarations: its hash with cffi's version, so that a
    module written for other headers or another cffi is never loaded."""
    import cffi  # type: ignore[import-untyped]

    return "_fc_ffi_" + hashlib.sha256(f"{cffi.__version__}\0{text}".encode()).hexdigest()[:16]


def _load_declarations(path: Path) -> Any:
    """The FFI of a declarations module (write_declarations), or None where there is none or it
    cannot be loaded (a damaged cache entry is parsed and written again)."""
    import importlib.util

    if not path.is_file():
        return None
    try:
        spec = importlib.util.spec_from_file_location(path.stem, path)
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return module.ffi
    except Exception:  # anything a damaged file raises
        return None


def write_declarations(folder: Path, text: str | None = None) -> Path:
    """Write the declarations of cdef() text (default: the double build's) into folder as the
    Python module cffi's out-of-line ABI mode makes of them (the types as data); its path. A
    wheel and an FMU ship it beside the library, so that an installed package loads the
    declarations without parsing them and writes nothing."""
    import cffi

    text = cdef() if text is None else text
    ffi = cffi.FFI()
    ffi.cdef(text)
    return _write_declarations(ffi, declarations_name(text), folder)


def _write_declarations(ffi: Any, name: str, folder: Path) -> Path:
    import io

    from cffi.recompiler import make_py_source  # type: ignore[import-untyped]

    source = io.StringIO()
    make_py_source(ffi, name, source)
    folder.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".py", dir=folder)
    path = folder / f"{name}.py"
    try:
        with os.fdopen(fd, "w") as f:
            f.write(source.getvalue())
        os.replace(tmp, path)  # atomic: a process loading meanwhile sees the whole module
    except BaseException:
        Path(tmp).unlink(missing_ok=True)  # no half-written file left behind
        raise
    return path


def declarations(text: str) -> Any:
    """A cffi FFI declaring `text` (cdef()'s). Parsing them takes pycparser a third of a second,
    so they are parsed once: loaded from the module shipped beside the sources (a wheel's, an
    FMU's: write_declarations) or kept in the cache, else parsed and written to the cache (where
    it cannot be written, parsed each time). cffi.CDefError and cffi.FFIError say what in the
    text is wrong."""
    import cffi

    name = declarations_name(text)
    for folder in (HERE, cache_dir() / "ffi"):
        ffi = _load_declarations(folder / f"{name}.py")
        if ffi is not None:
            return ffi
    ffi = cffi.FFI()
    ffi.cdef(text)
    with contextlib.suppress(OSError):  # no cache: the next process parses too
        _write_declarations(ffi, name, cache_dir() / "ffi")
    return ffi


def _load() -> None:
    global _lib, _ffi, _reason, _tried, _path
    try:
        _load_library()
    finally:
        _tried = True


def _load_library() -> None:
    global _lib, _ffi, _reason, _path
    try:
        import cffi  # type: ignore[import-untyped]
    except ImportError as err:
        _reason = f"cffi is not installed ({err})"
        return
    try:
        ffi = declarations(cdef())
    except (cffi.CDefError, cffi.FFIError) as err:
        _reason = str(err)
        return
    if PREBUILT.is_file():  # an FMU's copy: the library built with it, if it loads here
        try:
            _lib, _ffi, _reason = ffi.dlopen(str(PREBUILT)), ffi, None
            _path = PREBUILT
            return
        except OSError:
            pass
    try:
        built = build()
        _lib = ffi.dlopen(str(built))
        _ffi, _reason, _path = ffi, None, built
    except (RuntimeError, OSError) as err:
        _reason = str(err)


def available() -> bool:
    """Whether the C twin is built and loaded (building it on first use; thread-safe)."""
    if not _tried:
        with _loading:
            if not _tried:
                _load()
    return _lib is not None


def library_path() -> Path:
    """The file of the loaded library (PREBUILT or the built one); RuntimeError with the reason
    where the twin is unavailable."""
    if not available() or _path is None:
        raise RuntimeError(f"the native backend is unavailable: {reason()}")
    return _path


def reason() -> str | None:
    """Why the C twin is not available (no compiler, build failed, ...); None when it is."""
    available()
    return _reason


def lib_and_ffi() -> tuple[Any, Any]:
    """The loaded library and its cffi FFI; RuntimeError with the reason where unavailable."""
    if not available():
        raise RuntimeError(f"the native backend is unavailable: {reason()}")
    return _lib, _ffi

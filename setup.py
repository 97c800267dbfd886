"""The wheel carries what a compiler makes: the C twin's library and the native FMUs.

pyproject.toml holds the project's metadata; this file only adds a build step. A wheel built
where a C compiler exists holds
- fusion_core/native/libfusion_core.so (fusion_core.native.PREBUILT), loaded before any build,
  so that run(), stream() and the pythonfmu FMUs step through the twin on a machine without a
  compiler, and beside it its declarations as cffi's out-of-line module (_fc_ffi_<hash>.py,
  fusion_core.native.library.write_declarations), loaded without parsing the headers;
- fmu_src/native/prebuilt/<preset>/<fmi2|fmi3>/<Model>.fmu for the recommended and paper
  presets (fmu_src.native.prebuilt), which `imu-fusion build-fmus --kind native` copies where
  no compiler exists (a JSON preset's start values are compiled into the binary: it needs one).
- fusion_core/native/_fc_stream.abi3.so, stream()'s compiled entry point, where the Python
  headers exist too.
The wheel is then tagged for this platform: cp310-abi3-PLATFORM with the entry point (CPython's
stable ABI, any CPython from 3.10), else py3-none-PLATFORM (the library is plain C, called
through cffi's ABI mode). Where no compiler exists, or an editable
install is made, nothing is compiled and the package runs in Python or builds the twin on first
use, as a source checkout does.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

try:
    from setuptools.command.bdist_wheel import bdist_wheel
except ImportError:  # setuptools < 70.1
    from wheel.bdist_wheel import bdist_wheel  # type: ignore[no-redef]

HERE = Path(__file__).resolve().parent


class BuildWithTwin(build_py):
    """build_py, then the compiled artefacts into the build folder (never the sources)."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        sys.path.insert(0, str(HERE))
        try:
            from fmu_src.native.prebuilt import build_into

            for line in build_into(Path(self.build_lib)):
                print(line)
        except Exception as err:  # the sdist builds everywhere
            warnings.warn(f"the wheel carries no compiled twin ({err}): the package runs in "
                          "Python, or builds the twin where a compiler appears", stacklevel=1)
            self.distribution.compiled = False
        else:
            self.distribution.compiled = True
            # a binary inside: the wheel's root is platlib, as for an extension module
            self.distribution.has_ext_modules = lambda: True
        finally:
            sys.path.remove(str(HERE))


class PlatformWheel(bdist_wheel):
    """A platform wheel (py3-none-PLATFORM) where the twin was compiled, else a pure one."""

    def run(self) -> None:
        self.run_command("build_py")
        self.root_is_pure = not getattr(self.distribution, "compiled", False)
        super().run()

    def get_tag(self) -> tuple[str, str, str]:
        if self.root_is_pure:
            return "py3", "none", "any"
        _, _, plat = super().get_tag()
        if (Path(self.bdist_dir or "") / "fusion_core" / "native" / "_fc_stream.abi3.so").exists():
            return "cp310", "abi3", plat  # stream()'s entry point: CPython's stable ABI
        return "py3", "none", plat


setup(cmdclass={"build_py": BuildWithTwin, "bdist_wheel": PlatformWheel})

"""fusion_core's C twin: the same estimators in C99, and their Python binding.

The C sources beside this file (fc_core.c, fc_cf.c, ...) are the twins of the Python modules:
the same names, the same state fields, the same floating-point operations in the same order, libm
where Python calls math, compiled without fused multiply-add or fast-math, so that a run through
either gives the same numbers to the bit (tests/test_native.py). They
need libc and libm only, so the very same files go into the native FMUs and onto a
microcontroller.

This module builds them into a shared library with the C compiler it finds (CC, else cc; cached
under build/native/ in a source checkout, else ~/.cache/imu-fusion-fmu/native, keyed on the
sources and the flags) and binds it with cffi. `available()` says whether that worked and
`reason()` why not; where it did not, every estimator still runs in Python. `Estimator.run(...,
backend="auto")` uses the native twin where there is one and it is available.

By hand, the library is one command:

    cc -std=c99 -O3 -fno-semantic-interposition -fPIC -shared -ffp-contract=off \\
        -fno-fast-math -o libfusion_core.so fusion_core/native/*.c -lm
"""

from __future__ import annotations

from .estimators import (
    BASE_STATE,
    ESTIMATE_FIELDS,
    FC_SKIPPED,
    STATE_ATTRIBUTES,
    Stepper,
    has_twin,
    new_twin,
    poskf_pending_max,
    run,
    stepper,
    take_state,
)
from .library import (
    CFLAGS,
    DATA_HEADERS,
    HEADERS,
    HERE,
    PREBUILT,
    SOURCES,
    available,
    build,
    cache_dir,
    cdef,
    compiler,
    lib_and_ffi,
    library_path,
    reason,
)
from .models import normals, plant_truth, sensor_run
from .stream import Stream

__all__ = [
    "BASE_STATE", "CFLAGS", "DATA_HEADERS", "ESTIMATE_FIELDS", "FC_SKIPPED", "HEADERS", "HERE",
    "PREBUILT", "SOURCES", "STATE_ATTRIBUTES", "Stepper", "Stream", "available", "build",
    "cache_dir", "cdef", "compiler", "has_twin", "lib_and_ffi", "library_path", "new_twin",
    "normals", "plant_truth", "poskf_pending_max", "reason", "run", "sensor_run", "stepper",
    "take_state",
]

"""`make embedded` (`python -m testbenches.embedded`): the twins on a Cortex-M7 (double) and a
Cortex-M4F (float) under QEMU (testbenches.embedded.build), the MCU-style example, and the float
build's accuracy against double on the desktop (testbenches.embedded.float_accuracy); printed
and written to build/embedded/report.json."""

from __future__ import annotations

import contextlib
import functools
import io
import json
import os
import tempfile
from pathlib import Path
from typing import Any

from .build import (
    OUT,
    PACKAGES,
    TARGETS,
    N,
    build,
    build_example,
    flash_sizes,
    missing_tools,
    parse,
    report_lines,
    run_qemu,
    write_data,
)
from .float_accuracy import measure, summary_lines


def main(argv: list[str] | None = None, out: Path | None = None) -> int:
    """Build, run, measure and report into out (build/embedded); 0 also where the tools are
    missing (said so)."""
    folder = out or OUT
    missing = missing_tools()
    if missing:
        print(f"make embedded: {', '.join(missing)} not found; install the Debian packages "
              f"{PACKAGES} (apt-get install {PACKAGES}); nothing was built")
        return 0
    folder.mkdir(parents=True, exist_ok=True)
    names = write_data(folder)
    print(f"recordings: {', '.join(names)} ({N} samples each)")
    report: dict[str, Any] = {}
    for target in TARGETS:
        elf = build(target, folder)
        report[target.name] = parse(run_qemu(target, elf), flash_sizes(target, folder))
    print("\n".join(report_lines(report)))
    example = build_example(TARGETS[0], folder)
    print(f"examples/mcu_main_loop.c: built for {TARGETS[0].name} and run under QEMU: "
          f"{example}")
    accuracy = measure(folder)
    print("\n".join(summary_lines(accuracy)))
    (folder / "report.json").write_text(json.dumps({**report, "float_accuracy": accuracy},
                                                   indent=1))
    print(f"wrote {folder / 'report.json'}")
    return 0


@functools.lru_cache(maxsize=1)
def report_without_broad() -> tuple[dict[str, Any], str]:
    """main's report.json and what it printed, with BROAD_DIR unset (so the same on every
    machine), made once per process: the docs' table and the checks of the same run take it
    instead of building and running QEMU again. Raises where the tools are missing."""
    missing = missing_tools()
    if missing:
        raise RuntimeError(f"make embedded: {', '.join(missing)} not found "
                           f"(apt-get install {PACKAGES})")
    saved = os.environ.pop("BROAD_DIR", None)
    try:
        with tempfile.TemporaryDirectory() as tmp, \
                contextlib.redirect_stdout(io.StringIO()) as said:
            status = main(out=Path(tmp))
            report = json.loads(Path(tmp, "report.json").read_text())
    finally:
        if saved is not None:
            os.environ["BROAD_DIR"] = saved
    if status != 0:
        raise RuntimeError(f"make embedded ended with {status}:\n{said.getvalue()}")
    return report, said.getvalue()

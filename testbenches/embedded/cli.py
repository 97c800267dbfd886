"""`make embedded` (`python -m testbenches.embedded`): the twins on a Cortex-M7 (double) and a
Cortex-M4F (float) under QEMU (testbenches.embedded.build), the MCU-style example, and the float
build's accuracy against double on the desktop (testbenches.embedded.float_accuracy); printed
and written to build/embedded/report.json."""

from __future__ import annotations

import json
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

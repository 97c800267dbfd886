"""`python -m benchmarks [--quick] [--out DIR] [--fmu-dir DIR] [--core C]`: run the speed
benchmarks, print the table (every target beside its measurement) and write DIR/bench.json.

--core auto (default) or compiled times the mypyc-compiled fusion_core (fmu_src/compiled_core.py;
built once and cached) in this process and ships it in the FMUs; --core python times the
pure-Python sources."""

from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

from fmu_src.compiled_core import CORES, CompiledCoreError, is_compiled, resolve_core

from .config import BenchConfig
from .report import format_table, write_json


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the exit status (0: the benchmark ran, whatever it found)."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks", description=__doc__)
    parser.add_argument("--quick", action="store_true",
                        help="shorter recording, fewer repeats, scaling to 1e5 (under 2 minutes)")
    parser.add_argument("--out", type=Path, default=Path("reports"),
                        help="folder for bench.json (default: reports)")
    parser.add_argument("--fmu-dir", type=Path, default=None,
                        help="use the FMUs in this folder instead of building them")
    parser.add_argument("--core", choices=CORES, default="auto",
                        help="fusion_core to time and ship: compiled (mypyc), python, or auto = "
                        "compiled where it can be built (default)")
    args = parser.parse_args(argv)
    if "fusion_core.base" in sys.modules:  # called in a process that runs one already (tests)
        core = "compiled" if is_compiled(sys.modules["fusion_core.base"]) else "python"
        if args.core not in ("auto", core):
            parser.error(f"--core {args.core}: this process already runs the {core} fusion_core")
    else:
        try:
            core_dir = resolve_core(args.core)
        except CompiledCoreError as err:
            parser.error(f"--core compiled: {err}")
        if core_dir is not None:  # the compiled package shadows the sources for this process
            sys.path.insert(0, str(core_dir))
        core = "python" if core_dir is None else "compiled"
    from .suite import run_benchmarks  # imports fusion_core: only now

    config = BenchConfig.quick_config(args.fmu_dir) if args.quick else BenchConfig(
        fmu_dir=args.fmu_dir)
    config = dataclasses.replace(config, core=core)
    t0 = time.perf_counter()
    results = run_benchmarks(config, log=lambda msg: print(f"... {msg}", file=sys.stderr))
    results["wall_s"] = round(time.perf_counter() - t0, 1)
    print(format_table(results))
    path = write_json(results, args.out)
    print(f"\nwrote {path} ({results['wall_s']} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""`python -m benchmarks [--quick] [--out DIR] [--fmu-dir DIR] [--docs]`: run the speed
benchmarks, print the table (every target beside its measurement) and write DIR/bench.json;
with --docs also docs/results/speed.json, the measurement docs/results/speed.md shows."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

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
    parser.add_argument("--docs", action="store_true",
                        help="also keep the results as docs/results/speed.json and write "
                        "docs/results/speed.md's table of them (a full run only)")
    args = parser.parse_args(argv)
    if args.docs and args.quick:
        parser.error("--docs: the documentation shows a full run; leave out --quick")
    from .suite import run_benchmarks  # imports fusion_core: only now

    config = BenchConfig.quick_config(args.fmu_dir) if args.quick else BenchConfig(
        fmu_dir=args.fmu_dir)
    t0 = time.perf_counter()
    results = run_benchmarks(config, log=lambda msg: print(f"... {msg}", file=sys.stderr))
    results["wall_s"] = round(time.perf_counter() - t0, 1)
    print(format_table(results))
    path = write_json(results, args.out)
    print(f"\nwrote {path} ({results['wall_s']} s)")
    if args.docs:
        from testbenches.docs_figures import write_speed

        print(f"wrote {', '.join(map(str, write_speed(results)))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

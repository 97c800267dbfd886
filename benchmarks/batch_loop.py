"""`python -m benchmarks.batch_loop KEY [--samples N] [--repeat R]`: one estimator's batch run
through its C twin, over the benchmark's recording, and nothing else, for a profiler to look
at where a sample's time goes (`perf record python -m benchmarks.batch_loop kf`, then
`perf report --no-children`). The `native` section of `make bench` times the same run against
VQF's batch; this command times nothing itself but prints the wall time per sample."""

from __future__ import annotations

import argparse
import sys
import time

from fusion_core import ESTIMATORS, native
from fusion_core.registry import keys_help

from .common import recording
from .native import tiled


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.batch_loop",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("key", help=f"the estimator: {keys_help()}")
    parser.add_argument("--samples", type=int, default=200_000,
                        help="samples per run, the recording repeated (200000)")
    parser.add_argument("--repeat", type=int, default=40, help="runs (40)")
    args = parser.parse_args(argv)
    if args.key not in ESTIMATORS:
        parser.error(f"unknown estimator {args.key!r}: allowed {keys_help()}")
    if args.samples < 1 or args.repeat < 1:
        parser.error("--samples and --repeat must be at least 1")
    if not native.available():
        print(f"error: the C twin is not available ({native.reason()})", file=sys.stderr)
        return 2
    acc, gyro, dt = tiled(recording(60.0), args.samples)
    cls = ESTIMATORS[args.key]
    t0 = time.perf_counter()
    for _ in range(args.repeat):
        cls().run(acc, gyro, dt, backend="native")
    per_sample = (time.perf_counter() - t0) / (args.repeat * args.samples) * 1e6
    print(f"{args.key}: {per_sample:.3f} us per sample ({args.repeat} runs of {args.samples})")
    return 0


if __name__ == "__main__":
    sys.exit(main())

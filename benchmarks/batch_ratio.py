"""`python -m benchmarks.batch_ratio [--rounds N] [--estimator KEYS]`: each twin's batch run per
sample over VQF's C++ `updateBatch`, measured in turn within each of N rounds (VQF first), with
the median ratio and its range over the rounds beside the target. On a machine whose speed
swings between minutes, one pass of `make bench` can land a ratio anywhere in that range; the
median over rounds is the figure to compare with the targets."""

from __future__ import annotations

import argparse
import statistics
import sys

from fusion_core import ESTIMATORS, native
from fusion_core.registry import keys_help

from .common import recording
from .native import MIN_SAMPLES, VQF_RATIO_TARGETS, _median_seconds, tiled, vqf_batch_us


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.batch_ratio",
                                     description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3, help="rounds (3)")
    parser.add_argument("--repeats", type=int, default=5,
                        help="runs per estimator and round, their median taken (5)")
    parser.add_argument("--estimator", default=",".join(VQF_RATIO_TARGETS),
                        help=f"comma-separated keys ({keys_help()})")
    args = parser.parse_args(argv)
    keys = [k.strip() for k in args.estimator.split(",") if k.strip()]
    unknown = [k for k in keys if k not in ESTIMATORS]
    if unknown:
        parser.error(f"unknown estimator {', '.join(unknown)}: allowed {keys_help()}")
    if args.rounds < 1 or args.repeats < 1:
        parser.error("--rounds and --repeats must be at least 1")
    if not native.available():
        print(f"no C twin: {native.reason()}", file=sys.stderr)
        return 1
    rec = recording(60.0)
    acc, gyro, dt = tiled(rec, MIN_SAMPLES)
    ratios: dict[str, list[float]] = {k: [] for k in keys}
    for r in range(args.rounds):
        vqf = vqf_batch_us(rec, args.repeats)
        if not isinstance(vqf, float):
            print(f"VQF unavailable ({vqf}): install the bench extra", file=sys.stderr)
            return 1
        line = [f"round {r + 1}: VQF {vqf:.3f} us"]
        for key in keys:
            cls = ESTIMATORS[key]
            cls().run(acc[:100], gyro[:100], dt[:100], backend="native")  # first-call costs
            us = _median_seconds(lambda cls=cls: cls().run(acc, gyro, dt, backend="native"),
                                 args.repeats) / len(dt) * 1e6
            ratios[key].append(us / vqf)
            line.append(f"{key} {us:.3f} us ({us / vqf:.2f}x)")
        print(", ".join(line))
    print(f"{'twin':<6} {'median':>7} {'range':>12} {'target':>7}")
    for key in keys:
        med = statistics.median(ratios[key])
        target = VQF_RATIO_TARGETS.get(key)
        verdict = "" if target is None else ("met" if med <= target else "not met")
        span = f"{min(ratios[key]):.2f}-{max(ratios[key]):.2f}"
        print(f"{key:<6} {med:>6.2f}x {span:>12} {target or '':>6}x {verdict}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

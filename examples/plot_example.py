"""Plot an estimator FMU's fmpy output against the example's truth (needs matplotlib).

    fmpy simulate dist/AngleBiasKalmanFilter.fmu --input-file examples/tilt_motion.csv \
        --output-interval 0.01 --output-file AngleBiasKalmanFilter_out.csv
    python examples/plot_example.py AngleBiasKalmanFilter_out.csv examples/tilt_motion_truth.csv \
        docs/fmu_example.png

Top: roll and pitch, estimate and truth [deg]; bottom: gyro bias estimates and the true bias
[deg/s]. Prints the roll and pitch RMSE after the first second.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

DEG = 180.0 / math.pi


def read(path: Path) -> np.ndarray:
    """A CSV with a header row as a structured array (fmpy's and make_inputs' files)."""
    return np.genfromtxt(path, delimiter=",", names=True, deletechars="")


def rmse_deg(out: np.ndarray, truth: np.ndarray, name: str, after: float = 1.0) -> float:
    """RMSE [deg] of an angle output against the truth at the same times, from `after` s on."""
    t = truth["time"]
    est = np.interp(t, out["time"], out[name])
    keep = t >= after
    err = np.remainder(est[keep] - truth[name][keep] + math.pi, 2 * math.pi) - math.pi
    return float(np.sqrt(np.mean(err**2)) * DEG)


def plot(out: np.ndarray, truth: np.ndarray, title: str, png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 5.2), sharex=True,
                                      gridspec_kw={"height_ratios": [3, 2]})
    for name, color in (("roll", "C0"), ("pitch", "C1")):
        top.plot(truth["time"], truth[name] * DEG, color=color, lw=3, alpha=0.3,
                 label=f"{name} truth")
        top.plot(out["time"], out[name] * DEG, color=color, lw=1, label=f"{name} FMU")
    top.set_ylabel("angle [deg]")
    top.legend(ncol=4, fontsize=8, loc="upper right")
    top.set_title(title, fontsize=10)
    for axis, color in zip("xyz", ("C2", "C3", "C4"), strict=True):
        name = f"bias_{axis}"
        bottom.plot(truth["time"], truth[name] * DEG, color=color, lw=3, alpha=0.3,
                    label=f"{name} truth")
        bottom.plot(out["time"], out[name] * DEG, color=color, lw=1, label=f"{name} FMU")
    bottom.set_ylabel("gyro bias [deg/s]")
    bottom.set_xlabel("time [s]")
    bottom.legend(ncol=3, fontsize=8, loc="lower right")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=90)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", type=Path, help="fmpy's --output-file CSV")
    parser.add_argument("truth", type=Path, help="the example's *_truth.csv")
    parser.add_argument("png", type=Path, help="where to write the plot")
    parser.add_argument("--title", default="AngleBiasKalmanFilter.fmu on examples/tilt_motion.csv")
    args = parser.parse_args(argv)
    out, truth = read(args.output), read(args.truth)
    for name in ("roll", "pitch"):
        print(f"{name} RMSE after 1 s: {rmse_deg(out, truth, name):.3f} deg")
    plot(out, truth, args.title, args.png)


if __name__ == "__main__":
    main()

"""The picture `imu-fusion estimate` draws: the up direction each estimator finds, the
reference's, and each one's inclination error."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from .runs import Thinned


def import_pyplot() -> Any:
    """matplotlib's pyplot on the Agg backend, or None where matplotlib is not installed."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    return plt


ORIGIN_SHOWN_S = 1e5
"""A recording whose time starts this far from 0 [s] (a clock since 1970, as bags and loggers'
epochs count) is plotted from its first sample, the axis naming when that was."""


def when(t: float) -> str:
    """The instant a time [s] names: a date where it counts since 1970, else the number."""
    import datetime as dt

    if 1e8 <= t <= 4.1e9:
        return dt.datetime.fromtimestamp(t, dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    return f"{t:.9g} s"


def draw(path: Path, runs: list[Any], vqf: Any, truth: Thinned, name: str) -> str:
    """The up direction each estimator finds (its three components: readable at any attitude,
    where roll is not near 90 deg of pitch), the reference's, and with a reference each one's
    inclination error; every series thinned alike (Thinned)."""
    plt = import_pyplot()
    if plt is None:
        return "(no plot: matplotlib is not installed)"
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    from ..broad.metric import inclination_error

    scored = len(truth.rows) > 0
    fig, axes = plt.subplots(4 if scored else 3, 1, sharex=True,
                             figsize=(9, 8.5 if scored else 6.5))
    series = [(run.key, run.trace) for run in runs]
    if vqf is not None and vqf.stream is not None:
        series.append(("vqf", vqf.trace))
    firsts = [float(trace.values["t"][0]) for _, trace in series if trace.values]
    origin = min(firsts) if firsts and abs(min(firsts)) >= ORIGIN_SHOWN_S else 0.0
    decades = [np.inf, -np.inf]  # the error's span, log10 [deg]
    for key, trace in series:
        if not trace.values:
            continue
        t, up = trace.values["t"] - origin, trace.values["up"]
        for i, ax in enumerate(axes[:3]):
            ax.plot(t, up[:, i], lw=0.9, label=key)
        if scored:  # the same rows: every series is thinned alike
            _, a, b = np.intersect1d(trace.rows, truth.rows, return_indices=True)
            err = np.maximum(np.degrees(inclination_error(up[a], truth.values["up"][b])), 1e-3)
            axes[3].plot(t[a], err, lw=0.8, label=key)
            if np.isfinite(err).any():
                decades = [min(decades[0], np.log10(np.nanmin(err))),
                           max(decades[1], np.log10(np.nanmax(err)))]
    if scored:
        for i, ax in enumerate(axes[:3]):
            ax.plot(truth.values["t"] - origin, truth.values["up"][:, i], "k--", lw=0.8,
                    label="reference")
        axes[3].set_ylabel("inclination\nerror [deg]")
        axes[3].set_yscale("log")
        # plain numbers (0.1, 1, 10; and 0.2, 0.5 where the error spans few decades, so that
        # any span has labels): the default labels are typeset by mathtext, whose parser is
        # built on its first use, at a cost a short recording's plot feels
        few = decades[1] - decades[0] <= 3.0
        axes[3].yaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0) if few else (1.0,)))
        axes[3].yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axes[3].yaxis.set_minor_formatter(NullFormatter())
    for i, ax in enumerate(axes[:3]):
        ax.set_ylabel(f"up, {'xyz'[i]}")
        ax.set_ylim(-1.05, 1.05)
    axes[-1].set_xlabel(f"time [s] since {when(origin)}" if origin else "time [s]")
    axes[0].legend(fontsize=8, ncol=4, loc="lower right")
    axes[0].set_title(f"{name}: the up direction in the sensor frame (gravity's, unit length)")
    # fixed margins that fit these labels: tight_layout would measure every tick label
    # first, a third of the plot's time on a long recording
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.07 if scored else 0.09,
                        top=0.95 if scored else 0.93, hspace=0.1)
    try:
        fig.savefig(path, dpi=110)
    except OSError as err:  # a full disk: no half-written picture left
        path.unlink(missing_ok=True)
        raise OSError(f"{path}: cannot be written ({err})") from None
    finally:
        plt.close(fig)
    return f"plot: {path}"

"""An estimator's run over a recording's blocks (its outputs written, scored and thinned for
the plot) and VQF's on the same samples: the tasks of `imu-fusion estimate` (lanes.Lanes runs
them in parallel)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from ..table_out import TableWriter

PLOT_POINTS = 1000
"""The plot keeps at most about twice this many samples per line (every kth, k doubling): about
two per pixel column of the figure (9 in at 110 dpi); more only cost drawing time."""


def _columns(out: dict[str, np.ndarray], t: np.ndarray, names: list[str], keep: slice
             ) -> list[np.ndarray]:
    pick = {"time": t, "roll": out["roll"], "pitch": out["pitch"], "rejected": out["rejected"]}
    for group in ("bias", "pos", "vel"):
        if group in out:
            pick.update({f"{group}_{a}": out[group][:, i] for i, a in enumerate("xyz")})
    return [np.asarray(pick[n][keep], dtype=float) for n in names]


class Score:
    """An inclination RMSE [deg] summed block by block (BROAD's rule: the counted samples with
    a reference and an estimate)."""

    def __init__(self) -> None:
        self.sum_sq, self.n = 0.0, 0

    def add(self, up: np.ndarray, rec: Any) -> None:
        from ..broad.metric import inclination_error

        if rec.up_ref is None:
            return
        e = inclination_error(up, rec.up_ref)[rec.counted]
        e = e[np.isfinite(e)]
        self.sum_sq += float(np.sum(e * e))
        self.n += len(e)

    @property
    def rmse(self) -> float:
        return float(np.degrees(np.sqrt(self.sum_sq / self.n))) if self.n else float("nan")


class Thinned:
    """Every kth sample of a long series, k doubling whenever more than 2 * PLOT_POINTS are
    kept: what a plot of any length shows."""

    def __init__(self) -> None:
        self.k, self.rows = 1, np.empty(0, dtype=np.int64)
        self.values: dict[str, np.ndarray] = {}

    def add(self, row0: int, values: dict[str, np.ndarray]) -> None:
        """A block's series (each [n] or [n, m]) from the recording's row row0."""
        n = len(next(iter(values.values())))
        self.add_at(row0, n, lambda i: {name: v[i] for name, v in values.items()})

    def add_at(self, row0: int, n: int,
               make: Callable[[np.ndarray], dict[str, np.ndarray]]) -> None:
        """A block of n rows from row row0 whose series `make` gives at the block's indices
        it is passed: only the rows kept are computed (k is doubled first as far as the block
        would double it: a long first block is not computed whole to be thinned)."""

        def kept(k: int) -> int:
            return int(np.count_nonzero(self.rows % k == 0)) + len(range(-row0 % k, n, k))

        k = self.k
        while kept(k) > 2 * PLOT_POINTS:
            k *= 2
        self._thin(k)
        at = np.arange(-row0 % self.k, n, self.k)  # the block's rows r with r % k == 0
        self.rows = np.concatenate([self.rows, row0 + at])
        for name, v in make(at).items():
            old = self.values.get(name)
            self.values[name] = v if old is None else np.concatenate([old, v])

    def _thin(self, k: int) -> None:
        """Every kth sample of those kept (k a power-of-two multiple of self.k)."""
        if k != self.k:
            self.k = k
            keep = self.rows % k == 0
            self.rows = self.rows[keep]
            self.values = {name: v[keep] for name, v in self.values.items()}


class Run:
    """One estimator over a recording's blocks: its outputs written, its score and plot trace
    kept."""

    def __init__(self, key: str, est: Any, path: Path, fmt: str, names: list[str]) -> None:
        self.key, self.est = key, est
        self.writer = TableWriter(path, fmt, names)
        self.score, self.trace, self.rejected = Score(), Thinned(), 0
        self.also: list[Run] = []  # runs whose outputs this one's give (running)

    def block(self, rec: Any, t: np.ndarray, row0: int, every: int) -> None:
        out = self.est.run(rec.acc, rec.gyro, rec.dt)
        for run in (self, *self.also):
            run.take(out, rec, t, row0, every)

    def take(self, out: dict[str, np.ndarray], rec: Any, t: np.ndarray, row0: int,
             every: int) -> None:
        """A block's outputs written, scored and kept for the plot."""
        from ..broad.metric import gravity_from_roll_pitch

        keep = slice(-row0 % every, None, every)  # the recording's rows 0, every, 2 every, ...
        self.writer.write(_columns(out, t, self.writer.names, keep))
        if rec.up_ref is None:  # the up direction for the plot's rows only
            self.trace.add_at(row0, len(t), lambda i: {
                "t": t[i], "up": gravity_from_roll_pitch(out["roll"][i], out["pitch"][i])})
        else:
            up = gravity_from_roll_pitch(out["roll"], out["pitch"])
            self.score.add(up, rec)
            self.trace.add(row0, {"t": t, "up": up})
        self.rejected += int(out["rejected"].sum())


def shared_runs(estimators: dict[str, Any]) -> dict[str, str]:
    """Of estimators by key, those whose outputs another's run gives to the bit, each with
    that one's key: a kf whose roll, pitch, bias and rejected samples the position filter's
    gives (PositionKalmanFilter.attitude_params: that filter runs the same kf on the same
    samples) need not run a second time on every sample."""
    from fusion_core.kalman import AngleBiasKalmanFilter
    from fusion_core.position import PositionKalmanFilter

    given: dict[str, str] = {}
    for pos_key, pos in estimators.items():
        if type(pos) is not PositionKalmanFilter:
            continue
        same = pos.attitude_params()
        key = next((key for key, est in estimators.items() if key not in given
                    and type(est) is AngleBiasKalmanFilter and est.params == same), None)
        if key is not None:
            given[key] = pos_key
    return given


def running(runs: list[Run]) -> list[Run]:
    """The runs that run their estimator, each also giving the outputs of those it gives
    (shared_runs)."""
    by_key = {run.key: run for run in runs}
    given = shared_runs({run.key: run.est for run in runs})
    for key, source in given.items():
        by_key[source].also.append(by_key[key])
    return [run for run in runs if run.key not in given]


class VqfRun:
    """VQF on the samples the estimators took (their calibration and mounting applied, the
    samples they reject left out), block by block; `note` says why there is none."""

    def __init__(self, rate: float, params: dict[str, Any]) -> None:
        from fusion_core.base import COMMON_PARAMS

        from ..peers import PeerUnavailable, VqfStream

        self.params, self.score, self.trace = params, Score(), Thinned()
        max_dt = next(float(p.default) for p in COMMON_PARAMS if p.name == "max_dt")
        self.rate, self.most = rate, max(1, round(max_dt * rate))
        self.missed = 0  # samples rejected since the last one taken
        try:
            self.stream: Any = VqfStream(rate)
            self.note = "VQF on the same samples"
        except PeerUnavailable as err:
            self.stream, self.note = None, f"(VQF not run: {str(err).split('; ')[-1]})"

    def block(self, rec: Any, t: np.ndarray, row0: int, every: int) -> None:
        if self.stream is None:
            return
        valid = rec.valid
        acc, gyro = conditioned(rec.acc[valid], rec.gyro[valid], self.params)
        # VQF takes no sample the estimators rejected; as they integrate the sample after
        # such samples over its dt, which spans them, VQF takes it once per sampling period
        # its dt spans, up to once more per sample missed (not for a row written twice,
        # which takes no time) and to max_dt's
        where = np.flatnonzero(valid)
        missed = np.diff(where, prepend=-1 - self.missed) - 1
        self.missed = len(valid) - 1 - int(where[-1]) if len(where) else self.missed + len(valid)
        steps = np.nan_to_num(np.rint(rec.dt[valid] * self.rate), nan=1.0)
        repeats = np.clip(steps, 1, np.minimum(1 + missed, self.most)).astype(int)
        up = np.full((len(valid), 3), np.nan)
        up[valid] = self.stream(np.repeat(acc, repeats, axis=0),
                                np.repeat(gyro, repeats, axis=0))[np.cumsum(repeats) - 1]
        self.score.add(up, rec)
        self.trace.add(row0, {"t": t, "up": up})


def conditioned(acc: np.ndarray, gyro: np.ndarray, params: dict[str, Any]
                ) -> tuple[np.ndarray, np.ndarray]:
    """The samples as every estimator's input stage makes them of the parameters: calibrated
    (M (raw - b)), then turned by the mounting into the filter's frame."""
    from fusion_core.base import mounting_matrix
    from fusion_core.calibration import Calibration

    acc, gyro = Calibration.from_params(params).apply(acc, gyro)
    r = np.asarray(mounting_matrix(float(params.get("mount_roll", 0.0)),
                                   float(params.get("mount_pitch", 0.0)),
                                   float(params.get("mount_yaw", 0.0)))).reshape(3, 3)
    return acc @ r.T, gyro @ r.T

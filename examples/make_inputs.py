"""Write the example input CSVs for the estimator FMUs (see examples/README.md).

    python examples/make_inputs.py

tilt_motion.csv / tilt_motion_truth.csv
    at rest for 3 s (as a session starts: the rest detection measures the gyro bias), then
    roll 0.5 rad at 0.5 Hz and pitch 0.35 rad at 0.35 Hz together, about a fixed point, faded in
    over 1 s by a minimum-jerk ramp, to 10 s, at 100 Hz.
move_2m.csv / move_2m_truth.csv
    at rest for 2 s, a 2 m minimum-jerk move along x in 3 s, at rest again (for the position
    filter).
Both with MPU-6050 white noise and a constant gyro bias GYRO_BIAS.

Timing: fmpy applies the CSV row of time t at the start of the communication step [t, t+h], and
docs/interface.md says the inputs set before doStep(t, h) are the sample taken at t+h. So the row
of time t holds the sample taken at t + 0.01 s, and the FMU's output at time t+h is the estimate
at the sample's time, aligned with the truth file's row of the same time.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from fusion_core import synthetic

HERE = Path(__file__).resolve().parent
RATE = 100.0
INPUT_COLUMNS = ("acc_x", "acc_y", "acc_z", "gyro_x", "gyro_y", "gyro_z", "dt")
GYRO_BIAS = (0.02, -0.01, 0.005)
"""Constant gyro bias of the example IMU [rad/s] (about 1.1, -0.6, 0.3 deg/s)."""


def move_2m() -> synthetic.Trajectory:
    """At rest for 2 s, a 2 m move along x in 3 s, at rest again (like fusion_core.scenarios'
    translation_2m)."""
    s = synthetic
    return s.Trajectory(pos=(s.min_jerk(0.0, 2.0, 2.0, 3.0), s.constant(), s.constant()))


def tilt_motion() -> synthetic.Trajectory:
    """At rest for 3 s, then two-axis motion faded in over 1 s (module docstring)."""
    s = synthetic
    ramp = s.min_jerk(0.0, 1.0, 3.0, 1.0)
    return s.Trajectory(roll=s.product(ramp, s.sine(0.5, 0.5)),
                        pitch=s.product(ramp, s.sine(0.35, 0.35)))


def recordings() -> dict[str, dict[str, np.ndarray]]:
    """The example recordings by file stem."""
    noise = synthetic.ImuNoise(gyro_bias=GYRO_BIAS)
    return {
        "tilt_motion": synthetic.record(tilt_motion(), 10.0, RATE, noise, seed=2026),
        "move_2m": synthetic.record(move_2m(), 10.0, RATE, noise, seed=2026),
    }


def input_table(rec: dict[str, np.ndarray]) -> np.ndarray:
    """Rows (time, acc_x..z, gyro_x..z, dt): the sample taken at t + dt in the row of time t;
    the sample at t = 0 is left out (it has no row time >= 0)."""
    time = rec["t"][1:] - rec["dt"][1:]
    return np.column_stack([time, rec["acc_meas"][1:], rec["gyro_meas"][1:], rec["dt"][1:]])


def truth_table(rec: dict[str, np.ndarray]) -> tuple[list[str], np.ndarray]:
    """Truth at the sample times: attitude, gyro bias, position and velocity."""
    names = ["time", "roll", "pitch", "yaw", "bias_x", "bias_y", "bias_z",
             "pos_x", "pos_y", "pos_z", "vel_x", "vel_y", "vel_z"]
    n = len(rec["t"])
    columns = [rec["t"], rec["roll"], rec["pitch"], rec["yaw"],
               *np.tile(GYRO_BIAS, (n, 1)).T, *rec["pos"].T, *rec["vel"].T]
    return names, np.column_stack(columns)[1:]


def write(directory: Path = HERE) -> list[Path]:
    """Write every example CSV into directory; return the paths."""
    paths = []
    for stem, rec in recordings().items():
        path = directory / f"{stem}.csv"
        np.savetxt(path, input_table(rec), fmt="%.10g", delimiter=",",
                   header=",".join(("time", *INPUT_COLUMNS)), comments="")
        names, truth = truth_table(rec)
        truth_path = directory / f"{stem}_truth.csv"
        np.savetxt(truth_path, truth, fmt="%.10g", delimiter=",", header=",".join(names),
                   comments="")
        paths += [path, truth_path]
    return paths


if __name__ == "__main__":
    for p in write():
        print(p.relative_to(Path.cwd()) if p.is_relative_to(Path.cwd()) else p)

"""Command-line option helpers shared by the testbench commands."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

PRESET_HELP = ("estimator parameters: recommended (the defaults, for real MEMS sensors), paper "
               "(the seed papers' own filters, fusion_core.papers), or a JSON file of "
               "parameters per estimator")
RECORDING_HELP = ("CSV (and its kin), Parquet, HDF5 or MAT, a ROS bag or a PX4 log, or a phone "
                  "app's export: a folder or zip archive of one file per sensor")
"""What a recording a command reads may be (testbenches.reader, testbenches.bags,
testbenches.fit.sensor_files)."""
SENSOR_HELP = ("ImuSensor parameters: realistic (the defaults: an MPU-6050 as a user meets it), "
               "ideal (white noise only, the papers' simulations), or a JSON file of sensor "
               "parameters")


def add_preset(parser: argparse.ArgumentParser, flag: str = "--preset", more: str = "") -> None:
    """The --preset option every command that runs estimators takes (default recommended);
    `more` names what a command accepts beyond PRESET_HELP."""
    parser.add_argument(flag, default="recommended",
                        help=f"{PRESET_HELP}{more} (recommended)")


def add_recording_options(parser: argparse.ArgumentParser) -> None:
    """How a recording is read: the options every command that reads one takes (estimate,
    calibrate, noise, tune; testbenches.fit.recording.load_recording)."""
    parser.add_argument("--rate", type=positive_float, default=None,
                        help="sample rate [Hz]: where the file has no time or dt column, or to "
                        "space the samples by it where its time cannot serve (a time coarser "
                        "than the sampling repeats), the time column left; beside a time that "
                        "serves it must agree with its steps within 2 %%")
    parser.add_argument("--time-column", default=None, help="the time column's name")
    parser.add_argument("--topic", default=None, metavar="NAME",
                        help="a ROS bag's IMU topic (sensor_msgs/Imu), where it has several")
    parser.add_argument("--time-unit", choices=("auto", "s", "ms", "us", "ns"), default="auto",
                        help="the unit of the time (or dt) column (auto: the header's, else the "
                        "one in which its steps are an IMU's sample rate, the data deciding "
                        "where two are)")
    parser.add_argument("--column", action="append", default=[], metavar="QUANTITY=NAME",
                        help="the column of a quantity (acc_x..gyro_z, time, dt, roll, pitch, "
                        "q_w..q_z) where its name is none the reader knows (repeatable); "
                        "acc=NAME or gyro=NAME for a sensor's three (NAME_x, NAME.x, NAME[0] or "
                        "NAME_1 and on), acc=X,Y,Z to name them")
    parser.add_argument("--acc-unit", choices=("auto", "m/s2", "g", "mg"), default="auto",
                        help="the accelerometer's unit (auto: the header's, else from its norm)")
    parser.add_argument("--acc-sign", choices=("auto", "+1", "-1"), default="auto",
                        help="+1: the accelerometer reads specific force, +1 g up at rest "
                        "(Android, IMUs); -1: its negative, as iOS's Core Motion gives it (a "
                        "phone flat on a table reads z = -1 g). auto: -1 for iOS SensorLog's "
                        "columns, +1 elsewhere; a Sensor Logger export from iOS is refused "
                        "until given (its 'Standardise Units & Frames' setting decides)")
    parser.add_argument("--gyro-axes", default="x,y,z", metavar="X,Y,Z",
                        help="the gyro's axes in the accelerometer's, each with its sign, where "
                        "its columns differ (x,-y,z: its y negated; y,x,-z); a gyro whose turn "
                        "explains the accelerometer's only so is refused until given")
    parser.add_argument("--gyro-unit", choices=("auto", "rad/s", "deg/s", "mdps"),
                        default="auto",
                        help="the gyro's unit (auto: the header's, else the unit in which the "
                        "gyro's turn explains the accelerometer's turn of gravity; a given or "
                        "stated unit the data contradict is refused)")
    parser.add_argument("--counts", type=counts_pair, default=None, metavar="PER_G,PER_DPS",
                        help="the accelerometer and the gyro as a converter's raw counts: its "
                        "counts per g and per deg/s (the datasheet's sensitivity; an MPU-6050's "
                        "16384,131 at +-2 g and +-250 deg/s), in place of --acc-unit and "
                        "--gyro-unit; the gyro's scale is still checked against the data")


def add_calibration(parser: argparse.ArgumentParser) -> None:
    """The --calibration option of every command that runs estimators: a part's calibration
    (fusion_core.calibration), applied at each estimator's input."""
    parser.add_argument("--calibration", type=Path, default=None, metavar="FILE.json",
                        help="the part's calibration (calibration.json, as `calibrate` writes "
                        "it): acc_cal and gyro_cal applied at every estimator's input")


def with_calibration(entries: dict[str, dict[str, Any]], path: Path | None
                     ) -> dict[str, dict[str, Any]]:
    """Each estimator's parameters with the calibration file's on top (none: unchanged);
    ValueError or FileNotFoundError saying what is wrong with the file."""
    if path is None:
        return entries
    from fusion_core.calibration import Calibration

    params = Calibration.read(path).params()
    return {key: {**values, **params} for key, values in entries.items()}


def add_cluster(parser: argparse.ArgumentParser) -> None:
    """The Dask options of every command that splits its runs over a cluster: a LocalCluster
    by default, or the user's scheduler."""
    parser.add_argument("--scheduler", default="local",
                        help="local (a LocalCluster, the default) or the address HOST:PORT of "
                        "your own Dask scheduler")
    parser.add_argument("--workers", type=positive_int, default=2,
                        help="LocalCluster processes (2)")


def add_sensor(parser: argparse.ArgumentParser) -> None:
    """The --sensor option every command that simulates the sensor takes (default realistic)."""
    parser.add_argument("--sensor", default="realistic", help=f"{SENSOR_HELP} (realistic)")


def choose(value: str, allowed: list[str], what: str) -> list[str]:
    """'all' or a comma list of names from `allowed`; ValueError naming the unknown ones."""
    if value == "all":
        return allowed
    names = [v for v in value.split(",") if v]
    bad = [n for n in names if n not in allowed]
    if bad or not names:
        raise ValueError(f"unknown {what} {', '.join(bad) or value!r}: allowed all, "
                         f"{', '.join(allowed)}")
    return names


def positive_int(text: str) -> int:
    """argparse type: an integer of at least 1 (seeds, workers, jobs, batch sizes)."""
    return _number(text, int, "an integer of at least 1", lambda v: v >= 1)


def non_negative_int(text: str) -> int:
    """argparse type: an integer of at least 0 (retries)."""
    return _number(text, int, "an integer of at least 0", lambda v: v >= 0)


def positive_float(text: str) -> float:
    """argparse type: a finite number above 0 (durations [s], rates [Hz])."""
    return _number(text, float, "a finite number above 0", lambda v: 0.0 < v < math.inf)


def counts_pair(text: str) -> tuple[float, float]:
    """argparse type: PER_G,PER_DPS, two finite numbers above 0 (--counts)."""
    parts = text.split(",")
    try:
        pair = tuple(float(p) for p in parts)
    except ValueError:
        pair = ()
    if len(pair) != 2 or not all(0.0 < v < math.inf for v in pair):
        raise argparse.ArgumentTypeError(
            f"{text!r}: allowed two numbers above 0, the counts per g and per deg/s "
            "(16384,131 for an MPU-6050 at +-2 g and +-250 deg/s)")
    return pair[0], pair[1]


def non_negative_float(text: str) -> float:
    """argparse type: a finite number of at least 0 (fractions)."""
    return _number(text, float, "a finite number of at least 0", lambda v: 0.0 <= v < math.inf)


def jitter_fraction(text: str) -> float:
    """argparse type: a fraction of the period in [0, 1) (at 1 or more the shortest step,
    1 - jitter of the period, would reach zero)."""
    return _number(text, float, "a fraction in [0, 1)", lambda v: 0.0 <= v < 1.0)


def add_no_plots(parser: argparse.ArgumentParser, skipped: str) -> None:
    """--no-plots (or --no-plot): every command that draws takes it, to skip `skipped`."""
    parser.add_argument("--no-plots", "--no-plot", dest="no_plots", action="store_true",
                        help=f"skip {skipped}")


def out_folder(text: str) -> Path:
    """argparse type: the folder a command writes to (--out), made where missing; a file of
    that name is refused before anything runs (mkdir would raise on it after the work)."""
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a file: the outputs go to a folder")
    return path


def _number(text: str, kind: type, allowed: str, ok: Callable[[Any], bool]) -> Any:
    try:
        value = kind(text)
    except ValueError:
        value = None
    if value is None or not ok(value):
        raise argparse.ArgumentTypeError(f"{text!r}: allowed {allowed}")
    return value


def load_sensor(spec: str | Path) -> dict[str, Any]:
    """ImuSensor parameters by name (fusion_core.sensor.SENSOR_PRESETS: realistic, ideal) or
    from a JSON file of parameters; each is checked by building the sensor model."""
    from fusion_core.sensor import SENSOR_PRESETS, ImuSensorModel, sensor_preset
    from fusion_core.types import read_json

    text = str(spec)
    if text in SENSOR_PRESETS or not text.endswith(".json"):
        return sensor_preset(text)
    params = read_json(text, "sensor file")
    try:
        ImuSensorModel(**params)
    except (TypeError, ValueError) as err:
        raise ValueError(f"sensor file {text}: {err}") from None
    return dict(params)


def parse_params(items: list[str]) -> dict[str, object]:
    """NAME=VALUE strings to a dict: numbers as float or int, true/false, else the string."""
    out: dict[str, object] = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name:
            raise ValueError(f"--param {item!r}: expected NAME=VALUE")
        value: object = text
        if text.lower() in ("true", "false"):
            value = text.lower() == "true"
        else:
            for kind in (int, float):
                try:
                    value = kind(text)
                    break
                except ValueError:
                    pass
        out[name] = value
    return out

"""What a recording's columns are called: the names loggers, phone apps, ROS and data tools give
the accelerometer's, the gyro's and the time's columns, and the one spelling they are compared
in (norm_name)."""

from __future__ import annotations

import re

ACC_STEMS = ("acc", "accel", "accelerometer", "acceleration", "linear_acceleration",
             "accelerometer_acceleration", "accel_ln", "accel_wr")
"""Names of the accelerometer's columns before the axis (acc_x, accelX, linear_acceleration.x
as ROS writes it, accelerometerAccelerationX as iOS's SensorLog). Not a phone's linear or user
acceleration, which leaves gravity out (its median norm is then no gravity's, and refused).
Shimmer's low-noise and wide-range accelerometers (Accel_LN_X, Accel_WR_X) in that order."""
GYRO_STEMS = ("gyro", "gyr", "gyroscope", "angular_velocity", "rotation_rate", "omega",
              "gyro_rotation")
"""Names of the gyro's columns before the axis (gyro_x, gyroX, angular_velocity.x,
gyroRotationX as iOS's SensorLog)."""


def axis_names(stems: tuple[str, ...], axis: str, short: tuple[str, ...]) -> tuple[str, ...]:
    return (*(n for stem in stems for n in (f"{stem}_{axis}", f"{stem}{axis}")),
            *(f"{s}{axis}" for s in short))


ALIASES: dict[str, tuple[str, ...]] = {
    **{f"acc_{a}": (*axis_names(ACC_STEMS, a, ("g_f", "a", "a_", "a_rs_s_", "ac", "ac_")),
                    f"acc_{a}_g", f"acc_{a}_ms2") for a in "xyz"},
    **{f"gyro_{a}": (*axis_names(GYRO_STEMS, a, ("g", "g_", "w", "w_", "w_rs_s_", "gy", "gy_")),
                     f"gyro_{a}_dps") for a in "xyz"},
    "time": ("header_stamp", "time", "timestamp", "time_s", "time_ms", "time_us", "time_ns",
             "timestamp_s", "timestamp_ms", "timestamp_us", "timestamp_ns", "time_stamp",
             "timestamp_unix", "unix_time", "unix_timestamp", "epoch", "epoch_time",
             "timestamp_epoch", *(f"{stem}_{unit}" for stem in ("epoch", "timestamp_epoch",
                                                                "unix_time")
                                  for unit in ("s", "ms", "us", "ns")),
             "millis", "micros", "elapsed", "elapsed_time", "time_elapsed",
             "seconds_elapsed", "time_since_start", "time_since_start_in_ms",
             "gyro_timestamp_since_reboot", "accelerometer_timestamp_since_reboot", "x_value",
             "t_s", "t_ms", "t_us", "t_ns", "sensor_timestamp", "receive_time",
             "phone_timestamp", "t"),
    **{f"q_{c}": (f"q_{c}", f"q{c}", f"quat_{c}", f"quaternion_{c}", f"rotation_{c}",
                  f"q_rs_{c}", f"transform_rotation_{c}", f"pose_orientation_{c}",
                  f"pose_pose_orientation_{c}") for c in "wxyz"},
}
"""Column names a recording may use per quantity, as norm_name makes them (case ignored; spaces,
hyphens, dots and slashes as underscores; a leading ROS "field.", "%", "#" and "_" left out; an
index [0], [1], [2] as the axis x, y, z, but a quaternion's, whose first may be w or x), in the
order they are taken: a ROS message's own stamp ("field.header.stamp") first, the time it was
received last but one (rostopic's "%time", PlotJuggler's "__time": "receive_time"), which lags
the sample by the transport's delay and bunches where messages arrive together; "t" last, as a
flight log's "T" is its temperature beside a "timestamp". EuRoC's and TUM-VI's "w_RS_S_x" and
"a_RS_S_x" (the rate and the specific force of the sensor frame S against the reference R, in
S). SensorLog's (iOS) gyro's clock before its accelerometer's. Polar Sensor Logger's "sensor
timestamp [ns]" (the sensor's clock) before its "Phone timestamp" (when the phone received
the packet, which bunches its samples). LabVIEW's measurement file's
(.lvm) "X_Value", its waveforms' time. The Arduino MPU-6050 example's "AcX" and "GyX" (raw
counts as it prints them, which the accelerometer's norm then tells). Physics Toolbox's
g-force "gFx"
is the accelerometer (its "ax" there leaves gravity out, and is refused for it). A reference
quaternion's components (sensor to world) too, as motion capture names them ("Rotation W" in
OptiTrack Motive's stacked header, testbenches.reader), EuRoC's ground truth ("q_RS_w") and
ROS's messages a motion-capture system or an odometry publishes (TransformStamped's
"transform.rotation", PoseStamped's "pose.orientation", Odometry's "pose.pose.orientation"); not
"orientation" alone, which in a ROS Imu message is the device's own estimate, no reference."""


LAST_RESORT: dict[str, tuple[str, ...]] = {"time": ("t",)}
"""Aliases taken only where no other alias fits a name in any of name_forms: "t", a flight
log's temperature beside a device's prefixed timestamp. PlotJuggler's "__time" is taken before
a topic's ".../header/stamp": an export of several topics has one such stamp per topic, empty
on the others' rows, and "__time" on every row."""


def norm_name(name: str) -> str:
    """A column name as ALIASES spell them: "Gyroscope X" -> "gyroscope_x", "rotationRateX" ->
    "rotation_rate_x", ROS's "field.angular_velocity.x" -> "angular_velocity_x", "%time" ->
    "receive_time" (PlotJuggler's "__time" too), "/imu/angular_velocity/x" ->
    "imu_angular_velocity_x", EuRoC's "#timestamp" -> "timestamp"."""
    name = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", name.strip()).lower()
    if name in ("%time", "__time"):  # ROS's receive time (rostopic, PlotJuggler)
        return "receive_time"
    name = name.lstrip("%#_/")
    for sep in (" ", "-", ".", "/"):
        name = name.replace(sep, "_")
    if not re.search(r"(^|_)(q|quat|quaternion|rotation|orientation|attitude)\[", name):
        name = re.sub(r"\[([012])\]$", lambda m: "_" + "xyz"[int(m.group(1))], name)
    return name.removeprefix("field_")


UNIT_TOKENS: dict[str, dict[str, str]] = {
    "gyro": {"rad": "rad/s", "rad_s": "rad/s", "rads": "rad/s", "rps": "rad/s",
             "dps": "deg/s", "deg_s": "deg/s", "degs": "deg/s", "mdps": "mdps"},
    "acc": {"g": "g", "mg": "mg", "m_s2": "m/s2", "m_s_2": "m/s2", "ms2": "m/s2",
            "mps2": "m/s2"},
}
"""Units a name may carry as a word of its own before or after the axis (PX4's "gyro_rad[0]",
"accelerometer_m_s2[0]"; "gyro_x_dps"), per sensor, as norm_name spells them."""
_WORDS = "|".join(sorted({t for tokens in UNIT_TOKENS.values() for t in tokens}, key=len,
                         reverse=True))
_UNIT_WORD = re.compile(rf"_({_WORDS})(?=(_[xyz])?$)")


def _without_unit(name: str) -> tuple[str, str | None]:
    """A normed name without a unit word (UNIT_TOKENS) and that word (None: none)."""
    m = _UNIT_WORD.search(name)
    return (name[:m.start()] + name[m.end():], m.group(1)) if m else (name, None)


def unit_in_name(quantity: str, name: str) -> str | None:
    """The unit an accelerometer's or gyro's column name carries as a word (UNIT_TOKENS), None
    where it carries none or one of the other sensor's."""
    sensor = quantity.partition("_")[0]
    word = _without_unit(norm_name(name))[1]
    return UNIT_TOKENS.get(sensor, {}).get(word) if word else None


def _without_device(normed: list[str]) -> list[str]:
    """Names without the device's prefix that every one of them shares and without a trailing
    "_cal" (Shimmer's "Shimmer_A1B2_Gyro_X_CAL": "gyro_x"); as they are where they share
    none."""
    words = [n.split("_") for n in normed if n]
    shared = 0  # the words every name starts with, one at least left to each
    while (len(words) > 1 and all(len(w) > shared + 1 for w in words)
           and len({w[shared] for w in words}) == 1):
        shared += 1
    prefix = "".join(f"{w}_" for w in words[0][:shared]) if shared else ""
    return [n.removeprefix(prefix).removesuffix("_cal") for n in normed]


def _path_tails(names: list[str]) -> list[list[str]]:
    """The names without the first 1, 2, ... parts of a path ("/imu/data/angular_velocity/x",
    as PlotJuggler names a ROS topic's field: "data/angular_velocity/x", then
    "angular_velocity/x"), then the last part alone where it is a name of more than one letter
    (an HDF5 file's "imu0/acc_x", testbenches.array_files), as norm_name spells them; a name
    of fewer parts as it is."""
    parts = [[p for p in n.split("/") if p] for n in names]
    deepest = max((len(p) for p in parts if len(p) > 1), default=1)
    tails = [[norm_name("/".join(p[k:])) if len(p) > k + 1 else norm_name(n)
              for n, p in zip(names, parts, strict=True)] for k in range(1, deepest - 1)]
    leaves = [norm_name(p[-1]) if len(p) > 1 and len(norm_name(p[-1])) > 1 else norm_name(n)
              for n, p in zip(names, parts, strict=True)]
    return [*tails, leaves] if deepest > 1 else tails


_ONE_BASED = re.compile(r"(.+)_([1-9])")


def _one_based_axes(normed: list[str]) -> list[str]:
    """The columns MATLAB's writetable makes of a variable of three columns ("Acceleration_1",
    "_2", "_3") as its axes x, y, z, where a name has exactly these three; the others as they
    are (a quaternion's "_1" to "_4" among them: its first may be w or x)."""
    found = [_ONE_BASED.fullmatch(n) for n in normed]
    indices: dict[str, set[str]] = {}
    for m in found:
        if m:
            indices.setdefault(m.group(1), set()).add(m.group(2))
    three = {stem for stem, got in indices.items() if got == {"1", "2", "3"}}
    return [f"{m.group(1)}_{'xyz'[int(m.group(2)) - 1]}" if m and m.group(1) in three else n
            for n, m in zip(normed, found, strict=True)]


_NUMBERED = re.compile(r"(?<=[a-z])\d+(?=_[xyz]$)")


def _unnumbered(normed: list[str]) -> list[str]:
    """The names without a sensor's number before the axis ("acc1_x", "gyro2_x": a logger of
    several IMUs numbers each): the number left out, so that two sensors' columns fit one
    quantity alike and are refused naming both (find_columns), one sensor's are taken."""
    return [_NUMBERED.sub("", n) for n in normed]


def name_forms(names: list[str]) -> list[list[str]]:
    """The names as norm_name spells them, then without a unit word (UNIT_TOKENS), then also
    without a device's prefix and a "_cal" (_without_device), then with MATLAB's "_1", "_2",
    "_3" as the axes (_one_based_axes), then without a sensor's number (_unnumbered), then
    without a path's first parts (_path_tails, a topic's): the forms find_name tries in
    turn, so that a name as written is taken before one read into."""
    normed = [norm_name(n) for n in names]
    bare = [_without_unit(n)[0] for n in normed]
    return [normed, bare, [_without_unit(n)[0] for n in _without_device(normed)],
            _one_based_axes(bare), _unnumbered(bare),
            *([_without_unit(n)[0] for n in tails] for tails in _path_tails(names))]


def find_names(names: list[str], quantity: str, given: str | None = None,
               more: tuple[str, ...] = ()) -> list[int]:
    """The columns of a quantity: the one given (by its name as written, with or without its
    unit), else the first of its aliases and then of `more` in the first of name_forms that
    has one; every column that spells it so (two where a header names one twice, or two
    topics the same field), none where none does."""
    if given:  # as written, then with MATLAB's "_1", "_2", "_3" as the axes (acc=NAME)
        normed = [norm_name(n) for n in names]
        forms = [normed, _one_based_axes(normed)]
        passes: list[tuple[str, ...]] = [(norm_name(given),)]
    else:
        forms, wanted = name_forms(names), (*ALIASES[quantity], *more)
        last = LAST_RESORT.get(quantity, ())
        passes = [tuple(a for a in wanted if a not in last), last]
    for aliases in passes:
        for normed in forms:
            for alias in aliases:
                if alias in normed:
                    return [j for j, n in enumerate(normed) if n == alias]
    return []


def find_name(names: list[str], quantity: str, given: str | None = None,
              more: tuple[str, ...] = ()) -> int | None:
    """The first of find_names, None for none."""
    found = find_names(names, quantity, given, more)
    return found[0] if found else None

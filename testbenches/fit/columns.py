"""What a recording's columns are called: the names loggers, phone apps, ROS and data tools give
the accelerometer's, the gyro's and the time's columns, and the one spelling they are compared
in (norm_name)."""

from __future__ import annotations

import re

ACC_STEMS = ("acc", "accel", "accelerometer", "acceleration", "linear_acceleration",
             "accelerometer_acceleration")
"""Names of the accelerometer's columns before the axis (acc_x, accelX, linear_acceleration.x
as ROS writes it, accelerometerAccelerationX as iOS's SensorLog). Not a phone's linear or user
acceleration, which leaves gravity out (its median norm is then no gravity's, and refused)."""
GYRO_STEMS = ("gyro", "gyr", "gyroscope", "angular_velocity", "rotation_rate", "omega",
              "gyro_rotation")
"""Names of the gyro's columns before the axis (gyro_x, gyroX, angular_velocity.x,
gyroRotationX as iOS's SensorLog)."""


def axis_names(stems: tuple[str, ...], axis: str, short: tuple[str, ...]) -> tuple[str, ...]:
    return (*(n for stem in stems for n in (f"{stem}_{axis}", f"{stem}{axis}")),
            *(f"{s}{axis}" for s in short))


ALIASES: dict[str, tuple[str, ...]] = {
    **{f"acc_{a}": (*axis_names(ACC_STEMS, a, ("a", "a_")), f"acc_{a}_g", f"acc_{a}_ms2")
       for a in "xyz"},
    **{f"gyro_{a}": (*axis_names(GYRO_STEMS, a, ("g", "g_", "w", "w_")), f"gyro_{a}_dps")
       for a in "xyz"},
    "time": ("time", "t", "timestamp", "time_s", "time_ms", "time_us", "time_ns",
             "timestamp_s", "timestamp_ms", "timestamp_us", "timestamp_ns", "time_stamp",
             "header_stamp", "millis", "micros"),
    **{f"q_{c}": (f"q_{c}", f"q{c}", f"quat_{c}", f"quaternion_{c}", f"rotation_{c}")
       for c in "wxyz"},
}
"""Column names a recording may use per quantity, as norm_name makes them (case ignored;
spaces, hyphens and dots as underscores; a leading ROS "field." and "%" left out). A reference
quaternion's components (sensor to world) too, as motion capture names them ("Rotation W" in
OptiTrack Motive's stacked header, testbenches.reader); not "orientation", which in a ROS Imu
message is the device's own estimate, no reference."""


def norm_name(name: str) -> str:
    """A column name as ALIASES spell them: "Gyroscope X" -> "gyroscope_x", "rotationRateX" ->
    "rotation_rate_x", ROS's "field.angular_velocity.x" -> "angular_velocity_x", "%time" ->
    "time"."""
    name = re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", name.strip()).lower().lstrip("%")
    for sep in (" ", "-", "."):
        name = name.replace(sep, "_")
    return name.removeprefix("field_")


def find_name(names: list[str], quantity: str, given: str | None = None,
              more: tuple[str, ...] = ()) -> int | None:
    """The column of a quantity: the one given (by its name as written, with or without its
    unit), else the first of its aliases and then of `more`."""
    normed = [norm_name(n) for n in names]
    wanted = (norm_name(given),) if given else (*ALIASES[quantity], *more)
    for alias in wanted:
        if alias in normed:
            return normed.index(alias)
    return None

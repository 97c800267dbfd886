"""An accelerometer that holds no gravity (a phone's linear or user acceleration) or a gyro
whose axes are not the accelerometer's is refused, even where the units are given, and every
real recording and synthetic motion holds it (testbenches.gravity)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from fusion_core import G
from testbenches import battery
from testbenches.fit.recording import RecordingError, open_recording
from testbenches.gravity import HELD_RANGE, held_gravity

BROAD = Path(__file__).resolve().parents[2] / "shared" / "data" / "broad"


def _gravity(truth: dict[str, np.ndarray]) -> np.ndarray:
    r, p = truth["roll"], truth["pitch"]
    return G * np.stack([-np.sin(p), np.sin(r) * np.cos(p), np.cos(r) * np.cos(p)], axis=1)


@pytest.mark.parametrize("motion,sensor", [
    ("handheld_fast", "mpu6050_raw"),  # turn-on gyro biases of degrees per second
    ("waving", "worse"),
    ("vehicle", "mpu6050"),            # sustained linear acceleration
    ("shaking", "mpu6050"),            # linear acceleration far above g
    ("clipping", "worse"),             # a gyro at its rail
])
def test_the_samples_keep_gravity_and_a_linear_acceleration_keeps_little(motion, sensor):
    """With gravity in the samples, about 1 g; the same samples less gravity (what a phone's
    fusion gives as linear acceleration), under the range's low end."""
    _, truth, s = battery.part_samples(motion, sensor, 1)
    held = held_gravity(s["acc"], s["gyro"], s["dt"])
    assert held is not None and held.held and abs(held.g - 1.0) < 0.1
    linear = held_gravity(s["acc"] - _gravity(truth), s["gyro"], s["dt"])
    assert linear is not None and not linear.held and linear.g < HELD_RANGE[0] / 2


def _write(path: Path, t: np.ndarray, acc: np.ndarray, gyro: np.ndarray) -> Path:
    np.savetxt(path, np.column_stack([t, acc, gyro]), delimiter=",", comments="", fmt="%.8g",
               header="time,acc_x,acc_y,acc_z,gyro_x,gyro_y,gyro_z")
    return path


def test_a_linear_acceleration_read_as_g_is_refused_though_the_gyro_unit_is_given(tmp_path):
    """A hand's linear acceleration in m/s2 has a median norm of about 1.8: it passes for g.
    The gyro's unit given, nothing else would stop it (the filters ran on it before)."""
    t, truth, s = battery.part_samples("handheld_fast", "mpu6050", 0)
    path = _write(tmp_path / "linear.csv", t, s["acc"] - _gravity(truth), s["gyro"])
    with pytest.raises(RecordingError, match=r"holds no gravity as read.*linear or user "
                                              r"acceleration.*acc in g \(from its median norm"):
        open_recording(path, gyro_unit="rad/s")
    fine = _write(tmp_path / "total.csv", t, s["acc"], s["gyro"])
    assert open_recording(fine, gyro_unit="rad/s").rate == pytest.approx(100.0)


def test_the_two_sensors_columns_swapped_are_refused_asking_so(tmp_path):
    """The accelerometer's columns named gyro and the gyro's acc: refused as a gyro unit no
    data explain or the data contradict, or as an accelerometer without gravity ("a phone's
    linear acceleration"), none naming the mistake; each refusal now asks whether the columns
    are swapped. A refusal for another reason (gravity taken out) does not ask."""
    t, _, s = battery.part_samples("handheld_slow", "mpu6050", 0)
    path = _write(tmp_path / "swapped.csv", t, s["gyro"], s["acc"])
    asked = r"gravity's in m/s2, whose mean vector keeps .*: are the accelerometer's and the " \
            r"gyro's columns swapped\? Map them with --column acc=NAME --column gyro=NAME"
    with pytest.raises(RecordingError, match=asked):
        open_recording(path)
    with pytest.raises(RecordingError, match=r"contradicts the data.*" + asked):
        open_recording(path, gyro_unit="rad/s")
    t, truth, s = battery.part_samples("handheld_fast", "mpu6050", 0)
    linear = _write(tmp_path / "linear.csv", t, s["acc"] - _gravity(truth), s["gyro"])
    with pytest.raises(RecordingError, match="holds no gravity") as err:
        open_recording(linear, gyro_unit="rad/s")
    assert "swapped" not in str(err.value)


def test_a_gyro_whose_axes_are_swapped_is_refused_though_its_unit_is_given(tmp_path):
    """Its turn explains the accelerometer's only with x and y swapped: refused saying so
    (before gravity is looked for), and read with --gyro-axes y,x,z as the part's samples."""
    t, _, s = battery.part_samples("handheld_fast", "mpu6050", 0)
    path = _write(tmp_path / "swapped.csv", t, s["acc"], s["gyro"][:, [1, 0, 2]])
    with pytest.raises(RecordingError, match=r"the gyro's axes are not the accelerometer's: .* "
                                             r"as \(y, x, z\) in rad/s .* --gyro-axes y,x,z"):
        open_recording(path, gyro_unit="rad/s")
    rec, _ = open_recording(path, gyro_unit="rad/s", gyro_axes="y,x,z").load()
    np.testing.assert_allclose(rec.gyro, s["gyro"], rtol=1e-7, atol=1e-9)  # written to 8 digits


def test_every_shared_broad_trial_holds_gravity():
    if not BROAD.is_dir():
        pytest.skip(f"no BROAD trials at {BROAD} (../shared is beside the CI's checkout only)")
    from testbenches.broad.data import load_trial
    from testbenches.fit.recording import trial_recording

    trials = sorted(p for p in BROAD.iterdir() if p.suffix in (".mat", ".hdf5"))
    assert trials
    for path in trials:
        rec = trial_recording(load_trial(path))
        held = held_gravity(rec.acc, rec.gyro, rec.dt)
        assert held is not None and abs(held.g - 1.0) < 0.05, path.name

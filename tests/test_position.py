"""PositionKalmanFilter: a 2 m minimum-jerk move along x ends where it should."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from helpers import RATE, angle_difference, make, run_recording
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fusion_core import G, synthetic

MOVE = 2.0  # m along x
T_MOVE = 3.0  # s, minimum-jerk
T_STILL = 2.0  # s at rest before and after


def tilt_filter_error_std(
    params: dict, dt: float, acc_density: float, gyro_density: float
) -> tuple[float, float]:
    """Steady-state standard deviation of the tilt filter's angle [rad] and bias [rad/s] errors
    at rest: its DARE gain K, and the error recursion e+ = (I - K H) F e + (I - K H) [dt w; 0]
    + K v solved as a discrete Lyapunov equation, with v the accelerometer-angle noise
    (acc_density sqrt(rate) / g per sample) and w the gyro noise (gyro_density sqrt(rate))."""
    F = np.array([[1.0, -dt], [0.0, 1.0]])
    H = np.array([[1.0, 0.0]])
    Q = np.diag([params["Q_angle"], params["Q_bias"]]) * dt
    r = params["R_measure"]
    P = scipy.linalg.solve_discrete_are(F.T, H.T, Q, np.array([[r]]))
    K = P @ H.T / (H @ P @ H.T + r)
    A = (np.eye(2) - K @ H) @ F
    Bw = (np.eye(2) - K @ H) @ np.array([[dt], [0.0]])
    sigma_v = acc_density / math.sqrt(dt) / G
    sigma_w = gyro_density / math.sqrt(dt)
    S = scipy.linalg.solve_discrete_lyapunov(
        A, sigma_w**2 * (Bw @ Bw.T) + sigma_v**2 * (K @ K.T)
    )
    return math.sqrt(S[0, 0]), math.sqrt(S[1, 1])


def test_final_position_error_after_2_m_move_is_within_the_noise_budget() -> None:
    """Error budget, 1 sigma, without credit for anything the zero-velocity update does to
    position (it can only help):
      1. accelerometer white noise n_a = 400 ug/sqrt(Hz), double-integrated while velocity is
         free: from the start of the move until the stationary detector's zupt_window (0.25 s)
         confirms rest, T_free = 3.25 s: s1 = n_a sqrt(T_free^3 / 3) = 0.013 m per axis;
      2. tilt error: at rest the tilt filter (papers' Q, R) averages the accelerometer angle
         (4 mrad per sample at 100 Hz) to s_angle = 0.033 deg; during the move it leaks
         g * angle into the level acceleration: s2 = g s_angle T^2 / 2 = 0.025 m (x, y);
      3. its bias error s_bias = 0.029 deg/s turns the tilt during the move:
         s3 = g s_bias T^3 / 6 = 0.022 m (x, y);
      4. gyro white noise n_g = 0.005 deg/s/sqrt(Hz) turns the tilt as a random walk during the
         move: s4 = g n_g sqrt(T^5 / 20) = 0.003 m (x, y).
    Horizontal axes: sqrt(s1^2 + ... + s4^2) = 0.036 m each; vertical s1 = 0.013 m. The norm of
    the final error has rms sqrt(2 * 0.036^2 + 0.013^2) = 0.053 m; the bound is 3 times that,
    0.16 m (8 % of the move). Without the ZUPT, or with the tilt corrected by the accelerometer
    during the move, the error is 0.2 m to 1.9 m."""
    move_x = synthetic.min_jerk(0.0, MOVE, T_STILL, T_MOVE)
    traj = synthetic.Trajectory(pos=(move_x, synthetic.constant(), synthetic.constant()))
    noise = synthetic.MPU6050
    rec = synthetic.record(traj, 2 * T_STILL + T_MOVE, RATE, noise=noise, seed=0)
    est = make("poskf")
    out = run_recording(est, rec)

    dt = 1.0 / RATE
    t_free = T_MOVE + est.params["zupt_window"]
    s1 = noise.acc_density * math.sqrt(t_free**3 / 3.0)
    s_angle, s_bias = tilt_filter_error_std(est.params, dt, noise.acc_density, noise.gyro_density)
    s2 = G * s_angle * T_MOVE**2 / 2.0
    s3 = G * s_bias * T_MOVE**3 / 6.0
    s4 = G * noise.gyro_density * math.sqrt(T_MOVE**5 / 20.0)
    s_horizontal = math.sqrt(s1**2 + s2**2 + s3**2 + s4**2)
    bound = 3.0 * math.sqrt(2.0 * s_horizontal**2 + s1**2)

    error = out["pos"][-1] - rec["pos"][-1]
    norm = float(np.linalg.norm(error))
    print(
        f"\nposkf final position error {norm:.4f} m "
        f"(x {error[0]:+.4f}, y {error[1]:+.4f}, z {error[2]:+.4f}); "
        f"bound {bound:.3f} m (s1 {s1:.4f}, s2 {s2:.4f}, s3 {s3:.4f}, s4 {s4:.4f} m)"
    )
    assert not out["rejected"].any()
    assert norm < bound


@pytest.mark.parametrize(("distance", "duration"), [(1.0, 3.0), (3.0, 2.0)])
def test_zero_velocity_update_does_not_fire_while_gliding_mid_move(
    distance: float, duration: float
) -> None:
    """In the middle of a minimum-jerk move the acceleration stays below the detector threshold
    for longer than its window (0.36 s for 1 m in 3 s); a zero-velocity update there would stop
    the estimate (it ended at 0.18 m of 1 m before the speed gate). The final error stays within
    the same 0.05 m scale as the 2 m move's."""
    trajectory = synthetic.Trajectory(
        pos=(synthetic.min_jerk(0.0, distance, 2.0, duration), synthetic.constant(),
             synthetic.constant())
    )
    rec = synthetic.record(trajectory, duration + 4.0, RATE, noise=synthetic.MPU6050, seed=0)
    out = run_recording(make("poskf"), rec)
    error = out["pos"][-1] - rec["pos"][-1]
    print(f"\n{distance} m in {duration} s: final error {error} m")
    assert np.linalg.norm(error) < 0.05


def test_one_false_level_first_sample_fades_from_the_position_filters_levelling() -> None:
    """A Jacobi master or a tool that passes start values on can hand the filter one level
    sample at rest before a motion that starts tilted (moderate_dynamics starts at 3.8/17.2
    deg). The tilt stage then levels with the attitude filter's roll and pitch, which fade that
    sample as the kf fades it, so the velocity stays what it is without the false sample
    (a tilt stage set from that one sample and corrected only at rest is tens of m/s off at
    10 s)."""
    from fusion_core.scenarios import get_scenario

    rec = synthetic.record(get_scenario("moderate_dynamics").trajectory(), 10.0, RATE,
                           noise=synthetic.MPU6050, seed=3)
    level = (np.array([[0.0, 0.0, G]]), np.zeros((1, 3)), np.array([1.0 / RATE]))
    plain = make("poskf").run(rec["acc_meas"], rec["gyro_meas"], rec["dt"])
    falsed = make("poskf").run(np.vstack([level[0], rec["acc_meas"]]),
                               np.vstack([level[1], rec["gyro_meas"]]),
                               np.concatenate([level[2], rec["dt"]]))
    vel_err = {name: np.linalg.norm(run["vel"][-1] - rec["vel"][-1])
               for name, run in (("plain", plain), ("false start", falsed))}
    att_err = np.abs(angle_difference(falsed["roll"][-100:], rec["roll"][-100:]))
    assert vel_err["false start"] <= 1.5, vel_err
    assert vel_err["false start"] <= vel_err["plain"] + 0.5, vel_err
    assert att_err.max() < np.radians(1.0)


@pytest.mark.parametrize("backend", ["python", "native"])
def test_the_position_filters_attitude_is_the_kfs_with_the_same_sensor_rail_included(
        backend: str) -> None:
    """The poskf's roll, pitch and bias are the recommended kf's on the same samples with the
    same sensor properties: a gyro of +-1000 deg/s clipping in a hand's swings, a mounting that
    mixes its axes and a gyro calibration. The attitude kf inside takes the samples as the
    position filter conditioned them, with its rail flag judged on the sensor's own axes: with
    its own default range of 2000 deg/s it would miss every rail here."""
    from fusion_core import native
    from testbenches.battery import SENSOR_CLASSES, part_samples

    if backend == "native" and not native.available():
        pytest.skip("no C twin (no C compiler)")
    _, _, sample = part_samples("clipping", "worse", 0)
    sensor = {"gyro_range": SENSOR_CLASSES["worse"].value("gyro_range"), "mount_roll": 0.3,
              "mount_yaw": 0.5, "gyro_cal_xx": 1.01, "gyro_cal_xy": 0.004, "gyro_cal_zz": 0.99}
    wide = {k: v for k, v in sensor.items() if k != "gyro_range"}
    runs = {name: make(key, **params).run(sample["acc"], sample["gyro"], sample["dt"],
                                          backend=backend)
            for name, key, params in (("kf", "kf", sensor), ("poskf", "poskf", sensor),
                                      ("kf at 2000 deg/s", "kf", wide))}
    at_rail = np.abs(sample["gyro"]) >= 0.999 * sensor["gyro_range"]
    assert at_rail.any(axis=1).sum() > 100
    for name in ("roll", "pitch", "bias"):
        np.testing.assert_array_equal(runs["poskf"][name], runs["kf"][name])
    assert not np.array_equal(runs["kf"]["roll"], runs["kf at 2000 deg/s"]["roll"])


_value = st.one_of(st.floats(-30.0, 30.0), st.sampled_from([np.nan, np.inf, 0.0, 1e300]))
_sample = st.tuples(st.tuples(_value, _value, _value), st.tuples(_value, _value, _value),
                    st.one_of(st.floats(1e-3, 0.05), st.sampled_from([0.0, -1.0, 2.0, np.nan])))
_position_params = st.fixed_dictionaries({}, optional={
    "sensor_delay": st.sampled_from([0.0, 0.004]), "gyro_range": st.sampled_from([4.0, 35.0]),
    "max_dt": st.sampled_from([0.02, 1.0]), "gyro_sampling": st.sampled_from(["mean", "point"]),
    "mount_roll": st.floats(-3.0, 3.0), "mount_yaw": st.floats(-3.0, 3.0),
    "acc_cal_xy": st.floats(-0.05, 0.05), "gyro_off_z": st.floats(-0.1, 0.1),
    "q": st.sampled_from([0.5, 20.0]), "zupt_acc": st.sampled_from([0.05, 1.0]),
})


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(samples=st.lists(_sample, min_size=1, max_size=80), params=_position_params,
       backend=st.sampled_from(["python", "native"]))
def test_a_kf_with_the_attitude_params_gives_the_position_filters_attitude(
        samples: list, params: dict, backend: str) -> None:
    """PositionKalmanFilter.attitude_params: the kf so made gives the position filter's roll,
    pitch, bias and rejected samples to the bit, whatever the samples (bad ones included) and
    the position filter's parameters (its input stage's and its own); `imu-fusion estimate`
    takes the kf's outputs from the position filter's run where they are so."""
    from fusion_core import native

    if backend == "native" and not native.available():
        backend = "python"
    acc = np.array([s[0] for s in samples], dtype=float)
    gyro = np.array([s[1] for s in samples], dtype=float)
    dt = np.array([s[2] for s in samples], dtype=float)
    pos = make("poskf", **params)
    kf = make("kf", **pos.attitude_params())
    with np.errstate(all="ignore"):
        want = pos.run(acc, gyro, dt, backend=backend)
        got = kf.run(acc, gyro, dt, backend=backend)
    for name in ("roll", "pitch", "bias", "rejected"):
        np.testing.assert_array_equal(got[name], want[name], err_msg=name)


def test_the_attitude_params_are_the_kfs_only_where_the_kf_is_the_same() -> None:
    """A kf's own parameter changed (or one of the input stage) makes another filter: the
    position filter's attitude_params are then not that kf's."""
    assert make("poskf").attitude_params() == make("kf").params
    assert make("poskf").attitude_params() != make("kf", Q_angle=0.01).params
    assert make("poskf", sensor_delay=0.004).attitude_params() != make("kf").params
    assert (make("poskf", sensor_delay=0.004, q=20.0).attitude_params()
            == make("kf", sensor_delay=0.004).params)

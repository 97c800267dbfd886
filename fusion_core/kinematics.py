"""Attitude kinematics shared by the estimators, in this project's frame (x fwd, y left, z up).

Plain-float functions taking and returning scalars (tuples only where a value is one): the
estimators call them once or twice per sample, where numpy's per-call overhead on 3-vectors would
dominate, and so would building a tuple only to unpack it again.

Hot paths skip the call of wrap_angle and clamp_pitch when the value is already in range, where
both return it unchanged: `x if -PI <= x <= PI else wrap_angle(x)` and
`x if -HALF_PI <= x <= HALF_PI else clamp_pitch(x)` are the same numbers without a call.
"""

from __future__ import annotations

import math
from math import copysign, cos, sin, sqrt
from typing import Final

atan: Final = math.atan
atan2: Final = math.atan2
asin: Final = math.asin
hypot: Final = math.hypot
remainder: Final = math.remainder

PI: Final = math.pi
TWO_PI: Final = 2.0 * math.pi
HALF_PI: Final = 0.5 * math.pi
_MIN_COS_PITCH: Final = 1e-9  # keeps tan(pitch) finite at gimbal lock (pitch = +-pi/2)
_SERIES_A2: Final = 1e-2
"""rotvec_terms' series bound on the squared angle (0.1 rad, 5.7 deg in one interval: 10 rad/s at
100 Hz): below it, Taylor series through a^8, whose first omitted term is below 3e-18 (under a
thirtieth of an ulp of 1), so they are exact to double precision there and need no sine, cosine,
square root or division: most of a sigma-point filter's time otherwise."""
_SERIES_T2: Final = 1e-2
"""angle_of's series bound on the squared tangent (an angle of 0.0997 rad, 5.7 deg): below it,
arctan's Taylor series through t^15, whose first omitted term is below 6e-18 of the angle (under a
twentieth of an ulp), so it is exact to double precision there and needs no arctangent: the
innovations of a converged filter are such angles."""


def wrap_angle(x: float) -> float:
    """x wrapped to [-pi, pi]; exact (x itself) when |x| <= pi."""
    return remainder(x, TWO_PI)


def accel_roll_pitch(ax: float, ay: float, az: float) -> tuple[float, float]:
    """Roll and pitch from a specific-force sample of a sensor at rest.

    Inverts docs/interface.md's  acc = g (-sin(theta), sin(phi) cos(theta), cos(phi) cos(theta)):
    roll = atan2(ay, az) (Gui et al. eq. 3), pitch = atan2(-ax, sqrt(ay^2 + az^2)) (eq. 4,
    written with atan2 so that it is defined for every direction).
    """
    return atan2(ay, az), atan2(-ax, sqrt(ay * ay + az * az))


def roll_pitch_sines(roll: float, pitch: float) -> tuple[float, float, float, float]:
    """(sin roll, cos roll, sin pitch, cos pitch): what euler_rates, heun_euler_step and the
    position filters' levelling read of two angles (a caller that has them passes them on)."""
    return sin(roll), cos(roll), sin(pitch), cos(pitch)


def euler_rates(
    phi: float, theta: float, p: float, q: float, r: float,
    sc: tuple[float, float, float, float] | None = None,
) -> tuple[float, float]:
    """Roll and pitch rates from body rates (Z-Y-X Euler kinematics, Duong Quoc et al. eq. 2).

    phi_dot   = p + (q sin(phi) + r cos(phi)) tan(theta)
    theta_dot = q cos(phi) - r sin(phi)

    sc: (sin phi, cos phi, sin theta, cos theta) where the caller has them.
    """
    sp, cp, st, ct = roll_pitch_sines(phi, theta) if sc is None else sc
    if -_MIN_COS_PITCH < ct < _MIN_COS_PITCH:  # abs(ct) < _MIN_COS_PITCH
        ct = copysign(_MIN_COS_PITCH, ct)
    return p + (q * sp + r * cp) * st / ct, q * cp - r * sp


def heun_euler_step(
    phi: float, theta: float,
    p0: float, q0: float, r0: float, p1: float, q1: float, r1: float, dt: float,
    sc: tuple[float, float, float, float] | None = None,
) -> tuple[float, float]:
    """Propagate roll and pitch over dt with Heun's method on the Euler-rate kinematics.

    (p0, q0, r0) is the (bias-corrected) body rate at the start of the interval, (p1, q1, r1) at
    its end: the rate is linear over the interval (trapezoid rule), so the local error is O(dt^3).
    sc: (sin phi, cos phi, sin theta, cos theta) where the caller has them. The end point's
    sines and cosines are the start's turned by the Euler step (angle addition, with sin_cos
    of the step: no libm call for a step below 5.7 deg), one sine-cosine pair per angle fewer.
    """
    # euler_rates at both ends, written out (this runs once per sample in the tilt stages)
    sp, cp, st, c0 = roll_pitch_sines(phi, theta) if sc is None else sc
    ct = c0 if not -_MIN_COS_PITCH < c0 < _MIN_COS_PITCH else copysign(_MIN_COS_PITCH, c0)
    d1p, d1t = p0 + (q0 * sp + r0 * cp) * st / ct, q0 * cp - r0 * sp
    a, b = dt * d1p, dt * d1t  # the step: phi + a, theta + b
    sa, ca = sin_cos(a)
    sb, cb = sin_cos(b)
    sp, cp = sp * ca + cp * sa, cp * ca - sp * sa
    st, ct = st * cb + c0 * sb, c0 * cb - st * sb
    if -_MIN_COS_PITCH < ct < _MIN_COS_PITCH:
        ct = copysign(_MIN_COS_PITCH, ct)
    d2p, d2t = p1 + (q1 * sp + r1 * cp) * st / ct, q1 * cp - r1 * sp
    return phi + 0.5 * dt * (d1p + d2p), theta + 0.5 * dt * (d1t + d2t)


def euler_step(
    phi: float, theta: float, p: float, q: float, r: float, dt: float,
    sc: tuple[float, float, float, float] | None = None,
) -> tuple[float, float]:
    """Propagate roll and pitch with the papers' rectangle rule: the end-of-interval body rate
    (p, q, r) times dt; sc as euler_rates'."""
    dp, dtheta = euler_rates(phi, theta, p, q, r, sc)
    return phi + dt * dp, theta + dt * dtheta


def clamp_pitch(theta: float) -> float:
    """Pitch limited to [-pi/2, pi/2] (docs/interface.md range)."""
    # max(-pi/2, min(pi/2, theta)), without the two builtin calls
    theta = theta if theta < HALF_PI else HALF_PI
    return theta if theta > -HALF_PI else -HALF_PI


def quat_from_roll_pitch_yaw(
    phi: float, theta: float, psi: float = 0.0
) -> tuple[float, float, float, float]:
    """Quaternion (w, x, y, z), body to world, of the Z-Y-X Euler angles (yaw psi, pitch, roll)."""
    cr, sr = cos(0.5 * phi), sin(0.5 * phi)
    cp, sp = cos(0.5 * theta), sin(0.5 * theta)
    cy, sy = cos(0.5 * psi), sin(0.5 * psi)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def quat_roll_pitch(w: float, x: float, y: float, z: float) -> tuple[float, float]:
    """Roll and pitch of a unit quaternion (body to world, Z-Y-X Euler). Roll is atan2 of
    sin(roll) cos(pitch) and cos(roll) cos(pitch); where the second is positive (|roll| < 90
    deg: always in the kf's face frame) the arctangent of their ratio, the same angle to an ulp
    for half of atan2's cost in glibc (the filters read roll off their quaternion every
    sample)."""
    sr, cr = 2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)
    roll = atan(sr / cr) if cr > 0.0 else atan2(sr, cr)
    s = 2.0 * (w * y - x * z)
    # max(-1, min(1, s)) (rounding can put |s| a little above 1), the builtins called only then
    return roll, asin(s if -1.0 <= s <= 1.0 else max(-1.0, min(1.0, s)))


def quat_gravity_body(w: float, x: float, y: float, z: float) -> tuple[float, float, float]:
    """World up axis in body axes, R^T e_z: the direction a resting accelerometer reads."""
    return (
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        w * w - x * x - y * y + z * z,
    )


def _half_angle_series(a2: float) -> tuple[float, float]:
    """cos(a/2) and sin(a/2)/a by their Taylor series through a^8 in a2 = a^2 (below
    _SERIES_A2): rotvec_terms' and half_angle's."""
    return (1.0 - a2 * (1.0 / 8.0 - a2 * (1.0 / 384.0 - a2 * (1.0 / 46080.0
                                                              - a2 * (1.0 / 10321920.0)))),
            0.5 - a2 * (1.0 / 48.0 - a2 * (1.0 / 3840.0 - a2 * (1.0 / 645120.0
                                                                - a2 * (1.0 / 185794560.0)))))


def rotvec_terms(vx: float, vy: float, vz: float) -> tuple[float, float, float, float]:
    """The trigonometry of a rotation vector v of angle a: (cos(a/2), sin(a/2)/a) for
    quat_mul_rotvec and (sin(a)/a, (1 - cos a)/a^2) for rotate_back. Below a^2 = _SERIES_A2
    their Taylor series in a^2 (Horner's rule); above, from one sine-cosine pair of a/2, by
    sin a = 2 sin(a/2) cos(a/2) and 1 - cos a = 2 sin^2(a/2) (the second without the
    cancellation of 1 - cos a). A filter that turns its attitude and its pre-filter by the same
    interval computes them once."""
    a2 = vx * vx + vy * vy + vz * vz
    if a2 < _SERIES_A2:
        return (
            *_half_angle_series(a2),
            1.0 - a2 * (1.0 / 6.0 - a2 * (1.0 / 120.0 - a2 * (1.0 / 5040.0
                                                              - a2 * (1.0 / 362880.0)))),
            0.5 - a2 * (1.0 / 24.0 - a2 * (1.0 / 720.0 - a2 * (1.0 / 40320.0
                                                               - a2 * (1.0 / 3628800.0)))),
        )
    angle = sqrt(a2)
    ch, sh = cos(0.5 * angle), sin(0.5 * angle)
    return ch, sh / angle, 2.0 * sh * ch / angle, 2.0 * sh * sh / a2


def quat_mul_rotvec(
    q: tuple[float, float, float, float], vx: float, vy: float, vz: float,
    terms: tuple[float, float, float, float] | None = None,
) -> tuple[float, float, float, float]:
    """q (x) exp(v/2): rotate the body frame by the rotation vector v (body axes), renormalised;
    terms: rotvec_terms(vx, vy, vz) when the caller has them. q is a unit quaternion (to
    rounding, as every caller's is: a state check holds it within 1e-6), so the product's
    |r|^2 is 1 + O(eps) and one Newton step of 1/sqrt, 1.5 - 0.5 |r|^2, renormalises it to
    O(eps^2), below rounding: no square root and no division on the attitude's path from one
    sample to the next (a step from 1e-6 off leaves 1e-12, the next 1e-24)."""
    w, x, y, z = q
    c, s, _, _ = rotvec_terms(vx, vy, vz) if terms is None else terms
    bx, by, bz = s * vx, s * vy, s * vz
    rw = w * c - x * bx - y * by - z * bz
    rx = w * bx + x * c + y * bz - z * by
    ry = w * by - x * bz + y * c + z * bx
    rz = w * bz + x * by - y * bx + z * c
    n = 1.5 - 0.5 * (rw * rw + rx * rx + ry * ry + rz * rz)
    return rw * n, rx * n, ry * n, rz * n


def roll_pitch_ahead(
    roll: float, pitch: float, wx: float, wy: float, wz: float, delay: float
) -> tuple[float, float]:
    """Roll and pitch turned ahead by the body rate (wx, wy, wz) [rad/s] held for delay [s]: the
    attitude quaternion of roll and pitch (yaw 0, which the tilt does not depend on) times
    exp(w delay / 2), read back as roll and pitch."""
    q = quat_mul_rotvec(quat_from_roll_pitch_yaw(roll, pitch, 0.0), wx * delay, wy * delay,
                        wz * delay)
    return quat_roll_pitch(*q)


def rotation_increment(
    p0: float, q0: float, r0: float, p1: float, q1: float, r1: float, dt: float
) -> tuple[float, float, float]:
    """Body rotation vector over one interval from the rates w0 = (p0, q0, r0) and
    w1 = (p1, q1, r1) at its ends (trapezoid + coning).

    phi = (w0 + w1)/2 dt + (w0 dt x w1 dt)/12: the two-sample coning correction for a rate that is
    linear over the interval (Bortz 1971; Savage, Strapdown Analytics, eq. 7.1.1.1-11), so
    simultaneous rotation about several axes integrates without an O(dt^3) drift.
    """
    a0, a1, a2 = p0 * dt, q0 * dt, r0 * dt
    b0, b1, b2 = p1 * dt, q1 * dt, r1 * dt
    k = 1.0 / 12.0
    return (
        0.5 * (a0 + b0) + k * (a1 * b2 - a2 * b1),
        0.5 * (a1 + b1) + k * (a2 * b0 - a0 * b2),
        0.5 * (a2 + b2) + k * (a0 * b1 - a1 * b0),
    )


def rotation_back_matrix(phi: tuple[float, float, float],
                         terms: tuple[float, float, float, float]
                         ) -> tuple[float, float, float, float, float, float, float, float, float]:
    """rotate_back's rotation exp(-[phi]x) = I - sin(a)/a [phi]x + (1 - cos a)/a^2 [phi]x^2 as a
    matrix, row by row, from terms = rotvec_terms(*phi): a filter that turns several vectors by
    one interval (the measured vector's six stages) builds it once and turns each with nine
    products instead of Rodrigues' two cross products."""
    p0, p1, p2 = phi
    _, _, s, c = terms
    x0, x1, x2 = s * p0, s * p1, s * p2
    c01, c02, c12 = c * (p0 * p1), c * (p0 * p2), c * (p1 * p2)
    q0, q1, q2 = p0 * p0, p1 * p1, p2 * p2
    return (1.0 - c * (q1 + q2), x2 + c01, c02 - x1,
            c01 - x2, 1.0 - c * (q0 + q2), x0 + c12,
            x1 + c02, c12 - x0, 1.0 - c * (q0 + q1))


def up_terms(w: float, x: float, y: float, z: float) -> tuple[float, float, float, float]:
    """sin(roll) cos(pitch), cos(roll) cos(pitch), sin(pitch) and cos(pitch) of a unit
    quaternion: quat_roll_pitch's arguments (roll is the angle of the first two, pitch the
    arcsine of the third) and the length of the first two."""
    sr = 2.0 * (w * x + y * z)
    cr = 1.0 - 2.0 * (x * x + y * y)
    return sr, cr, 2.0 * (w * y - x * z), sqrt(sr * sr + cr * cr)


def angle_of(num: float, den: float) -> float:
    """atan2(num, den), the angle from one direction to another given the sine and cosine of
    their difference (each times the same positive length): below (num/den)^2 = _SERIES_T2 with
    den > 0, arctan's Taylor series in t = num/den (Estrin's scheme: four pairs of terms, then
    t^4 and t^8, so that few operations wait on each other), else atan2."""
    if den > 0.0 and num * num < _SERIES_T2 * (den * den):
        t = num / den
        t2 = t * t
        t4 = t2 * t2
        lo = (1.0 - t2 * (1.0 / 3.0)) + t4 * (1.0 / 5.0 - t2 * (1.0 / 7.0))
        hi = (1.0 / 9.0 - t2 * (1.0 / 11.0)) + t4 * (1.0 / 13.0 - t2 * (1.0 / 15.0))
        return t * (lo + (t4 * t4) * hi)
    return atan2(num, den)


def half_angle(a: float) -> tuple[float, float]:
    """cos(a/2) and sin(a/2): below a^2 = _SERIES_A2 rotvec_terms' series of cos(a/2) and of
    sin(a/2)/a (times a), else a sine-cosine pair."""
    a2 = a * a
    if a2 < _SERIES_A2:
        c, s_over_a = _half_angle_series(a2)
        return c, a * s_over_a
    return cos(0.5 * a), sin(0.5 * a)


def sin_cos(a: float) -> tuple[float, float]:
    """sin a and cos a from half_angle: 2 sin(a/2) cos(a/2) and 1 - 2 sin^2(a/2) (series for a
    below 0.1 rad, without the cancellation of 1 - cos a)."""
    ch, sh = half_angle(a)
    return 2.0 * sh * ch, 1.0 - 2.0 * sh * sh


def quat_turn_roll_pitch(q: tuple[float, float, float, float],
                         up: tuple[float, float, float, float], dr: float, dp: float
                         ) -> tuple[float, float, float, float]:
    """q with its roll grown by dr and its pitch by dp, its yaw kept; up = up_terms(*q), whose
    cos(pitch) must not be 0. With q = q_z(yaw) q_y(pitch) q_x(roll) (Z-Y-X Euler), the new
    attitude is q q_x(-roll) q_y(dp) q_x(roll) q_x(dr): q times a turn by dp about the body axis
    (0, cos roll, -sin roll), then one by dr about body x; no sine or cosine of roll or pitch,
    and those of dr/2 and dp/2 from half_angle."""
    cr, sr = half_angle(dr)
    cp, sp = half_angle(dp)
    sphi, cphi = up[0] / up[3], up[1] / up[3]
    a2, a3 = sp * cphi, -(sp * sphi)
    dw, dx, dy, dz = cp * cr, cp * sr, a2 * cr + a3 * sr, a3 * cr - a2 * sr
    w, x, y, z = q
    return (w * dw - x * dx - y * dy - z * dz,
            w * dx + x * dw + y * dz - z * dy,
            w * dy - x * dz + y * dw + z * dx,
            w * dz + x * dy - y * dx + z * dw)


def rotate_back(v: tuple[float, float, float], phi: tuple[float, float, float],
                terms: tuple[float, float, float, float] | None = None
                ) -> tuple[float, float, float]:
    """v as seen from a body that turned by the rotation vector phi: exp(-[phi]x) v (Rodrigues),
    v - sin(a)/a (phi x v) + (1 - cos a)/a^2 phi x (phi x v), a = |phi|; terms:
    rotvec_terms(*phi) when the caller has them."""
    p0, p1, p2 = phi
    _, _, s, c = rotvec_terms(p0, p1, p2) if terms is None else terms
    v0, v1, v2 = v
    u0, u1, u2 = p1 * v2 - p2 * v1, p2 * v0 - p0 * v2, p0 * v1 - p1 * v0  # phi x v
    return (
        v0 - s * u0 + c * (p1 * u2 - p2 * u1),
        v1 - s * u1 + c * (p2 * u0 - p0 * u2),
        v2 - s * u2 + c * (p0 * u1 - p1 * u0),
    )

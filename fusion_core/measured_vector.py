"""The vector the filters measure, and its measurement noise: the accelerometer side of every
recommended estimator (cf, mgcf, kf, ukf), one mechanism with named state.

An accelerometer sample is gravity plus the body's linear acceleration plus white noise. The
filters do not measure the raw sample; they measure a low-passed specific force that turns with
the gyro (Laidig & Seel 2023, VQF: in an almost inertial frame gravity is constant and the linear
acceleration of a body that ends where it started averages to its velocity change over time).
Seven things follow, and this module is each of them:

1. The measured vector `f` is a second-order low-pass: two first-order stages of time constant
   acc_lowpass / 2 each, every stage turned by the gyro's rotation increment. A second-order
   filter passes a disturbance at frequency w with (w tau)^-2 where a first-order one passes
   (w tau)^-1: a hand shaking the sensor at 3 Hz reaches the vector at a few thousandths of its
   amplitude instead of a few hundredths (VQF's own pre-filter is a second-order Butterworth).
   Its length adapts as the first-order pre-filter's did: it shortens towards the raw sample
   where the disturbance it should average is no more than the white noise
   (building_blocks.adaptive_prefilter_time), since then the raw sample carries no memory of the
   gyro's scale errors. While it first fills (the first acc_lowpass after the first sample) each
   stage's time constant is half the time since then, so the vector is a weighted mean of the
   samples so far in which none weighs more than 1.5 / n, never one sample's tilt.
2. Its measurement noise `r` (a tilt variance, rad^2) is one sample's white variance plus the
   disturbance that reaches the vector: the linear acceleration slower than what the
   pre-filter removes. That part is measured as the mean square difference between a short
   second-order low-pass (BAND_PARAM: two stages of slow_band_time) and the full-length
   reference, less the white noise's share that passes the short one: shaking and vibration,
   which the pre-filter removes, do not count; the slow swing of a translation or of a combined
   motion does, in full, since a filter that assumes white measurement noise cannot average a
   disturbance that stays for seconds. While the sensor turns, the two low-passes also part
   because the gyro that turns them is off by a fraction of the rate (its scale-factor error
   and two cross-axis sensitivities: sigma = sqrt(3) gyro_scale_std, each of that std): each
   holds samples turned by the gyro since they came, so each is off by sigma times the angle
   the sensor turned since its samples, weighted as it weighs them (its lag, `lag_ref` and
   `lag_s`: a rotation vector low-passed as the samples are), and the two part by g sigma
   times the difference of their lags. At a steady rate w that is |w| times the difference of
   their delays; a swing that turns back within the vector's length parts them by less, as
   far as it turned back. That is no linear acceleration, and the process noise already holds
   it (ADAPTIVE_NOISE_PARAMS' rotation term), so the statistic leaves it out: counted as
   disturbance, it slows the correction in exactly the rotations where a gyro's scale error
   asks for a faster one (the realistic sensor's high_dynamics).
   The statistic rises within DISTURBANCE_ATTACK (a disturbance that starts counts before a filter
   learns a gyro bias from it) and decays over disturbance_time.
3. A gyro sample at its rail (the sensor's gyro_range, base.Estimator) is no measurement of the
   rate: the vectors turned with it are wrong by the rate beyond the rail, as the attitude is.
   `settle` then counts the time since (measure_clipped), and a filter learns no gyro bias from
   the accelerometer until it has reached the full length: until then the vector holds samples
   turned by the rotation the gyro did not measure. The vector itself goes on: started again
   from the sample at the rail it would be that one sample's tilt, and on the synthetic
   gyro_clipping scenario the complementary filter's error would be several times larger.

4. The vector grows longer (up to acc_lowpass_stretch times, STRETCH_PARAM) where linear
   acceleration slower than it reaches it: a hand carrying a turning sensor back and forth with
   periods of 5-8 s passes a 1.5 s vector at about two thirds of its amplitude, and the filters
   then trust a vector degrees off (BROAD's combined trial 32, where VQF's 3 s vector is
   ahead). A longer vector costs in two ways. It turns with the gyro's scale
   error for longer, so it grows only by the share of the slow band that the turn of the longer
   vector would not explain (`stretched`, with the mean square rate over a stage, `rate2`): in
   BROAD's rotation trials and in the contract's sweeps it keeps its length. And it turns with
   the estimated gyro bias for longer: the attitude and the vector then drift together, and the
   innovation a bias error leaves shrinks from the correction time to the correction time less
   the vector's lag, so a bias learned wrongly is unlearned more slowly: a filter started in a
   moving hand learns a wrong bias from its first seconds, and a long vector keeps it
   (tests/test_start_alignment.py). So the vector grows only once a rest has measured the bias
   (the filters' rest detector, `bias_measured`), as at the start of most recordings and of
   every BROAD trial. What each of these is worth out of sample: docs/results/mechanisms.md
   (`imu-fusion mechanisms`).

5. The slow band's second-order low-pass still passes a fast disturbance at (w b)^-4 of its
   power, b = slow_band_time: a running torso's 2.8 Hz bounce of 1.1 g reaches it at about 1.6 %
   (0.9 m^2/s^4 of disturbance), while the vector (two stages of acc_lowpass / 2) passes 3e-5 of
   it. Counted as disturbance, that leak makes a filter trust the accelerometer less in
   exactly the motions whose fast content the vector removes. The band's two stages measure
   the leak themselves: before the first stage the fast power is all there (`band_in`, the
   mean square of a - s1), after it 1/(w b)^2 of it is left (`band_mid`, s1 - s), so after the
   second it is band_mid^2 / band_in, at any frequency above the corner and without a value
   to tune (LEAK_PARAM: the share taken off; 1, all of it). Near the corner the estimate falls
   to a fraction of what passes, so the slow swing of a translation still counts (a 0.3 Hz sway
   keeps more than 90 % of it, tests/test_adaptive_noise.py). The
   leak's mean is taken off each sample before the statistic's peak follower, which still
   catches its ripple (a tone along one axis swings between none and twice its mean): a bounce
   then counts about half as much as before, not nothing.
6. The statistic counts no more than a held linear acceleration can be (HELD_PARAM): one held
   longer than the vector tilts it by atan(a / g), and beyond gross_innovation's 30 deg
   (0.58 g held for seconds, more than a hand or a vehicle holds;
   building_blocks.GROSS_INNOVATION) what reaches the slow band is mostly no linear
   acceleration but absurd samples, a knock or a restart; a real one past it (a synthetic
   scenario's seconds of 0.7 g) leaves the vector's tilt uncertain by 30 deg and more, and the
   capped noise already gives the accelerometer that little weight. Counted in full, the
   statistic after such a burst
   makes the vector's tilt uncertain by radians, and stays so for disturbance_time times the
   logarithm of its size over the held level: just when the attitude the burst threw, its
   variance raised to the innovation's (gross_innovation), needs the accelerometer to come
   back. Capped, the measurement noise is at most tan^2 30 deg = 1/3 rad^2 over one sample's,
   the most a held acceleration makes (tests/test_adaptive_noise.py). The kf caps it; the
   cf, the mgcf and the ukf do not (complementary.CF_HELD, mgcf.MGCF_HELD, ukf.UKF_HELD give
   why).
7. A burst: samples of no motion (a glitch, a bus returning garbage, each value within the
   ranges so that no rule of the input stage refuses it) reach the vector as a disturbance the
   filters then follow back to gravity over two or three times its length, tens of degrees off
   for five to ten seconds after one second of them. Two things tell them from any motion: the
   slow band parts from the reference by more than a body's linear acceleration moves it
   (BURST_PARAM, g), and the fast power is as white as independent samples', the mean square
   change from one sample to the next (`diff`) above the fast power itself (`band_in`):
   independent samples give about twice it, a body's motion at f well below the sampling rate
   (2 pi f dt)^2 of it. A fast hand's translation may part the slow band by nearly as much, but
   smoothly; a tap is white, but too short to part the slow band. The vector takes none of a
   burst's samples: it is only turned with the gyro, as the attitude is, and `fresh` counts the
   time since the last. After the burst it fills again as after the first sample (each stage
   half the time since), a mean of the samples since the burst, none older, and the filters
   take it as they take a filling vector (its tilt, no gyro bias learned from it). The first
   fill is no burst: the reference is as short then. The contract's scenarios, the battery's
   motions on the parts that do not glitch and BROAD's trials hold none (tests/test_burst.py).

The statistic of the adaptive length (`dist`: the raw sample against the full-length reference)
is the first-order pre-filter's, kept: it decides whether there is anything to average.
"""

from __future__ import annotations

import math
from typing import Final, NamedTuple

from .building_blocks import (
    GROSS_INNOVATION,
    PREFILTER_FULL,
    Vec3,
    adaptive_prefilter_time,
    lowpass_specific_force,
    on_the_mark,
)
from .kinematics import rotation_back_matrix
from .linalg import Mat9, mat_vec
from .state import NONNEG, REAL, Segments
from .types import G, Param

ZERO: Final = (0.0, 0.0, 0.0)
"""No lag: a low-pass whose samples all came at this attitude."""
DISTURBANCE_ATTACK: Final = 0.05
"""Time constant [s] with which the slow-band statistic rises. A disturbance that starts (the
onset of a move, a burst of linear acceleration) must count in the measurement noise before a
Kalman filter takes its apparent tilt for a gyro bias's drift (a statistic that rose as slowly
as it falls, over disturbance_time, let the kf learn a bias of degrees per second at the onset of
the contract's high_dynamics moves). It falls over disturbance_time."""
BAND_PARAM: Final = Param(
    "slow_band_time", 0.15,
    "Time constant of each stage of the short low-pass that splits the measured linear "
    "acceleration: the part it passes (below about 1/(4 pi slow_band_time) Hz) reaches the "
    "pre-filtered vector and counts in its measurement noise; faster disturbance (shaking, "
    "vibration) the second-order pre-filter removes",
    unit="s", low=0.01, high=10.0,
)
"""Recommended 0.15 s: a corner near 0.5 Hz, below hand shaking (3-8 Hz) and vibration, above
the swing of a translation or a combined motion. Chosen by cross-validation over BROAD's groups of
trials (`python -m testbenches broad --cv`), with the synthetic shaking scenario as the check of
the fast side."""
LEAK_PARAM: Final = Param(
    "slow_band_leak", 1.0,
    "Share of the fast disturbance that leaks through the slow band (estimated from the power "
    "before and between its two stages) taken off its statistic: shaking, running and waving "
    "that the pre-filter removes then do not count as disturbance (0: the band's output as it "
    "is)",
    low=0.0, high=1.0,
)
"""Recommended 1: the estimate is the leak's mean (module docstring, item 5); nothing is fitted.
`imu-fusion mechanisms` scores it against 0 (docs/results/mechanisms.md)."""
HELD_PARAM: Final = Param(
    "held_acceleration", G * math.tan(GROSS_INNOVATION),
    "The largest linear acceleration the slow band's statistic counts: more than a body holds "
    "for seconds (absurd samples, a knock) raises the measurement noise no further, so that it "
    "falls back as after a hard real move (0: no limit)",
    unit="m/s2", low=0.0, high=1000.0,
)
"""Recommended g tan(30 deg) = 5.66 m/s^2 (0.58 g): the acceleration that tilts a held vector by
gross_innovation's 30 deg (building_blocks.GROSS_INNOVATION), the largest tilt the filters take
for linear acceleration rather than for an attitude grossly off; derived, not fitted. Module
docstring, item 6."""
STRETCH_PARAM: Final = Param(
    "acc_lowpass_stretch", 2.0,
    "The longest the measured vector may grow, as a multiple of acc_lowpass, once a rest has "
    "measured the gyro bias and while the slow band finds more linear acceleration reaching the "
    "vector than the gyro's scale error would turn a vector of that length by (1: never longer "
    "than acc_lowpass)",
    low=1.0, high=10.0,
)
"""Recommended 2: 3 s at acc_lowpass 1.5 s, the time constant of VQF's vector, where the slow
combined motion from rest (tests/test_slow_combined_motion.py) comes within VQF + 10 %. The
cross-validation over BROAD's motion folds (testbenches.broad.cv.CV_GRID holds 1, 1.5 and 2)
chooses 1.5 or 2 without every fold, never 1. Module docstring, item 4."""
BURST_PARAM: Final = Param(
    "burst_acceleration", G,
    "How far the slow band may part from the full-length reference, its fast power as white as "
    "independent samples', before the samples are taken for a burst of no motion (a glitch): the "
    "measured vector takes none of them and fills again from the samples after it (0: never)",
    unit="m/s2", low=0.0, high=1000.0,
)
"""Recommended g: the slow band parting from the reference by g means the specific force's slow
part moved by as much as gravity itself within the vector's length, more than a car's braking
or a hand's carrying; a fast hand's translation comes near it but not with white fast power,
while samples anywhere in the ranges part the two by more (their spread is several g).
Derived, not fitted. Module docstring, item 7."""
MEASURE_CHECK: Final = Segments(((REAL, 18), (NONNEG, 7), (REAL, 12), (REAL, 3), (NONNEG, 2)))
"""The state check of a Measure (fusion_core.state): six vectors, two mean squares, two
times, a mean square rate, the slow band's two fast powers, four lag angles, the last sample,
the mean square of its changes and the time since a burst."""


class Measure(NamedTuple):
    """The measured vector's state: each second-order low-pass as its two stages (the first
    stage, then the output), all turned with the gyro, and the two disturbance statistics."""

    f1: Vec3
    f: Vec3
    """The measured vector: the pre-filtered specific force (adaptive length)."""
    ref1: Vec3
    ref: Vec3
    """The full-length reference of both statistics (acc_lowpass, not adaptive)."""
    s1: Vec3
    s: Vec3
    """The short low-pass of the slow band (slow_band_time)."""
    dist: float
    """Mean square of raw - ref [m^2/s^4] over disturbance_time: the adaptive length's."""
    slow: float
    """Mean square of s - ref [m^2/s^4]: the slow band that reaches f."""
    fill: float
    """Time [s] since the first sample, counted up to the full length (acc_lowpass)."""
    settle: float
    """Time [s] since the last gyro sample at its rail, counted up to the full length (the full
    length from the start)."""
    rate2: float
    """Mean square rate [rad^2/s^2] over one stage (acc_lowpass / 2): what a longer vector would
    turn with (the stretch, module docstring item 4)."""
    band_in: float
    """Mean square of a - s1 [m^2/s^4] over disturbance_time: the fast power before the slow
    band's first stage (module docstring, item 5)."""
    band_mid: float
    """Mean square of s1 - s [m^2/s^4] over disturbance_time: what of it the first stage lets
    through."""
    lag_ref1: Vec3
    lag_ref: Vec3
    """The reference's lag [rad]: the rotation vector the sensor turned since the samples each
    of its stages holds, weighted as the stage weighs them (module docstring, item 2)."""
    lag_s1: Vec3
    lag_s: Vec3
    """The slow band's lag [rad], the same for its stages."""
    prev: Vec3
    """The last raw sample [m/s^2]."""
    diff: float
    """Mean square of the change from one raw sample to the next [m^2/s^4] over
    disturbance_time: beside band_in, how white the fast power is (item 7)."""
    fresh: float
    """Time [s] since the last sample of a burst (the slow band further from the reference than
    burst_acceleration, its fast power white), counted up to the full length (the full length
    from the start): the vector fills again from the samples since (module docstring, item 7)."""

    def settled(self, c: MeasureConstants) -> bool:
        """Whether the vector holds no sample turned by a rotation the gyro did not measure (no
        sample at the rail, or a full length since the last one): a filter may learn a gyro bias
        from it."""
        return self.settle >= 2.0 * c.stage


def measure_start(a: Vec3, c: MeasureConstants) -> Measure:
    """The state at a first sample a: every low-pass starts at it, no disturbance measured, and
    settled (no gyro sample at its rail yet: the vector holds no rotation the gyro missed)."""
    return Measure(a, a, a, a, a, a, 0.0, 0.0, 0.0, 2.0 * c.stage, 0.0, 0.0, 0.0, ZERO, ZERO,
                   ZERO, ZERO, a, 0.0, 2.0 * c.stage)


class MeasureConstants(NamedTuple):
    """What measure_step needs of the parameters, derived once (measure_constants)."""

    stage: float
    """acc_lowpass / 2: each stage's time constant [s]."""
    dist_tau: float
    """disturbance_time [s] (0: no statistics; the full-length, constant pre-filter)."""
    noise: float
    """The white noise's share of the raw statistic: 3 axes of one sample's variance
    [m^2/s^4]."""
    band: float
    """slow_band_time [s] (0: no slow band measured)."""
    r: float
    """One sample's tilt variance [rad^2], the white part of the measurement noise."""
    turn: float
    """(g sigma)^2 [m^2/s^4] with sigma = sqrt(3) gyro_scale_std, the gyro's rate error as a
    fraction of the rate: the slow band's share per rad^2 of lag between its two low-passes
    that a turn explains (module docstring, item 2)."""
    stretch: float
    """acc_lowpass_stretch: the longest vector as a multiple of the full length (1: none)."""
    leak: float
    """slow_band_leak: the share of the slow band's estimated fast leak taken off its statistic
    (0: none)."""
    held2: float
    """held_acceleration squared [m^2/s^4]: the most the slow band's statistic counts (0: no
    limit)."""
    burst2: float
    """burst_acceleration squared [m^2/s^4]: a slow band further from the reference is a burst
    (0: none is)."""


def measure_constants(acc_lowpass: float, disturbance_time: float, band: float, r: float,
                      gyro_scale_std: float, stretch: float = 1.0, leak: float = 0.0,
                      held: float = 0.0, burst: float = 0.0) -> MeasureConstants:
    """The constants of measure_step from the parameters, one sample's tilt variance r, the
    gyro's scale uncertainty (0: no turn discounted from the slow band), the longest vector's
    multiple of acc_lowpass (STRETCH_PARAM; 1: none), the share of the slow band's fast leak
    taken off its statistic (LEAK_PARAM; 0: none), the largest linear acceleration it counts
    (HELD_PARAM; 0: no limit) and the distance of a burst (BURST_PARAM; 0: none)."""
    return MeasureConstants(0.5 * acc_lowpass, disturbance_time, 3.0 * r * G * G, band, r,
                            3.0 * gyro_scale_std * gyro_scale_std * G * G, stretch, leak,
                            held * held, burst * burst)


def two_stage_noise(k: float) -> float:
    """The share of white noise's variance that passes two first-order stages of gain k each:
    k^4 (1 + a^2) / (1 - a^2)^3 with a = 1 - k (about k / 4 for a small k)."""
    a2 = (1.0 - k) * (1.0 - k)
    d = 1.0 - a2
    return k * k * k * k * (1.0 + a2) / (d * d * d)


def _lowpass2(s1: Vec3, s: Vec3, back: Mat9, a: Vec3, dt: float, tau: float
              ) -> tuple[Vec3, Vec3]:
    """One step of a second-order low-pass: two first-order stages of time constant tau, each
    turned by back (building_blocks.lowpass_specific_force)."""
    k = dt / (tau + dt)
    s1 = lowpass_specific_force(s1, back, a, k)
    return s1, lowpass_specific_force(s, back, s1, k)


def _lag2(l1: Vec3, lag: Vec3, back: Mat9, phi: Vec3, k: float) -> tuple[Vec3, Vec3]:
    """One step of the lags of a second-order low-pass's two stages (each of gain k): every
    sample a stage holds has turned by phi more (the lags turned with the body by back, as the
    stages' vectors are), and the new sample comes with none (the first stage's input) or with
    the first stage's lag (the second's)."""
    j = 1.0 - k
    a0, a1, a2 = mat_vec(back, l1)
    l1 = (j * (a0 + phi[0]), j * (a1 + phi[1]), j * (a2 + phi[2]))
    b0, b1, b2 = mat_vec(back, lag)
    return l1, (j * (b0 + phi[0]) + k * l1[0], j * (b1 + phi[1]) + k * l1[1],
                j * (b2 + phi[2]) + k * l1[2])


def measure_step(m: Measure, a: Vec3, phi: Vec3, terms: tuple[float, float, float, float],
                 dt: float, c: MeasureConstants, bias_measured: bool = False
                 ) -> tuple[Measure, float, bool]:
    """One sample a of the measured vector (the module docstring), phi the interval's rotation
    vector with its rotvec_terms; bias_measured: whether a rest has measured the gyro bias (the
    vector may then grow longer, item 4). Returns the new state (its f is the measured vector),
    the measurement noise r [rad^2] and whether the vector is filling (after the first sample,
    or again after a burst)."""
    (f1, f, ref1, ref, s1, s, dist, slow, fill, settle, rate2, band_in, band_mid, lag_ref1,
     lag_ref, lag_s1, lag_s, prev, diff, fresh) = m
    stage = c.stage
    full = 2.0 * stage
    if settle < full:  # the times counted up to the full length (building_blocks.on_the_mark)
        settle = on_the_mark(settle + dt, dt, full)
    if fresh < full:
        fresh = on_the_mark(fresh + dt, dt, full)
    filling = fill < full
    if filling:  # a mean of the samples so far (each stage half the time since the start)
        fill = on_the_mark(fill + dt, dt, full)
        stage = 0.5 * fill if fill < full else stage
    r = c.r
    tau = stage
    back = rotation_back_matrix(phi, terms)  # once, for the six stages
    burst = False
    if c.dist_tau > 0.0:
        ref1, ref = _lowpass2(ref1, ref, back, a, dt, stage)
        e0, e1, e2 = a[0] - ref[0], a[1] - ref[1], a[2] - ref[2]
        k = dt / (c.dist_tau + dt)  # one step of a mean over disturbance_time
        dist += k * (e0 * e0 + e1 * e1 + e2 * e2 - dist)
        if not filling:
            tau = stage * adaptive_prefilter_time(1.0, dist, c.noise)
        if c.band > 0.0:  # the slow band (band 0: not measured, r stays white: raw_noise's users)
            s1, s = _lowpass2(s1, s, back, a, dt, c.band)
            e0, e1, e2 = s[0] - ref[0], s[1] - ref[1], s[2] - ref[2]
            inst = e0 * e0 + e1 * e1 + e2 * e2
            # less what the gyro's rate error turns the two apart by: sigma times the
            # difference of their lags (item 2)
            lag_ref1, lag_ref = _lag2(lag_ref1, lag_ref, back, phi, dt / (stage + dt))
            lag_s1, lag_s = _lag2(lag_s1, lag_s, back, phi, dt / (c.band + dt))
            d0, d1, d2 = lag_ref[0] - lag_s[0], lag_ref[1] - lag_s[1], lag_ref[2] - lag_s[2]
            turn = c.turn * (d0 * d0 + d1 * d1 + d2 * d2)
            inst = inst - turn if inst > turn else 0.0
            # the fast power before the band's first stage, and that of the change from one
            # sample to the next: about twice it for white samples, a small share of it for a
            # body's motion well below the sampling rate (item 7)
            h0, h1, h2 = a[0] - s1[0], a[1] - s1[1], a[2] - s1[2]
            band_in += k * (h0 * h0 + h1 * h1 + h2 * h2 - band_in)
            d0, d1, d2 = a[0] - prev[0], a[1] - prev[1], a[2] - prev[2]
            diff += k * (d0 * d0 + d1 * d1 + d2 * d2 - diff)
            if c.leak > 0.0:  # less the fast disturbance that leaks through the band (item 5)
                q0, q1, q2 = s1[0] - s[0], s1[1] - s[1], s1[2] - s[2]
                band_mid += k * (q0 * q0 + q1 * q1 + q2 * q2 - band_mid)
                leak = c.leak * band_mid * band_mid / band_in if band_in > 0.0 else 0.0
                inst = inst - leak if inst > leak else 0.0
            # further from the reference than a body's linear acceleration moves it, and fast
            # power as white as samples of no motion: a burst (item 7; not while the vector
            # first fills, when the reference is as short)
            burst = c.burst2 > 0.0 and inst > c.burst2 and diff > band_in and not filling
            if c.held2 > 0.0 and inst > c.held2:  # no more than a held acceleration (item 6)
                inst = c.held2
            rise = DISTURBANCE_ATTACK if inst > slow else c.dist_tau
            slow += dt / (rise + dt) * (inst - slow)
            w2 = (phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]) / (dt * dt)
            rate2 += dt / (stage + dt) * (w2 - rate2)
            excess = slow - c.noise * two_stage_noise(dt / (c.band + dt))
            if excess > 0.0:
                r += excess / (G * G)
                if c.stretch > 1.0 and bias_measured and not filling:
                    tau = tau * stretched(c, excess, rate2, 2.0 * (stage - c.band), full)
    if burst:  # none of the burst's samples: the vector turned with the gyro alone (item 7)
        fresh = 0.0
        f1, f = mat_vec(back, f1), mat_vec(back, f)
    else:
        if fresh < full and not filling:  # after a burst, a mean of the samples since
            tau = 0.5 * fresh
        f1, f = _lowpass2(f1, f, back, a, dt, tau)
    return (Measure(f1, f, ref1, ref, s1, s, dist, slow, fill, settle, rate2, band_in, band_mid,
                    lag_ref1, lag_ref, lag_s1, lag_s, a, diff, fresh), r,
            filling or fresh < full)


def stretched(c: MeasureConstants, excess: float, rate2: float, lag: float, full: float
              ) -> float:
    """The measured vector's length as a multiple of the full length (1 to c.stretch), from the
    slow band's excess over the white noise [m^2/s^4], the mean square rate rate2, the slow
    band's lag against the reference [s] and the full length [s] (module docstring, item 4).

    A vector k = stretch^2 times as long in lag passes what of the slow band lies below its
    corner at about (1/stretch)^2 of its power, and turns with a gyro's scale error by k times
    the turn: c.turn rate2 full^2 at the full length. The slow band is measured against the full
    length, with one turn discounted (measure_step); counted at the longer vector's scale, k - 1
    more of it is turn, not linear acceleration. What is left, over the turn the longest vector
    would carry (and PREFILTER_FULL times the white noise, below which nothing is worth
    averaging), is the share of the stretch taken: the vector grows where linear acceleration
    slower than it reaches it and the gyro's turn would cost less."""
    k = c.stretch * c.stretch
    ts = c.turn * rate2
    left = excess - (k - 1.0) * ts * (lag * lag)
    x = left / (PREFILTER_FULL * c.noise + k * ts * (full * full))
    if x <= 0.0:
        return 1.0
    return 1.0 + (c.stretch - 1.0) * (x if x < 1.0 else 1.0)


def fill_noise(m: Measure, r: float, dt: float, c: MeasureConstants) -> tuple[float, float]:
    """While the vector fills, its tilt variance and its samples' mean age [s] (half the fill):
    one sample's white variance as much as passes two stages each of half the time since the
    start or the last burst (two_stage_noise), plus the disturbance in r (measure_step's noise,
    less c.r). A filter that takes the vector's tilt then is that sure of it, and a bias error
    has turned it over that age (kalman.measured_axis, ukf.measured_covariance)."""
    age = 0.5 * (m.fill if m.fill < m.fresh else m.fresh)
    return c.r * two_stage_noise(dt / (age + dt)) + (r - c.r), age


def gate_norm2(m: Measure, c: MeasureConstants, raw2: float) -> float:
    """The squared norm [m^2/s^4] a bias gate judges: the slow band's output where it is measured
    (slow_band_time > 0, the statistics on), else the raw sample's, raw2. A bias gate keeps the
    linear acceleration that reaches the measured vector out of the bias; the slow band holds
    the specific force below its corner (about 1 Hz at 0.15 s), so a move's acceleration
    sustained for a second or more shows in its norm, while a shaking hand's 3-8 Hz, which
    keeps the raw sample's norm off g at almost every sample and which the vector does not
    hold, leaves the bias free to learn what a start-up calibration left (0.16 deg/s on the
    realistic sensor, tenths of a degree of tilt over a shaking's correction time). The
    contract's shaking and high_dynamics over parts show the difference (`python -m
    testbenches run --scenario shaking,high_dynamics --seeds 20 --estimator kf,ukf
    --no-contract`)."""
    if band_measured(c):
        s0, s1, s2 = m.s
        return s0 * s0 + s1 * s1 + s2 * s2
    return raw2


def within_bias_band(m: Measure, c: MeasureConstants, band2: tuple[float, float], a2: float,
                     raw2: float) -> bool:
    """Whether a bias may be learned from this sample by the bias gate band2 = (lo, hi), squared
    norms [m^2/s^4]: what reaches the measured vector (gate_norm2; raw2 the raw sample's squared
    norm) within it and, where that is the slow band, what the vector still holds (a2, its own
    squared norm) too."""
    lo, hi = band2
    n2 = gate_norm2(m, c, raw2)
    return lo < n2 < hi and (lo < a2 < hi or not band_measured(c))


def band_measured(c: MeasureConstants) -> bool:
    """Whether the slow band is measured (slow_band_time > 0, the statistics on)."""
    return c.dist_tau > 0.0 and c.band > 0.0


def raw_noise(m: Measure, c: MeasureConstants) -> float:
    """The measurement noise [rad^2] sized by the raw sample's disturbance (`dist`, all of the
    linear acceleration against the full-length reference, fast or slow) instead of the slow band
    alone: one sample's white variance plus that disturbance's excess over the white noise, over
    g^2. An upper bound of what reaches the vector, for a filter that learns its bias from every
    error its correction passes (mgcf.GainScheduledComplementaryFilter)."""
    excess = m.dist - c.noise
    return c.r + excess / (G * G) if excess > 0.0 else c.r


def measure_aligned(m: Measure, f: Vec3) -> Measure:
    """The state with every low-pass at f (a rest alignment: the rest's mean specific force)
    and no lag, the statistics kept."""
    return m._replace(f1=f, f=f, ref1=f, ref=f, s1=f, s=f, lag_ref1=ZERO, lag_ref=ZERO,
                      lag_s1=ZERO, lag_s=ZERO)


def measure_restarted(m: Measure, f: Vec3) -> Measure:
    """The state at the first rest of a Kalman filter: every low-pass at the rest's mean
    specific force f, and the slow band from nothing (it read the vectors' disagreement, turned
    with a bias not yet measured, as disturbance)."""
    return measure_aligned(m, f)._replace(slow=0.0)


def measure_clipped(m: Measure) -> Measure:
    """The state after a gyro sample at its rail: the vector goes on (starting it again from one
    sample costs more than the turn it carries), but the settle time starts again, so the
    filters learn no bias until the turned samples have left its memory."""
    return m._replace(settle=0.0)


def measure_turned(m: Measure, turn) -> Measure:  # type: ignore[no-untyped-def]
    """The state with every vector turned by turn (a function of a vector: the kf's face
    switch), the lags and the last sample too."""
    return m._replace(f1=turn(m.f1), f=turn(m.f), ref1=turn(m.ref1), ref=turn(m.ref),
                      s1=turn(m.s1), s=turn(m.s), lag_ref1=turn(m.lag_ref1),
                      lag_ref=turn(m.lag_ref), lag_s1=turn(m.lag_s1), lag_s=turn(m.lag_s),
                      prev=turn(m.prev))

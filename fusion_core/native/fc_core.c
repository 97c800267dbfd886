/* fc_core.c: see fc_core.h. Each function names its Python twin; the operations are the
 * twin's, in its order. */
#include "fc_core.h"

#include <math.h>
#include <string.h>

#define MIN_COS_PITCH 1e-9   /* kinematics._MIN_COS_PITCH */
#define SERIES_A2 1e-2       /* kinematics._SERIES_A2 */
#define PREFILTER_FULL 4.0   /* building_blocks.PREFILTER_FULL */

/* ----- kinematics.py ----------------------------------------------------------------------- */

fc_real fc_wrap_angle(fc_real x)  /* wrap_angle */
{
    return fc_remainder(x, FC_TWO_PI);
}

fc_real fc_clamp_pitch(fc_real theta)  /* clamp_pitch */
{
    theta = theta < FC_HALF_PI ? theta : FC_HALF_PI;
    return theta > -FC_HALF_PI ? theta : -FC_HALF_PI;
}

void fc_accel_roll_pitch(fc_real ax, fc_real ay, fc_real az, fc_real *roll, fc_real *pitch)
{
    *roll = fc_atan2(ay, az);
    *pitch = fc_atan2(-ax, fc_sqrt(ay * ay + az * az));
}

void fc_roll_pitch_sines(fc_real roll, fc_real pitch, fc_real sc[4])
{
    sc[0] = fc_sin(roll);
    sc[1] = fc_cos(roll);
    sc[2] = fc_sin(pitch);
    sc[3] = fc_cos(pitch);
}

/* euler_rates (with the fc_cos(pitch) guard of heun_euler_step) from sc, the sines and cosines
 * of phi and theta (fc_roll_pitch_sines) */
static void euler_rates(const fc_real sc[4], fc_real p, fc_real q, fc_real r, fc_real *dphi,
                        fc_real *dtheta)
{
    fc_real sp = sc[0], cp = sc[1], st = sc[2], ct = sc[3];
    if (-MIN_COS_PITCH < ct && ct < MIN_COS_PITCH) {
        ct = fc_copysign(MIN_COS_PITCH, ct);
    }
    *dphi = p + (q * sp + r * cp) * st / ct;
    *dtheta = q * cp - r * sp;
}

void fc_euler_step(fc_real phi, fc_real theta, fc_real p, fc_real q, fc_real r, fc_real dt,
                   const fc_real sc[4], fc_real *phi_out, fc_real *theta_out)
{
    fc_real dp, dtheta, s[4];
    if (!sc) {
        fc_roll_pitch_sines(phi, theta, s);
        sc = s;
    }
    euler_rates(sc, p, q, r, &dp, &dtheta);
    *phi_out = phi + dt * dp;
    *theta_out = theta + dt * dtheta;
}

void fc_heun_euler_step(fc_real phi, fc_real theta, fc_real p0, fc_real q0, fc_real r0, fc_real p1,
                        fc_real q1, fc_real r1, fc_real dt, const fc_real sc[4], fc_real *phi_out,
                        fc_real *theta_out)
{
    fc_real d1p, d1t, d2p, d2t, s[4], s1[4], sa, ca, sb, cb;
    if (!sc) {
        fc_roll_pitch_sines(phi, theta, s);
        sc = s;
    }
    euler_rates(sc, p0, q0, r0, &d1p, &d1t);
    fc_real a = dt * d1p, b = dt * d1t;  /* the step: the end point's sines by angle addition */
    fc_sin_cos(a, &sa, &ca);
    fc_sin_cos(b, &sb, &cb);
    s1[0] = sc[0] * ca + sc[1] * sa;
    s1[1] = sc[1] * ca - sc[0] * sa;
    s1[2] = sc[2] * cb + sc[3] * sb;
    s1[3] = sc[3] * cb - sc[2] * sb;
    euler_rates(s1, p1, q1, r1, &d2p, &d2t);
    *phi_out = phi + 0.5 * dt * (d1p + d2p);
    *theta_out = theta + 0.5 * dt * (d1t + d2t);
}

void fc_quat_from_roll_pitch_yaw(fc_real phi, fc_real theta, fc_real psi, fc_real q[4])
{
    fc_real cr = fc_cos(0.5 * phi), sr = fc_sin(0.5 * phi);
    fc_real cp = fc_cos(0.5 * theta), sp = fc_sin(0.5 * theta);
    fc_real cy = fc_cos(0.5 * psi), sy = fc_sin(0.5 * psi);
    q[0] = cr * cp * cy + sr * sp * sy;
    q[1] = sr * cp * cy - cr * sp * sy;
    q[2] = cr * sp * cy + sr * cp * sy;
    q[3] = cr * cp * sy - sr * sp * cy;
}

void fc_quat_roll_pitch(const fc_real q[4], fc_real *roll, fc_real *pitch)
{
    fc_real w = q[0], x = q[1], y = q[2], z = q[3];
    fc_real sr = 2.0 * (w * x + y * z), cr = 1.0 - 2.0 * (x * x + y * y);
    *roll = cr > 0.0 ? fc_atan(sr / cr) : fc_atan2(sr, cr);
    fc_real s = 2.0 * (w * y - x * z);
    if (!(-1.0 <= s && s <= 1.0)) {
        s = s < 1.0 ? s : 1.0;     /* max(-1, min(1, s)) */
        s = -1.0 > s ? -1.0 : s;
    }
    *pitch = fc_asin(s);
}

void fc_quat_gravity_body(const fc_real q[4], fc_real g[3])
{
    fc_real w = q[0], x = q[1], y = q[2], z = q[3];
    g[0] = 2.0 * (x * z - w * y);
    g[1] = 2.0 * (y * z + w * x);
    g[2] = w * w - x * x - y * y + z * z;
}

/* _half_angle_series: cos(a/2) and sin(a/2)/a by their Taylor series in a2 = a^2 (a2 below
 * SERIES_A2) */
static void half_angle_series(fc_real a2, fc_real *c, fc_real *s_over_a)
{
    *c = 1.0 - a2 * (1.0 / 8.0 - a2 * (1.0 / 384.0 - a2 * (1.0 / 46080.0
                                                        - a2 * (1.0 / 10321920.0))));
    *s_over_a = 0.5 - a2 * (1.0 / 48.0 - a2 * (1.0 / 3840.0 - a2 * (1.0 / 645120.0
                                                             - a2 * (1.0 / 185794560.0))));
}

/* rotvec_terms: fc_cos(a/2), fc_sin(a/2)/a, fc_sin(a)/a, (1 - cos a)/a^2; below a^2 = SERIES_A2 their
 * Taylor series through a^8 (exact to fc_real precision there), else from one sine-cosine pair */
void fc_rotvec_terms(fc_real vx, fc_real vy, fc_real vz, fc_real t[4])
{
    fc_real a2 = vx * vx + vy * vy + vz * vz;
    if (a2 < SERIES_A2) {
        half_angle_series(a2, &t[0], &t[1]);
        t[2] = 1.0 - a2 * (1.0 / 6.0 - a2 * (1.0 / 120.0 - a2 * (1.0 / 5040.0
                                                              - a2 * (1.0 / 362880.0))));
        t[3] = 0.5 - a2 * (1.0 / 24.0 - a2 * (1.0 / 720.0 - a2 * (1.0 / 40320.0
                                                               - a2 * (1.0 / 3628800.0))));
        return;
    }
    fc_real angle = fc_sqrt(a2);
    fc_real ch = fc_cos(0.5 * angle), sh = fc_sin(0.5 * angle);
    t[0] = ch;
    t[1] = sh / angle;
    t[2] = 2.0 * sh * ch / angle;
    t[3] = 2.0 * sh * sh / a2;
}

void fc_quat_mul_rotvec_terms(fc_real q[4], fc_real vx, fc_real vy, fc_real vz, const fc_real t[4])
{
    fc_real w = q[0], x = q[1], y = q[2], z = q[3];
    fc_real c = t[0], s = t[1];
    fc_real bx = s * vx, by = s * vy, bz = s * vz;
    fc_real rw = w * c - x * bx - y * by - z * bz;
    fc_real rx = w * bx + x * c + y * bz - z * by;
    fc_real ry = w * by - x * bz + y * c + z * bx;
    fc_real rz = w * bz + x * by - y * bx + z * c;
    fc_real n = 1.5 - 0.5 * (rw * rw + rx * rx + ry * ry + rz * rz);  /* 1/|r| (Newton) */
    q[0] = rw * n;
    q[1] = rx * n;
    q[2] = ry * n;
    q[3] = rz * n;
}

void fc_quat_mul_rotvec(fc_real q[4], fc_real vx, fc_real vy, fc_real vz)
{
    fc_real t[4];
    fc_rotvec_terms(vx, vy, vz, t);
    fc_quat_mul_rotvec_terms(q, vx, vy, vz, t);
}

void fc_roll_pitch_ahead(fc_real roll, fc_real pitch, fc_real wx, fc_real wy, fc_real wz,
                         fc_real delay, fc_real *roll_out, fc_real *pitch_out)
{
    fc_real q[4];
    fc_quat_from_roll_pitch_yaw(roll, pitch, 0.0, q);
    fc_quat_mul_rotvec(q, wx * delay, wy * delay, wz * delay);
    fc_quat_roll_pitch(q, roll_out, pitch_out);
}

void fc_rotation_increment(fc_real p0, fc_real q0, fc_real r0, fc_real p1, fc_real q1, fc_real r1,
                           fc_real dt, fc_real phi[3])
{
    fc_real a0 = p0 * dt, a1 = q0 * dt, a2 = r0 * dt;
    fc_real b0 = p1 * dt, b1 = q1 * dt, b2 = r1 * dt;
    fc_real k = 1.0 / 12.0;
    phi[0] = 0.5 * (a0 + b0) + k * (a1 * b2 - a2 * b1);
    phi[1] = 0.5 * (a1 + b1) + k * (a2 * b0 - a0 * b2);
    phi[2] = 0.5 * (a2 + b2) + k * (a0 * b1 - a1 * b0);
}

void fc_rotate_back_terms(const fc_real v[3], const fc_real phi[3], const fc_real t[4],
                          fc_real out[3])
{
    fc_real p0 = phi[0], p1 = phi[1], p2 = phi[2];
    fc_real s = t[2], c = t[3];
    fc_real v0 = v[0], v1 = v[1], v2 = v[2];
    fc_real u0 = p1 * v2 - p2 * v1, u1 = p2 * v0 - p0 * v2, u2 = p0 * v1 - p1 * v0;
    out[0] = v0 - s * u0 + c * (p1 * u2 - p2 * u1);
    out[1] = v1 - s * u1 + c * (p2 * u0 - p0 * u2);
    out[2] = v2 - s * u2 + c * (p0 * u1 - p1 * u0);
}

void fc_rotation_back_matrix(const fc_real phi[3], const fc_real t[4], fc_real m[9])
{
    fc_real p0 = phi[0], p1 = phi[1], p2 = phi[2], s = t[2], c = t[3];
    fc_real x0 = s * p0, x1 = s * p1, x2 = s * p2;
    fc_real c01 = c * (p0 * p1), c02 = c * (p0 * p2), c12 = c * (p1 * p2);
    fc_real q0 = p0 * p0, q1 = p1 * p1, q2 = p2 * p2;
    m[0] = 1.0 - c * (q1 + q2);
    m[1] = x2 + c01;
    m[2] = c02 - x1;
    m[3] = c01 - x2;
    m[4] = 1.0 - c * (q0 + q2);
    m[5] = x0 + c12;
    m[6] = x1 + c02;
    m[7] = c12 - x0;
    m[8] = 1.0 - c * (q0 + q1);
}

void fc_rotate_back(const fc_real v[3], const fc_real phi[3], fc_real out[3])
{
    fc_real t[4];
    fc_rotvec_terms(phi[0], phi[1], phi[2], t);
    fc_rotate_back_terms(v, phi, t, out);
}

/* up_terms: sin(roll) cos(pitch), cos(roll) cos(pitch), sin(pitch) and cos(pitch) of q */
void fc_up_terms(const fc_real q[4], fc_real t[4])
{
    fc_real w = q[0], x = q[1], y = q[2], z = q[3];
    t[0] = 2.0 * (w * x + y * z);
    t[1] = 1.0 - 2.0 * (x * x + y * y);
    t[2] = 2.0 * (w * y - x * z);
    t[3] = fc_sqrt(t[0] * t[0] + t[1] * t[1]);
}

#define SERIES_T2 1e-2       /* kinematics._SERIES_T2 */

fc_real fc_angle_of(fc_real num, fc_real den)
{
    if (den > 0.0 && num * num < SERIES_T2 * (den * den)) {
        fc_real t = num / den, t2 = t * t, t4 = t2 * t2;
        fc_real lo = (1.0 - t2 * (1.0 / 3.0)) + t4 * (1.0 / 5.0 - t2 * (1.0 / 7.0));
        fc_real hi = (1.0 / 9.0 - t2 * (1.0 / 11.0)) + t4 * (1.0 / 13.0 - t2 * (1.0 / 15.0));
        return t * (lo + (t4 * t4) * hi);
    }
    return fc_atan2(num, den);
}

void fc_half_angle(fc_real a, fc_real *c, fc_real *s)
{
    fc_real a2 = a * a;
    if (a2 < SERIES_A2) {
        fc_real s_over_a;
        half_angle_series(a2, c, &s_over_a);
        *s = a * s_over_a;
        return;
    }
    *c = fc_cos(0.5 * a);
    *s = fc_sin(0.5 * a);
}

void fc_sin_cos(fc_real a, fc_real *s, fc_real *c)
{
    fc_real ch, sh;
    fc_half_angle(a, &ch, &sh);
    *s = 2.0 * sh * ch;
    *c = 1.0 - 2.0 * sh * sh;
}

/* quat_turn_roll_pitch: q with roll + dr and pitch + dp; t: q's up_terms */
void fc_quat_turn_roll_pitch(fc_real q[4], const fc_real t[4], fc_real dr, fc_real dp)
{
    fc_real cr, sr, cp, sp;
    fc_half_angle(dr, &cr, &sr);
    fc_half_angle(dp, &cp, &sp);
    fc_real sphi = t[0] / t[3], cphi = t[1] / t[3];
    fc_real a2 = sp * cphi, a3 = -(sp * sphi);
    fc_real dw = cp * cr, dx = cp * sr, dy = a2 * cr + a3 * sr, dz = a3 * cr - a2 * sr;
    fc_real w = q[0], x = q[1], y = q[2], z = q[3];
    q[0] = w * dw - x * dx - y * dy - z * dz;
    q[1] = w * dx + x * dw + y * dz - z * dy;
    q[2] = w * dy - x * dz + y * dw + z * dx;
    q[3] = w * dz + x * dy - y * dx + z * dw;
}

/* ----- building_blocks.py ------------------------------------------------------------------ */

const fc_real FC_FACES[6][9] = {
    {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0},
    {1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0},
    {0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0},
    {0.0, 1.0, 0.0, 0.0, 0.0, -1.0, -1.0, 0.0, 0.0},
    {0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0},
    {0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0},
};

/* quat_from_roll_pitch: roll and pitch with yaw 0 (the filters' free yaw) */
void fc_quat_from_roll_pitch(fc_real roll, fc_real pitch, fc_real q[4])
{
    fc_real cr = fc_cos(0.5 * roll), sr = fc_sin(0.5 * roll);
    fc_real cp = fc_cos(0.5 * pitch), sp = fc_sin(0.5 * pitch);
    q[0] = cr * cp;
    q[1] = sr * cp;
    q[2] = cr * sp;
    q[3] = -(sr * sp);
}

#define STEP_MIN_COS 0.1     /* building_blocks.STEP_MIN_COS */

void fc_tilt_innovation(fc_real ax, fc_real ay, fc_real az, const fc_real up[4], fc_real *y_roll,
                        fc_real *y_pitch)
{
    fc_real h = fc_sqrt(ay * ay + az * az);
    *y_roll = fc_angle_of(ay * up[1] - az * up[0], az * up[1] + ay * up[0]);
    *y_pitch = fc_angle_of(-ax * up[3] - h * up[2], h * up[3] - ax * up[2]);
}

void fc_corrected_quat(fc_real q[4], const fc_real up[4], fc_real roll, fc_real pitch, fc_real dr,
                       fc_real dp)
{
    if (up[3] > STEP_MIN_COS) {
        fc_quat_turn_roll_pitch(q, up, dr, dp);
        return;
    }
    fc_quat_from_roll_pitch(roll, pitch, q);
}

void fc_gate_bounds2(fc_real gate_low, fc_real gate_high, fc_real *low2, fc_real *high2)
{
    *low2 = fc_pow(gate_low * FC_G, 2.0);
    *high2 = fc_pow(gate_high * FC_G, 2.0);
}

fc_real fc_on_the_mark(fc_real t, fc_real dt, fc_real mark)
{
    fc_real d = t - mark;
    return -0.5 * dt < d && d < 0.5 * dt ? mark : t;
}

void fc_body_rotation(const fc_real g0[3], const fc_real g1[3], const fc_real bias[3], fc_real dt,
                      int trapezoid, fc_real phi[3])
{
    fc_real b0 = bias[0], b1 = bias[1], b2 = bias[2];
    if (trapezoid) {
        fc_rotation_increment(g0[0] - b0, g0[1] - b1, g0[2] - b2, g1[0] - b0, g1[1] - b1,
                              g1[2] - b2, dt, phi);
        return;
    }
    phi[0] = (g1[0] - b0) * dt;
    phi[1] = (g1[1] - b1) * dt;
    phi[2] = (g1[2] - b2) * dt;
}

void fc_lowpass_specific_force(fc_real f[3], const fc_real back[9], const fc_real a[3], fc_real k)
{
    fc_real t[3];
    fc_mat_vec(back, f, t);
    f[0] = t[0] + k * (a[0] - t[0]);
    f[1] = t[1] + k * (a[1] - t[1]);
    f[2] = t[2] + k * (a[2] - t[2]);
}

void fc_adaptive_noise_constants(fc_real gyro_scale_std, fc_real scale_time,
                                 fc_real disturbance_time, fc_real acc_tau, fc_real *q_rotation,
                                 fc_real *dist_tau)
{
    *q_rotation = fc_pow(gyro_scale_std, 2.0) * scale_time;
    *dist_tau = acc_tau > 0.0 ? disturbance_time : 0.0;
}

fc_real fc_correction_time(fc_real tau, fc_real r_ratio, fc_real q_rotation, fc_real w2, fc_real r,
                          fc_real dt, fc_real longest)
{
    fc_real q_ratio = 1.0 + q_rotation * w2 * tau * tau / (r * dt);
    fc_real t = tau * fc_sqrt(r_ratio / q_ratio);
    fc_real cap = longest > tau ? longest : tau;
    return t < cap ? t : cap;
}

fc_real fc_adaptive_prefilter_time(fc_real tau, fc_real dist, fc_real noise)
{
    fc_real excess = dist - noise;
    if (excess <= 0.0) {
        return 0.0;
    }
    fc_real full = PREFILTER_FULL * noise;
    if (excess >= full) {
        return tau;
    }
    return tau * (excess / full);
}

/* ----- measured_vector.py ------------------------------------------------------------------ */
#define DISTURBANCE_ATTACK 0.05 /* measured_vector.DISTURBANCE_ATTACK [s] */

void fc_measure_constants(fc_real acc_lowpass, fc_real disturbance_time, fc_real band, fc_real r,
                          fc_real gyro_scale_std, fc_real stretch, fc_real leak, fc_real held,
                          fc_real burst, fc_meas_constants *c)
{
    c->stage = 0.5 * acc_lowpass;
    c->dist_tau = disturbance_time;
    c->noise = 3.0 * r * FC_G * FC_G;
    c->band = band;
    c->r = r;
    c->turn = 3.0 * gyro_scale_std * gyro_scale_std * FC_G * FC_G;
    c->stretch = stretch;
    c->leak = leak;
    c->held2 = held * held;
    c->burst2 = burst * burst;
}

void fc_measure_start(fc_real m[FC_MEAS_SIZE], const fc_real a[3], const fc_meas_constants *c)
{
    fc_measure_align(m, a);
    m[FC_MEAS_DIST] = m[FC_MEAS_SLOW] = m[FC_MEAS_FILL] = 0.0;
    m[FC_MEAS_SETTLE] = m[FC_MEAS_FRESH] = 2.0 * c->stage;
    m[FC_MEAS_RATE2] = m[FC_MEAS_BAND_IN] = m[FC_MEAS_BAND_MID] = m[FC_MEAS_DIFF] = 0.0;
    memcpy(m + FC_MEAS_PREV, a, 3 * sizeof *a);
}

void fc_measure_align(fc_real m[FC_MEAS_SIZE], const fc_real f[3])
{
    for (int v = 0; v < FC_MEAS_DIST; v += 3) {
        m[v] = f[0];
        m[v + 1] = f[1];
        m[v + 2] = f[2];
    }
    for (int v = FC_MEAS_LAG_REF1; v < FC_MEAS_LAG_S + 3; v++) {  /* no lag */
        m[v] = 0.0;
    }
}

static fc_real two_stage_noise(fc_real k)
{
    fc_real a2 = (1.0 - k) * (1.0 - k);
    fc_real d = 1.0 - a2;
    return k * k * k * k * (1.0 + a2) / (d * d * d);
}

static void lowpass2(fc_real *s1, fc_real *s, const fc_real back[9], const fc_real a[3],
                     fc_real dt, fc_real tau)
{
    fc_real k = dt / (tau + dt);
    fc_lowpass_specific_force(s1, back, a, k);
    fc_lowpass_specific_force(s, back, s1, k);
}

/* lag2: one step of the lags of a second-order low-pass's two stages (each of gain k): every
 * sample a stage holds has turned by phi more (the lags turned with the body by back), and the
 * new sample comes with none (the first stage's input) or with the first stage's lag */
static void lag2(fc_real l1[3], fc_real lag[3], const fc_real back[9], const fc_real phi[3],
                 fc_real k)
{
    fc_real j = 1.0 - k, t[3];
    fc_mat_vec(back, l1, t);
    l1[0] = j * (t[0] + phi[0]);
    l1[1] = j * (t[1] + phi[1]);
    l1[2] = j * (t[2] + phi[2]);
    fc_mat_vec(back, lag, t);
    lag[0] = j * (t[0] + phi[0]) + k * l1[0];
    lag[1] = j * (t[1] + phi[1]) + k * l1[1];
    lag[2] = j * (t[2] + phi[2]) + k * l1[2];
}

/* stretched: the vector's length as a multiple of the full length, 1 to c->stretch */
static fc_real stretched(const fc_meas_constants *c, fc_real excess, fc_real rate2, fc_real lag,
                         fc_real full)
{
    fc_real k = c->stretch * c->stretch;
    fc_real ts = c->turn * rate2;
    fc_real left = excess - (k - 1.0) * ts * (lag * lag);
    fc_real x = left / (PREFILTER_FULL * c->noise + k * ts * (full * full));
    if (x <= 0.0) {
        return 1.0;
    }
    return 1.0 + (c->stretch - 1.0) * (x < 1.0 ? x : 1.0);
}

fc_real fc_measure_step(fc_real m[FC_MEAS_SIZE], const fc_real a[3], const fc_real phi[3],
                       const fc_real terms[4], fc_real dt, const fc_meas_constants *c,
                       int bias_measured, int *filling)
{
    fc_real stage = c->stage;
    fc_real full = 2.0 * stage;
    if (m[FC_MEAS_SETTLE] < full) {  /* the times counted up to the full length (fc_on_the_mark) */
        m[FC_MEAS_SETTLE] = fc_on_the_mark(m[FC_MEAS_SETTLE] + dt, dt, full);
    }
    if (m[FC_MEAS_FRESH] < full) {
        m[FC_MEAS_FRESH] = fc_on_the_mark(m[FC_MEAS_FRESH] + dt, dt, full);
    }
    *filling = m[FC_MEAS_FILL] < full;
    if (*filling) {  /* a mean of the samples so far (each stage half the time since the start) */
        m[FC_MEAS_FILL] = fc_on_the_mark(m[FC_MEAS_FILL] + dt, dt, full);
        stage = m[FC_MEAS_FILL] < full ? 0.5 * m[FC_MEAS_FILL] : stage;
    }
    fc_real r = c->r;
    fc_real tau = stage, back[9];
    fc_rotation_back_matrix(phi, terms, back);  /* once, for the six stages */
    int burst = 0;
    if (c->dist_tau > 0.0) {
        fc_real *ref = m + FC_MEAS_REF, *s = m + FC_MEAS_S;
        lowpass2(m + FC_MEAS_REF1, ref, back, a, dt, stage);
        fc_real e0 = a[0] - ref[0], e1 = a[1] - ref[1], e2 = a[2] - ref[2];
        fc_real k = dt / (c->dist_tau + dt);  /* one step of a mean over disturbance_time */
        m[FC_MEAS_DIST] += k * (e0 * e0 + e1 * e1 + e2 * e2 - m[FC_MEAS_DIST]);
        if (!*filling) {
            tau = stage * fc_adaptive_prefilter_time(1.0, m[FC_MEAS_DIST], c->noise);
        }
        if (c->band > 0.0) {  /* the slow band (band 0: not measured) */
            lowpass2(m + FC_MEAS_S1, s, back, a, dt, c->band);
            e0 = s[0] - ref[0];
            e1 = s[1] - ref[1];
            e2 = s[2] - ref[2];
            fc_real inst = e0 * e0 + e1 * e1 + e2 * e2;
            /* less what the gyro's rate error turns the two apart by: sigma times the
             * difference of their lags */
            lag2(m + FC_MEAS_LAG_REF1, m + FC_MEAS_LAG_REF, back, phi, dt / (stage + dt));
            lag2(m + FC_MEAS_LAG_S1, m + FC_MEAS_LAG_S, back, phi, dt / (c->band + dt));
            fc_real d0 = m[FC_MEAS_LAG_REF] - m[FC_MEAS_LAG_S];
            fc_real d1 = m[FC_MEAS_LAG_REF + 1] - m[FC_MEAS_LAG_S + 1];
            fc_real d2 = m[FC_MEAS_LAG_REF + 2] - m[FC_MEAS_LAG_S + 2];
            fc_real turn = c->turn * (d0 * d0 + d1 * d1 + d2 * d2);
            inst = inst > turn ? inst - turn : 0.0;
            /* the fast power before the band's first stage, and that of the change from one
             * sample to the next (white samples: about twice it) */
            const fc_real *s1 = m + FC_MEAS_S1, *prev = m + FC_MEAS_PREV;
            fc_real h0 = a[0] - s1[0], h1 = a[1] - s1[1], h2 = a[2] - s1[2];
            m[FC_MEAS_BAND_IN] += k * (h0 * h0 + h1 * h1 + h2 * h2 - m[FC_MEAS_BAND_IN]);
            fc_real g0 = a[0] - prev[0], g1 = a[1] - prev[1], g2 = a[2] - prev[2];
            m[FC_MEAS_DIFF] += k * (g0 * g0 + g1 * g1 + g2 * g2 - m[FC_MEAS_DIFF]);
            if (c->leak > 0.0) {  /* less the fast disturbance that leaks through the band */
                fc_real q0 = s1[0] - s[0], q1 = s1[1] - s[1], q2 = s1[2] - s[2];
                m[FC_MEAS_BAND_MID] += k * (q0 * q0 + q1 * q1 + q2 * q2 - m[FC_MEAS_BAND_MID]);
                fc_real leak = m[FC_MEAS_BAND_IN] > 0.0
                    ? c->leak * m[FC_MEAS_BAND_MID] * m[FC_MEAS_BAND_MID] / m[FC_MEAS_BAND_IN]
                    : 0.0;
                inst = inst > leak ? inst - leak : 0.0;
            }
            /* further from the reference than a body's linear acceleration moves it, and fast
             * power as white as samples of no motion: a burst (not while the vector first
             * fills, when the reference is as short) */
            burst = c->burst2 > 0.0 && inst > c->burst2 && m[FC_MEAS_DIFF] > m[FC_MEAS_BAND_IN]
                && !*filling;
            if (c->held2 > 0.0 && inst > c->held2) {  /* no more than a held acceleration */
                inst = c->held2;
            }
            fc_real rise = inst > m[FC_MEAS_SLOW] ? DISTURBANCE_ATTACK : c->dist_tau;
            m[FC_MEAS_SLOW] += dt / (rise + dt) * (inst - m[FC_MEAS_SLOW]);
            fc_real w2 = (phi[0] * phi[0] + phi[1] * phi[1] + phi[2] * phi[2]) / (dt * dt);
            m[FC_MEAS_RATE2] += dt / (stage + dt) * (w2 - m[FC_MEAS_RATE2]);
            fc_real excess = m[FC_MEAS_SLOW] - c->noise * two_stage_noise(dt / (c->band + dt));
            if (excess > 0.0) {
                r += excess / (FC_G * FC_G);
                if (c->stretch > 1.0 && bias_measured && !*filling) {  /* stretched */
                    tau = tau * stretched(c, excess, m[FC_MEAS_RATE2], 2.0 * (stage - c->band),
                                          full);
                }
            }
        }
    }
    if (burst) {  /* none of the burst's samples: the vector turned with the gyro alone */
        fc_real t[3];
        m[FC_MEAS_FRESH] = 0.0;
        fc_mat_vec(back, m + FC_MEAS_F1, t);
        memcpy(m + FC_MEAS_F1, t, sizeof t);
        fc_mat_vec(back, m + FC_MEAS_F, t);
        memcpy(m + FC_MEAS_F, t, sizeof t);
    } else {
        if (m[FC_MEAS_FRESH] < full && !*filling) {  /* after a burst, a mean of the samples since */
            tau = 0.5 * m[FC_MEAS_FRESH];
        }
        lowpass2(m + FC_MEAS_F1, m + FC_MEAS_F, back, a, dt, tau);
    }
    memcpy(m + FC_MEAS_PREV, a, 3 * sizeof *a);
    *filling = *filling || m[FC_MEAS_FRESH] < full;
    return r;
}

void fc_measure_fill_noise(const fc_real m[FC_MEAS_SIZE], fc_real r, fc_real dt,
                           const fc_meas_constants *c, fc_real *var, fc_real *age)
{
    fc_real a = 0.5 * (m[FC_MEAS_FILL] < m[FC_MEAS_FRESH] ? m[FC_MEAS_FILL] : m[FC_MEAS_FRESH]);
    *var = c->r * two_stage_noise(dt / (a + dt)) + (r - c->r);
    *age = a;
}

int fc_measure_settled(const fc_real m[FC_MEAS_SIZE], const fc_meas_constants *c)
{
    return m[FC_MEAS_SETTLE] >= 2.0 * c->stage;
}

int fc_measure_band_measured(const fc_meas_constants *c)
{
    return c->dist_tau > 0.0 && c->band > 0.0;
}

fc_real fc_measure_gate_norm2(const fc_real m[FC_MEAS_SIZE], const fc_meas_constants *c,
                              fc_real raw2)
{
    if (fc_measure_band_measured(c)) {
        const fc_real *s = m + FC_MEAS_S;
        return s[0] * s[0] + s[1] * s[1] + s[2] * s[2];
    }
    return raw2;
}

int fc_measure_within_bias_band(const fc_real m[FC_MEAS_SIZE], const fc_meas_constants *c,
                                fc_real lo2, fc_real hi2, fc_real a2, fc_real raw2)
{
    fc_real n2 = fc_measure_gate_norm2(m, c, raw2);
    return lo2 < n2 && n2 < hi2 && ((lo2 < a2 && a2 < hi2) || !fc_measure_band_measured(c));
}

fc_real fc_measure_raw_noise(const fc_real m[FC_MEAS_SIZE], const fc_meas_constants *c)
{
    fc_real excess = m[FC_MEAS_DIST] - c->noise;
    return excess > 0.0 ? c->r + excess / (FC_G * FC_G) : c->r;
}

void fc_measure_restart(fc_real m[FC_MEAS_SIZE], const fc_real f[3])
{
    fc_measure_align(m, f);
    m[FC_MEAS_SLOW] = 0.0;
}

void fc_measure_clipped(fc_real m[FC_MEAS_SIZE])
{
    m[FC_MEAS_SETTLE] = 0.0;
}

void fc_rest_start(fc_real rest[FC_REST_SIZE], const fc_real gyro[3], const fc_real acc[3])
{
    rest[0] = gyro[0];
    rest[1] = gyro[1];
    rest[2] = gyro[2];
    rest[3] = acc[0];
    rest[4] = acc[1];
    rest[5] = acc[2];
    rest[6] = 0.0;
    rest[7] = 0.0;
    rest[8] = acc[0];
    rest[9] = acc[1];
    rest[10] = acc[2];
    rest[11] = gyro[0];
    rest[12] = gyro[1];
    rest[13] = gyro[2];
    rest[14] = gyro[0];
    rest[15] = gyro[1];
    rest[16] = gyro[2];
}

void fc_rest_step(fc_real rest[FC_REST_SIZE], fc_real gx, fc_real gy, fc_real gz, fc_real ax,
                  fc_real ay, fc_real az, const fc_real bias[3], fc_real dt, fc_real th_gyro,
                  fc_real th_acc, fc_real rest_time, fc_real bound)
{
    fc_real wx = rest[0], wy = rest[1], wz = rest[2], fx = rest[3], fy = rest[4], fz = rest[5];
    fc_real quiet = rest[6], measured = rest[7], ox = rest[8], oy = rest[9], oz = rest[10];
    fc_real rx = rest[11], ry = rest[12], rz = rest[13];
    fc_real zx = rest[14], zy = rest[15], zz = rest[16];
    fc_real k = dt / (FC_ZERO_RATE_TAU + dt);
    zx += k * (gx - zx);
    zy += k * (gy - zy);
    zz += k * (gz - zz);
    k = dt / (FC_REST_MEAN_TAU + dt);
    wx += k * (gx - wx);
    wy += k * (gy - wy);
    wz += k * (gz - wz);
    fx += k * (ax - fx);
    fy += k * (ay - fy);
    fz += k * (az - fz);
    fc_real th_g2 = th_gyro * th_gyro;
    fc_real dx = gx - wx, dy = gy - wy, dz = gz - wz;
    fc_real ex = ax - fx, ey = ay - fy, ez = az - fz;
    int still = dx * dx + dy * dy + dz * dz < th_g2
        && ex * ex + ey * ey + ez * ez < th_acc * th_acc;
    if (still && quiet >= FC_REST_MEAN_TAU) {  /* gravity's direction has not turned */
        ex = fx - ox;
        ey = fy - oy;
        ez = fz - oz;
        fc_real turn = FC_REST_TURN * th_gyro * rest_time;
        still = ex * ex + ey * ey + ez * ez < turn * turn * (fx * fx + fy * fy + fz * fz);
        if (still) {  /* nor has the mean rate ramped */
            dx = wx - rx;
            dy = wy - ry;
            dz = wz - rz;
            fc_real ramp = FC_REST_TURN * th_gyro;
            still = dx * dx + dy * dy + dz * dz < ramp * ramp;
        }
    }
    if (still && quiet < rest_time) {  /* only a mean rate the bias explains may start a rest */
        fc_real mx = wx - bias[0], my = wy - bias[1], mz = wz - bias[2];
        fc_real lim = measured == 0.0 ? th_gyro + bound : th_gyro;
        still = mx * mx + my * my + mz * mz < lim * lim;
    }
    if (still && quiet < FC_REST_MEAN_TAU) {  /* the means settle: the references follow them */
        ox = fx;
        oy = fy;
        oz = fz;
        rx = wx;
        ry = wy;
        rz = wz;
    }
    quiet = still ? fc_on_the_mark(fc_on_the_mark(quiet + dt, dt, FC_REST_MEAN_TAU), dt, rest_time)
                  : 0.0;
    rest[0] = wx;
    rest[1] = wy;
    rest[2] = wz;
    rest[3] = fx;
    rest[4] = fy;
    rest[5] = fz;
    rest[6] = quiet;
    rest[7] = quiet >= rest_time ? 1.0 : measured;
    rest[8] = ox;
    rest[9] = oy;
    rest[10] = oz;
    rest[11] = rx;
    rest[12] = ry;
    rest[13] = rz;
    rest[14] = zx;
    rest[15] = zy;
    rest[16] = zz;
}

fc_real fc_mean_share(fc_real dt, fc_real tau)
{
    fc_real k = dt / (tau + dt);
    return k / (2.0 - k);
}

fc_real fc_rest_mean_share(fc_real dt)
{
    return fc_mean_share(dt, FC_REST_MEAN_TAU);
}

int fc_first_rest(fc_real measured_before, const fc_real rest[FC_REST_SIZE])
{
    return measured_before == 0.0 && rest[7] != 0.0;
}

int fc_uncalibrated_first_rest(fc_real measured_before, const fc_real rest[FC_REST_SIZE],
                               const fc_real bias[3], fc_real th_gyro)
{
    if (!fc_first_rest(measured_before, rest)) {
        return 0;
    }
    fc_real mx = rest[0] - bias[0], my = rest[1] - bias[1], mz = rest[2] - bias[2];
    return mx * mx + my * my + mz * mz >= th_gyro * th_gyro;
}

void fc_rest_alignment(const fc_real rest[FC_REST_SIZE], fc_real bias[3], fc_real *roll,
                       fc_real *pitch, fc_real f[3])
{
    f[0] = rest[3];
    f[1] = rest[4];
    f[2] = rest[5];
    fc_accel_roll_pitch(rest[3], rest[4], rest[5], roll, pitch);
    bias[0] = rest[0];
    bias[1] = rest[1];
    bias[2] = rest[2];
}

void fc_bias_at_rest(fc_real bias[3], fc_real gx, fc_real gy, fc_real gz, fc_real dt,
                     fc_real rest_time, fc_real since)
{
    fc_real memory = since + FC_REST_MEAN_TAU;
    if (memory > rest_time) {
        memory = rest_time;
    }
    fc_real k = dt / (memory + dt);
    bias[0] = bias[0] + k * (gx - bias[0]);
    bias[1] = bias[1] + k * (gy - bias[1]);
    bias[2] = bias[2] + k * (gz - bias[2]);
}

#define ZERO_RATE_SPREAD 75.0  /* building_blocks.ZERO_RATE_SPREAD */
/* building_blocks.CONSTANT_REST_GYRO_VAR: REAL_GYRO_DENSITY (0.008 deg/s/sqrt(Hz)) squared */
#define REAL_GYRO_DENSITY (0.008 * (FC_PI / 180.0))
#define CONSTANT_REST_GYRO_VAR (REAL_GYRO_DENSITY * REAL_GYRO_DENSITY)

int fc_zero_rate_sample(const fc_real rest[FC_REST_SIZE], fc_real r, fc_real dt)
{
    fc_real dx = rest[14] - rest[0], dy = rest[15] - rest[1], dz = rest[16] - rest[2];
    return dx * dx + dy * dy + dz * dz
           <= ZERO_RATE_SPREAD * r * fc_mean_share(dt, FC_ZERO_RATE_TAU);
}

int fc_complementary_rest(fc_real rest[FC_REST_SIZE], fc_real bias[3], const fc_real g[3],
                          const fc_real a[3], fc_real dt, fc_real rest_time, fc_real rest_gyro,
                          fc_real rest_acc, fc_real bound, fc_real *roll, fc_real *pitch,
                          fc_real f[3])
{
    fc_real measured = rest[7];
    fc_rest_step(rest, g[0], g[1], g[2], a[0], a[1], a[2], bias, dt, rest_gyro, rest_acc,
                 rest_time, bound);
    if (fc_uncalibrated_first_rest(measured, rest, bias, rest_gyro)) {
        fc_rest_alignment(rest, bias, roll, pitch, f);
        return 1;
    }
    if (rest[6] >= rest_time && fc_zero_rate_sample(rest, CONSTANT_REST_GYRO_VAR / dt, dt)) {
        fc_bias_at_rest(bias, g[0], g[1], g[2], dt, rest_time, rest[6] - rest_time);
    }
    return 0;
}

/* motion_bias_ki: Ki of the PI loop whose proportional gain is 1 / tau, gain / tau^2, with tau
 * no shorter than one sample dt nor than one stage of the measured vector's low-pass
 * (building_blocks.motion_bias) */
fc_real fc_motion_bias_ki(fc_real tau, fc_real gain, fc_real dt, fc_real stage)
{
    if (tau < dt) {
        tau = dt;
    }
    if (tau < stage) {
        tau = stage;
    }
    return gain / (tau * tau);
}

void fc_bias_band2(fc_real gate, fc_real *lo, fc_real *hi)
{
    if (!(gate > 0.0)) {
        *lo = -1.0;
        *hi = HUGE_VAL;
        return;
    }
    fc_real low = 1.0 - gate;
    *lo = fc_pow((low >= 0.0 ? low : 0.0) * FC_G, 2.0);
    *hi = fc_pow((1.0 + gate) * FC_G, 2.0);
}

int fc_nearest_face(fc_real ux, fc_real uy, fc_real uz)
{
    fc_real ax = fc_fabs(ux), ay = fc_fabs(uy), az = fc_fabs(uz);
    if (az >= ax && az >= ay) {
        return uz >= 0.0 ? 0 : 1;
    }
    if (ax >= ay) {
        return ux > 0.0 ? 2 : 3;
    }
    return uy > 0.0 ? 4 : 5;
}

void fc_mat_vec(const fc_real m[9], const fc_real v[3], fc_real out[3])
{
    fc_real x = v[0], y = v[1], z = v[2];
    out[0] = m[0] * x + m[1] * y + m[2] * z;
    out[1] = m[3] * x + m[4] * y + m[5] * z;
    out[2] = m[6] * x + m[7] * y + m[8] * z;
}

void fc_mat_t_vec(const fc_real m[9], const fc_real v[3], fc_real out[3])
{
    fc_real x = v[0], y = v[1], z = v[2];
    out[0] = m[0] * x + m[3] * y + m[6] * z;
    out[1] = m[1] * x + m[4] * y + m[7] * z;
    out[2] = m[2] * x + m[5] * y + m[8] * z;
}

/* ----- base.py ----------------------------------------------------------------------------- */

#define MAX_ACC_NORM (1000.0 * FC_G)   /* base.MAX_ACC_NORM */
#define MIN_INIT_NORM (0.1 * FC_G)     /* base.MIN_INIT_NORM */
#define RAIL_MARGIN 1e-3               /* base.RAIL_MARGIN */

/* cos and sin of a, exact 0 and +-1 at multiples of pi/2 (mounting_matrix's cs) */
static void right_angle_cs(fc_real a, fc_real *c, fc_real *s)
{
    *c = fc_cos(a);
    *s = fc_sin(a);
    fc_real quarter = a / (0.5 * FC_PI);
    if (fc_fabs(quarter - fc_nearbyint(quarter)) < 1e-12) {
        *c = fc_nearbyint(*c);
        *s = fc_nearbyint(*s);
    }
}

void fc_mounting_matrix(fc_real roll, fc_real pitch, fc_real yaw, fc_real m[9])
{
    fc_real cr, sr, cp, sp, cy, sy;
    right_angle_cs(roll, &cr, &sr);
    right_angle_cs(pitch, &cp, &sp);
    right_angle_cs(yaw, &cy, &sy);
    m[0] = cy * cp;
    m[1] = cy * sp * sr - sy * cr;
    m[2] = cy * sp * cr + sy * sr;
    m[3] = sy * cp;
    m[4] = sy * sp * sr + cy * cr;
    m[5] = sy * sp * cr - cy * sr;
    m[6] = -sp;
    m[7] = cp * sr;
    m[8] = cp * cr;
}

static int differs(const fc_real *a, const fc_real *b, int n)
{
    for (int i = 0; i < n; i++) {
        if (a[i] != b[i]) {
            return 1;
        }
    }
    return 0;
}

void fc_base_configure(fc_base *b, const fc_input_params *in)
{
    static const fc_real identity[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
    static const fc_real zero[3] = {0.0, 0.0, 0.0};
    b->trapezoid = in->gyro_sampling == FC_GYRO_SAMPLING_POINT;
    b->max_dt = in->max_dt;
    b->max_rate = in->max_rate;
    b->delay = in->sensor_delay;
    b->max_rate2 = fc_pow(in->max_rate, 2.0);
    b->rail = in->gyro_range * (1.0 - RAIL_MARGIN);
    b->clipped = 0;
    fc_mounting_matrix(in->mount_roll, in->mount_pitch, in->mount_yaw, b->mounting);
    b->mounted = differs(b->mounting, identity, 9);
    /* the part's calibration (fusion_core.calibration): calibrated = cal (raw - off) */
    const fc_real acc_cal[9] = {in->acc_cal_xx, in->acc_cal_xy, in->acc_cal_xz,
                                in->acc_cal_yx, in->acc_cal_yy, in->acc_cal_yz,
                                in->acc_cal_zx, in->acc_cal_zy, in->acc_cal_zz};
    const fc_real gyro_cal[9] = {in->gyro_cal_xx, in->gyro_cal_xy, in->gyro_cal_xz,
                                 in->gyro_cal_yx, in->gyro_cal_yy, in->gyro_cal_yz,
                                 in->gyro_cal_zx, in->gyro_cal_zy, in->gyro_cal_zz};
    const fc_real acc_off[3] = {in->acc_off_x, in->acc_off_y, in->acc_off_z};
    const fc_real gyro_off[3] = {in->gyro_off_x, in->gyro_off_y, in->gyro_off_z};
    memcpy(b->acc_cal, acc_cal, sizeof acc_cal);
    memcpy(b->gyro_cal, gyro_cal, sizeof gyro_cal);
    memcpy(b->acc_off, acc_off, sizeof acc_off);
    memcpy(b->gyro_off, gyro_off, sizeof gyro_off);
    b->calibrated = differs(acc_cal, identity, 9) || differs(gyro_cal, identity, 9) ||
                    differs(acc_off, zero, 3) || differs(gyro_off, zero, 3);
}

void fc_base_reset(fc_base *b)
{
    b->initialized = 0;
    b->n_samples = 0;
    b->n_rejected = 0;
    b->gyro_prev[0] = b->gyro_prev[1] = b->gyro_prev[2] = 0.0;
}

fc_status fc_base_prepare(fc_base *b, fc_real acc[3], fc_real gyro[3], fc_real dt)
{
    fc_real ax = acc[0], ay = acc[1], az = acc[2], gx = gyro[0], gy = gyro[1], gz = gyro[2];
    fc_real w2 = gx * gx + gy * gy + gz * gz;
    fc_real total = ax + ay + az + w2 + dt;
    if (!(isfinite(total) && w2 <= b->max_rate2 && 0.0 < dt && dt <= b->max_dt)) {
        /* Estimator.check_sample: what is wrong (a finite sample whose sum overflowed passes) */
        if (!isfinite(ax) || !isfinite(ay) || !isfinite(az)) {
            return FC_BAD_ACC;
        }
        if (!isfinite(gx) || !isfinite(gy) || !isfinite(gz)) {
            return FC_BAD_GYRO;
        }
        if (!isfinite(dt) || !(0.0 < dt && dt <= b->max_dt)) {
            return FC_BAD_DT;
        }
        if (!(fc_hypot(fc_hypot(gx, gy), gz) <= b->max_rate)) {
            return FC_BAD_RATE;
        }
    }
    fc_real rail = b->rail;  /* on the sensor's own axes, before the mounting (gyro_range) */
    b->clipped = !(-rail < gx && gx < rail && -rail < gy && gy < rail && -rail < gz && gz < rail);
    if (b->calibrated) {  /* the part's calibration (fusion_core.calibration) */
        for (int i = 0; i < 3; i++) {
            acc[i] = acc[i] - b->acc_off[i];
            gyro[i] = gyro[i] - b->gyro_off[i];
        }
        fc_mat_vec(b->acc_cal, acc, acc);
        fc_mat_vec(b->gyro_cal, gyro, gyro);
    }
    if (b->mounted) {
        fc_mat_vec(b->mounting, acc, acc);
        fc_mat_vec(b->mounting, gyro, gyro);
    }
    fc_real norm2 = acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2];
    if (!(norm2 <= MAX_ACC_NORM * MAX_ACC_NORM)) {
        acc[0] = acc[1] = acc[2] = 0.0;
    }
    return FC_OK;
}

int fc_base_can_init(const fc_real acc[3])
{
    fc_real norm2 = acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2];
    return norm2 >= MIN_INIT_NORM * MIN_INIT_NORM;
}

void fc_base_output(const fc_base *b, fc_estimate *e)
{
    if (b->delay > 0.0 && b->initialized) {
        const fc_real *g = b->gyro_prev;
        fc_roll_pitch_ahead(e->roll, e->pitch, g[0] - e->bias[0], g[1] - e->bias[1],
                            g[2] - e->bias[2], b->delay, &e->roll, &e->pitch);
    }
}

/* fc_step after the input stage (Estimator._take): a, g the sample as the filter sees it */
static inline fc_status take(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last,
                             const fc_real a[3], const fc_real g[3], fc_real dt, fc_estimate *out)
{
    if (base->initialized) {
        ops->advance(self, a, g, dt);
    } else if (fc_base_can_init(a)) {
        ops->first_sample(self, a, g);
        base->initialized = 1;
    } else {  /* no gravity direction to start from yet: skipped, nothing changes */
        if (out) {
            *out = *last;
        }
        return FC_SKIPPED;
    }
    memcpy(base->gyro_prev, g, 3 * sizeof g[0]);
    ops->estimate(self, last);
    fc_base_output(base, last);
    base->n_samples += 1;
    if (out) {
        *out = *last;
    }
    return FC_OK;
}

fc_status fc_step(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last,
                  const fc_real acc[3], const fc_real gyro[3], fc_real dt, fc_estimate *out)
{
    fc_real a[3] = {acc[0], acc[1], acc[2]}, g[3] = {gyro[0], gyro[1], gyro[2]};
    fc_status status = fc_base_prepare(base, a, g, dt);
    if (status != FC_OK) {
        return status;
    }
    return take(ops, self, base, last, a, g, dt, out);
}

fc_status fc_step_prepared(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last,
                           const fc_real a[3], const fc_real g[3], fc_real dt, int clipped,
                           fc_estimate *out)
{
    base->clipped = clipped;
    return take(ops, self, base, last, a, g, dt, out);
}

/* one sample of a batch run: fc_step, a rejection counted; returns whether it was rejected
 * (*last is then the estimate before it) */
static int run_sample(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last,
                      const fc_real acc[3], const fc_real gyro[3], fc_real dt)
{
    if (fc_step(ops, self, base, last, acc, gyro, dt, NULL) > FC_SKIPPED) {
        base->n_rejected += 1;
        return 1;
    }
    return 0;
}

long fc_run(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last, long n,
            const fc_real *acc, const fc_real *gyro, const fc_real *dt, fc_estimate *out,
            unsigned char *rejected)
{
    long bad = 0;
    for (long i = 0; i < n; i++) {
        rejected[i] = (unsigned char)run_sample(ops, self, base, last, acc + 3 * i, gyro + 3 * i,
                                                dt[i]);
        bad += rejected[i];
        out[i] = *last;
    }
    return bad;
}

long fc_run_columns(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last, long n,
                    const fc_real *acc, const fc_real *gyro, const fc_real *dt, fc_real *roll,
                    fc_real *pitch, fc_real *bias, fc_real *pos, fc_real *vel,
                    unsigned char *rejected)
{
    long bad = 0;
    for (long i = 0; i < n; i++) {
        rejected[i] = (unsigned char)run_sample(ops, self, base, last, acc + 3 * i, gyro + 3 * i,
                                                dt[i]);
        bad += rejected[i];
        roll[i] = last->roll;
        pitch[i] = last->pitch;
        memcpy(bias + 3 * i, last->bias, sizeof last->bias);
        if (pos) {
            memcpy(pos + 3 * i, last->pos, sizeof last->pos);
            memcpy(vel + 3 * i, last->vel, sizeof last->vel);
        }
    }
    return bad;
}

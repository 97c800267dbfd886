/* fc_core.c: see fc_core.h. Each function names its Python twin; the operations are the
 * twin's, in its order. */
#include "fc_core.h"

#include <math.h>
#include <string.h>

#define MIN_COS_PITCH 1e-9   /* kinematics._MIN_COS_PITCH */
#define SERIES_A2 1e-2       /* kinematics._SERIES_A2 */
#define PREFILTER_FULL 4.0   /* building_blocks.PREFILTER_FULL */

/* ----- kinematics.py ----------------------------------------------------------------------- */

double fc_wrap_angle(double x)  /* wrap_angle */
{
    return remainder(x, FC_TWO_PI);
}

double fc_clamp_pitch(double theta)  /* clamp_pitch */
{
    theta = theta < FC_HALF_PI ? theta : FC_HALF_PI;
    return theta > -FC_HALF_PI ? theta : -FC_HALF_PI;
}

void fc_accel_roll_pitch(double ax, double ay, double az, double *roll, double *pitch)
{
    *roll = atan2(ay, az);
    *pitch = atan2(-ax, sqrt(ay * ay + az * az));
}

/* euler_rates (with the cos(pitch) guard of heun_euler_step) */
static void euler_rates(double phi, double theta, double p, double q, double r, double *dphi,
                        double *dtheta)
{
    double sp = sin(phi), cp = cos(phi), ct = cos(theta);
    if (-MIN_COS_PITCH < ct && ct < MIN_COS_PITCH) {
        ct = copysign(MIN_COS_PITCH, ct);
    }
    *dphi = p + (q * sp + r * cp) * sin(theta) / ct;
    *dtheta = q * cp - r * sp;
}

void fc_euler_step(double phi, double theta, double p, double q, double r, double dt,
                   double *phi_out, double *theta_out)
{
    double dp, dtheta;
    euler_rates(phi, theta, p, q, r, &dp, &dtheta);
    *phi_out = phi + dt * dp;
    *theta_out = theta + dt * dtheta;
}

void fc_heun_euler_step(double phi, double theta, double p0, double q0, double r0, double p1,
                        double q1, double r1, double dt, double *phi_out, double *theta_out)
{
    double d1p, d1t, d2p, d2t;
    euler_rates(phi, theta, p0, q0, r0, &d1p, &d1t);
    double phi1 = phi + dt * d1p, theta1 = theta + dt * d1t;
    euler_rates(phi1, theta1, p1, q1, r1, &d2p, &d2t);
    *phi_out = phi + 0.5 * dt * (d1p + d2p);
    *theta_out = theta + 0.5 * dt * (d1t + d2t);
}

void fc_quat_from_roll_pitch_yaw(double phi, double theta, double psi, double q[4])
{
    double cr = cos(0.5 * phi), sr = sin(0.5 * phi);
    double cp = cos(0.5 * theta), sp = sin(0.5 * theta);
    double cy = cos(0.5 * psi), sy = sin(0.5 * psi);
    q[0] = cr * cp * cy + sr * sp * sy;
    q[1] = sr * cp * cy - cr * sp * sy;
    q[2] = cr * sp * cy + sr * cp * sy;
    q[3] = cr * cp * sy - sr * sp * cy;
}

void fc_quat_roll_pitch(const double q[4], double *roll, double *pitch)
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    *roll = atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y));
    double s = 2.0 * (w * y - x * z);
    if (!(-1.0 <= s && s <= 1.0)) {
        s = s < 1.0 ? s : 1.0;     /* max(-1, min(1, s)) */
        s = -1.0 > s ? -1.0 : s;
    }
    *pitch = asin(s);
}

void fc_quat_gravity_body(const double q[4], double g[3])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    g[0] = 2.0 * (x * z - w * y);
    g[1] = 2.0 * (y * z + w * x);
    g[2] = w * w - x * x - y * y + z * z;
}

/* rotvec_terms: cos(a/2), sin(a/2)/a, sin(a)/a, (1 - cos a)/a^2; below a^2 = SERIES_A2 their
 * Taylor series through a^8 (exact to double precision there), else from one sine-cosine pair */
void fc_rotvec_terms(double vx, double vy, double vz, double t[4])
{
    double a2 = vx * vx + vy * vy + vz * vz;
    if (a2 < SERIES_A2) {
        t[0] = 1.0 - a2 * (1.0 / 8.0 - a2 * (1.0 / 384.0 - a2 * (1.0 / 46080.0
                                                              - a2 * (1.0 / 10321920.0))));
        t[1] = 0.5 - a2 * (1.0 / 48.0 - a2 * (1.0 / 3840.0 - a2 * (1.0 / 645120.0
                                                                - a2 * (1.0 / 185794560.0))));
        t[2] = 1.0 - a2 * (1.0 / 6.0 - a2 * (1.0 / 120.0 - a2 * (1.0 / 5040.0
                                                              - a2 * (1.0 / 362880.0))));
        t[3] = 0.5 - a2 * (1.0 / 24.0 - a2 * (1.0 / 720.0 - a2 * (1.0 / 40320.0
                                                               - a2 * (1.0 / 3628800.0))));
        return;
    }
    double angle = sqrt(a2);
    double ch = cos(0.5 * angle), sh = sin(0.5 * angle);
    t[0] = ch;
    t[1] = sh / angle;
    t[2] = 2.0 * sh * ch / angle;
    t[3] = 2.0 * sh * sh / a2;
}

void fc_quat_mul_rotvec_terms(double q[4], double vx, double vy, double vz, const double t[4])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double c = t[0], s = t[1];
    double bx = s * vx, by = s * vy, bz = s * vz;
    double rw = w * c - x * bx - y * by - z * bz;
    double rx = w * bx + x * c + y * bz - z * by;
    double ry = w * by - x * bz + y * c + z * bx;
    double rz = w * bz + x * by - y * bx + z * c;
    double n = 1.0 / sqrt(rw * rw + rx * rx + ry * ry + rz * rz);
    q[0] = rw * n;
    q[1] = rx * n;
    q[2] = ry * n;
    q[3] = rz * n;
}

void fc_quat_mul_rotvec(double q[4], double vx, double vy, double vz)
{
    double t[4];
    fc_rotvec_terms(vx, vy, vz, t);
    fc_quat_mul_rotvec_terms(q, vx, vy, vz, t);
}

void fc_roll_pitch_ahead(double roll, double pitch, double wx, double wy, double wz,
                         double delay, double *roll_out, double *pitch_out)
{
    double q[4];
    fc_quat_from_roll_pitch_yaw(roll, pitch, 0.0, q);
    fc_quat_mul_rotvec(q, wx * delay, wy * delay, wz * delay);
    fc_quat_roll_pitch(q, roll_out, pitch_out);
}

void fc_rotation_increment(double p0, double q0, double r0, double p1, double q1, double r1,
                           double dt, double phi[3])
{
    double a0 = p0 * dt, a1 = q0 * dt, a2 = r0 * dt;
    double b0 = p1 * dt, b1 = q1 * dt, b2 = r1 * dt;
    double k = 1.0 / 12.0;
    phi[0] = 0.5 * (a0 + b0) + k * (a1 * b2 - a2 * b1);
    phi[1] = 0.5 * (a1 + b1) + k * (a2 * b0 - a0 * b2);
    phi[2] = 0.5 * (a2 + b2) + k * (a0 * b1 - a1 * b0);
}

void fc_rotate_back_terms(const double v[3], const double phi[3], const double t[4],
                          double out[3])
{
    double p0 = phi[0], p1 = phi[1], p2 = phi[2];
    double s = t[2], c = t[3];
    double v0 = v[0], v1 = v[1], v2 = v[2];
    double u0 = p1 * v2 - p2 * v1, u1 = p2 * v0 - p0 * v2, u2 = p0 * v1 - p1 * v0;
    out[0] = v0 - s * u0 + c * (p1 * u2 - p2 * u1);
    out[1] = v1 - s * u1 + c * (p2 * u0 - p0 * u2);
    out[2] = v2 - s * u2 + c * (p0 * u1 - p1 * u0);
}

void fc_rotate_back(const double v[3], const double phi[3], double out[3])
{
    double t[4];
    fc_rotvec_terms(phi[0], phi[1], phi[2], t);
    fc_rotate_back_terms(v, phi, t, out);
}

/* ----- building_blocks.py ------------------------------------------------------------------ */

const double FC_FACES[6][9] = {
    {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0},
    {1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0},
    {0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0},
    {0.0, 1.0, 0.0, 0.0, 0.0, -1.0, -1.0, 0.0, 0.0},
    {0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0},
    {0.0, 0.0, 1.0, -1.0, 0.0, 0.0, 0.0, -1.0, 0.0},
};

/* quat_from_roll_pitch: roll and pitch with yaw 0 (the filters' free yaw) */
void fc_quat_from_roll_pitch(double roll, double pitch, double q[4])
{
    double cr = cos(0.5 * roll), sr = sin(0.5 * roll);
    double cp = cos(0.5 * pitch), sp = sin(0.5 * pitch);
    q[0] = cr * cp;
    q[1] = sr * cp;
    q[2] = cr * sp;
    q[3] = -(sr * sp);
}

void fc_gate_bounds2(double gate_low, double gate_high, double *low2, double *high2)
{
    *low2 = pow(gate_low * FC_G, 2.0);
    *high2 = pow(gate_high * FC_G, 2.0);
}

void fc_body_rotation(const double g0[3], const double g1[3], const double bias[3], double dt,
                      int trapezoid, double phi[3])
{
    double b0 = bias[0], b1 = bias[1], b2 = bias[2];
    if (trapezoid) {
        fc_rotation_increment(g0[0] - b0, g0[1] - b1, g0[2] - b2, g1[0] - b0, g1[1] - b1,
                              g1[2] - b2, dt, phi);
        return;
    }
    phi[0] = (g1[0] - b0) * dt;
    phi[1] = (g1[1] - b1) * dt;
    phi[2] = (g1[2] - b2) * dt;
}

void fc_lowpass_specific_force_terms(double f[3], const double phi[3], const double terms[4],
                                     const double a[3], double dt, double tau)
{
    double t[3];
    fc_rotate_back_terms(f, phi, terms, t);
    double k = dt / (tau + dt);
    f[0] = t[0] + k * (a[0] - t[0]);
    f[1] = t[1] + k * (a[1] - t[1]);
    f[2] = t[2] + k * (a[2] - t[2]);
}

void fc_adaptive_noise_constants(double gyro_scale_std, double scale_time,
                                 double disturbance_time, double acc_tau, double *q_rotation,
                                 double *dist_tau)
{
    *q_rotation = pow(gyro_scale_std, 2.0) * scale_time;
    *dist_tau = acc_tau > 0.0 ? disturbance_time : 0.0;
}

double fc_correction_time(double tau, double r_ratio, double q_rotation, double w2, double r,
                          double dt, double longest)
{
    double q_ratio = 1.0 + q_rotation * w2 * tau * tau / (r * dt);
    double t = tau * sqrt(r_ratio / q_ratio);
    double cap = longest > tau ? longest : tau;
    return t < cap ? t : cap;
}

double fc_adaptive_prefilter_time(double tau, double dist, double noise)
{
    double excess = dist - noise;
    if (excess <= 0.0) {
        return 0.0;
    }
    double full = PREFILTER_FULL * noise;
    if (excess >= full) {
        return tau;
    }
    return tau * (excess / full);
}

/* ----- measured_vector.py ------------------------------------------------------------------ */
#define DISTURBANCE_ATTACK 0.05 /* measured_vector.DISTURBANCE_ATTACK [s] */

void fc_measure_constants(double acc_lowpass, double disturbance_time, double band, double r,
                          fc_meas_constants *c)
{
    c->stage = 0.5 * acc_lowpass;
    c->dist_tau = disturbance_time;
    c->noise = 3.0 * r * FC_G * FC_G;
    c->band = band;
    c->r = r;
}

void fc_measure_start(double m[FC_MEAS_SIZE], const double a[3], const fc_meas_constants *c)
{
    fc_measure_align(m, a);
    m[FC_MEAS_DIST] = m[FC_MEAS_SLOW] = m[FC_MEAS_FILL] = 0.0;
    m[FC_MEAS_SETTLE] = 2.0 * c->stage;
}

void fc_measure_align(double m[FC_MEAS_SIZE], const double f[3])
{
    for (int v = 0; v < FC_MEAS_DIST; v += 3) {
        m[v] = f[0];
        m[v + 1] = f[1];
        m[v + 2] = f[2];
    }
}

static double two_stage_noise(double k)
{
    double a2 = (1.0 - k) * (1.0 - k);
    double d = 1.0 - a2;
    return k * k * k * k * (1.0 + a2) / (d * d * d);
}

static void lowpass2(double *s1, double *s, const double phi[3], const double a[3], double dt,
                     double tau, const double terms[4])
{
    fc_lowpass_specific_force_terms(s1, phi, terms, a, dt, tau);
    fc_lowpass_specific_force_terms(s, phi, terms, s1, dt, tau);
}

double fc_measure_step(double m[FC_MEAS_SIZE], const double a[3], const double phi[3],
                       const double terms[4], double dt, const fc_meas_constants *c,
                       int *filling)
{
    double stage = c->stage;
    double full = 2.0 * stage;
    if (m[FC_MEAS_SETTLE] < full) {
        m[FC_MEAS_SETTLE] += dt;
    }
    *filling = m[FC_MEAS_FILL] < full;
    if (*filling) {  /* a mean of the samples so far (each stage half the time since the start) */
        m[FC_MEAS_FILL] += dt;
        stage = m[FC_MEAS_FILL] < full ? 0.5 * m[FC_MEAS_FILL] : stage;
    }
    double r = c->r;
    double tau = stage;
    if (c->dist_tau > 0.0) {
        double *ref = m + FC_MEAS_REF, *s = m + FC_MEAS_S;
        lowpass2(m + FC_MEAS_REF1, ref, phi, a, dt, stage, terms);
        double e0 = a[0] - ref[0], e1 = a[1] - ref[1], e2 = a[2] - ref[2];
        m[FC_MEAS_DIST] += dt / (c->dist_tau + dt)
                           * (e0 * e0 + e1 * e1 + e2 * e2 - m[FC_MEAS_DIST]);
        if (!*filling) {
            tau = stage * fc_adaptive_prefilter_time(1.0, m[FC_MEAS_DIST], c->noise);
        }
        if (c->band > 0.0) {  /* the slow band (band 0: not measured) */
            lowpass2(m + FC_MEAS_S1, s, phi, a, dt, c->band, terms);
            e0 = s[0] - ref[0];
            e1 = s[1] - ref[1];
            e2 = s[2] - ref[2];
            double inst = e0 * e0 + e1 * e1 + e2 * e2;
            double rise = inst > m[FC_MEAS_SLOW] ? DISTURBANCE_ATTACK : c->dist_tau;
            m[FC_MEAS_SLOW] += dt / (rise + dt) * (inst - m[FC_MEAS_SLOW]);
            double excess = m[FC_MEAS_SLOW] - c->noise * two_stage_noise(dt / (c->band + dt));
            if (excess > 0.0) {
                r += excess / (FC_G * FC_G);
            }
        }
    }
    lowpass2(m + FC_MEAS_F1, m + FC_MEAS_F, phi, a, dt, tau, terms);
    return r;
}

int fc_measure_settled(const double m[FC_MEAS_SIZE], const fc_meas_constants *c)
{
    return m[FC_MEAS_SETTLE] >= 2.0 * c->stage;
}

double fc_measure_raw_noise(const double m[FC_MEAS_SIZE], const fc_meas_constants *c)
{
    double excess = m[FC_MEAS_DIST] - c->noise;
    return excess > 0.0 ? c->r + excess / (FC_G * FC_G) : c->r;
}

void fc_measure_restart(double m[FC_MEAS_SIZE], const double f[3])
{
    fc_measure_align(m, f);
    m[FC_MEAS_SLOW] = 0.0;
}

void fc_measure_clipped(double m[FC_MEAS_SIZE])
{
    m[FC_MEAS_SETTLE] = 0.0;
}

void fc_rest_start(double rest[8], const double gyro[3], const double acc[3])
{
    rest[0] = gyro[0];
    rest[1] = gyro[1];
    rest[2] = gyro[2];
    rest[3] = acc[0];
    rest[4] = acc[1];
    rest[5] = acc[2];
    rest[6] = 0.0;
    rest[7] = 0.0;
}

void fc_rest_step(double rest[8], double gx, double gy, double gz, double ax, double ay,
                  double az, const double bias[3], double dt, double th_gyro, double th_acc,
                  double rest_time, double bound)
{
    double wx = rest[0], wy = rest[1], wz = rest[2], fx = rest[3], fy = rest[4], fz = rest[5];
    double quiet = rest[6], measured = rest[7];
    double k = dt / (FC_REST_MEAN_TAU + dt);
    wx += k * (gx - wx);
    wy += k * (gy - wy);
    wz += k * (gz - wz);
    fx += k * (ax - fx);
    fy += k * (ay - fy);
    fz += k * (az - fz);
    double th_g2 = th_gyro * th_gyro;
    double dx = gx - wx, dy = gy - wy, dz = gz - wz;
    double ex = ax - fx, ey = ay - fy, ez = az - fz;
    int still = dx * dx + dy * dy + dz * dz < th_g2
        && ex * ex + ey * ey + ez * ez < th_acc * th_acc;
    if (still && quiet < rest_time) {  /* only a mean rate the bias explains may start a rest */
        double mx = wx - bias[0], my = wy - bias[1], mz = wz - bias[2];
        double lim = measured == 0.0 ? th_gyro + bound : th_gyro;
        still = mx * mx + my * my + mz * mz < lim * lim;
    }
    quiet = still ? quiet + dt : 0.0;
    rest[0] = wx;
    rest[1] = wy;
    rest[2] = wz;
    rest[3] = fx;
    rest[4] = fy;
    rest[5] = fz;
    rest[6] = quiet;
    rest[7] = quiet >= rest_time ? 1.0 : measured;
}

int fc_first_rest(double measured_before, const double rest[8])
{
    return measured_before == 0.0 && rest[7] != 0.0;
}

int fc_uncalibrated_first_rest(double measured_before, const double rest[8], const double bias[3],
                               double th_gyro)
{
    if (!fc_first_rest(measured_before, rest)) {
        return 0;
    }
    double mx = rest[0] - bias[0], my = rest[1] - bias[1], mz = rest[2] - bias[2];
    return mx * mx + my * my + mz * mz >= th_gyro * th_gyro;
}

void fc_rest_alignment(const double rest[8], double bias[3], double *roll, double *pitch,
                       double f[3])
{
    f[0] = rest[3];
    f[1] = rest[4];
    f[2] = rest[5];
    fc_accel_roll_pitch(rest[3], rest[4], rest[5], roll, pitch);
    bias[0] = rest[0];
    bias[1] = rest[1];
    bias[2] = rest[2];
}

void fc_bias_at_rest(double bias[3], double gx, double gy, double gz, double dt,
                     double rest_time)
{
    double k = dt / (rest_time + dt);
    bias[0] = bias[0] + k * (gx - bias[0]);
    bias[1] = bias[1] + k * (gy - bias[1]);
    bias[2] = bias[2] + k * (gz - bias[2]);
}

int fc_complementary_rest(double rest[8], double bias[3], const double g[3], const double a[3],
                          double dt, double rest_time, double rest_gyro, double rest_acc,
                          double bound, double *roll, double *pitch, double f[3])
{
    double measured = rest[7];
    fc_rest_step(rest, g[0], g[1], g[2], a[0], a[1], a[2], bias, dt, rest_gyro, rest_acc,
                 rest_time, bound);
    if (fc_uncalibrated_first_rest(measured, rest, bias, rest_gyro)) {
        fc_rest_alignment(rest, bias, roll, pitch, f);
        return 1;
    }
    if (rest[6] >= rest_time) {
        fc_bias_at_rest(bias, g[0], g[1], g[2], dt, rest_time);
    }
    return 0;
}

void fc_bias_band2(double gate, double *lo, double *hi)
{
    if (!(gate > 0.0)) {
        *lo = -1.0;
        *hi = HUGE_VAL;
        return;
    }
    double low = 1.0 - gate;
    *lo = pow((low >= 0.0 ? low : 0.0) * FC_G, 2.0);
    *hi = pow((1.0 + gate) * FC_G, 2.0);
}

int fc_nearest_face(double ux, double uy, double uz)
{
    double ax = fabs(ux), ay = fabs(uy), az = fabs(uz);
    if (az >= ax && az >= ay) {
        return uz >= 0.0 ? 0 : 1;
    }
    if (ax >= ay) {
        return ux > 0.0 ? 2 : 3;
    }
    return uy > 0.0 ? 4 : 5;
}

void fc_mat_vec(const double m[9], const double v[3], double out[3])
{
    double x = v[0], y = v[1], z = v[2];
    out[0] = m[0] * x + m[1] * y + m[2] * z;
    out[1] = m[3] * x + m[4] * y + m[5] * z;
    out[2] = m[6] * x + m[7] * y + m[8] * z;
}

void fc_mat_t_vec(const double m[9], const double v[3], double out[3])
{
    double x = v[0], y = v[1], z = v[2];
    out[0] = m[0] * x + m[3] * y + m[6] * z;
    out[1] = m[1] * x + m[4] * y + m[7] * z;
    out[2] = m[2] * x + m[5] * y + m[8] * z;
}

/* ----- base.py ----------------------------------------------------------------------------- */

#define MAX_ACC_NORM (1000.0 * FC_G)   /* base.MAX_ACC_NORM */
#define MIN_INIT_NORM (0.1 * FC_G)     /* base.MIN_INIT_NORM */
#define RAIL_MARGIN 1e-3               /* base.RAIL_MARGIN */

/* cos and sin of a, exact 0 and +-1 at multiples of pi/2 (mounting_matrix's cs) */
static void right_angle_cs(double a, double *c, double *s)
{
    *c = cos(a);
    *s = sin(a);
    double quarter = a / (0.5 * FC_PI);
    if (fabs(quarter - nearbyint(quarter)) < 1e-12) {
        *c = nearbyint(*c);
        *s = nearbyint(*s);
    }
}

void fc_mounting_matrix(double roll, double pitch, double yaw, double m[9])
{
    double cr, sr, cp, sp, cy, sy;
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

void fc_base_configure(fc_base *b, double max_dt, double max_rate, double mount_roll,
                       double mount_pitch, double mount_yaw, double sensor_delay,
                       double gyro_range)
{
    static const double identity[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
    b->max_dt = max_dt;
    b->max_rate = max_rate;
    b->delay = sensor_delay;
    b->max_rate2 = pow(max_rate, 2.0);
    b->rail = gyro_range * (1.0 - RAIL_MARGIN);
    b->clipped = 0;
    fc_mounting_matrix(mount_roll, mount_pitch, mount_yaw, b->mounting);
    b->mounted = 0;
    for (int i = 0; i < 9; i++) {
        if (b->mounting[i] != identity[i]) {
            b->mounted = 1;
        }
    }
}

void fc_base_calibrate(fc_base *b, const double acc_cal[9], const double acc_off[3],
                       const double gyro_cal[9], const double gyro_off[3])
{
    static const double identity[9] = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
    b->calibrated = 0;
    for (int i = 0; i < 9; i++) {
        b->acc_cal[i] = acc_cal[i];
        b->gyro_cal[i] = gyro_cal[i];
        if (acc_cal[i] != identity[i] || gyro_cal[i] != identity[i]) {
            b->calibrated = 1;
        }
    }
    for (int i = 0; i < 3; i++) {
        b->acc_off[i] = acc_off[i];
        b->gyro_off[i] = gyro_off[i];
        if (acc_off[i] != 0.0 || gyro_off[i] != 0.0) {
            b->calibrated = 1;
        }
    }
}

void fc_base_reset(fc_base *b)
{
    b->initialized = 0;
    b->n_samples = 0;
    b->n_rejected = 0;
    b->gyro_prev[0] = b->gyro_prev[1] = b->gyro_prev[2] = 0.0;
}

fc_status fc_base_prepare(fc_base *b, double acc[3], double gyro[3], double dt)
{
    double ax = acc[0], ay = acc[1], az = acc[2], gx = gyro[0], gy = gyro[1], gz = gyro[2];
    double w2 = gx * gx + gy * gy + gz * gz;
    double total = ax + ay + az + w2 + dt;
    if (!(total - total == 0.0 && w2 <= b->max_rate2 && 0.0 < dt && dt <= b->max_dt)) {
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
        if (!(hypot(hypot(gx, gy), gz) <= b->max_rate)) {
            return FC_BAD_RATE;
        }
    }
    double rail = b->rail;  /* on the sensor's own axes, before the mounting (gyro_range) */
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
    double norm2 = acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2];
    if (!(norm2 <= MAX_ACC_NORM * MAX_ACC_NORM)) {
        acc[0] = acc[1] = acc[2] = 0.0;
    }
    return FC_OK;
}

int fc_base_can_init(const double acc[3])
{
    double norm2 = acc[0] * acc[0] + acc[1] * acc[1] + acc[2] * acc[2];
    return norm2 >= MIN_INIT_NORM * MIN_INIT_NORM;
}

fc_estimate fc_base_output(const fc_base *b, fc_estimate e)
{
    if (b->delay > 0.0 && b->initialized) {
        const double *g = b->gyro_prev;
        fc_roll_pitch_ahead(e.roll, e.pitch, g[0] - e.bias[0], g[1] - e.bias[1], g[2] - e.bias[2],
                            b->delay, &e.roll, &e.pitch);
    }
    return e;
}

fc_status fc_step(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last,
                  const double acc[3], const double gyro[3], double dt, fc_estimate *out)
{
    double a[3] = {acc[0], acc[1], acc[2]}, g[3] = {gyro[0], gyro[1], gyro[2]};
    fc_status status = fc_base_prepare(base, a, g, dt);
    if (status != FC_OK) {
        return status;
    }
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
    memcpy(base->gyro_prev, g, sizeof g);
    *last = fc_base_output(base, ops->estimate(self));
    base->n_samples += 1;
    if (out) {
        *out = *last;
    }
    return FC_OK;
}

long fc_run(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last, long n,
            const double *acc, const double *gyro, const double *dt, fc_estimate *out,
            unsigned char *rejected)
{
    long bad = 0;
    for (long i = 0; i < n; i++) {
        fc_status s = fc_step(ops, self, base, last, acc + 3 * i, gyro + 3 * i, dt[i], out + i);
        rejected[i] = s > FC_SKIPPED;
        if (rejected[i]) {
            base->n_rejected += 1;
            out[i] = *last;
            bad++;
        }
    }
    return bad;
}

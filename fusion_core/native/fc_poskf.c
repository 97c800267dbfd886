/* fc_poskf.c: see fc_poskf.h; the twin of fusion_core/position.py line by line. */
#include "fc_poskf.h"

#include <math.h>
#include <string.h>

/* process_noise: Q of one axis for the named form (upper triangle) */
static void process_noise(int form, double q, double dt, double Q[6])
{
    double d2 = dt * dt, d3 = pow(dt, 3.0), d4 = pow(dt, 4.0), d5 = pow(dt, 5.0);
    if (form == FC_POSKF_QR_FORM_PIECEWISE_JERK) {
        double g0 = d3 / 6.0, g1 = d2 / 2.0, g2 = dt;
        double s = q / dt;
        Q[0] = s * g0 * g0;
        Q[1] = s * g0 * g1;
        Q[2] = s * g0 * g2;
        Q[3] = s * g1 * g1;
        Q[4] = s * g1 * g2;
        Q[5] = s * g2 * g2;
        return;
    }
    double q00 = q * d5 / 20.0, q11 = q * d3 / 3.0, q22 = q * dt;
    Q[0] = q00;
    Q[3] = q11;
    Q[5] = q22;
    if (form == FC_POSKF_QR_FORM_DIAGONAL) {
        Q[1] = Q[2] = Q[4] = 0.0;
        return;
    }
    Q[1] = q * d4 / 8.0;
    Q[2] = q * d3 / 6.0;
    Q[4] = q * d2 / 2.0;
}

/* axis_filters: one sample of the three [p, v, a] filters (eq. 20-29); with_zupt: the
 * zero-velocity update (variance zupt_r) too */
static void axis_filters(double x[9], double P[6], const double Q[6], double dt,
                         const double acc[3], double r, int with_zupt, double zupt_r)
{
    double p0 = x[0], v0 = x[1], a0 = x[2], p1 = x[3], v1 = x[4], a1 = x[5];
    double p2 = x[6], v2 = x[7], a2 = x[8];
    double h = 0.5 * dt * dt;
    p0 += dt * v0 + h * a0;
    v0 += dt * a0;
    p1 += dt * v1 + h * a1;
    v1 += dt * a1;
    p2 += dt * v2 + h * a2;
    v2 += dt * a2;
    double m00 = P[0], m01 = P[1], m02 = P[2], m11 = P[3], m12 = P[4], m22 = P[5];
    double r00 = m00 + dt * m01 + h * m02;
    double r01 = m01 + dt * m11 + h * m12;
    double r02 = m02 + dt * m12 + h * m22;
    double r11 = m11 + dt * m12;
    double r12 = m12 + dt * m22;
    m00 = r00 + dt * r01 + h * r02 + Q[0];
    m01 = r01 + dt * r02 + Q[1];
    m02 = r02 + Q[2];
    m11 = r11 + dt * r12 + Q[3];
    m12 = r12 + Q[4];
    m22 = m22 + Q[5];
    double s = m22 + r;
    double k0 = m02 / s, k1 = m12 / s, k2 = m22 / s;
    double y = acc[0] - a0;
    p0 += k0 * y;
    v0 += k1 * y;
    a0 += k2 * y;
    y = acc[1] - a1;
    p1 += k0 * y;
    v1 += k1 * y;
    a1 += k2 * y;
    y = acc[2] - a2;
    p2 += k0 * y;
    v2 += k1 * y;
    a2 += k2 * y;
    double c2 = m12 - k2 * m12;
    /* P - K c^T, in an order where each entry still reads the old values it needs */
    m00 -= k0 * m02;
    m01 -= k0 * m12;
    m02 -= k0 * m22;
    m11 -= k1 * m12;
    m12 -= k1 * m22;
    m22 -= k2 * m22;
    if (with_zupt) {
        s = m11 + zupt_r;
        k0 = m01 / s;
        k1 = m11 / s;
        k2 = c2 / s;
        y = 0.0 - v0;
        p0 += k0 * y;
        v0 += k1 * y;
        a0 += k2 * y;
        y = 0.0 - v1;
        p1 += k0 * y;
        v1 += k1 * y;
        a1 += k2 * y;
        y = 0.0 - v2;
        p2 += k0 * y;
        v2 += k1 * y;
        a2 += k2 * y;
        double c0 = m01, c1 = m11;
        m00 -= k0 * c0;
        m01 -= k0 * c1;
        m02 -= k0 * c2;
        m11 -= k1 * c1;
        m12 -= k1 * c2;
        m22 -= k2 * c2;
    }
    const double xn[9] = {p0, v0, a0, p1, v1, a1, p2, v2, a2};
    const double Pn[6] = {m00, m01, m02, m11, m12, m22};
    memcpy(x, xn, sizeof xn);
    memcpy(P, Pn, sizeof Pn);
}

/* level_acceleration: R f - g e_z, R = Rz Ry Rx (body to level frame) */
static void level_acceleration(double ax, double ay, double az, double sr, double cr, double sp,
                               double cp, double sy, double cy, double out[3])
{
    double w = sr * ay + cr * az;
    double u0 = cp * ax + sp * w;
    double u1 = cr * ay - sr * az;
    double u2 = -sp * ax + cp * w;
    out[0] = cy * u0 - sy * u1;
    out[1] = sy * u0 + cy * u1;
    out[2] = u2 - FC_G;
}

void fc_poskf_configure(fc_poskf *f)
{
    const fc_poskf_params *p = &f->params;
    fc_base_configure(&f->base, p->max_dt, p->max_rate, p->mount_roll, p->mount_pitch,
                      p->mount_yaw, p->sensor_delay, p->gyro_range);
    /* the tilt stage: the papers' kf options (TILT_FIXED) and the TILT_PARAMS given */
    fc_kf_params tp;
    fc_kf_params_default(&tp);
    tp.propagation = FC_KF_PROPAGATION_EULER;
    tp.acc_lowpass = 0.0;
    tp.rest_time = 0.0;
    tp.gyro_scale_std = 0.0;
    tp.disturbance_time = 0.0;
    tp.init_bias_std = 0.0;
    tp.tilt_axes = FC_KF_TILT_AXES_BODY;
    tp.bias_innovation = FC_PI;
    tp.Q_angle = p->Q_angle;
    tp.Q_bias = p->Q_bias;
    tp.R_measure = p->R_measure;
    tp.R_loop_time = p->R_loop_time;
    tp.gate_low = p->gate_low;
    tp.gate_high = p->gate_high;
    tp.gyro_sampling = p->gyro_sampling;
    tp.max_dt = p->max_dt;
    tp.max_rate = p->max_rate;
    f->tilt.params = tp;
    fc_kf_configure(&f->tilt);
    /* the attitude output: the recommended kf */
    fc_kf_params ap;
    fc_kf_params_default(&ap);
    ap.gyro_sampling = p->gyro_sampling;
    ap.max_dt = p->max_dt;
    ap.max_rate = p->max_rate;
    f->att.params = ap;
    fc_kf_configure(&f->att);
    f->own_attitude = p->attitude == FC_POSKF_ATTITUDE_KF;
    f->acc_var_density = p->acc_psd;
    f->zupt_var = pow(p->zupt_noise, 2.0);
    f->gyro_var_density = p->gyro_psd;
    f->always = p->tilt_update == FC_POSKF_TILT_UPDATE_ALWAYS;
    f->Q_dt = 0.0;
}

fc_estimate fc_poskf_estimate(const fc_poskf *f)
{
    fc_estimate e;
    if (f->own_attitude) {
        e = f->att.last;
    } else {
        memset(&e, 0, sizeof e);
        e.roll = f->tilt.roll;
        e.pitch = f->tilt.pitch;
        e.bias[0] = f->tilt.bias_x;
        e.bias[1] = f->tilt.bias_y;
        e.bias[2] = 0.0;
    }
    e.pos[0] = f->x[0];
    e.pos[1] = f->x[3];
    e.pos[2] = f->x[6];
    e.vel[0] = f->x[1];
    e.vel[1] = f->x[4];
    e.vel[2] = f->x[7];
    return e;
}

void fc_poskf_reset(fc_poskf *f)
{
    fc_base_reset(&f->base);
    fc_kf_reset(&f->tilt);
    fc_kf_reset(&f->att);
    f->yaw = 0.0;
    memset(f->x, 0, sizeof f->x);
    memset(f->P, 0, sizeof f->P);
    f->quiet_time = 0.0;
    f->stationary = 0;
    f->pending_head = f->pending_count = 0;
    f->turned[0] = f->turned[1] = 0.0;
    memset(f->f_mean, 0, sizeof f->f_mean);
    f->last = fc_poskf_estimate(f);
}

FC_DEFINE_INIT(fc_poskf)

void fc_poskf_restored(fc_poskf *f)  /* the nested filters' last estimates too (_restored) */
{
    fc_kf_restored(&f->tilt);
    fc_kf_restored(&f->att);
    f->last = fc_base_output(&f->base, fc_poskf_estimate(f));
}

static void first_sample(fc_poskf *f, const double a[3], const double g[3])  /* _init */
{
    fc_kf_step(&f->tilt, a, g, f->params.max_dt, NULL);
    if (f->own_attitude) {
        fc_kf_step(&f->att, a, g, f->params.max_dt, NULL);
    }
    memcpy(f->f_mean, a, sizeof f->f_mean);
    double roll = f->tilt.roll, pitch = f->tilt.pitch, yaw = f->yaw, l[3];
    level_acceleration(a[0], a[1], a[2], sin(roll), cos(roll), sin(pitch), cos(pitch), sin(yaw),
                       cos(yaw), l);
    double r = f->acc_var_density * 100.0;  /* one sample's variance at a nominal 100 Hz */
    const double P0[6] = {0.0, 0.0, 0.0, 0.0, 0.0, r};
    const double x0[9] = {0.0, 0.0, l[0], 0.0, 0.0, l[1], 0.0, 0.0, l[2]};
    memcpy(f->P, P0, sizeof P0);
    memcpy(f->x, x0, sizeof x0);
}

static int slow_enough(const fc_poskf *f)  /* _slow_enough */
{
    const double *x = f->x;
    double speed = sqrt(x[1] * x[1] + x[4] * x[4] + x[7] * x[7]);
    double sigma = sqrt(f->P[3] + f->zupt_var);
    double bound = 5.0 * sigma > f->params.zupt_speed ? 5.0 * sigma : f->params.zupt_speed;
    return speed <= bound;
}

static void advance(fc_poskf *f, const double a[3], const double g[3], double dt)
{
    const fc_poskf_params *p = &f->params;
    fc_kf *tilt = &f->tilt;
    double ax = a[0], ay = a[1], az = a[2], gx = g[0], gy = g[1], gz = g[2];
    /* 1. stationary detector */
    double mx = f->f_mean[0], my = f->f_mean[1], mz = f->f_mean[2];
    double dx = ax - mx, dy = ay - my, dz = az - mz;
    double wx = gx - tilt->bias_x, wy = gy - tilt->bias_y;
    double roll = tilt->roll, pitch = tilt->pitch, l[3];
    level_acceleration(ax, ay, az, sin(roll), cos(roll), sin(pitch), cos(pitch), 0.0, 1.0, l);
    int quiet = sqrt(dx * dx + dy * dy + dz * dz) < p->zupt_acc
        && sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]) < p->zupt_level_acc
        && sqrt(wx * wx + wy * wy + gz * gz) < p->zupt_gyro;
    double window = p->zupt_window;
    double k = window > 0.0 ? dt / window : 1.0;
    if (k > 1.0) {
        k = 1.0;
    }
    f->f_mean[0] = mx + k * dx;
    f->f_mean[1] = my + k * dy;
    f->f_mean[2] = mz + k * dz;
    double quiet_time = f->quiet_time = quiet ? f->quiet_time + dt : 0.0;
    int stationary = f->stationary = quiet && quiet_time >= window
        && (quiet_time >= p->zupt_force_after || slow_enough(f));
    /* 2. tilt stage */
    memcpy(tilt->base.gyro_prev, f->base.gyro_prev, sizeof f->base.gyro_prev);
    fc_kf_propagate(tilt, g, dt, NULL, NULL);
    double d_roll = tilt->roll - roll;
    double turned_roll = f->turned[0], turned_pitch = f->turned[1];
    turned_roll += -FC_PI <= d_roll && d_roll <= FC_PI ? d_roll : fc_wrap_angle(d_roll);
    turned_pitch = turned_pitch + tilt->pitch - pitch;
    f->turned[0] = turned_roll;
    f->turned[1] = turned_pitch;
    double n2 = ax * ax + ay * ay + az * az;
    if (f->always) {
        if (fc_kf_accel_trusted(tilt, n2)) {
            fc_kf_correct(tilt, ax, ay, az, 1);
        }
    } else if (!quiet) {
        f->pending_head = f->pending_count = 0;
    } else {
        if (stationary && fc_kf_accel_trusted(tilt, n2)) {
            if (f->pending_count >= FC_POSKF_PENDING_MAX) {  /* full: drop the oldest */
                f->pending_head = (f->pending_head + 1) % FC_POSKF_PENDING_MAX;
                f->pending_count--;
            }
            double *e = f->pending[(f->pending_head + f->pending_count) % FC_POSKF_PENDING_MAX];
            e[0] = quiet_time;
            fc_accel_roll_pitch(ax, ay, az, &e[1], &e[2]);
            e[3] = turned_roll;
            e[4] = turned_pitch;
            f->pending_count++;
        }
        while (f->pending_count && quiet_time - f->pending[f->pending_head][0] >= window) {
            const double *e = f->pending[f->pending_head];
            double acc_roll = e[1], acc_pitch = e[2], then_roll = e[3], then_pitch = e[4];
            f->pending_head = (f->pending_head + 1) % FC_POSKF_PENDING_MAX;
            f->pending_count--;
            fc_kf_correct_innovation(
                tilt, fc_wrap_angle(acc_roll - tilt->roll + turned_roll - then_roll),
                acc_pitch - tilt->pitch + turned_pitch - then_pitch, 1);
        }
    }
    if (stationary && p->zaru) {
        fc_kf_correct_bias(tilt, gx, gy, f->gyro_var_density / dt);
    }
    memcpy(tilt->base.gyro_prev, g, sizeof tilt->base.gyro_prev);
    tilt->base.n_samples += 1;
    if (f->own_attitude) {
        fc_kf_step(&f->att, a, g, dt, NULL);
    }
    roll = tilt->roll;
    pitch = tilt->pitch;
    double yaw = f->yaw;
    double sr = sin(roll), cr = cos(roll), sp = sin(pitch), cp = cos(pitch);
    if (cp > 1e-6 || cp < -1e-6) {
        yaw += dt * (wy * sr + gz * cr) / cp;
        yaw = f->yaw = -FC_PI <= yaw && yaw <= FC_PI ? yaw : fc_wrap_angle(yaw);
    }
    /* 3. level-frame acceleration with the new attitude */
    double acc[3];
    level_acceleration(ax, ay, az, sr, cr, sp, cp, sin(yaw), cos(yaw), acc);
    /* 4. [p, v, a] filter per axis (eq. 20-29) */
    if (dt != f->Q_dt) {
        process_noise(p->qr_form, p->q, dt, f->Q);
        f->R = f->acc_var_density / dt;
        f->Q_dt = dt;
    }
    axis_filters(f->x, f->P, f->Q, dt, acc, f->R, stationary && p->zupt, f->zupt_var);
}

FC_DEFINE_STEP_AND_RUN(fc_poskf)

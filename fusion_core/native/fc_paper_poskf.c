/* fc_paper_poskf.c: see fc_paper_poskf.h; the twin of fusion_core/papers/position.py line by
 * line. */
#include "fc_paper_poskf.h"

#include <math.h>
#include <string.h>

/* process_noise: Q of one axis for the named form (upper triangle) */
void fc_paper_poskf_process_noise(int form, fc_real q, fc_real dt, fc_real Q[6])
{
    fc_real d2 = dt * dt, d3 = fc_pow(dt, 3.0), d4 = fc_pow(dt, 4.0), d5 = fc_pow(dt, 5.0);
    if (form == FC_PAPER_POSKF_QR_FORM_PIECEWISE_JERK) {
        fc_real g0 = d3 / 6.0, g1 = d2 / 2.0, g2 = dt;
        fc_real s = q / dt;
        Q[0] = s * g0 * g0;
        Q[1] = s * g0 * g1;
        Q[2] = s * g0 * g2;
        Q[3] = s * g1 * g1;
        Q[4] = s * g1 * g2;
        Q[5] = s * g2 * g2;
        return;
    }
    fc_real q00 = q * d5 / 20.0, q11 = q * d3 / 3.0, q22 = q * dt;
    Q[0] = q00;
    Q[3] = q11;
    Q[5] = q22;
    if (form == FC_PAPER_POSKF_QR_FORM_DIAGONAL) {
        Q[1] = Q[2] = Q[4] = 0.0;
        return;
    }
    Q[1] = q * d4 / 8.0;
    Q[2] = q * d3 / 6.0;
    Q[4] = q * d2 / 2.0;
}

/* axis_filters: one sample of the three [p, v, a] filters (eq. 20-29); with_zupt: the
 * zero-velocity update (variance zupt_r) too */
void fc_paper_poskf_axis_filters(fc_real x[9], fc_real P[6], const fc_real Q[6], fc_real dt,
                                 const fc_real acc[3], fc_real r, int with_zupt, fc_real zupt_r)
{
    fc_real p0 = x[0], v0 = x[1], a0 = x[2], p1 = x[3], v1 = x[4], a1 = x[5];
    fc_real p2 = x[6], v2 = x[7], a2 = x[8];
    fc_real h = 0.5 * dt * dt;
    p0 += dt * v0 + h * a0;
    v0 += dt * a0;
    p1 += dt * v1 + h * a1;
    v1 += dt * a1;
    p2 += dt * v2 + h * a2;
    v2 += dt * a2;
    fc_real m00 = P[0], m01 = P[1], m02 = P[2], m11 = P[3], m12 = P[4], m22 = P[5];
    fc_real r00 = m00 + dt * m01 + h * m02;
    fc_real r01 = m01 + dt * m11 + h * m12;
    fc_real r02 = m02 + dt * m12 + h * m22;
    fc_real r11 = m11 + dt * m12;
    fc_real r12 = m12 + dt * m22;
    m00 = r00 + dt * r01 + h * r02 + Q[0];
    m01 = r01 + dt * r02 + Q[1];
    m02 = r02 + Q[2];
    m11 = r11 + dt * r12 + Q[3];
    m12 = r12 + Q[4];
    m22 = m22 + Q[5];
    fc_real s = m22 + r;
    fc_real k0 = m02 / s, k1 = m12 / s, k2 = m22 / s;
    fc_real y = acc[0] - a0;
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
    fc_real c2 = m12 - k2 * m12;
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
        fc_real c0 = m01, c1 = m11;
        m00 -= k0 * c0;
        m01 -= k0 * c1;
        m02 -= k0 * c2;
        m11 -= k1 * c1;
        m12 -= k1 * c2;
        m22 -= k2 * c2;
    }
    const fc_real xn[9] = {p0, v0, a0, p1, v1, a1, p2, v2, a2};
    const fc_real Pn[6] = {m00, m01, m02, m11, m12, m22};
    memcpy(x, xn, sizeof xn);
    memcpy(P, Pn, sizeof Pn);
}

/* level_acceleration: R f - g e_z, R = Rz Ry Rx (body to level frame) */
void fc_paper_poskf_level_acceleration(fc_real ax, fc_real ay, fc_real az, fc_real sr, fc_real cr,
                                       fc_real sp, fc_real cp, fc_real sy, fc_real cy, fc_real out[3])
{
    fc_real w = sr * ay + cr * az;
    fc_real u0 = cp * ax + sp * w;
    fc_real u1 = cr * ay - sr * az;
    fc_real u2 = -sp * ax + cp * w;
    out[0] = cy * u0 - sy * u1;
    out[1] = sy * u0 + cy * u1;
    out[2] = u2 - FC_G;
}

/* yaw_and_level_acceleration: yaw from the gyro (Euler kinematics), the level-frame
 * acceleration with the new attitude */
void fc_paper_poskf_yaw_and_level_acceleration(fc_real roll, fc_real pitch, fc_real *yaw, fc_real wy,
                                               fc_real gz, const fc_real a[3], fc_real dt,
                                               const fc_real sc[4], fc_real acc[3])
{
    fc_real y = *yaw, s[4];
    if (!sc) {
        fc_roll_pitch_sines(roll, pitch, s);
        sc = s;
    }
    fc_real sr = sc[0], cr = sc[1], sp = sc[2], cp = sc[3];
    if (cp > 1e-6 || cp < -1e-6) {
        y += dt * (wy * sr + gz * cr) / cp;
        y = *yaw = -FC_PI <= y && y <= FC_PI ? y : fc_wrap_angle(y);
    }
    fc_paper_poskf_level_acceleration(a[0], a[1], a[2], sr, cr, sp, cp, fc_sin(y), fc_cos(y), acc);
}

/* first_axis_states: the tilt stage initialised with the first sample, x and P from it */
void fc_paper_poskf_first_axis_states(fc_paper_kf *tilt, const fc_real a[3], const fc_real g[3],
                                      fc_real dt, fc_real acc_var_density, fc_real x[9],
                                      fc_real P[6])
{
    fc_paper_kf_step(tilt, a, g, dt, NULL);
    fc_real roll = tilt->roll, pitch = tilt->pitch, l[3];
    fc_paper_poskf_level_acceleration(a[0], a[1], a[2], fc_sin(roll), fc_cos(roll), fc_sin(pitch),
                                      fc_cos(pitch), fc_sin(0.0), fc_cos(0.0), l);
    fc_real r = acc_var_density * 100.0;  /* one sample's variance at a nominal 100 Hz */
    const fc_real P0[6] = {0.0, 0.0, 0.0, 0.0, 0.0, r};
    const fc_real x0[9] = {0.0, 0.0, l[0], 0.0, 0.0, l[1], 0.0, 0.0, l[2]};
    memcpy(P, P0, sizeof P0);
    memcpy(x, x0, sizeof x0);
}

/* the tilt stage's parameters from the position filter's (TILT_PARAM_NAMES) */
static void tilt_params(const fc_paper_poskf_params *p, fc_paper_kf_params *tp)
{
    fc_paper_kf_params_default(tp);
    tp->Q_angle = p->Q_angle;
    tp->Q_bias = p->Q_bias;
    tp->R_measure = p->R_measure;
    tp->R_loop_time = p->R_loop_time;
    tp->gate_low = p->gate_low;
    tp->gate_high = p->gate_high;
    tp->input.gyro_sampling = p->input.gyro_sampling;
    tp->input.max_dt = p->input.max_dt;
    tp->input.max_rate = p->input.max_rate;
}

void fc_paper_poskf_configure(fc_paper_poskf *f)
{
    const fc_paper_poskf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    tilt_params(p, &f->tilt.params);
    fc_paper_kf_configure(&f->tilt);
    f->acc_var_density = p->acc_psd;
    f->Q_dt = 0.0;
}

fc_estimate fc_paper_poskf_estimate(const fc_paper_poskf *f)
{
    fc_estimate e;
    memset(&e, 0, sizeof e);
    e.roll = f->tilt.roll;
    e.pitch = f->tilt.pitch;
    e.bias[0] = f->tilt.bias_x;
    e.bias[1] = f->tilt.bias_y;
    fc_paper_poskf_put_axes(f->x, &e);
    return e;
}

void fc_paper_poskf_put_axes(const fc_real x[9], fc_estimate *e)
{
    e->pos[0] = x[0];
    e->pos[1] = x[3];
    e->pos[2] = x[6];
    e->vel[0] = x[1];
    e->vel[1] = x[4];
    e->vel[2] = x[7];
}

void fc_paper_poskf_reset(fc_paper_poskf *f)
{
    fc_base_reset(&f->base);
    fc_paper_kf_reset(&f->tilt);
    f->yaw = 0.0;
    memset(f->x, 0, sizeof f->x);
    memset(f->P, 0, sizeof f->P);
    f->last = fc_paper_poskf_estimate(f);
}

FC_DEFINE_INIT(fc_paper_poskf)

void fc_paper_poskf_restored(fc_paper_poskf *f)  /* the tilt stage's last estimate too */
{
    fc_paper_kf_restored(&f->tilt);
    f->last = fc_paper_poskf_estimate(f);
    fc_base_output(&f->base, &f->last);
}

static void first_sample(fc_paper_poskf *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    fc_paper_poskf_first_axis_states(&f->tilt, a, g, f->params.input.max_dt, f->acc_var_density,
                                     f->x, f->P);
}

static void advance(fc_paper_poskf *f, const fc_real a[3], const fc_real g[3], fc_real dt)
{
    const fc_paper_poskf_params *p = &f->params;
    fc_paper_kf *tilt = &f->tilt;
    fc_real ax = a[0], ay = a[1], az = a[2], gy = g[1], gz = g[2];
    fc_real wy = gy - tilt->bias_y;  /* the bias before this sample's update, for the yaw rate */
    fc_paper_kf_propagate(tilt, f->base.gyro_prev, g, dt, NULL);
    if (fc_paper_kf_accel_trusted(tilt, ax * ax + ay * ay + az * az)) {
        fc_paper_kf_correct(tilt, ax, ay, az);
    }
    fc_paper_kf_took_sample(tilt, g);
    fc_real acc[3];
    fc_paper_poskf_yaw_and_level_acceleration(tilt->roll, tilt->pitch, &f->yaw, wy, gz, a, dt,
                                              NULL, acc);
    if (dt != f->Q_dt) {
        fc_paper_poskf_process_noise(p->qr_form, p->q, dt, f->Q);
        f->R = f->acc_var_density / dt;
        f->Q_dt = dt;
    }
    fc_paper_poskf_axis_filters(f->x, f->P, f->Q, dt, acc, f->R, 0, 0.0);
}

FC_DEFINE_STEP_AND_RUN(fc_paper_poskf)

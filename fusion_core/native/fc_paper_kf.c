/* fc_paper_kf.c: see fc_paper_kf.h; the twin of fusion_core/papers/kalman.py line by line. */
#include "fc_paper_kf.h"

#include <string.h>

/* predict_covariance: F P F' + Q (Das & Mary eq. 19-22) */
void fc_paper_kf_predict_covariance(const fc_real P[4], fc_real dt, fc_real q_angle, fc_real q_bias,
                                    fc_real out[4])
{
    fc_real P00 = P[0], P01 = P[1], P10 = P[2], P11 = P[3];
    out[0] = P00 + dt * (dt * P11 - P01 - P10 + q_angle);
    out[1] = P01 - dt * P11;
    out[2] = P10 - dt * P11;
    out[3] = P11 + q_bias * dt;
}

/* measurement_gain (Das & Mary eq. 23-27), with the papers' temporaries */
void fc_paper_kf_measurement_gain(const fc_real P[4], fc_real r, fc_real K[2], fc_real out[4])
{
    fc_real P00 = P[0], P01 = P[1], P10 = P[2], P11 = P[3];
    fc_real S = P00 + r;
    fc_real K0 = P00 / S, K1 = P10 / S;
    K[0] = K0;
    K[1] = K1;
    out[0] = P00 - K0 * P00;
    out[1] = P01 - K0 * P01;
    out[2] = P10 - K1 * P00;
    out[3] = P11 - K1 * P01;
}

/* bias_update: a direct bias measurement, H = [0, 1] */
void fc_paper_kf_bias_update(fc_real *angle, fc_real *bias, fc_real P[4], fc_real y, fc_real r)
{
    fc_real P00 = P[0], P01 = P[1], P10 = P[2], P11 = P[3];
    fc_real S = P11 + r;
    fc_real K0 = P01 / S, K1 = P11 / S;
    *angle = *angle + K0 * y;
    *bias = *bias + K1 * y;
    P[0] = P00 - K0 * P10;
    P[1] = P01 - K0 * P11;
    P[2] = P10 - K1 * P10;
    P[3] = P11 - K1 * P11;
}

static int same4(const fc_real a[4], const fc_real b[4])
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2] && a[3] == b[3];
}

/* RollPitchAxes.predict_covariances */
void fc_roll_pitch_predict_covariances(const fc_roll_pitch_axes *a, fc_real dt, fc_real q_angle,
                                       fc_real q_bias)
{
    fc_real P[4];
    memcpy(P, a->P_roll, sizeof P);
    fc_paper_kf_predict_covariance(P, dt, q_angle, q_bias, a->P_roll);
    if (same4(a->P_pitch, P)) {
        memcpy(a->P_pitch, a->P_roll, sizeof P);
    } else {
        fc_real Pp[4];
        memcpy(Pp, a->P_pitch, sizeof Pp);
        fc_paper_kf_predict_covariance(Pp, dt, q_angle, q_bias, a->P_pitch);
    }
}

/* RollPitchAxes.update_angles */
void fc_roll_pitch_update_angles(const fc_roll_pitch_axes *a, fc_real r, fc_real y_roll,
                                 fc_real y_pitch, fc_kf_gain_rule gain)
{
    fc_real P[4];
    memcpy(P, a->P_roll, sizeof P);
    int shared = same4(a->P_pitch, P);
    gain(P, r, a->gain_roll, a->P_roll);
    if (shared) {
        memcpy(a->gain_pitch, a->gain_roll, 2 * sizeof *a->gain_roll);
        memcpy(a->P_pitch, a->P_roll, sizeof P);
    } else {
        fc_real Pp[4];
        memcpy(Pp, a->P_pitch, sizeof Pp);
        gain(Pp, r, a->gain_pitch, a->P_pitch);
    }
    fc_real roll = *a->roll + a->gain_roll[0] * y_roll;
    *a->bias_x += a->gain_roll[1] * y_roll;
    fc_real pitch = *a->pitch + a->gain_pitch[0] * y_pitch;
    *a->bias_y += a->gain_pitch[1] * y_pitch;
    *a->roll = -FC_PI <= roll && roll <= FC_PI ? roll : fc_wrap_angle(roll);
    *a->pitch = -FC_HALF_PI <= pitch && pitch <= FC_HALF_PI ? pitch : fc_clamp_pitch(pitch);
}

/* RollPitchAxes.correct_bias */
void fc_roll_pitch_correct_bias(const fc_roll_pitch_axes *a, fc_real z_x, fc_real z_y, fc_real r)
{
    fc_paper_kf_bias_update(a->roll, a->bias_x, a->P_roll, z_x - *a->bias_x, r);
    fc_paper_kf_bias_update(a->pitch, a->bias_y, a->P_pitch, z_y - *a->bias_y, r);
}

void fc_paper_kf_configure(fc_paper_kf *f)
{
    const fc_paper_kf_params *p = &f->params;
    FC_BASE_CONFIGURE(&f->base, p, HUGE_VAL);
    f->q_angle = p->Q_angle;
    f->q_bias = p->Q_bias;
    f->r = p->R_measure;
    f->r_loop = f->r * p->R_loop_time;
    f->r_step = f->r;
    fc_gate_bounds2(p->gate_low, p->gate_high, &f->gate_low2, &f->gate_high2);
    f->trapezoid = p->gyro_sampling == FC_PAPER_KF_GYRO_SAMPLING_POINT;
}

fc_estimate fc_paper_kf_estimate(const fc_paper_kf *f)  /* _estimate */
{
    fc_estimate e;
    memset(&e, 0, sizeof e);
    e.roll = f->roll;
    e.pitch = f->pitch;
    e.bias[0] = f->bias_x;
    e.bias[1] = f->bias_y;
    return e;
}

void fc_paper_kf_reset(fc_paper_kf *f)
{
    fc_base_reset(&f->base);
    f->roll = f->pitch = f->bias_x = f->bias_y = 0.0;
    memset(f->P_roll, 0, sizeof f->P_roll);
    memset(f->P_pitch, 0, sizeof f->P_pitch);
    f->r_step = f->r;
    f->gain_roll[0] = f->gain_roll[1] = f->gain_pitch[0] = f->gain_pitch[1] = 0.0;
    f->last = fc_paper_kf_estimate(f);
}

FC_DEFINE_INIT(fc_paper_kf)
FC_DEFINE_RESTORED(fc_paper_kf)

static void first_sample(fc_paper_kf *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    (void)g;
    fc_accel_roll_pitch(a[0], a[1], a[2], &f->roll, &f->pitch);
}

/* propagate: the angles by the Euler rates, P by the papers' F and Q */
void fc_paper_kf_propagate(fc_paper_kf *f, const fc_real prev[3], const fc_real g[3], fc_real dt,
                           const fc_real sc[4])
{
    fc_real bx = f->bias_x, by = f->bias_y, roll, pitch;
    if (f->trapezoid) {
        fc_heun_euler_step(f->roll, f->pitch, prev[0] - bx, prev[1] - by, prev[2], g[0] - bx,
                           g[1] - by, g[2], dt, sc, &roll, &pitch);
    } else {
        fc_euler_step(f->roll, f->pitch, g[0] - bx, g[1] - by, g[2], dt, sc, &roll, &pitch);
    }
    f->roll = -FC_PI <= roll && roll <= FC_PI ? roll : fc_wrap_angle(roll);
    f->pitch = -FC_HALF_PI <= pitch && pitch <= FC_HALF_PI ? pitch : fc_clamp_pitch(pitch);
    if (f->r_loop > 0.0) {
        f->r_step = f->r_loop / dt;
    }
    fc_roll_pitch_predict_covariances(FC_ROLL_PITCH_AXES(f), dt, f->q_angle, f->q_bias);
}

int fc_paper_kf_accel_trusted(const fc_paper_kf *f, fc_real norm2)
{
    return f->gate_low2 <= norm2 && norm2 <= f->gate_high2;
}

/* correct: the accelerometer's roll and pitch (eq. 23-26) */
void fc_paper_kf_correct(fc_paper_kf *f, fc_real ax, fc_real ay, fc_real az)
{
    fc_real acc_roll, acc_pitch;
    fc_accel_roll_pitch(ax, ay, az, &acc_roll, &acc_pitch);
    fc_real y_roll = acc_roll - f->roll;
    if (!(-FC_PI <= y_roll && y_roll <= FC_PI)) {
        y_roll = fc_wrap_angle(y_roll);
    }
    fc_paper_kf_correct_innovation(f, y_roll, acc_pitch - f->pitch);
}

/* correct_innovation: the update with given innovations */
void fc_paper_kf_correct_innovation(fc_paper_kf *f, fc_real y_roll, fc_real y_pitch)
{
    fc_roll_pitch_update_angles(FC_ROLL_PITCH_AXES(f), f->r_step, y_roll, y_pitch,
                                fc_paper_kf_measurement_gain);
}

/* correct_bias: direct measurements of the x and y gyro bias (variance r each) */
void fc_paper_kf_correct_bias(fc_paper_kf *f, fc_real z_x, fc_real z_y, fc_real r)
{
    fc_roll_pitch_correct_bias(FC_ROLL_PITCH_AXES(f), z_x, z_y, r);
}

/* took_sample: g becomes the previous gyro sample, the sample is counted (as fc_step does) */
void fc_paper_kf_took_sample(fc_paper_kf *f, const fc_real g[3])
{
    memcpy(f->base.gyro_prev, g, sizeof f->base.gyro_prev);
    f->base.n_samples += 1;
}

static void advance(fc_paper_kf *f, const fc_real a[3], const fc_real g[3], fc_real dt)
{
    fc_paper_kf_propagate(f, f->base.gyro_prev, g, dt, NULL);
    if (fc_paper_kf_accel_trusted(f, a[0] * a[0] + a[1] * a[1] + a[2] * a[2])) {
        fc_paper_kf_correct(f, a[0], a[1], a[2]);
    }
}

FC_DEFINE_STEP_AND_RUN(fc_paper_kf)

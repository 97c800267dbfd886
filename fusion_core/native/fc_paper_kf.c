/* fc_paper_kf.c: see fc_paper_kf.h; the twin of fusion_core/papers/kalman.py line by line. */
#include "fc_paper_kf.h"

#include <string.h>

void fc_paper_kf_configure(fc_paper_kf *f)
{
    const fc_paper_kf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    f->q_angle = p->Q_angle;
    f->q_bias = p->Q_bias;
    f->r = p->R_measure;
    f->r_loop = f->r * p->R_loop_time;
    f->r_step = f->r;
    fc_gate_bounds2(p->gate_low, p->gate_high, &f->gate_low2, &f->gate_high2);
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
    if (f->base.trapezoid) {
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

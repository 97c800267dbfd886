/* fc_mgcf.c: see fc_mgcf.h; the twin of fusion_core/mgcf.py line by line. */
#include "fc_mgcf.h"

#include "fc_paper_mgcf.h"

#include <math.h>
#include <string.h>

void fc_mgcf_configure(fc_mgcf *f)
{
    const fc_mgcf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    f->w0 = p->w0;
    f->two_zeta = 2.0 * p->zeta;
    f->acc_tau = p->acc_lowpass;
    f->rest_time = p->rest_time;
    f->rest_gyro = p->rest_gyro;
    f->rest_acc = p->rest_acc;
    f->rest_bias_bound = p->rest_bias_bound;
    f->r_ref = fc_pow(p->acc_noise, 2.0);
    fc_adaptive_noise_constants(p->gyro_scale_std, p->scale_time, p->disturbance_time,
                                f->acc_tau, &f->q_rotation, &f->dist_tau);
    f->longest = p->max_correction_time;
    /* the slow band only decides the longer vector: the mgcf's noise is the raw disturbance
     * (fc_measure_raw_noise) */
    fc_measure_constants(f->acc_tau, f->dist_tau, p->slow_band_time, f->r_ref, p->gyro_scale_std,
                         p->acc_lowpass_stretch, p->slow_band_leak, p->held_acceleration,
                         p->burst_acceleration, &f->measure);
    f->motion_gain = p->motion_bias_gain;
    fc_bias_band2(p->bias_gate, &f->bias_lo2, &f->bias_hi2);
}

fc_estimate fc_mgcf_estimate(const fc_mgcf *f)
{
    return fc_paper_mgcf_quat_estimate(f->q, f->bias);
}

void fc_mgcf_reset(fc_mgcf *f)
{
    fc_base_reset(&f->base);
    f->q[0] = 1.0;
    f->q[1] = f->q[2] = f->q[3] = 0.0;
    memset(f->bias, 0, sizeof f->bias);
    f->w0_now = 0.0;
    static const fc_real zero[3] = {0.0, 0.0, 0.0};
    fc_measure_start(f->meas, zero, &f->measure);
    memset(f->rest, 0, sizeof f->rest);
    f->last = fc_mgcf_estimate(f);
}

FC_DEFINE_INIT(fc_mgcf)
FC_DEFINE_RESTORED(fc_mgcf)

static void first_sample(fc_mgcf *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    fc_real roll, pitch;
    fc_accel_roll_pitch(a[0], a[1], a[2], &roll, &pitch);
    fc_quat_from_roll_pitch_yaw(roll, pitch, 0.0, f->q);
    fc_measure_start(f->meas, a, &f->measure);
    fc_rest_start(f->rest, g, a);
}

/* _learns_in_motion: before the first rest, the vector a (raw2 the raw sample's squared norm)
 * within the bias gate (building_blocks.motion_bias) */
static int learns_in_motion(const fc_mgcf *f, const fc_real a[3], fc_real raw2)
{
    if (!(f->motion_gain > 0.0 && f->acc_tau > 0.0 && f->rest[7] <= 0.0)) {
        return 0;
    }
    fc_real a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    return fc_measure_within_bias_band(f->meas, &f->measure, f->bias_lo2, f->bias_hi2, a2, raw2);
}

static void advance(fc_mgcf *f, const fc_real a_in[3], const fc_real g[3], fc_real dt)
{
    fc_real ax = a_in[0], ay = a_in[1], az = a_in[2];
    fc_real gx = g[0], gy = g[1], gz = g[2];
    fc_real r = f->r_ref;
    fc_real raw2 = ax * ax + ay * ay + az * az;
    int aligning = 0;
    int clipped = f->base.clipped;
    fc_real roll, pitch, fa[3];  /* _real_sensor_options */
    if (f->rest_time > 0.0 && !clipped &&
        fc_complementary_rest(f->rest, f->bias, g, a_in, dt, f->rest_time, f->rest_gyro,
                              f->rest_acc, f->rest_bias_bound, &roll, &pitch, fa)) {
        fc_measure_align(f->meas, fa);  /* an uncalibrated first rest: its tilt */
        fc_quat_from_roll_pitch(roll, pitch, f->q);
    }
    if (f->acc_tau > 0.0) {
        fc_real phi[3], terms[4];
        fc_body_rotation(f->base.gyro_prev, g, f->bias, dt, f->base.trapezoid, phi);
        fc_rotvec_terms(phi[0], phi[1], phi[2], terms);
        if (clipped) {
            fc_measure_clipped(f->meas);
        }
        fc_measure_step(f->meas, a_in, phi, terms, dt, &f->measure, f->rest[7] > 0.0,
                        &aligning);
        ax = f->meas[FC_MEAS_F];
        ay = f->meas[FC_MEAS_F + 1];
        az = f->meas[FC_MEAS_F + 2];
        r = fc_measure_raw_noise(f->meas, &f->measure);
    }
    fc_real norm = fc_sqrt(ax * ax + ay * ay + az * az);
    fc_real w0 = f->w0;
    if (!(norm > 0.0)) {  /* no gravity direction in this sample: gyro only */
        w0 = 0.0;
    }
    f->w0_now = w0;
    if (aligning && w0 > 0.0) {  /* the vector still fills: the attitude is the mean's tilt */
        fc_accel_roll_pitch(ax, ay, az, &roll, &pitch);
        fc_quat_from_roll_pitch(roll, pitch, f->q);
        return;
    }
    fc_real bx = f->bias[0], by = f->bias[1], bz = f->bias[2];
    fc_real kp = f->two_zeta * w0;
    /* the adaptive noise: 1/Kp follows correction_time */
    if (kp * FC_SLOWEST_CORRECTION > 1.0 && (f->q_rotation > 0.0 || r != f->r_ref)) {
        fc_real wx = gx - bx, wy = gy - by, wz = gz - bz;
        fc_real tau = 1.0 / kp;
        kp *= tau / fc_correction_time(tau, r / f->r_ref, f->q_rotation,
                                       wx * wx + wy * wy + wz * wz, f->r_ref, dt, f->longest);
    }
    /* the integral term learns nothing from a gyro sample at its rail, nor from a vector
     * still holding its turns */
    int learn = !clipped && (f->acc_tau == 0.0 || fc_measure_settled(f->meas, &f->measure));
    const fc_real af[3] = {ax, ay, az};
    fc_real w_i = w0;  /* Ki = w_i^2: the paper's, or more until the first rest (motion_bias) */
    fc_real kp0 = f->two_zeta * w0;
    if (learn && kp0 * FC_SLOWEST_CORRECTION > 1.0 && learns_in_motion(f, af, raw2)) {
        fc_real tau_d = 1.0 / kp0;  /* the disturbance's correction time */
        if (r != f->r_ref) {
            tau_d = fc_correction_time(tau_d, r / f->r_ref, 0.0, 0.0, f->r_ref, dt, f->longest);
        }
        fc_real ki = fc_motion_bias_ki(tau_d, f->motion_gain, dt, 0.5 * f->acc_tau);
        if (ki > w0 * w0) {
            w_i = fc_sqrt(ki);
        }
    }
    fc_paper_mgcf_pi_step(f->q, f->bias, f->base.gyro_prev, g, af, norm, w_i, kp, dt,
                          f->base.trapezoid, learn);
}

FC_DEFINE_STEP_AND_RUN(fc_mgcf)

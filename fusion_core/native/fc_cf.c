/* fc_cf.c: see fc_cf.h; the twin of fusion_core/complementary.py line by line. */
#include "fc_cf.h"

#include <string.h>

void fc_cf_configure(fc_cf *f)
{
    const fc_cf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    f->tau = p->tau;
    fc_gate_bounds2(p->gate_low, p->gate_high, &f->gate_low2, &f->gate_high2);
    f->acc_tau = p->acc_lowpass;
    f->r_ref = fc_pow(p->acc_noise, 2.0);
    fc_adaptive_noise_constants(p->gyro_scale_std, p->scale_time, p->disturbance_time,
                                f->acc_tau, &f->q_rotation, &f->dist_tau);
    f->longest = p->max_correction_time;
    fc_measure_constants(f->acc_tau, f->dist_tau, p->slow_band_time, f->r_ref, p->gyro_scale_std,
                         p->acc_lowpass_stretch, p->slow_band_leak, p->held_acceleration,
                         p->burst_acceleration, &f->measure);
    fc_bias_band2(p->bias_gate, &f->bias_lo2, &f->bias_hi2);
}

fc_estimate fc_cf_estimate(const fc_cf *f)
{
    return fc_attitude_estimate(f->roll, f->pitch, f->bias[0], f->bias[1], f->bias[2]);
}

void fc_cf_reset(fc_cf *f)
{
    fc_base_reset(&f->base);
    f->roll = f->pitch = 0.0;
    static const fc_real zero[3] = {0.0, 0.0, 0.0};
    fc_measure_start(f->meas, zero, &f->measure);
    f->q_att[0] = 1.0;
    f->q_att[1] = f->q_att[2] = f->q_att[3] = 0.0;
    memset(f->bias, 0, sizeof f->bias);
    memset(f->rest, 0, sizeof f->rest);
    f->last = fc_cf_estimate(f);
}

FC_DEFINE_INIT(fc_cf)
FC_DEFINE_RESTORED(fc_cf)

static void first_sample(fc_cf *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    fc_accel_roll_pitch(a[0], a[1], a[2], &f->roll, &f->pitch);
    fc_measure_start(f->meas, a, &f->measure);
    fc_quat_from_roll_pitch_yaw(f->roll, f->pitch, 0.0, f->q_att);
    fc_rest_start(f->rest, g, a);
}

/* _learns_in_motion: before the first rest, a settled vector a (raw2 the raw sample's squared
 * norm) within the bias gates, no sample at the rail (building_blocks.motion_bias) */
static int learns_in_motion(const fc_cf *f, const fc_real a[3], fc_real raw2, fc_real y_roll,
                            fc_real y_pitch, int aligning, int clipped)
{
    const fc_cf_params *p = &f->params;
    if (!(p->motion_bias_gain > 0.0 && f->acc_tau > 0.0 && f->rest[7] <= 0.0 && !aligning
          && !clipped && fc_measure_settled(f->meas, &f->measure))) {
        return 0;
    }
    fc_real gate = p->bias_innovation;
    if (!(-gate <= y_roll && y_roll <= gate && -gate <= y_pitch && y_pitch <= gate)) {
        return 0;
    }
    fc_real a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    return a2 > 0.0 && fc_measure_within_bias_band(f->meas, &f->measure, f->bias_lo2,
                                                   f->bias_hi2, a2, raw2);
}

static void advance(fc_cf *f, const fc_real a_in[3], const fc_real g[3], fc_real dt)  /* _advance */
{
    const fc_cf_params *p = &f->params;
    fc_real a[3] = {a_in[0], a_in[1], a_in[2]};
    fc_real rest_time = p->rest_time;
    fc_real roll, pitch, phi[3], terms[4];
    int clipped = f->base.clipped;  /* at the gyro's rail: no rate measured (gyro_range) */
    fc_real fa[3];
    if (rest_time > 0.0 && !clipped &&  /* at rest the gyro reads its bias: follow it */
        fc_complementary_rest(f->rest, f->bias, g, a, dt, rest_time, p->rest_gyro, p->rest_acc,
                              p->rest_bias_bound, &f->roll, &f->pitch, fa)) {
        fc_measure_align(f->meas, fa);  /* an uncalibrated first rest: its tilt */
        fc_quat_from_roll_pitch(f->roll, f->pitch, f->q_att);
    }
    fc_real bx = f->bias[0], by = f->bias[1], bz = f->bias[2];
    fc_real r = f->r_ref;
    int aligning = 0;
    fc_body_rotation(f->base.gyro_prev, g, f->bias, dt, f->base.trapezoid, phi);
    fc_rotvec_terms(phi[0], phi[1], phi[2], terms);  /* once, for both rotations */
    fc_real raw2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    if (f->acc_tau > 0.0) {  /* the filter and its gate use the measured vector */
        if (clipped) {
            fc_measure_clipped(f->meas);
        }
        r = fc_measure_step(f->meas, a, phi, terms, dt, &f->measure, f->rest[7] > 0.0, &aligning);
        memcpy(a, f->meas + FC_MEAS_F, sizeof a);
    }
    fc_real up[4];  /* the attitude turned (building_blocks.attitude) */
    fc_quat_mul_rotvec_terms(f->q_att, phi[0], phi[1], phi[2], terms);
    fc_up_terms(f->q_att, up);
    fc_quat_roll_pitch(f->q_att, &roll, &pitch);
    fc_real n2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    if (f->gate_low2 <= n2 && n2 <= f->gate_high2) {
        fc_real y_roll, y_pitch;
        fc_tilt_innovation(a[0], a[1], a[2], up, &y_roll, &y_pitch);
        fc_real tau = f->tau;
        if (f->q_rotation > 0.0 || r != f->r_ref) {  /* the adaptive noise */
            fc_real wx = g[0] - bx, wy = g[1] - by, wz = g[2] - bz;
            tau = fc_correction_time(tau, r / f->r_ref, f->q_rotation,
                                     wx * wx + wy * wy + wz * wz, f->r_ref, dt, f->longest);
        }
        fc_real k = aligning ? 1.0 : dt / (tau + dt);  /* 1 - a, Gui et al. eq. 2 */
        if (learns_in_motion(f, a, raw2, y_roll, y_pitch, aligning, clipped)) {
            fc_real tau_d = f->tau;  /* the disturbance's correction time, without the rotation's */
            if (r != f->r_ref) {
                tau_d = fc_correction_time(tau_d, r / f->r_ref, 0.0, 0.0, f->r_ref, dt, f->longest);
            }
            fc_real ki_dt = fc_motion_bias_ki(tau_d, p->motion_bias_gain, dt, 0.5 * f->acc_tau) * dt;
            /* Mahony's e = f/|f| x v, v the estimated gravity direction (up_terms) */
            fc_real inv = 1.0 / fc_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
            fc_real nx = a[0] * inv, ny = a[1] * inv, nz = a[2] * inv;
            fc_real vx = -up[2], vy = up[0], vz = up[1];
            fc_real ex = ny * vz - nz * vy, ey = nz * vx - nx * vz, ez = nx * vy - ny * vx;
            f->bias[0] = bx - ki_dt * ex;
            f->bias[1] = by - ki_dt * ey;
            f->bias[2] = bz - ki_dt * ez;
        }
        fc_real dr = k * y_roll, dp = k * y_pitch;
        roll += dr;
        pitch += dp;
        fc_corrected_quat(f->q_att, up, roll, pitch, dr, dp);
    }
    f->roll = -FC_PI <= roll && roll <= FC_PI ? roll : fc_wrap_angle(roll);
    f->pitch = -FC_HALF_PI <= pitch && pitch <= FC_HALF_PI ? pitch : fc_clamp_pitch(pitch);
}

FC_DEFINE_STEP_AND_RUN(fc_cf)

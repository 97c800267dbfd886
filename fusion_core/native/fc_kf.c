/* fc_kf.c: see fc_kf.h; the twin of fusion_core/kalman.py line by line. */
#include "fc_kf.h"

#include "fc_paper_kf.h"

#include <math.h>
#include <string.h>

/* angle_only_gain: the update of measurement_gain with the bias a consider state */
static void angle_only_gain(const fc_real P[4], fc_real r, fc_real K[2], fc_real out[4])
{
    fc_real P00 = P[0], P01 = P[1], P10 = P[2], P11 = P[3];
    fc_real K0 = P00 / (P00 + r);
    K[0] = K0;
    K[1] = 0.0;
    out[0] = P00 - K0 * P00;
    out[1] = P01 - K0 * P01;
    out[2] = P10 - K0 * P10;
    out[3] = P11;
}

void fc_kf_configure(fc_kf *f)
{
    const fc_kf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    f->q_angle = p->Q_angle;
    f->q_bias = p->Q_bias;
    f->r = p->R_measure;
    f->r_step = f->r;
    fc_gate_bounds2(p->gate_low, p->gate_high, &f->gate_low2, &f->gate_high2);
    f->acc_tau = p->acc_lowpass;
    fc_adaptive_noise_constants(p->gyro_scale_std, p->scale_time, p->disturbance_time,
                                f->acc_tau, &f->q_rotation, &f->dist_tau);
    fc_measure_constants(f->acc_tau, f->dist_tau, p->slow_band_time, f->r, p->gyro_scale_std,
                         p->acc_lowpass_stretch, p->slow_band_leak, p->held_acceleration,
                         p->burst_acceleration, &f->measure);
    f->longest2 = fc_pow(p->max_correction_time, 2.0);
    f->rail_var = fc_pow(p->input.gyro_range, 2.0) / 3.0;  /* the rate beyond the rail, per axis */
    f->rest_time = p->rest_time;
    f->rest_gyro = p->rest_gyro;
    f->rest_acc = p->rest_acc;
    f->rest_bias_bound = p->rest_bias_bound;
    f->gyro_var = p->gyro_psd;
    fc_bias_band2(p->bias_gate, &f->bias_lo2, &f->bias_hi2);
}

fc_estimate fc_kf_estimate(const fc_kf *f)  /* _estimate */
{
    if (f->face) {  /* from the face frame back to the sensor's */
        fc_estimate e;
        memset(&e, 0, sizeof e);
        fc_real b[3] = {f->bias_x, f->bias_y, f->bias_z};
        const fc_real *C = FC_FACES[f->face];
        fc_real cp = fc_cos(f->pitch);
        fc_real v[3] = {-fc_sin(f->pitch), fc_sin(f->roll) * cp, fc_cos(f->roll) * cp}, up[3];
        fc_mat_t_vec(C, v, up);
        fc_accel_roll_pitch(up[0], up[1], up[2], &e.roll, &e.pitch);
        fc_mat_t_vec(C, b, e.bias);
        return e;
    }
    return fc_attitude_estimate(f->roll, f->pitch, f->bias_x, f->bias_y, f->bias_z);
}

void fc_kf_reset(fc_kf *f)
{
    fc_base_reset(&f->base);
    f->roll = f->pitch = f->bias_x = f->bias_y = 0.0;
    memset(f->P_roll, 0, sizeof f->P_roll);
    memset(f->P_pitch, 0, sizeof f->P_pitch);
    f->bias_z = f->P_z = 0.0;
    static const fc_real zero[3] = {0.0, 0.0, 0.0};
    fc_measure_start(f->meas, zero, &f->measure);
    memset(f->rest, 0, sizeof f->rest);
    f->q_att[0] = 1.0;
    f->q_att[1] = f->q_att[2] = f->q_att[3] = 0.0;
    f->gain_roll[0] = f->gain_roll[1] = f->gain_pitch[0] = f->gain_pitch[1] = 0.0;
    f->face = 0;
    f->r_step = f->r;
    f->q_step = f->q_angle;
    f->last = fc_kf_estimate(f);
}

FC_DEFINE_INIT(fc_kf)
FC_DEFINE_RESTORED(fc_kf)

static void first_sample(fc_kf *f, const fc_real a_in[3], const fc_real g_in[3])  /* _init */
{
    fc_real a[3] = {a_in[0], a_in[1], a_in[2]}, g[3] = {g_in[0], g_in[1], g_in[2]};
    f->face = fc_nearest_face(a[0], a[1], a[2]);
    if (f->face) {
        fc_mat_vec(FC_FACES[f->face], a, a);
        fc_mat_vec(FC_FACES[f->face], g, g);
    }
    fc_accel_roll_pitch(a[0], a[1], a[2], &f->roll, &f->pitch);
    fc_measure_start(f->meas, a, &f->measure);
    fc_rest_start(f->rest, g, a);
    fc_quat_from_roll_pitch_yaw(f->roll, f->pitch, 0.0, f->q_att);
    fc_real p_b = fc_pow(f->params.init_bias_std, 2.0);
    /* a sample whose norm is off g by d carries at least d of linear acceleration */
    fc_real p_a = f->r;
    if (f->acc_tau > 0.0) {
        fc_real d = (fc_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) - FC_G) / FC_G;
        p_a += d * d;
    }
    f->P_roll[0] = p_a;
    f->P_roll[1] = f->P_roll[2] = 0.0;
    f->P_roll[3] = p_b;
    memcpy(f->P_pitch, f->P_roll, sizeof f->P_roll);
    f->P_z = p_b;
}

/* propagate: the attitude quaternion turned by phi (with its fc_rotvec_terms), P by the papers'
 * F and Q with the adaptive Q_angle */
static void propagate(fc_kf *f, const fc_real g[3], fc_real dt, const fc_real phi[3],
                      const fc_real terms[4], fc_real up[4])
{
    fc_real bx = f->bias_x, by = f->bias_y, bz = f->bias_z, roll, pitch;
    fc_quat_mul_rotvec_terms(f->q_att, phi[0], phi[1], phi[2], terms);
    fc_up_terms(f->q_att, up);
    fc_quat_roll_pitch(f->q_att, &roll, &pitch);
    f->roll = -FC_PI <= roll && roll <= FC_PI ? roll : fc_wrap_angle(roll);
    f->pitch = -FC_HALF_PI <= pitch && pitch <= FC_HALF_PI ? pitch : fc_clamp_pitch(pitch);
    fc_real q_angle = f->q_angle;
    if (f->q_rotation > 0.0) {  /* gyro_scale_std: a scale error adds up while the sensor turns */
        fc_real wx = g[0] - bx, wy = g[1] - by, wz = g[2] - bz;
        q_angle += f->q_rotation * (wx * wx + wy * wy + wz * wz);
    }
    f->q_step = q_angle;
    fc_roll_pitch_predict_covariances(FC_ROLL_PITCH_AXES(f), dt, q_angle, f->q_bias);
}

/* correct_innovation: the biases consider states unless learn_bias */
static void correct_innovation(fc_kf *f, fc_real y_roll, fc_real y_pitch, int learn_bias)
{
    if (learn_bias) {  /* (one call per rule: each inlines its gain) */
        fc_roll_pitch_update_angles(FC_ROLL_PITCH_AXES(f), f->r_step, y_roll, y_pitch,
                                    fc_paper_kf_measurement_gain);
    } else {
        fc_roll_pitch_update_angles(FC_ROLL_PITCH_AXES(f), f->r_step, y_roll, y_pitch,
                                    angle_only_gain);
    }
}

/* raised_angle_variance: an axis's angle variance at least var (gross_innovation) */
static void raised_angle_variance(fc_real P[4], fc_real var)
{
    if (var > P[0]) {
        P[0] = var;
    }
}

/* correct: the accelerometer's roll and pitch against up (propagate's); turn: what a zero-rate
 * update moved the angles by, in, and that plus the correction, out (q's turn) */
static void correct(fc_kf *f, fc_real ax, fc_real ay, fc_real az, int learn_bias,
                    const fc_real up[4], fc_real turn[2])
{
    fc_real y_roll, y_pitch, moved_roll = turn[0], moved_pitch = turn[1];
    fc_tilt_innovation(ax, ay, az, up, &y_roll, &y_pitch);
    y_roll -= moved_roll;
    y_pitch -= moved_pitch;
    fc_real gate = f->params.bias_innovation;
    if (!(-gate <= y_roll && y_roll <= gate && -gate <= y_pitch && y_pitch <= gate)) {
        learn_bias = 0;  /* grossly off: the angle only (bias_innovation) */
    }
    fc_real gross = f->params.gross_innovation;
    if (!(-gross <= y_roll && y_roll <= gross)) {  /* off by more than y: variance >= y^2 */
        raised_angle_variance(f->P_roll, y_roll * y_roll);
    }
    if (!(-gross <= y_pitch && y_pitch <= gross)) {
        raised_angle_variance(f->P_pitch, y_pitch * y_pitch);
    }
    correct_innovation(f, y_roll, y_pitch, learn_bias);
    turn[0] = moved_roll + f->gain_roll[0] * y_roll;
    turn[1] = moved_pitch + f->gain_pitch[0] * y_pitch;
}

/* _zero_rate_update: at rest the gyro measures the bias */
/* measured_axis: the covariance once the angle is set from a measurement of variance var whose
 * samples the gyro turned over age [s] on average */
static void measured_axis(fc_real P[4], fc_real var, fc_real age)
{
    fc_real c = 0.0 - P[3] * age;
    P[0] = var + P[3] * age * age;
    P[1] = c;
    P[2] = c;
}

/* _zero_rate_update: returns whether this sample is the first rest's, which set the angles */
static int zero_rate_update(fc_kf *f, const fc_real a[3], const fc_real g[3], fc_real dt)
{
    fc_real b[3] = {f->bias_x, f->bias_y, f->bias_z};
    fc_real measured = f->rest[7];
    fc_rest_step(f->rest, g[0], g[1], g[2], a[0], a[1], a[2], b, dt, f->rest_gyro, f->rest_acc,
                 f->rest_time, f->rest_bias_bound);
    int rested = f->acc_tau > 0.0 && fc_first_rest(measured, f->rest);
    if (rested) {
        /* the measured vector starts again from the rest's mean, the angles from its tilt, as
         * sure of them as that mean is (and independent of the bias) */
        fc_measure_restart(f->meas, f->rest + 3);
        fc_accel_roll_pitch(f->rest[3], f->rest[4], f->rest[5], &f->roll, &f->pitch);
        fc_real p = f->r * fc_rest_mean_share(dt);
        measured_axis(f->P_roll, p, 0.0);
        measured_axis(f->P_pitch, p, 0.0);
    }
    f->P_z += f->q_bias * dt;
    if (f->rest[6] >= f->rest_time) {
        fc_real r = f->gyro_var / dt;
        if (fc_zero_rate_sample(f->rest, r, dt)) {  /* a still gyro's sample */
            fc_roll_pitch_correct_bias(FC_ROLL_PITCH_AXES(f), g[0], g[1], r);
            fc_real k = f->P_z / (f->P_z + r);
            f->bias_z += k * (g[2] - f->bias_z);
            f->P_z -= k * f->P_z;
        }
    }
    return rested;
}

/* _update, in the filters' frame; prev: the previous gyro sample there */
static void update(fc_kf *f, const fc_real a_in[3], const fc_real g[3], fc_real dt,
                   const fc_real prev[3])
{
    fc_real a[3] = {a_in[0], a_in[1], a_in[2]}, phi[3], terms[4], up[4];
    fc_real b[3] = {f->bias_x, f->bias_y, f->bias_z};
    fc_body_rotation(prev, g, b, dt, f->base.trapezoid, phi);
    fc_rotvec_terms(phi[0], phi[1], phi[2], terms);  /* once, for both rotations */
    propagate(f, g, dt, phi, terms, up);
    int clipped = f->base.clipped;  /* at the gyro's rail: the rate beyond it is unknown */
    if (clipped) {
        fc_real grow = f->rail_var * dt * dt;
        int shared = fc_same4(f->P_pitch, f->P_roll);
        f->P_roll[0] = f->P_roll[0] + grow;
        if (shared) {
            memcpy(f->P_pitch, f->P_roll, sizeof f->P_roll);
        } else {
            f->P_pitch[0] = f->P_pitch[0] + grow;
        }
    }
    fc_real pred_roll = f->roll, pred_pitch = f->pitch;
    fc_real raw2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    int learn_bias;
    /* at a first rest the angles are its tilt (zero_rate_update) */
    int rested = f->rest_time > 0.0 && !clipped && zero_rate_update(f, a, g, dt);
    int filling = 0, reset = rested;  /* the angles set from a tilt: q rebuilt from them */
    /* what a zero-rate update moved the angles by; the correction adds to it (correct), and q
     * is turned by the sum (a branch, not a subtraction of 0: q's turn then does not wait on
     * the arctangents that read pred off q) */
    fc_real turn[2] = {0.0, 0.0};
    if (f->roll != pred_roll || f->pitch != pred_pitch) {
        turn[0] = f->roll - pred_roll;
        turn[1] = f->pitch - pred_pitch;
    }
    fc_real r_meas = f->r;
    fc_real a2;  /* the squared norm of what the update measures */
    if (f->acc_tau > 0.0) {
        if (clipped) {
            fc_measure_clipped(f->meas);
        }
        fc_real r = fc_measure_step(f->meas, a, phi, terms, dt, &f->measure, f->rest[7] > 0.0,
                                   &filling);
        /* one sample's variance plus the disturbance that reaches the measured vector, up to
         * the longest correction time */
        fc_real base = f->r;
        r = base + (r - f->measure.r);
        r_meas = r;
        fc_real cap = f->q_step * f->longest2 / dt;
        f->r_step = r < cap ? r : (cap > base ? cap : base);
        memcpy(a, f->meas + FC_MEAS_F, sizeof a);
        a2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
        /* the bias gate on what reaches the vector (gate_norm2) and, where that is the slow
         * band, on what the vector still holds, its own norm; no bias from a vector that is
         * filling or holds turns the gyro did not measure */
        learn_bias = fc_measure_within_bias_band(f->meas, &f->measure, f->bias_lo2, f->bias_hi2,
                                                 a2, raw2)
                     && !clipped && !filling && fc_measure_settled(f->meas, &f->measure);
    } else {  /* the raw sample (bias_gate); never a sample at the rail */
        a2 = raw2;
        learn_bias = f->bias_lo2 < raw2 && raw2 < f->bias_hi2 && !clipped;
    }
    if (f->gate_low2 <= a2 && a2 <= f->gate_high2) {
        if (!filling) {
            correct(f, a[0], a[1], a[2], learn_bias, up, turn);
        } else if (!rested) {  /* (a first rest's mean, which no gyro error turned, stands) */
            /* the vector still fills: the attitude is its tilt, as uncertain as that vector */
            fc_accel_roll_pitch(a[0], a[1], a[2], &f->roll, &f->pitch);
            reset = 1;
            fc_real var, age;
            fc_measure_fill_noise(f->meas, r_meas, dt, &f->measure, &var, &age);
            measured_axis(f->P_roll, var, age);
            measured_axis(f->P_pitch, var, age);
        }
    }
    if (reset) {
        fc_quat_from_roll_pitch(f->roll, f->pitch, f->q_att);
    } else if (f->roll != pred_roll || f->pitch != pred_pitch) {  /* q turned by the correction */
        fc_corrected_quat(f->q_att, up, f->roll, f->pitch, turn[0], turn[1]);
    }
}

/* _switch_face: to the face nearest to up, every state turned by C_new C_old^T */
static void switch_face(fc_kf *f)
{
    fc_real roll = f->roll, pitch = f->pitch, cp = fc_cos(pitch);
    const fc_real *C = FC_FACES[f->face];
    fc_real up[3] = {-fc_sin(pitch), fc_sin(roll) * cp, fc_cos(roll) * cp}, t[3];
    fc_mat_t_vec(C, up, t);
    int next = fc_nearest_face(t[0], t[1], t[2]);
    if (next == f->face) {
        return;
    }
    const fc_real *C2 = FC_FACES[next];
#define TURN(v, out) do { fc_real tmp_[3]; fc_mat_t_vec(C, (v), tmp_); fc_mat_vec(C2, tmp_, (out)); } while (0)
    fc_real u2[3];
    TURN(up, u2);
    fc_accel_roll_pitch(u2[0], u2[1], u2[2], &f->roll, &f->pitch);
    fc_quat_from_roll_pitch_yaw(f->roll, f->pitch, 0.0, f->q_att);
    fc_real b[3] = {f->bias_x, f->bias_y, f->bias_z}, b2[3];
    TURN(b, b2);
    f->bias_x = b2[0];
    f->bias_y = b2[1];
    f->bias_z = b2[2];
    /* the measured vector's vectors, then its lags and last sample (the statistics between them
     * are scalars) */
    for (int v = 0; v < FC_MEAS_PREV + 3; v = v + 3 == FC_MEAS_DIST ? FC_MEAS_LAG_REF1 : v + 3) {
        fc_real turned[3];
        TURN(f->meas + v, turned);
        memcpy(f->meas + v, turned, sizeof turned);
    }
    for (int v = 0; v < FC_REST_SIZE; v += v == 3 ? 5 : 3) {  /* rates, means, start's, short mean */
        fc_real turned[3];
        TURN(f->rest + v, turned);
        memcpy(f->rest + v, turned, sizeof turned);
    }
#undef TURN
    fc_real old[3][4];
    memcpy(old[0], f->P_roll, sizeof old[0]);
    memcpy(old[1], f->P_pitch, sizeof old[1]);
    old[2][0] = f->P_pitch[0] > f->P_roll[0] ? f->P_pitch[0] : f->P_roll[0];  /* max(...) */
    old[2][1] = old[2][2] = 0.0;
    old[2][3] = f->P_z;
    int source[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++) {  /* the old axis that new axis k is: row k of C2 C^T */
        for (int j = 0; j < 3; j++) {
            fc_real d = C2[3 * k] * C[3 * j] + C2[3 * k + 1] * C[3 * j + 1]
                + C2[3 * k + 2] * C[3 * j + 2];
            if (d != 0.0) {
                source[k] = j;
            }
        }
    }
    memcpy(f->P_roll, old[source[0]], sizeof f->P_roll);
    memcpy(f->P_pitch, old[source[1]], sizeof f->P_pitch);
    f->P_z = old[source[2]][3];
    f->face = next;
}

static void advance(fc_kf *f, const fc_real a_in[3], const fc_real g_in[3], fc_real dt)
{
    fc_real a[3] = {a_in[0], a_in[1], a_in[2]}, g[3] = {g_in[0], g_in[1], g_in[2]};
    fc_real prev[3] = {f->base.gyro_prev[0], f->base.gyro_prev[1], f->base.gyro_prev[2]};
    if (f->face) {  /* into the face frame */
        const fc_real *C = FC_FACES[f->face];
        fc_mat_vec(C, a, a);
        fc_mat_vec(C, g, g);
        fc_mat_vec(C, prev, prev);
    }
    update(f, a, g, dt, prev);
    /* up's z in the face frame, fc_cos(roll) fc_cos(pitch), read off the attitude quaternion */
    const fc_real *q = f->q_att;
    if (q[0] * q[0] - q[1] * q[1] - q[2] * q[2] + q[3] * q[3] < FC_FACE_SWITCH_COS) {
        switch_face(f);
    }
}

FC_DEFINE_STEP_AND_RUN(fc_kf)

fc_status fc_kf_step_prepared(fc_kf *f, const fc_real a[3], const fc_real g[3], fc_real dt,
                              int clipped, fc_estimate *out)
{
    return fc_step_prepared(&OPS, f, &f->base, &f->last, a, g, dt, clipped, out);
}

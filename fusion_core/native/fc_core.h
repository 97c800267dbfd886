/* fc_core.h: what every estimator of fusion_core's C twin shares.
 *
 * The twin of fusion_core/kinematics.py, fusion_core/building_blocks.py and the sample rules of
 * fusion_core/base.py (Estimator.step): the same names, the same floating-point operations in
 * the same order, libm where Python calls math. Compiled without fused multiply-add
 * (-ffp-contract=off) and without fast-math, every result equals the Python reference's.
 *
 * C99, libc and libm only; no globals, no allocation: the same file builds into the Python
 * binding, the native FMUs and a microcontroller's firmware.
 */
#ifndef FC_CORE_H
#define FC_CORE_H

#include <stddef.h>

#include "fc_params.h"
#include "fc_real.h"

#define FC_G 9.80665            /* standard gravity [m/s^2] (fusion_core.types.G) */
#define FC_PI 3.141592653589793
#define FC_TWO_PI (2.0 * FC_PI)
#define FC_HALF_PI (0.5 * FC_PI)

/* What a step did with its sample (fusion_core.base.Estimator.step). */
typedef enum fc_status {
    FC_OK = 0,              /* processed */
    FC_SKIPPED = 1,         /* before the first sample with a gravity direction: waiting */
    FC_BAD_ACC = 2,         /* rejected: an accelerometer value is NaN or infinite */
    FC_BAD_GYRO = 3,        /* rejected: a gyro value is NaN or infinite */
    FC_BAD_DT = 4,          /* rejected: dt is NaN, infinite or outside (0, max_dt] */
    FC_BAD_RATE = 5         /* rejected: the gyro reading is above max_rate */
} fc_status;

/* An estimate: roll and pitch [rad], gyro bias [rad/s]; position [m] and velocity [m/s] for the
 * position filter (0 elsewhere). */
typedef struct fc_estimate {
    fc_real roll, pitch;
    fc_real bias[3];
    fc_real pos[3];
    fc_real vel[3];
} fc_estimate;

/* The estimate of an attitude filter: roll, pitch and bias, no position (every field written
 * once, by an initialiser, rather than cleared and then written) */
static inline fc_estimate fc_attitude_estimate(fc_real roll, fc_real pitch, fc_real bx,
                                               fc_real by, fc_real bz)
{
    fc_estimate e = {roll, pitch, {bx, by, bz}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    return e;
}

/* The state every estimator has (Estimator._BASE_STATE) and the sample rules' constants. */
typedef struct fc_base {
    int initialized;
    long n_samples;
    long n_rejected;
    fc_real gyro_prev[3];
    /* derived from the parameters (Estimator._set_params) */
    fc_real max_dt, max_rate, max_rate2;
    fc_real mounting[9];
    int mounted;
    fc_real acc_cal[9], acc_off[3], gyro_cal[9], gyro_off[3];  /* fusion_core.calibration */
    int calibrated;
    fc_real delay;  /* sensor_delay [s] */
    int trapezoid;  /* gyro_sampling "point": the interval's rate linear between the samples */
    fc_real rail;   /* gyro_range (1 - RAIL_MARGIN): a gyro axis at or beyond it is at the rail */
    int clipped;   /* Estimator.clipped: whether this sample's gyro is at its rail */
} fc_base;

/* ----- kinematics.py ----------------------------------------------------------------------- */
fc_real fc_wrap_angle(fc_real x);
fc_real fc_clamp_pitch(fc_real theta);
void fc_accel_roll_pitch(fc_real ax, fc_real ay, fc_real az, fc_real *roll, fc_real *pitch);
/* kinematics.roll_pitch_sines: sin roll, cos roll, sin pitch, cos pitch */
void fc_roll_pitch_sines(fc_real roll, fc_real pitch, fc_real sc[4]);
/* euler_step, heun_euler_step: sc the sines and cosines of phi and theta (fc_roll_pitch_sines)
 * where the caller has them, else NULL */
void fc_euler_step(fc_real phi, fc_real theta, fc_real p, fc_real q, fc_real r, fc_real dt,
                   const fc_real sc[4], fc_real *phi_out, fc_real *theta_out);
void fc_heun_euler_step(fc_real phi, fc_real theta, fc_real p0, fc_real q0, fc_real r0, fc_real p1,
                        fc_real q1, fc_real r1, fc_real dt, const fc_real sc[4], fc_real *phi_out,
                        fc_real *theta_out);
void fc_quat_from_roll_pitch_yaw(fc_real phi, fc_real theta, fc_real psi, fc_real q[4]);
void fc_quat_roll_pitch(const fc_real q[4], fc_real *roll, fc_real *pitch);
void fc_quat_gravity_body(const fc_real q[4], fc_real g[3]);
void fc_rotvec_terms(fc_real vx, fc_real vy, fc_real vz, fc_real t[4]);
void fc_quat_mul_rotvec(fc_real q[4], fc_real vx, fc_real vy, fc_real vz);
void fc_quat_mul_rotvec_terms(fc_real q[4], fc_real vx, fc_real vy, fc_real vz, const fc_real t[4]);
void fc_roll_pitch_ahead(fc_real roll, fc_real pitch, fc_real wx, fc_real wy, fc_real wz,
                         fc_real delay, fc_real *roll_out, fc_real *pitch_out);
void fc_rotation_increment(fc_real p0, fc_real q0, fc_real r0, fc_real p1, fc_real q1, fc_real r1,
                           fc_real dt, fc_real phi[3]);
void fc_rotate_back(const fc_real v[3], const fc_real phi[3], fc_real out[3]);
/* kinematics.rotation_back_matrix: rotate_back's rotation exp(-[phi]x), row by row */
void fc_rotation_back_matrix(const fc_real phi[3], const fc_real t[4], fc_real m[9]);
/* kinematics.up_terms: sin(roll) cos(pitch), cos(roll) cos(pitch), sin(pitch), cos(pitch) of q */
void fc_up_terms(const fc_real q[4], fc_real t[4]);
/* kinematics.angle_of: atan2(num, den), a small angle by arctan's series */
fc_real fc_angle_of(fc_real num, fc_real den);
/* kinematics.half_angle: cos(a/2) and sin(a/2) */
void fc_half_angle(fc_real a, fc_real *c, fc_real *s);
/* kinematics.sin_cos: sin a and cos a from half_angle */
void fc_sin_cos(fc_real a, fc_real *s, fc_real *c);
/* kinematics.quat_turn_roll_pitch: q with roll + dr and pitch + dp, its yaw kept (t: up_terms) */
void fc_quat_turn_roll_pitch(fc_real q[4], const fc_real t[4], fc_real dr, fc_real dp);
void fc_rotate_back_terms(const fc_real v[3], const fc_real phi[3], const fc_real t[4],
                          fc_real out[3]);

/* ----- building_blocks.py ------------------------------------------------------------------ */
#define FC_REST_MEAN_TAU 0.5
#define FC_REST_TURN 0.1
#define FC_ZERO_RATE_TAU 0.01
#define FC_REST_SIZE 17  /* building_blocks.RestState */
#define FC_SLOWEST_CORRECTION 1e9
#define FC_FACE_SWITCH_COS 0.5
extern const fc_real FC_FACES[6][9];
void fc_quat_from_roll_pitch(fc_real roll, fc_real pitch, fc_real q[4]);
/* building_blocks.tilt_innovation: the accelerometer's roll and pitch less those of up */
void fc_tilt_innovation(fc_real ax, fc_real ay, fc_real az, const fc_real up[4], fc_real *y_roll,
                        fc_real *y_pitch);
/* building_blocks.corrected_quat: q (up: its up_terms) turned by the correction dr, dp to roll
 * and pitch */
void fc_corrected_quat(fc_real q[4], const fc_real up[4], fc_real roll, fc_real pitch, fc_real dr,
                       fc_real dp);
void fc_gate_bounds2(fc_real gate_low, fc_real gate_high, fc_real *low2, fc_real *high2);
/* building_blocks.on_the_mark: t, or mark where t is within half a sample of it (a count
 * reaches its mark at the nearest sample in float as in double) */
fc_real fc_on_the_mark(fc_real t, fc_real dt, fc_real mark);
void fc_body_rotation(const fc_real g0[3], const fc_real g1[3], const fc_real bias[3], fc_real dt,
                      int trapezoid, fc_real phi[3]);
/* building_blocks.lowpass_specific_force: f turned by back (rotation_back_matrix), blended
 * with a by k = dt / (tau + dt) */
void fc_lowpass_specific_force(fc_real f[3], const fc_real back[9], const fc_real a[3], fc_real k);
/* adaptive_noise_constants: the rotation term of the process noise per (rad/s)^2 and the
 * disturbance's averaging time (0: off, also without the pre-filter acc_tau) */
void fc_adaptive_noise_constants(fc_real gyro_scale_std, fc_real scale_time,
                                 fc_real disturbance_time, fc_real acc_tau, fc_real *q_rotation,
                                 fc_real *dist_tau);
/* correction_time: a complementary filter's time constant under the adaptive noise, at most the
 * larger of tau and longest */
fc_real fc_correction_time(fc_real tau, fc_real r_ratio, fc_real q_rotation, fc_real w2, fc_real r,
                          fc_real dt, fc_real longest);
/* adaptive_prefilter_time: tau times the disturbance's excess over the noise, in units of
 * PREFILTER_FULL times the noise, between 0 and tau */
fc_real fc_adaptive_prefilter_time(fc_real tau, fc_real dist, fc_real noise);
/* ----- measured_vector.py ------------------------------------------------------------------ */
/* Measure: the measured vector's state as one array of doubles, in the Python NamedTuple's
 * order: each second-order low-pass as its two stages (the first stage, then the output), the
 * disturbance statistics, the two times and the mean square rate, the slow band's fast powers,
 * the lags, the last sample, the mean square of its changes and the time since a burst. */
enum {
    FC_MEAS_F1 = 0, FC_MEAS_F = 3, FC_MEAS_REF1 = 6, FC_MEAS_REF = 9, FC_MEAS_S1 = 12,
    FC_MEAS_S = 15, FC_MEAS_DIST = 18, FC_MEAS_SLOW = 19, FC_MEAS_FILL = 20, FC_MEAS_SETTLE = 21,
    FC_MEAS_RATE2 = 22, FC_MEAS_BAND_IN = 23, FC_MEAS_BAND_MID = 24, FC_MEAS_LAG_REF1 = 25,
    FC_MEAS_LAG_REF = 28, FC_MEAS_LAG_S1 = 31, FC_MEAS_LAG_S = 34, FC_MEAS_PREV = 37,
    FC_MEAS_DIFF = 40, FC_MEAS_FRESH = 41,
    FC_MEAS_SIZE = 42
};
/* MeasureConstants */
typedef struct fc_meas_constants {
    fc_real stage, dist_tau, noise, band, r, turn, stretch, leak, held2, burst2;
} fc_meas_constants;
void fc_measure_constants(fc_real acc_lowpass, fc_real disturbance_time, fc_real band, fc_real r,
                          fc_real gyro_scale_std, fc_real stretch, fc_real leak, fc_real held,
                          fc_real burst, fc_meas_constants *c);
/* measure_start: every low-pass at a, no disturbance measured, settled */
void fc_measure_start(fc_real m[FC_MEAS_SIZE], const fc_real a[3], const fc_meas_constants *c);
/* measure_step: one sample a (bias_measured: a rest has measured the gyro bias, the vector may
 * grow longer); returns the measurement noise r [rad^2], *filling whether the vector is still
 * filling */
fc_real fc_measure_step(fc_real m[FC_MEAS_SIZE], const fc_real a[3], const fc_real phi[3],
                       const fc_real terms[4], fc_real dt, const fc_meas_constants *c,
                       int bias_measured, int *filling);
/* fill_noise: while the vector fills, its tilt variance and its samples' mean age [s], from
 * measure_step's noise r */
void fc_measure_fill_noise(const fc_real m[FC_MEAS_SIZE], fc_real r, fc_real dt,
                           const fc_meas_constants *c, fc_real *var, fc_real *age);
/* Measure.settled */
int fc_measure_settled(const fc_real m[FC_MEAS_SIZE], const fc_meas_constants *c);
/* within_bias_band: whether a bias may be learned by the gate (lo2, hi2): gate_norm2 within it
 * and, where that is the slow band, the vector's own squared norm a2 too */
int fc_measure_within_bias_band(const fc_real m[FC_MEAS_SIZE], const fc_meas_constants *c,
                                fc_real lo2, fc_real hi2, fc_real a2, fc_real raw2);
/* band_measured: whether the slow band is measured (the statistics on) */
int fc_measure_band_measured(const fc_meas_constants *c);
/* gate_norm2: the squared norm a bias gate judges (the slow band's, else raw2) */
fc_real fc_measure_gate_norm2(const fc_real m[FC_MEAS_SIZE], const fc_meas_constants *c,
                              fc_real raw2);
/* raw_noise */
fc_real fc_measure_raw_noise(const fc_real m[FC_MEAS_SIZE], const fc_meas_constants *c);
/* measure_restarted: aligned at f, the slow band from nothing */
void fc_measure_restart(fc_real m[FC_MEAS_SIZE], const fc_real f[3]);
/* measure_clipped */
void fc_measure_clipped(fc_real m[FC_MEAS_SIZE]);
/* every vector of the low-passes set to f (a rest alignment) */
void fc_measure_align(fc_real m[FC_MEAS_SIZE], const fc_real f[3]);

/* The rest detector's state at the first sample: its means start at that sample, quiet 0, the
 * bias not measured yet. */
void fc_rest_start(fc_real rest[FC_REST_SIZE], const fc_real gyro[3], const fc_real acc[3]);
/* rest_step: bias is the filter's gyro bias estimate in the frame of g */
void fc_rest_step(fc_real rest[FC_REST_SIZE], fc_real gx, fc_real gy, fc_real gz, fc_real ax,
                  fc_real ay, fc_real az, const fc_real bias[3], fc_real dt, fc_real th_gyro,
                  fc_real th_acc, fc_real rest_time, fc_real bound);
/* mean_share: the share of one sample's white variance in a first-order mean of time constant
 * tau; rest_mean_share: that of the rest detector's mean */
fc_real fc_mean_share(fc_real dt, fc_real tau);
fc_real fc_rest_mean_share(fc_real dt);
/* first_rest: measured_before is rest[7] before this sample's fc_rest_step */
int fc_first_rest(fc_real measured_before, const fc_real rest[FC_REST_SIZE]);
/* uncalibrated_first_rest: measured_before is rest[7] before this sample's fc_rest_step */
int fc_uncalibrated_first_rest(fc_real measured_before, const fc_real rest[FC_REST_SIZE],
                               const fc_real bias[3], fc_real th_gyro);
/* rest_alignment: bias, roll, pitch and the specific force f from the rest's means */
void fc_rest_alignment(const fc_real rest[FC_REST_SIZE], fc_real bias[3], fc_real *roll,
                       fc_real *pitch, fc_real f[3]);
/* bias_at_rest: since, the time since the rest was measured (its memory grows with it) */
void fc_bias_at_rest(fc_real bias[3], fc_real gx, fc_real gy, fc_real gz, fc_real dt,
                     fc_real rest_time, fc_real since);
/* zero_rate_sample: whether the gyro sample fc_rest_step last took may update the bias at rest
 * (the rate's short mean within ZERO_RATE_SPREAD times its white-noise variance per axis, from
 * r = psd / dt, of the rest detector's running mean rate) */
int fc_zero_rate_sample(const fc_real rest[FC_REST_SIZE], fc_real r, fc_real dt);
/* complementary_rest: the rest detection of cf and mgcf, one sample; returns 1 where they
 * aligned (*roll, *pitch and f, the specific force the vector starts again from, set), else 0 */
int fc_complementary_rest(fc_real rest[FC_REST_SIZE], fc_real bias[3], const fc_real g[3],
                          const fc_real a[3], fc_real dt, fc_real rest_time, fc_real rest_gyro,
                          fc_real rest_acc, fc_real bound, fc_real *roll, fc_real *pitch,
                          fc_real f[3]);
void fc_bias_band2(fc_real gate, fc_real *lo, fc_real *hi);
fc_real fc_motion_bias_ki(fc_real tau, fc_real gain, fc_real dt, fc_real stage);
int fc_nearest_face(fc_real ux, fc_real uy, fc_real uz);
void fc_mat_vec(const fc_real m[9], const fc_real v[3], fc_real out[3]);
void fc_mat_t_vec(const fc_real m[9], const fc_real v[3], fc_real out[3]);

/* ----- base.py ----------------------------------------------------------------------------- */
void fc_mounting_matrix(fc_real roll, fc_real pitch, fc_real yaw, fc_real m[9]);
/* Estimator._set_params' shared part, the input stage's constants from its parameters
 * (fc_input_params, base.COMMON_PARAMS): the gyro sampling rule, the sample rules, the part's
 * calibration, the mounting, the gyro's range and the sensor's delay. */
void fc_base_configure(fc_base *b, const fc_input_params *in);
void fc_base_reset(fc_base *b);
/* The sample rules of Estimator.step: checks the sample (a rejection leaves every state as it
 * was), applies the calibration, turns it into the filter frame (mounting) and takes an absurd
 * accelerometer reading as
 * none. Returns FC_OK with acc and gyro rewritten in place, or the rejection. */
fc_status fc_base_prepare(fc_base *b, fc_real acc[3], fc_real gyro[3], fc_real dt);
/* Estimator.output: *e as the outputs give it, its roll and pitch turned ahead over sensor_delay
 * with the last sample's rate minus e's bias (fc_roll_pitch_ahead) once initialised; in place. */
void fc_base_output(const fc_base *b, fc_estimate *e);
/* Whether a prepared sample may initialise the filter (its accelerometer norm >= 0.1 g). */
int fc_base_can_init(const fc_real acc[3]);

/* What an estimator adds to the shared step (Estimator._init, _advance, _estimate), on a
 * prepared sample (in the filter frame); self is the estimator's struct. */
typedef struct fc_ops {
    void (*first_sample)(void *self, const fc_real acc[3], const fc_real gyro[3]);
    void (*advance)(void *self, const fc_real acc[3], const fc_real gyro[3], fc_real dt);
    void (*estimate)(const void *self, fc_estimate *out);  /* T_estimate, written to *out */
} fc_ops;

/* Estimator.step for any estimator: the sample rules, then first_sample or advance; *last is the
 * estimator's last estimate. FC_OK or FC_SKIPPED with *out the estimate (out may be NULL); a
 * rejection leaves everything as it was. */
fc_status fc_step(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last,
                  const fc_real acc[3], const fc_real gyro[3], fc_real dt, fc_estimate *out);
/* Estimator.step_prepared: a sample a filter holding this one has already checked and conditioned
 * (fc_base_prepare with the same limits), with its rail flag clipped; the rest of fc_step. */
fc_status fc_step_prepared(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last,
                           const fc_real a[3], const fc_real g[3], fc_real dt, int clipped,
                           fc_estimate *out);
/* Estimator.run for any estimator: n samples (acc, gyro [n][3] row-major, dt [n]), out[i] the
 * estimate after sample i, the last one for a rejected sample (rejected[i] = 1, counted in
 * n_rejected). Returns the number of rejected samples. */
long fc_run(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last, long n,
            const fc_real *acc, const fc_real *gyro, const fc_real *dt, fc_estimate *out,
            unsigned char *rejected);
/* fc_run with the estimates written as columns, each where its caller keeps it: roll[n],
 * pitch[n], bias[n][3], and pos[n][3] and vel[n][3] unless NULL (Estimator.run's arrays,
 * without an array of whole estimates between) */
long fc_run_columns(const fc_ops *ops, void *self, fc_base *base, fc_estimate *last, long n,
                    const fc_real *acc, const fc_real *gyro, const fc_real *dt, fc_real *roll,
                    fc_real *pitch, fc_real *bias, fc_real *pos, fc_real *vel,
                    unsigned char *rejected);

/* The functions every estimator T's twin has (fc_cf, ...; Estimator's life cycle), declared by
 * its header with FC_DECLARE_ESTIMATOR(T):
 * - T_init(f, params): params (NULL: the defaults) in, a filter waiting for its first sample out;
 * - T_configure(f): take a change of f->params (the state is kept);
 * - T_reset(f): forget every sample;
 * - T_step(f, acc, gyro, dt, out): one sample, acc [m/s^2], gyro [rad/s], dt [s]; FC_OK or
 *   FC_SKIPPED with *out the estimate (the last one when skipped); a rejection leaves the filter
 *   and *out as they were;
 * - T_run(f, n, acc, gyro, dt, out, rejected): n samples (acc, gyro row-major [n][3], dt [n]),
 *   out[i] the estimate after sample i (the last one for a rejected sample, rejected[i] = 1,
 *   counted in n_rejected); returns the number of rejected samples;
 * - T_run_columns: T_run with the estimates written as columns (fc_run_columns);
 * - T_estimate(f): the estimate of the state as it is;
 * - T_restored(f): after a restore of the state fields (fc_state.h), recompute what follows
 *   from them.
 * fusion_core.native.library expands it for the cffi binding, which reads no macros. */
#define FC_DECLARE_ESTIMATOR(T)                                                               \
    void T##_init(T *f, const T##_params *params);                                            \
    void T##_configure(T *f);                                                                 \
    void T##_reset(T *f);                                                                     \
    fc_status T##_step(T *f, const fc_real acc[3], const fc_real gyro[3], fc_real dt,         \
                       fc_estimate *out);                                                     \
    long T##_run(T *f, long n, const fc_real *acc, const fc_real *gyro, const fc_real *dt,    \
                 fc_estimate *out, unsigned char *rejected);                                  \
    long T##_run_columns(T *f, long n, const fc_real *acc, const fc_real *gyro,               \
                         const fc_real *dt, fc_real *roll, fc_real *pitch, fc_real *bias,     \
                         fc_real *pos, fc_real *vel, unsigned char *rejected);                \
    fc_estimate T##_estimate(const T *f);                                                     \
    void T##_restored(T *f)

/* T_init(f, params) for an estimator T: params (NULL: the defaults) in, T_configure, T_reset. */
#define FC_DEFINE_INIT(T)                                                                     \
    void T##_init(T *f, const T##_params *params)                                             \
    {                                                                                         \
        if (params) {                                                                         \
            f->params = *params;                                                              \
        } else {                                                                              \
            T##_params_default(&f->params);                                                   \
        }                                                                                     \
        T##_configure(f);                                                                     \
        T##_reset(f);                                                                         \
    }

/* T_restored(f) for an estimator T: after its state fields were restored (fc_state_load), the
 * last estimate, which follows from them (Estimator.set_state: last = output()). */
#define FC_DEFINE_RESTORED(T)                                                                 \
    void T##_restored(T *f)                                                                   \
    {                                                                                         \
        f->last = T##_estimate(f);                                                            \
        fc_base_output(&f->base, &f->last);                                                   \
    }

/* The fc_ops glue of an estimator T (fc_cf, ...), written once: defines T_step and T_run from the
 * file's static first_sample(T *, acc, gyro) and advance(T *, acc, gyro, dt) and its public
 * T_estimate. */
#define FC_DEFINE_STEP_AND_RUN(T)                                                             \
    static void first_sample_op(void *self, const fc_real acc[3], const fc_real gyro[3])       \
    {                                                                                         \
        first_sample((T *)self, acc, gyro);                                                   \
    }                                                                                         \
    static void advance_op(void *self, const fc_real acc[3], const fc_real gyro[3], fc_real dt) \
    {                                                                                         \
        advance((T *)self, acc, gyro, dt);                                                    \
    }                                                                                         \
    static void estimate_op(const void *self, fc_estimate *out)                               \
    {                                                                                         \
        *out = T##_estimate((const T *)self);                                                 \
    }                                                                                         \
    static const fc_ops OPS = {first_sample_op, advance_op, estimate_op};                     \
    fc_status T##_step(T *f, const fc_real acc[3], const fc_real gyro[3], fc_real dt,            \
                       fc_estimate *out)                                                      \
    {                                                                                         \
        return fc_step(&OPS, f, &f->base, &f->last, acc, gyro, dt, out);                      \
    }                                                                                         \
    long T##_run(T *f, long n, const fc_real *acc, const fc_real *gyro, const fc_real *dt,       \
                 fc_estimate *out, unsigned char *rejected)                                   \
    {                                                                                         \
        return fc_run(&OPS, f, &f->base, &f->last, n, acc, gyro, dt, out, rejected);          \
    }                                                                                         \
    long T##_run_columns(T *f, long n, const fc_real *acc, const fc_real *gyro,                \
                         const fc_real *dt, fc_real *roll, fc_real *pitch, fc_real *bias,        \
                         fc_real *pos, fc_real *vel, unsigned char *rejected)                  \
    {                                                                                         \
        return fc_run_columns(&OPS, f, &f->base, &f->last, n, acc, gyro, dt, roll, pitch,      \
                              bias, pos, vel, rejected);                                      \
    }

#endif /* FC_CORE_H */

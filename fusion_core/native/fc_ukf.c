/* fc_ukf.c: see fc_ukf.h; the twin of fusion_core/ukf.py line by line. */
#include "fc_ukf.h"

#include "fc_paper_ukf.h"

#include <math.h>
#include <string.h>

void fc_ukf_configure(fc_ukf *f)
{
    const fc_ukf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    fc_paper_ukf_unscented_constants(p->alpha, p->beta, p->kappa, &f->gamma, &f->w, &f->w_mu);
    f->q_gyro = p->gyro_psd;
    f->q_bias = p->bias_psd;
    f->r_acc = fc_pow(p->acc_noise, 2.0);
    fc_adaptive_noise_constants(p->gyro_scale_std, p->scale_time, p->disturbance_time,
                                p->acc_lowpass, &f->q_rotation, &f->dist_tau);
    fc_measure_constants(p->acc_lowpass, f->dist_tau, p->slow_band_time, f->r_acc,
                         p->gyro_scale_std, p->acc_lowpass_stretch, p->slow_band_leak,
                         p->held_acceleration, p->burst_acceleration, &f->measure);
    f->longest2 = fc_pow(p->max_correction_time, 2.0);
    f->rail_var = fc_pow(p->input.gyro_range, 2.0) / 3.0;  /* the rate beyond the rail, per axis */
    fc_bias_band2(p->bias_gate, &f->bias_lo2, &f->bias_hi2);
    f->cos_innovation = p->bias_innovation < FC_PI ? fc_cos(p->bias_innovation) : -2.0;
    f->cos_gross = p->gross_innovation < FC_PI ? fc_cos(p->gross_innovation) : -2.0;
}

fc_estimate fc_ukf_estimate(const fc_ukf *f)
{
    return fc_paper_ukf_gravity_estimate(f->x);
}

void fc_ukf_reset(fc_ukf *f)
{
    fc_base_reset(&f->base);
    const fc_real x0[6] = {0.0, 0.0, 1.0, 0.0, 0.0, 0.0};
    memcpy(f->x, x0, sizeof x0);
    memset(f->P, 0, sizeof f->P);
    static const fc_real zero[3] = {0.0, 0.0, 0.0};
    fc_measure_start(f->meas, zero, &f->measure);
    memset(f->rest, 0, sizeof f->rest);
    f->last = fc_ukf_estimate(f);
}

FC_DEFINE_INIT(fc_ukf)
FC_DEFINE_RESTORED(fc_ukf)

static void first_sample(fc_ukf *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    fc_real n = fc_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    f->x[0] = a[0] / n;
    f->x[1] = a[1] / n;
    f->x[2] = a[2] / n;
    f->x[3] = f->x[4] = f->x[5] = 0.0;
    /* a sample whose norm is off g by d carries at least d of linear acceleration */
    fc_real p_x = fc_pow(f->params.acc_noise, 2.0);
    if (f->params.acc_lowpass > 0.0) {
        fc_real d = (n - FC_G) / FC_G;
        p_x += d * d;
    }
    fc_real p_b = fc_pow(f->params.init_bias_std, 2.0);
    memset(f->P, 0, sizeof f->P);
    f->P[0] = f->P[2] = f->P[5] = p_x;
    f->P[9] = f->P[14] = f->P[20] = p_b;
    fc_measure_start(f->meas, a, &f->measure);
    fc_rest_start(f->rest, g, a);
}

/* _zero_rate_update: at rest the gyro reads its bias (z = gyro, h(x) = b, variance r) */
static void zero_rate_update(fc_ukf *f, const fc_real z[3], fc_real r)
{
    const fc_real *P = f->P;
    fc_real L[6];
    if (!fc_paper_ukf_cholesky3(P[9] + r, P[13], P[14] + r, P[18], P[19], P[20] + r, L)) {
        return;
    }
    fc_real l00 = L[0], l10 = L[1], l11 = L[2], l20 = L[3], l21 = L[4], l22 = L[5];
    fc_real cols[7][3];
    for (int j = 0; j < 7; j++) {
        fc_real c0, c1, c2;
        if (j < 6) {
            c0 = P[fc_paper_ukf_packed(3, j)];
            c1 = P[fc_paper_ukf_packed(4, j)];
            c2 = P[15 + j];
        } else {
            c0 = z[0] - f->x[3];
            c1 = z[1] - f->x[4];
            c2 = z[2] - f->x[5];
        }
        fc_real y0 = c0 / l00;
        fc_real y1 = (c1 - l10 * y0) / l11;
        cols[j][0] = y0;
        cols[j][1] = y1;
        cols[j][2] = (c2 - l20 * y0 - l21 * y1) / l22;
    }
    const fc_real *v = cols[6];
    fc_real x[6], Pn[21];
    for (int i = 0; i < 6; i++) {
        x[i] = f->x[i] + (cols[i][0] * v[0] + cols[i][1] * v[1] + cols[i][2] * v[2]);
    }
    for (int i = 0, k = 0; i < 6; i++) {
        for (int j = 0; j <= i; j++, k++) {
            Pn[k] = P[fc_paper_ukf_packed(i, j)]
                - (cols[i][0] * cols[j][0] + cols[i][1] * cols[j][1] + cols[i][2] * cols[j][2]);
        }
    }
    memcpy(f->P, Pn, sizeof Pn);
    fc_real n = fc_sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    f->x[0] = x[0] / n;
    f->x[1] = x[1] / n;
    f->x[2] = x[2] / n;
    f->x[3] = x[3];
    f->x[4] = x[4];
    f->x[5] = x[5];
}

/* raised_direction_variance: each of X's variances at least var (gross_innovation) */
static void raised_direction_variance(fc_real P[21], fc_real var)
{
    for (int i = 0; i < 3; i++) {
        int k = fc_paper_ukf_packed(i, i);
        if (var > P[k]) {
            P[k] = var;
        }
    }
}

/* measured_covariance: P once X is taken from a measured vector of variance var per axis whose
 * samples the gyro turned over age [s] on average: P_XX = var I + age^2 [X]x P_bb [X]x^T,
 * P_Xb = -age [X]x P_bb, P_bb kept (packed lower triangle of [X, b]) */
static void measured_covariance(fc_real P[21], const fc_real X[3], fc_real var, fc_real age)
{
    const fc_real S[3][3] = {{0.0, -X[2], X[1]}, {X[2], 0.0, -X[0]}, {-X[1], X[0], 0.0}};
    fc_real B[3][3], M[3][3];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            B[i][j] = P[fc_paper_ukf_packed(3 + i, 3 + j)];
        }
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            M[i][j] = S[i][0] * B[0][j] + S[i][1] * B[1][j] + S[i][2] * B[2][j];
        }
    }
    fc_real a2 = age * age;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            P[fc_paper_ukf_packed(3 + j, i)] = 0.0 - age * M[i][j];
        }
        for (int k = 0; k <= i; k++) {
            fc_real s = a2 * (M[i][0] * S[k][0] + M[i][1] * S[k][1] + M[i][2] * S[k][2]);
            P[fc_paper_ukf_packed(i, k)] = k == i ? var + s : s;
        }
    }
}

/* _filter_update: one sample of the paper's UKF (eq. 14-17) with the recommended noise; capped:
 * r is the measured vector's, at most max_correction_time's; fill (NULL unless the vector still
 * fills): its variance and its samples' mean age, and X is its direction */
static void filter_update(fc_ukf *f, fc_real ax, fc_real ay, fc_real az, const fc_real g[3],
                          fc_real dt, int learn_bias, fc_real r, int capped, const fc_real *fill)
{
    fc_real b[3] = {f->x[3], f->x[4], f->x[5]};
    fc_real terms[6];
    fc_paper_ukf_rotation_terms(f->base.gyro_prev, g, dt, f->base.trapezoid, terms);
    fc_ukf_prediction pred;
    fc_paper_ukf_sigma_predict(f->x, f->P, terms, dt, f->gamma, f->w, f->w_mu, 0, &pred);
    fc_real X0 = pred.X[0], X1 = pred.X[1], X2 = pred.X[2];
    fc_real n = fc_sqrt(X0 * X0 + X1 * X1 + X2 * X2);
    fc_real inv = 1.0 / n;
    fc_real q_gyro = f->q_gyro;
    if (f->q_rotation > 0.0) {  /* gyro_scale_std: a scale error adds up while the sensor turns */
        fc_real wx = g[0] - b[0], wy = g[1] - b[1], wz = g[2] - b[2];
        q_gyro += f->q_rotation * (wx * wx + wy * wy + wz * wz);
    }
    if (f->base.clipped) {  /* at the rail the rate beyond it is unknown (gyro_range) */
        q_gyro += f->rail_var * dt;
    }
    fc_real h[3] = {X0 * inv, X1 * inv, X2 * inv}, P[21];
    fc_paper_ukf_predicted_covariance(&pred, f->P, h, q_gyro * dt, f->q_bias * dt, P);
    fc_real x[6] = {X0, X1, X2, b[0], b[1], b[2]};
    fc_real norm = fc_sqrt(ax * ax + ay * ay + az * az);
    int gate = fc_fabs(norm / FC_G - 1.0) < FC_UKF_ACC_GATE && norm > 0.0;
    if (gate && fill) {  /* the vector still fills: X is its direction, as uncertain */
        x[0] = ax;
        x[1] = ay;
        x[2] = az;
        n = norm;
        const fc_real h_new[3] = {x[0] / n, x[1] / n, x[2] / n};
        measured_covariance(P, h_new, fill[0], fill[1]);
    } else if (gate) {
        fc_real dot = ax * X0 + ay * X1 + az * X2;
        if (dot < f->cos_innovation * norm * n) {
            learn_bias = 0;  /* grossly off: X only (bias_innovation) */
        }
        if (dot < f->cos_gross * norm * n) {  /* off by more than gross_innovation: X's
                                               * variance at least the two directions' distance^2 */
            raised_direction_variance(P, 2.0 - 2.0 * (dot / (norm * n)));
        }
        if (capped) {  /* the longest correction time: r at most q T^2 / dt */
            fc_real cap = q_gyro * f->longest2 / dt;
            r = r < cap ? r : (cap > f->r_acc ? cap : f->r_acc);
        }
        const fc_real acc[3] = {ax, ay, az};
        fc_paper_ukf_measurement_update(&pred, b, P, acc, r, f->w, f->w_mu, 0, 0.0, learn_bias,
                                        x);
        n = fc_sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    }
    f->x[0] = x[0] / n;
    f->x[1] = x[1] / n;
    f->x[2] = x[2] / n;
    f->x[3] = x[3];
    f->x[4] = x[4];
    f->x[5] = x[5];
    memcpy(f->P, P, sizeof P);
}

static void advance(fc_ukf *f, const fc_real a[3], const fc_real g[3], fc_real dt)
{
    const fc_ukf_params *p = &f->params;
    fc_real raw2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    int clipped = f->base.clipped;
    if (p->acc_lowpass > 0.0) {  /* _update: the real-sensor options */
        fc_real phi[3], terms[4], b[3] = {f->x[3], f->x[4], f->x[5]};
        fc_body_rotation(f->base.gyro_prev, g, b, dt, f->base.trapezoid, phi);
        fc_rotvec_terms(phi[0], phi[1], phi[2], terms);  /* once, for the low-passes */
        int filling;
        if (clipped) {
            fc_measure_clipped(f->meas);
        }
        fc_real r = fc_measure_step(f->meas, a, phi, terms, dt, &f->measure, f->rest[7] > 0.0,
                                   &filling);
        /* the bias gate on what reaches the vector (gate_norm2); no bias from a vector that is
         * filling or holds turns the gyro did not measure */
        fc_real n2 = fc_measure_gate_norm2(f->meas, &f->measure, raw2);
        int learn_bias = f->bias_lo2 < n2 && n2 < f->bias_hi2 && !clipped && !filling
                         && fc_measure_settled(f->meas, &f->measure);
        const fc_real *m = f->meas + FC_MEAS_F;
        fc_real fill[2];
        if (filling) {
            fc_measure_fill_noise(f->meas, r, dt, &f->measure, &fill[0], &fill[1]);
        }
        filter_update(f, m[0], m[1], m[2], g, dt, learn_bias, r, 1, filling ? fill : NULL);
    } else {  /* the raw sample (bias_gate); never a sample at the rail */
        int learn_bias = f->bias_lo2 < raw2 && raw2 < f->bias_hi2 && !clipped;
        filter_update(f, a[0], a[1], a[2], g, dt, learn_bias, f->r_acc, 0, NULL);
    }
    if (p->rest_time > 0.0 && !clipped) {
        fc_real measured = f->rest[7];
        fc_rest_step(f->rest, g[0], g[1], g[2], a[0], a[1], a[2], &f->x[3], dt, p->rest_gyro,
                     p->rest_acc, p->rest_time, p->rest_bias_bound);
        if (p->acc_lowpass > 0.0 && fc_first_rest(measured, f->rest)) {
            /* the measured vector starts again from the rest's mean, X from its direction, as
             * sure of it as that mean is (and independent of the bias) */
            const fc_real *m = f->rest + 3;
            fc_measure_restart(f->meas, m);
            fc_real n = fc_sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
            f->x[0] = m[0] / n;
            f->x[1] = m[1] / n;
            f->x[2] = m[2] / n;
            measured_covariance(f->P, f->x, fc_pow(p->acc_noise, 2.0) * fc_rest_mean_share(dt),
                                0.0);
        }
        if (f->rest[6] >= p->rest_time) {
            fc_real r = p->zaru_psd / dt;
            if (fc_zero_rate_sample(f->rest, r, dt)) {  /* a still gyro's sample */
                zero_rate_update(f, g, r);
            }
        }
    }
}

FC_DEFINE_STEP_AND_RUN(fc_ukf)

/* fc_sensor.c: see fc_sensor.h; the twin of fusion_core/sensor.py line by line. */
#include "fc_sensor.h"

#include <math.h>
#include <string.h>

#include "fc_core.h"
#include "fc_noise.h"

#define DEG (FC_PI / 180.0)
#define MG (1e-3 * FC_G)

/* sensor.DLPF_TABLE: accelerometer bandwidth [Hz], delay [s], gyro bandwidth, delay */
static const double DLPF_TABLE[7][4] = {
    {260.0, 0.0, 256.0, 0.00098}, {184.0, 0.002, 188.0, 0.0019}, {94.0, 0.003, 98.0, 0.0028},
    {44.0, 0.0049, 42.0, 0.0048}, {21.0, 0.0085, 20.0, 0.0083}, {10.0, 0.0138, 10.0, 0.0134},
    {5.0, 0.019, 5.0, 0.0186},
};

/* sensor.CALIBRATION: per-axis std of the gyro and accelerometer biases, the accelerometer's
 * scale and cross-axis std, for calibration = startup, none, perfect */
static void calibration(int which, double gyro_std[3], double acc_std[3], double *acc_scale,
                        double *acc_cross)
{
    if (which == FC_SENSOR_CALIBRATION_STARTUP) {
        gyro_std[0] = gyro_std[1] = gyro_std[2] = 0.16 * DEG;
        acc_std[0] = acc_std[1] = acc_std[2] = 0.5 * MG;
        *acc_scale = 0.001;
        *acc_cross = 0.001;
    } else if (which == FC_SENSOR_CALIBRATION_NONE) {
        gyro_std[0] = gyro_std[1] = gyro_std[2] = 20.0 / 3.0 * DEG;
        acc_std[0] = acc_std[1] = 50.0 / 3.0 * MG;
        acc_std[2] = 80.0 / 3.0 * MG;
        *acc_scale = 0.01;
        *acc_cross = 0.02 / 3.0;
    } else {
        gyro_std[0] = gyro_std[1] = gyro_std[2] = 0.0;
        acc_std[0] = acc_std[1] = acc_std[2] = 0.0;
        *acc_scale = 0.0;
        *acc_cross = 0.0;
    }
}

static void lowpass_init(fc_lowpass2 *lp, double bandwidth, double delay)
{
    memset(lp, 0, sizeof *lp);
    lp->bandwidth = bandwidth;
    lp->delay = delay;
}

static void lowpass_design(fc_lowpass2 *lp, double h)  /* LowPass2._design */
{
    lp->h = h;
    if (lp->bandwidth >= 0.45 / h) {
        double c = lp->delay / h;
        lp->coef[0] = c < 1.0 ? c : 1.0;  /* min(delay / h, 1.0) */
        lp->n_coef = 1;
        return;
    }
    double k = tan(FC_PI * lp->bandwidth * h);
    double norm = 1.0 / (1.0 + sqrt(2.0) * k + k * k);
    double b0 = k * k * norm;
    lp->coef[0] = b0;
    lp->coef[1] = 2.0 * b0;
    lp->coef[2] = b0;
    lp->coef[3] = 2.0 * (k * k - 1.0) * norm;
    lp->coef[4] = (1.0 - sqrt(2.0) * k + k * k) * norm;
    lp->n_coef = 5;
}

static void lowpass(fc_lowpass2 *lp, double x[3], double h)  /* LowPass2.__call__ */
{
    if (h != lp->h) {
        lowpass_design(lp, h);
    }
    if (!lp->started) {
        for (int i = 0; i < 3; i++) {
            lp->state[i][0] = lp->state[i][1] = lp->state[i][2] = lp->state[i][3] = x[i];
        }
        lp->started = 1;
    }
    for (int i = 0; i < 3; i++) {
        double v = x[i], *s = lp->state[i], y;
        if (lp->n_coef == 1) {
            y = v - lp->coef[0] * (v - s[0]);
        } else {
            y = lp->coef[0] * v + lp->coef[1] * s[0] + lp->coef[2] * s[1] - lp->coef[3] * s[2]
                - lp->coef[4] * s[3];
        }
        s[1] = s[0];
        s[0] = v;
        s[3] = s[2];
        s[2] = y;
        x[i] = y;
    }
}

/* _error_matrix: I + diag(scale errors) + cross-axis terms, from 9 normals */
static void error_matrix(const double *z, double scale_std, double cross_std, double m[3][3])
{
    int c = 3;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            m[i][j] = i == j ? 1.0 + z[i] * scale_std : z[c++] * cross_std;
        }
    }
}

static void apply(const double *m, const double v[3], double out[3])  /* _apply; m row-major */
{
    for (int i = 0; i < 3; i++) {
        out[i] = m[3 * i] * v[0] + m[3 * i + 1] * v[1] + m[3 * i + 2] * v[2];
    }
}

static double convert(double v, double full_scale, long bits, double lsb)  /* _convert */
{
    v = v > -full_scale ? v : -full_scale;
    v = full_scale > v ? v : full_scale;
    return bits ? nearbyint(v / lsb) * lsb : v;
}

void fc_sensor_reset(fc_sensor *s)
{
    const fc_sensor_params *p = &s->params;
    s->noise_key = fc_stream_key((uint64_t)p->seed, 0);
    s->k = 0;
    double r[FC_SENSOR_RUN_NORMALS], gyro_std[3], acc_std[3], acc_scale, acc_cross;
    fc_normals(fc_stream_key((uint64_t)p->seed, 1), 0, FC_SENSOR_RUN_NORMALS, r);
    calibration(p->calibration, gyro_std, acc_std, &acc_scale, &acc_cross);
    for (int i = 0; i < 3; i++) {
        s->gyro_turn_on[i] = r[i] * gyro_std[i];
        s->acc_turn_on[i] = r[3 + i] * acc_std[i];
    }
    error_matrix(r + 6, p->gyro_scale_std, p->gyro_cross_axis_std, s->gyro_matrix);
    error_matrix(r + 15, acc_scale, acc_cross, s->acc_matrix);
    for (int i = 0; i < 3; i++) {
        s->gyro_walk[i] = s->acc_walk[i] = 0.0;
        s->gyro_gm[i] = r[24 + i] * p->gyro_bias_instability;
        s->acc_gm[i] = r[27 + i] * p->acc_bias_instability;
    }
    s->has_omega_prev = 0;
    memset(s->omega_prev, 0, sizeof s->omega_prev);
    s->time_error = 0.0;
    s->filtered = p->dlpf_cfg >= 0;
    if (s->filtered) {
        const double *row = DLPF_TABLE[p->dlpf_cfg];
        lowpass_init(&s->acc_filter, row[0], row[1]);
        lowpass_init(&s->gyro_filter, row[2], row[3]);
    }
}

void fc_sensor_init(fc_sensor *s, const fc_sensor_params *params)
{
    if (params) {
        s->params = *params;
    } else {
        fc_sensor_params_default(&s->params);
    }
    fc_sensor_reset(s);
}

void fc_sensor_gyro_bias(const fc_sensor *s, double out[3])
{
    const fc_sensor_params *p = &s->params;
    const double constant[3] = {p->gyro_bias_x, p->gyro_bias_y, p->gyro_bias_z};
    for (int i = 0; i < 3; i++) {
        out[i] = constant[i] + s->gyro_turn_on[i] + s->gyro_walk[i] + s->gyro_gm[i];
    }
}

static void acc_bias(const fc_sensor *s, double out[3])
{
    const fc_sensor_params *p = &s->params;
    const double constant[3] = {p->acc_bias_x, p->acc_bias_y, p->acc_bias_z};
    for (int i = 0; i < 3; i++) {
        out[i] = constant[i] + s->acc_turn_on[i] + s->acc_walk[i] + s->acc_gm[i];
    }
}

/* What a sample computes from its interval h and the parameters only: the noise and drive
 * scales, the quantisation steps, and which normals the sample uses (a term switched off, whose
 * scale is 0, adds 0 whatever its deviate). fc_sensor_run computes them once per distinct h. */
typedef struct interval {
    double h, gw, aw, decay, g_gm, a_gm, gn, an, lsb_a, lsb_g;
    unsigned char used[FC_SENSOR_NORMALS];
} interval;

static void interval_constants(const fc_sensor_params *p, double h, interval *c)
{
    c->h = h;
    c->gw = sqrt(p->gyro_bias_psd * h);
    c->aw = sqrt(p->acc_bias_psd * h);
    c->decay = exp(-h / p->bias_time_constant);
    double drive = sqrt(1.0 - c->decay * c->decay);
    c->g_gm = drive * p->gyro_bias_instability;
    c->a_gm = drive * p->acc_bias_instability;
    c->gn = sqrt(p->gyro_psd / h);
    c->an = sqrt(p->acc_psd / h);
    c->lsb_a = p->bits ? 2.0 * p->acc_range / pow(2.0, (double)p->bits) : 0.0;
    c->lsb_g = p->bits ? 2.0 * p->gyro_range / pow(2.0, (double)p->bits) : 0.0;
    /* channels: white noise 0-5, random walk 6-11, Gauss-Markov 12-17, jitter 18 */
    const double scale[6] = {c->gn, c->an, c->gw, c->aw, c->g_gm, c->a_gm};
    for (int b = 0; b < 6; b++) {
        for (int i = 0; i < 3; i++) {
            c->used[3 * b + i] = scale[b] != 0.0;
        }
    }
    c->used[18] = p->jitter > 0.0;
}

static void sample_in(fc_sensor *s, const interval *c, const double omega[3],
                      const double f[3], double acc_out[3], double gyro_out[3], double *dt)
{
    const fc_sensor_params *p = &s->params;
    double h = c->h;
    double z[FC_SENSOR_NORMALS];
    fc_normals_used(s->noise_key, (uint64_t)s->k, FC_SENSOR_NORMALS, c->used, z);
    s->k += 1;
    double rate[3] = {omega[0], omega[1], omega[2]};
    if (p->gyro_sampling == FC_SENSOR_GYRO_SAMPLING_MEAN) {
        double prev[3];
        memcpy(prev, s->has_omega_prev ? s->omega_prev : rate, sizeof prev);
        memcpy(s->omega_prev, omega, sizeof s->omega_prev);
        s->has_omega_prev = 1;
        for (int i = 0; i < 3; i++) {
            rate[i] = 0.5 * (prev[i] + omega[i]);
        }
    }
    double decay = c->decay;
    for (int i = 0; i < 3; i++) {
        s->gyro_walk[i] += c->gw * z[6 + i];
        s->acc_walk[i] += c->aw * z[9 + i];
        s->gyro_gm[i] = decay * s->gyro_gm[i] + c->g_gm * z[12 + i];
        s->acc_gm[i] = decay * s->acc_gm[i] + c->a_gm * z[15 + i];
    }
    double gn = c->gn, an = c->an;
    double gb[3], ab[3], g[3], a[3];
    fc_sensor_gyro_bias(s, gb);
    acc_bias(s, ab);
    apply(&s->gyro_matrix[0][0], rate, g);
    apply(&s->acc_matrix[0][0], f, a);
    for (int i = 0; i < 3; i++) {
        g[i] = g[i] + gb[i] + gn * z[i];
        a[i] = a[i] + ab[i] + an * z[3 + i];
    }
    if (s->filtered) {
        lowpass(&s->gyro_filter, g, h);
        lowpass(&s->acc_filter, a, h);
    }
    /* a host's step h carries the rounding of its time grid: without jitter, h to the ps */
    *dt = floor(h * 1e12 + 0.5) / 1e12;
    if (p->jitter > 0.0) {
        double new_error = p->jitter * z[18];
        double d = h + new_error - s->time_error, floor = 1e-6 * h;
        *dt = floor > d ? floor : d;  /* max(d, 1e-6 h) */
        s->time_error = new_error;
    }
    for (int i = 0; i < 3; i++) {
        acc_out[i] = convert(a[i], p->acc_range, p->bits, c->lsb_a);
        gyro_out[i] = convert(g[i], p->gyro_range, p->bits, c->lsb_g);
    }
}

int fc_sensor_sample(fc_sensor *s, const double omega[3], const double f[3], double h,
                     double acc_out[3], double gyro_out[3], double *dt)
{
    if (!(h > 0.0)) {
        return -1;
    }
    interval c;
    interval_constants(&s->params, h, &c);
    sample_in(s, &c, omega, f, acc_out, gyro_out, dt);
    return 0;
}

int fc_sensor_run(fc_sensor *s, long n, const double *omega, const double *f, const double *h,
                  double *acc, double *gyro, double *dt, double *gyro_bias)
{
    interval c;
    c.h = 0.0;  /* no interval yet: the first sample computes its constants */
    for (long i = 0; i < n; i++) {
        if (!(h[i] > 0.0)) {
            return -1;
        }
        if (h[i] != c.h) {
            interval_constants(&s->params, h[i], &c);
        }
        sample_in(s, &c, omega + 3 * i, f + 3 * i, acc + 3 * i, gyro + 3 * i, dt + i);
        fc_sensor_gyro_bias(s, gyro_bias + 3 * i);
    }
    return 0;
}

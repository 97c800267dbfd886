/* fc_ukf.c: see fc_ukf.h; the twin of fusion_core/ukf.py line by line. */
#include "fc_ukf.h"

#include <math.h>
#include <string.h>

#define N_STATE 6
#define JACOBI_SWEEPS 30

static int packed(int i, int j)  /* _packed_index */
{
    if (j > i) {
        int t = i;
        i = j;
        j = t;
    }
    return i * (i + 1) / 2 + j;
}

/* _psd_sqrt_columns: gamma V sqrt(max(w, 0)) by cyclic Jacobi rotations; off[j] is column j */
static void psd_sqrt_columns(const double P[21], double gamma, double off[6][6])
{
    const int n = N_STATE;
    double A[6][6], V[6][6];
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) {
            A[i][j] = P[packed(i, j)];
            V[i][j] = i == j ? 1.0 : 0.0;
        }
    }
    for (int sweep = 0; sweep < JACOBI_SWEEPS; sweep++) {
        double o = 0.0;
        for (int i = 0; i < n; i++) {
            for (int j = i + 1; j < n; j++) {
                o += A[i][j] * A[i][j];
            }
        }
        if (o == 0.0) {
            break;
        }
        for (int p = 0; p < n; p++) {
            for (int q = p + 1; q < n; q++) {
                double apq = A[p][q];
                if (apq == 0.0) {
                    continue;
                }
                double theta = (A[q][q] - A[p][p]) / (2.0 * apq);
                double t = (theta >= 0.0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0);
                double s = t * c;
                for (int k = 0; k < n; k++) {
                    double akp = A[k][p], akq = A[k][q];
                    A[k][p] = c * akp - s * akq;
                    A[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < n; k++) {
                    double apk = A[p][k], aqk = A[q][k];
                    A[p][k] = c * apk - s * aqk;
                    A[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < n; k++) {
                    double vkp = V[k][p], vkq = V[k][q];
                    V[k][p] = c * vkp - s * vkq;
                    V[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for (int j = 0; j < n; j++) {
        double root = A[j][j] > 0.0 ? gamma * sqrt(A[j][j]) : 0.0;
        for (int k = 0; k < n; k++) {
            off[j][k] = V[k][j] * root;
        }
    }
}

/* _sigma_offsets: the columns of gamma L, P = L L^T (Cholesky-Banachiewicz, written out) */
static void sigma_offsets(const double P[21], double gamma, double off[6][6])
{
    double p00 = P[0], p10 = P[1], p11 = P[2], p20 = P[3], p21 = P[4], p22 = P[5];
    double p30 = P[6], p31 = P[7], p32 = P[8], p33 = P[9];
    double p40 = P[10], p41 = P[11], p42 = P[12], p43 = P[13], p44 = P[14];
    double p50 = P[15], p51 = P[16], p52 = P[17], p53 = P[18], p54 = P[19], p55 = P[20];
    double d;
    if (!(p00 > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    double l00 = sqrt(p00), i0 = 1.0 / l00;
    double l10 = p10 * i0;
    d = p11 - l10 * l10;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    double l11 = sqrt(d), i1 = 1.0 / l11;
    double l20 = p20 * i0;
    double l21 = (p21 - l20 * l10) * i1;
    d = p22 - l20 * l20 - l21 * l21;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    double l22 = sqrt(d), i2 = 1.0 / l22;
    double l30 = p30 * i0;
    double l31 = (p31 - l30 * l10) * i1;
    double l32 = (p32 - l30 * l20 - l31 * l21) * i2;
    d = p33 - l30 * l30 - l31 * l31 - l32 * l32;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    double l33 = sqrt(d), i3 = 1.0 / l33;
    double l40 = p40 * i0;
    double l41 = (p41 - l40 * l10) * i1;
    double l42 = (p42 - l40 * l20 - l41 * l21) * i2;
    double l43 = (p43 - l40 * l30 - l41 * l31 - l42 * l32) * i3;
    d = p44 - l40 * l40 - l41 * l41 - l42 * l42 - l43 * l43;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    double l44 = sqrt(d);
    double l50 = p50 * i0;
    double l51 = (p51 - l50 * l10) * i1;
    double l52 = (p52 - l50 * l20 - l51 * l21) * i2;
    double l53 = (p53 - l50 * l30 - l51 * l31 - l52 * l32) * i3;
    double l54 = (p54 - l50 * l40 - l51 * l41 - l52 * l42 - l53 * l43) / l44;
    d = p55 - l50 * l50 - l51 * l51 - l52 * l52 - l53 * l53 - l54 * l54;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    double g = gamma;
    const double cols[6][6] = {
        {g * l00, g * l10, g * l20, g * l30, g * l40, g * l50},
        {0.0, g * l11, g * l21, g * l31, g * l41, g * l51},
        {0.0, 0.0, g * l22, g * l32, g * l42, g * l52},
        {0.0, 0.0, 0.0, g * l33, g * l43, g * l53},
        {0.0, 0.0, 0.0, 0.0, g * l44, g * l54},
        {0.0, 0.0, 0.0, 0.0, 0.0, g * sqrt(d)},
    };
    memcpy(off, cols, sizeof cols);
}

/* _cholesky3 / _cholesky4: the packed lower factor, 0 when not positive definite */
static int cholesky3(double s00, double s10, double s11, double s20, double s21, double s22,
                     double L[6])
{
    if (!(s00 > 0.0)) {
        return 0;
    }
    double l00 = sqrt(s00), l10 = s10 / l00, d = s11 - l10 * l10;
    if (!(d > 0.0)) {
        return 0;
    }
    double l11 = sqrt(d), l20 = s20 / l00, l21 = (s21 - l20 * l10) / l11;
    d = s22 - l20 * l20 - l21 * l21;
    if (!(d > 0.0)) {
        return 0;
    }
    L[0] = l00;
    L[1] = l10;
    L[2] = l11;
    L[3] = l20;
    L[4] = l21;
    L[5] = sqrt(d);
    return 1;
}

static int cholesky4(const double S[10], double L[10])  /* cholesky3, then the last row */
{
    if (!cholesky3(S[0], S[1], S[2], S[3], S[4], S[5], L)) {
        return 0;
    }
    double l00 = L[0], l10 = L[1], l11 = L[2], l20 = L[3], l21 = L[4], l22 = L[5];
    double l30 = S[6] / l00, l31 = (S[7] - l30 * l10) / l11;
    double l32 = (S[8] - l30 * l20 - l31 * l21) / l22;
    double d = S[9] - l30 * l30 - l31 * l31 - l32 * l32;
    if (!(d > 0.0)) {
        return 0;
    }
    L[6] = l30;
    L[7] = l31;
    L[8] = l32;
    L[9] = sqrt(d);
    return 1;
}

/* _general_update: K^T = S^-1 P_xz^T by Gauss-Jordan with partial pivoting; x and P in place */
static void general_update(double x[6], double P[21], const double S[10],
                           const double rows[6][4], const double y[4])
{
    enum { M = 4, WIDTH = 4 + N_STATE + 1 };
    double aug[M][WIDTH];
    for (int i = 0; i < M; i++) {
        for (int j = 0; j < M; j++) {
            aug[i][j] = S[packed(i, j)];
        }
        for (int k = 0; k < N_STATE; k++) {
            aug[i][M + k] = rows[k][i];
        }
        aug[i][WIDTH - 1] = y[i];
    }
    for (int col = 0; col < M; col++) {
        int pivot = col;
        for (int i = col + 1; i < M; i++) {
            if (fabs(aug[i][col]) > fabs(aug[pivot][col])) {
                pivot = i;
            }
        }
        if (aug[pivot][col] == 0.0) {
            return;  /* singular S: x and P as they were */
        }
        double tmp[WIDTH];
        memcpy(tmp, aug[col], sizeof tmp);
        memcpy(aug[col], aug[pivot], sizeof tmp);
        memcpy(aug[pivot], tmp, sizeof tmp);
        double inv = 1.0 / aug[col][col];
        for (int k = 0; k < WIDTH; k++) {
            aug[col][k] = aug[col][k] * inv;
        }
        for (int i = 0; i < M; i++) {
            if (i != col && aug[i][col] != 0.0) {
                double f = aug[i][col];
                for (int k = 0; k < WIDTH; k++) {
                    aug[i][k] = aug[i][k] - f * aug[col][k];
                }
            }
        }
    }
    double K[N_STATE][M], Siy[M], KSK[N_STATE][N_STATE];
    for (int i = 0; i < N_STATE; i++) {
        for (int k = 0; k < M; k++) {
            K[i][k] = aug[k][M + i];
        }
    }
    for (int k = 0; k < M; k++) {
        Siy[k] = aug[k][WIDTH - 1];
    }
    for (int i = 0; i < N_STATE; i++) {
        for (int j = 0; j < N_STATE; j++) {
            double sum = 0.0;
            for (int k = 0; k < M; k++) {
                sum += K[i][k] * rows[j][k];
            }
            KSK[i][j] = sum;
        }
    }
    for (int i = 0; i < N_STATE; i++) {
        double sum = 0.0;
        for (int k = 0; k < M; k++) {
            sum += rows[i][k] * Siy[k];
        }
        x[i] = x[i] + sum;
    }
    for (int i = 0; i < N_STATE; i++) {
        for (int j = 0; j <= i; j++) {
            P[packed(i, j)] = P[packed(i, j)] - 0.5 * (KSK[i][j] + KSK[j][i]);
        }
    }
}

/* _kalman_update and _consider_bias: x + K y, P - K S K^T (eq. 17); x and P in place */
static void kalman_update(double x[6], double P[21], const double S[10], const double rows[6][4],
                          const double y[4], int learn_bias)
{
    double x_old[6], P_old[21];
    memcpy(x_old, x, sizeof x_old);
    memcpy(P_old, P, sizeof P_old);
    double L[10];
    if (!cholesky4(S, L)) {
        general_update(x, P, S, rows, y);
    } else {
        double l00 = L[0], l10 = L[1], l11 = L[2], l20 = L[3], l21 = L[4], l22 = L[5];
        double l30 = L[6], l31 = L[7], l32 = L[8], l33 = L[9];
        double i0 = 1.0 / l00, i1 = 1.0 / l11, i2 = 1.0 / l22, i3 = 1.0 / l33;
        double Y[7][4];
        for (int k = 0; k < 7; k++) {  /* forward substitution, L^-1 r, for each row and y */
            const double *r = k < 6 ? rows[k] : y;
            double y0 = r[0] * i0;
            double y1 = (r[1] - l10 * y0) * i1;
            double y2 = (r[2] - l20 * y0 - l21 * y1) * i2;
            Y[k][0] = y0;
            Y[k][1] = y1;
            Y[k][2] = y2;
            Y[k][3] = (r[3] - l30 * y0 - l31 * y1 - l32 * y2) * i3;
        }
        const double *z = Y[6];
        for (int i = 0; i < 6; i++) {
            x[i] = x_old[i] + (Y[i][0] * z[0] + Y[i][1] * z[1] + Y[i][2] * z[2] + Y[i][3] * z[3]);
        }
        for (int i = 0; i < 6; i++) {
            for (int j = 0; j <= i; j++) {
                P[packed(i, j)] = P_old[packed(i, j)] - (Y[i][0] * Y[j][0] + Y[i][1] * Y[j][1]
                                                         + Y[i][2] * Y[j][2] + Y[i][3] * Y[j][3]);
            }
        }
    }
    if (!learn_bias) {  /* the biases as consider states: b and P_bb as before */
        static const int bb[6] = {9, 13, 14, 18, 19, 20};
        x[3] = x_old[3];
        x[4] = x_old[4];
        x[5] = x_old[5];
        for (int k = 0; k < 6; k++) {
            P[bb[k]] = P_old[bb[k]];
        }
    }
}

void fc_ukf_configure(fc_ukf *f)
{
    const fc_ukf_params *p = &f->params;
    fc_base_configure(&f->base, p->max_dt, p->max_rate, p->mount_roll, p->mount_pitch,
                      p->mount_yaw, p->sensor_delay, p->gyro_range);
    double alpha2 = pow(p->alpha, 2.0);
    double lam = alpha2 * (N_STATE + p->kappa) - N_STATE;
    f->gamma = sqrt(N_STATE + lam);
    f->w = 0.5 / (N_STATE + lam);
    f->w_mu = p->beta - alpha2;
    f->q_gyro = p->gyro_psd;
    f->q_bias = p->bias_psd;
    f->r_acc = pow(p->acc_noise, 2.0);
    f->r_norm = pow(p->norm_noise, 2.0);
    fc_adaptive_noise_constants(p->gyro_scale_std, p->scale_time, p->disturbance_time,
                                p->acc_lowpass, &f->q_rotation, &f->dist_tau);
    fc_measure_constants(p->acc_lowpass, f->dist_tau, p->slow_band_time, f->r_acc, &f->measure);
    f->longest2 = pow(p->max_correction_time, 2.0);
    f->rail_var = pow(p->gyro_range, 2.0) / 3.0;  /* the rate beyond the rail, per axis */
    f->gate = p->acc_gate;
    f->trapezoid = p->gyro_sampling == FC_UKF_GYRO_SAMPLING_POINT;
    f->options = p->acc_lowpass > 0.0 || p->rest_time > 0.0;
    fc_bias_band2(p->bias_gate, &f->bias_lo2, &f->bias_hi2);
    f->cos_innovation = p->bias_innovation < FC_PI ? cos(p->bias_innovation) : -2.0;
}

fc_estimate fc_ukf_estimate(const fc_ukf *f)
{
    fc_estimate e;
    memset(&e, 0, sizeof e);
    fc_accel_roll_pitch(f->x[0], f->x[1], f->x[2], &e.roll, &e.pitch);
    e.bias[0] = f->x[3];
    e.bias[1] = f->x[4];
    e.bias[2] = f->x[5];
    return e;
}

void fc_ukf_reset(fc_ukf *f)
{
    fc_base_reset(&f->base);
    const double x0[6] = {0.0, 0.0, 1.0, 0.0, 0.0, 0.0};
    memcpy(f->x, x0, sizeof x0);
    memset(f->P, 0, sizeof f->P);
    static const double zero[3] = {0.0, 0.0, 0.0};
    fc_measure_start(f->meas, zero, &f->measure);
    memset(f->rest, 0, sizeof f->rest);
    f->last = fc_ukf_estimate(f);
}

FC_DEFINE_INIT(fc_ukf)
FC_DEFINE_RESTORED(fc_ukf)

static void first_sample(fc_ukf *f, const double a[3], const double g[3])  /* _init */
{
    double n = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    f->x[0] = a[0] / n;
    f->x[1] = a[1] / n;
    f->x[2] = a[2] / n;
    f->x[3] = f->x[4] = f->x[5] = 0.0;
    /* a sample whose norm is off g by d carries at least d of linear acceleration */
    double p_x = pow(f->params.acc_noise, 2.0);
    if (f->params.acc_lowpass > 0.0) {
        double d = (n - FC_G) / FC_G;
        p_x += d * d;
    }
    double p_b = pow(f->params.init_bias_std, 2.0);
    memset(f->P, 0, sizeof f->P);
    f->P[0] = f->P[2] = f->P[5] = p_x;
    f->P[9] = f->P[14] = f->P[20] = p_b;
    fc_measure_start(f->meas, a, &f->measure);
    fc_rest_start(f->rest, g, a);
}

/* _zero_rate_update: at rest the gyro reads its bias (z = gyro, h(x) = b, variance r) */
static void zero_rate_update(fc_ukf *f, const double z[3], double r)
{
    const double *P = f->P;
    double L[6];
    if (!cholesky3(P[9] + r, P[13], P[14] + r, P[18], P[19], P[20] + r, L)) {
        return;
    }
    double l00 = L[0], l10 = L[1], l11 = L[2], l20 = L[3], l21 = L[4], l22 = L[5];
    double cols[N_STATE + 1][3];
    for (int j = 0; j < N_STATE + 1; j++) {
        double c0, c1, c2;
        if (j < N_STATE) {
            c0 = P[packed(3, j)];
            c1 = P[packed(4, j)];
            c2 = P[15 + j];
        } else {
            c0 = z[0] - f->x[3];
            c1 = z[1] - f->x[4];
            c2 = z[2] - f->x[5];
        }
        double y0 = c0 / l00;
        double y1 = (c1 - l10 * y0) / l11;
        cols[j][0] = y0;
        cols[j][1] = y1;
        cols[j][2] = (c2 - l20 * y0 - l21 * y1) / l22;
    }
    const double *v = cols[N_STATE];
    double x[6], Pn[21];
    for (int i = 0; i < N_STATE; i++) {
        x[i] = f->x[i] + (cols[i][0] * v[0] + cols[i][1] * v[1] + cols[i][2] * v[2]);
    }
    for (int i = 0, k = 0; i < N_STATE; i++) {
        for (int j = 0; j <= i; j++, k++) {
            Pn[k] = P[packed(i, j)]
                - (cols[i][0] * cols[j][0] + cols[i][1] * cols[j][1] + cols[i][2] * cols[j][2]);
        }
    }
    memcpy(f->P, Pn, sizeof Pn);
    double n = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    f->x[0] = x[0] / n;
    f->x[1] = x[1] / n;
    f->x[2] = x[2] / n;
    f->x[3] = x[3];
    f->x[4] = x[4];
    f->x[5] = x[5];
}

/* _filter_update: one sample of the paper's UKF (eq. 14-17) */
static void filter_update(fc_ukf *f, double ax, double ay, double az, const double g[3],
                          double dt, int learn_bias, double r, int capped)
{
    double X0 = f->x[0], X1 = f->x[1], X2 = f->x[2], b0 = f->x[3], b1 = f->x[4], b2 = f->x[5];
    const double *P = f->P;
    double gx = g[0], gy = g[1], gz = g[2];
    double off[6][6];
    sigma_offsets(P, f->gamma, off);
    double c0, c1, c2, d0, d1, d2;
    if (f->trapezoid) {
        double h0 = f->base.gyro_prev[0], h1 = f->base.gyro_prev[1], h2 = f->base.gyro_prev[2];
        double k = dt * dt / 12.0, hdt = 0.5 * dt;
        c0 = hdt * (h0 + gx) + k * (h1 * gz - h2 * gy);
        c1 = hdt * (h1 + gy) + k * (h2 * gx - h0 * gz);
        c2 = hdt * (h2 + gz) + k * (h0 * gy - h1 * gx);
        d0 = k * (gx - h0);
        d1 = k * (gy - h1);
        d2 = k * (gz - h2);
    } else {
        c0 = gx * dt;
        c1 = gy * dt;
        c2 = gz * dt;
        d0 = d1 = d2 = 0.0;
    }
    double f0 = c0 - (dt * b0 - (d1 * b2 - d2 * b1));
    double f1 = c1 - (dt * b1 - (d2 * b0 - d0 * b2));
    double f2 = c2 - (dt * b2 - (d0 * b1 - d1 * b0));
    double Xv[3] = {X0, X1, X2}, fv[3] = {f0, f1, f2}, Yc[3];
    fc_rotate_back(Xv, fv, Yc);
    double Y0 = Yc[0], Y1 = Yc[1], Y2 = Yc[2];
    double norm = sqrt(ax * ax + ay * ay + az * az);
    int update = fabs(norm / FC_G - 1.0) < f->gate && norm > 0.0;
    int norm_row = update && f->r_norm > 0.0;  /* the pseudo-measurement |X|^2 = 1 */
    double m0 = 0.0, m1 = 0.0, m2 = 0.0;
    double e00 = 0.0, e10 = 0.0, e11 = 0.0, e20 = 0.0, e21 = 0.0, e22 = 0.0;
    double x00 = 0.0, x01 = 0.0, x02 = 0.0, x10 = 0.0, x11 = 0.0, x12 = 0.0;
    double x20 = 0.0, x21 = 0.0, x22 = 0.0;
    double v_sum = 0.0, vv = 0.0, ev0 = 0.0, ev1 = 0.0, ev2 = 0.0, bv0 = 0.0, bv1 = 0.0,
        bv2 = 0.0;
    for (int j = 0; j < 6; j++) {
        double s0 = off[j][0], s1 = off[j][1], s2 = off[j][2];
        double s3 = off[j][3], s4 = off[j][4], s5 = off[j][5];
        double t0 = dt * s3 - (d1 * s5 - d2 * s4);
        double t1 = dt * s4 - (d2 * s3 - d0 * s5);
        double t2 = dt * s5 - (d0 * s4 - d1 * s3);
        double xp[3] = {X0 + s0, X1 + s1, X2 + s2}, fp[3] = {f0 - t0, f1 - t1, f2 - t2};
        double xm[3] = {X0 - s0, X1 - s1, X2 - s2}, fm[3] = {f0 + t0, f1 + t1, f2 + t2};
        double r[3];
        fc_rotate_back(xp, fp, r);
        double ep0 = r[0] - Y0, ep1 = r[1] - Y1, ep2 = r[2] - Y2;
        fc_rotate_back(xm, fm, r);
        double em0 = r[0] - Y0, em1 = r[1] - Y1, em2 = r[2] - Y2;
        m0 += ep0 + em0;
        m1 += ep1 + em1;
        m2 += ep2 + em2;
        e00 += ep0 * ep0 + em0 * em0;
        e10 += ep1 * ep0 + em1 * em0;
        e11 += ep1 * ep1 + em1 * em1;
        e20 += ep2 * ep0 + em2 * em0;
        e21 += ep2 * ep1 + em2 * em1;
        e22 += ep2 * ep2 + em2 * em2;
        double u0 = ep0 - em0, u1 = ep1 - em1, u2 = ep2 - em2;
        x00 += u0 * s3;
        x01 += u0 * s4;
        x02 += u0 * s5;
        x10 += u1 * s3;
        x11 += u1 * s4;
        x12 += u1 * s5;
        x20 += u2 * s3;
        x21 += u2 * s4;
        x22 += u2 * s5;
        if (norm_row && (s0 != 0.0 || s1 != 0.0 || s2 != 0.0)) {
            double a = 2.0 * (X0 * s0 + X1 * s1 + X2 * s2);
            double q = s0 * s0 + s1 * s1 + s2 * s2;
            double vp = q + a, vm = q - a;
            v_sum += vp + vm;
            vv += vp * vp + vm * vm;
            ev0 += ep0 * vp + em0 * vm;
            ev1 += ep1 * vp + em1 * vm;
            ev2 += ep2 * vp + em2 * vm;
            a = vp - vm;
            bv0 += a * s3;
            bv1 += a * s4;
            bv2 += a * s5;
        }
    }
    double w = f->w, w_mu = f->w_mu;
    double mu0 = w * m0, mu1 = w * m1, mu2 = w * m2;
    double v_prior = X0 * X0 + X1 * X1 + X2 * X2;
    X0 = Y0 + mu0;
    X1 = Y1 + mu1;
    X2 = Y2 + mu2;
    double a00 = w * e00 + w_mu * mu0 * mu0;
    double a10 = w * e10 + w_mu * mu1 * mu0;
    double a11 = w * e11 + w_mu * mu1 * mu1;
    double a20 = w * e20 + w_mu * mu2 * mu0;
    double a21 = w * e21 + w_mu * mu2 * mu1;
    double a22 = w * e22 + w_mu * mu2 * mu2;
    x00 = w * x00;
    x01 = w * x01;
    x02 = w * x02;
    x10 = w * x10;
    x11 = w * x11;
    x12 = w * x12;
    x20 = w * x20;
    x21 = w * x21;
    x22 = w * x22;
    double n = sqrt(X0 * X0 + X1 * X1 + X2 * X2);
    double inv = 1.0 / n;
    double h0 = X0 * inv, h1 = X1 * inv, h2 = X2 * inv;
    double q_gyro = f->q_gyro;
    if (f->q_rotation > 0.0) {  /* gyro_scale_std: a scale error adds up while the sensor turns */
        double wx = gx - b0, wy = gy - b1, wz = gz - b2;
        q_gyro += f->q_rotation * (wx * wx + wy * wy + wz * wz);
    }
    if (f->base.clipped) {  /* at the rail the rate beyond it is unknown (gyro_range) */
        q_gyro += f->rail_var * dt;
    }
    double qg = q_gyro * dt, qb = f->q_bias * dt;
    double Pn[21] = {
        a00 + qg * (1.0 - h0 * h0),
        a10 - qg * (h1 * h0), a11 + qg * (1.0 - h1 * h1),
        a20 - qg * (h2 * h0), a21 - qg * (h2 * h1), a22 + qg * (1.0 - h2 * h2),
        x00, x10, x20, P[9] + qb,
        x01, x11, x21, P[13], P[14] + qb,
        x02, x12, x22, P[18], P[19], P[20] + qb,
    };
    if (update) {
        if (ax * X0 + ay * X1 + az * X2 < f->cos_innovation * norm * n) {
            learn_bias = 0;  /* grossly off: X only (bias_innovation) */
        }
        double mu_v = w * v_sum;
        double sv0 = w * ev0 + w_mu * mu0 * mu_v;
        double sv1 = w * ev1 + w_mu * mu1 * mu_v;
        double sv2 = w * ev2 + w_mu * mu2 * mu_v;
        /* no pseudo-measurement: with its sums 0, s33 = 1 and a zero innovation the last row
         * is independent of the others and changes nothing (exactly) */
        if (capped) {  /* the longest correction time: r at most q T^2 / dt */
            double cap = q_gyro * f->longest2 / dt;
            r = r < cap ? r : (cap > f->r_acc ? cap : f->r_acc);
        }
        double s33 = 1.0, y3 = 0.0;
        if (norm_row) {
            s33 = w * vv + w_mu * mu_v * mu_v + f->r_norm;
            y3 = 1.0 - (v_prior + mu_v);
        }
        const double S[10] = {a00 + r, a10, a11 + r, a20, a21, a22 + r, sv0, sv1, sv2, s33};
        const double rows[6][4] = {
            {a00, a10, a20, sv0}, {a10, a11, a21, sv1}, {a20, a21, a22, sv2},
            {x00, x10, x20, w * bv0}, {x01, x11, x21, w * bv1}, {x02, x12, x22, w * bv2},
        };
        const double innovation[4] = {
            ax / FC_G - X0, ay / FC_G - X1, az / FC_G - X2, y3,
        };
        double xs[6] = {X0, X1, X2, b0, b1, b2};
        kalman_update(xs, Pn, S, rows, innovation, learn_bias);
        X0 = xs[0];
        X1 = xs[1];
        X2 = xs[2];
        b0 = xs[3];
        b1 = xs[4];
        b2 = xs[5];
        n = sqrt(X0 * X0 + X1 * X1 + X2 * X2);
    }
    f->x[0] = X0 / n;
    f->x[1] = X1 / n;
    f->x[2] = X2 / n;
    f->x[3] = b0;
    f->x[4] = b1;
    f->x[5] = b2;
    memcpy(f->P, Pn, sizeof Pn);
}

static void advance(fc_ukf *f, const double a[3], const double g[3], double dt)
{
    const fc_ukf_params *p = &f->params;
    double raw2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    int learn_bias = f->bias_lo2 < raw2 && raw2 < f->bias_hi2;
    if (!f->options) {
        filter_update(f, a[0], a[1], a[2], g, dt, learn_bias, f->r_acc, 0);
        return;
    }
    int clipped = f->base.clipped;
    learn_bias = learn_bias && !clipped;  /* never a sample at the rail */
    if (p->acc_lowpass > 0.0) {  /* _update: the real-sensor options */
        double phi[3], terms[4], b[3] = {f->x[3], f->x[4], f->x[5]};
        fc_body_rotation(f->base.gyro_prev, g, b, dt, f->trapezoid, phi);
        fc_rotvec_terms(phi[0], phi[1], phi[2], terms);  /* once, for the low-passes */
        int filling;
        if (clipped) {
            fc_measure_clipped(f->meas);
        }
        double r = fc_measure_step(f->meas, a, phi, terms, dt, &f->measure, &filling);
        /* no bias from a vector that is filling or holds turns the gyro did not measure */
        learn_bias = learn_bias && !filling && fc_measure_settled(f->meas, &f->measure);
        const double *m = f->meas + FC_MEAS_F;
        filter_update(f, m[0], m[1], m[2], g, dt, learn_bias, r, 1);
    } else {
        filter_update(f, a[0], a[1], a[2], g, dt, learn_bias, f->r_acc, 0);
    }
    if (p->rest_time > 0.0 && !clipped) {
        double measured = f->rest[7];
        fc_rest_step(f->rest, g[0], g[1], g[2], a[0], a[1], a[2], &f->x[3], dt, p->rest_gyro,
                     p->rest_acc, p->rest_time, p->rest_bias_bound);
        if (p->acc_lowpass > 0.0 && fc_first_rest(measured, f->rest)) {
            /* the measured vector starts again from the rest's mean, X from its direction */
            const double *m = f->rest + 3;
            fc_measure_restart(f->meas, m);
            double n = sqrt(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
            f->x[0] = m[0] / n;
            f->x[1] = m[1] / n;
            f->x[2] = m[2] / n;
        }
        if (f->rest[6] >= p->rest_time) {
            zero_rate_update(f, g, p->zaru_psd / dt);
        }
    }
}

FC_DEFINE_STEP_AND_RUN(fc_ukf)

/* fc_paper_ukf.c: see fc_paper_ukf.h; the twin of fusion_core/papers/ukf.py line by line. */
#include "fc_paper_ukf.h"

#include <math.h>
#include <string.h>

#define N_STATE 6
#define JACOBI_SWEEPS 30

int fc_paper_ukf_packed(int i, int j)  /* packed_index */
{
    if (j > i) {
        int t = i;
        i = j;
        j = t;
    }
    return i * (i + 1) / 2 + j;
}

/* psd_sqrt_columns: gamma V fc_sqrt(max(w, 0)) by cyclic Jacobi rotations; off[j] is column j */
static void psd_sqrt_columns(const fc_real P[21], fc_real gamma, fc_real off[6][6])
{
    const int n = N_STATE;
    fc_real A[6][6], V[6][6];
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) {
            A[i][j] = P[fc_paper_ukf_packed(i, j)];
            V[i][j] = i == j ? 1.0 : 0.0;
        }
    }
    for (int sweep = 0; sweep < JACOBI_SWEEPS; sweep++) {
        fc_real o = 0.0;
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
                fc_real apq = A[p][q];
                if (apq == 0.0) {
                    continue;
                }
                fc_real theta = (A[q][q] - A[p][p]) / (2.0 * apq);
                fc_real t = (theta >= 0.0 ? 1.0 : -1.0) / (fc_fabs(theta) + fc_sqrt(theta * theta + 1.0));
                fc_real c = 1.0 / fc_sqrt(t * t + 1.0);
                fc_real s = t * c;
                for (int k = 0; k < n; k++) {
                    fc_real akp = A[k][p], akq = A[k][q];
                    A[k][p] = c * akp - s * akq;
                    A[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < n; k++) {
                    fc_real apk = A[p][k], aqk = A[q][k];
                    A[p][k] = c * apk - s * aqk;
                    A[q][k] = s * apk + c * aqk;
                }
                for (int k = 0; k < n; k++) {
                    fc_real vkp = V[k][p], vkq = V[k][q];
                    V[k][p] = c * vkp - s * vkq;
                    V[k][q] = s * vkp + c * vkq;
                }
            }
        }
    }
    for (int j = 0; j < n; j++) {
        fc_real root = A[j][j] > 0.0 ? gamma * fc_sqrt(A[j][j]) : 0.0;
        for (int k = 0; k < n; k++) {
            off[j][k] = V[k][j] * root;
        }
    }
}

/* _sigma_offsets: the columns of gamma L, P = L L^T (Cholesky-Banachiewicz, written out) */
static void sigma_offsets(const fc_real P[21], fc_real gamma, fc_real off[6][6])
{
    fc_real p00 = P[0], p10 = P[1], p11 = P[2], p20 = P[3], p21 = P[4], p22 = P[5];
    fc_real p30 = P[6], p31 = P[7], p32 = P[8], p33 = P[9];
    fc_real p40 = P[10], p41 = P[11], p42 = P[12], p43 = P[13], p44 = P[14];
    fc_real p50 = P[15], p51 = P[16], p52 = P[17], p53 = P[18], p54 = P[19], p55 = P[20];
    fc_real d;
    if (!(p00 > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    fc_real l00 = fc_sqrt(p00), i0 = 1.0 / l00;
    fc_real l10 = p10 * i0;
    d = p11 - l10 * l10;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    fc_real l11 = fc_sqrt(d), i1 = 1.0 / l11;
    fc_real l20 = p20 * i0;
    fc_real l21 = (p21 - l20 * l10) * i1;
    d = p22 - l20 * l20 - l21 * l21;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    fc_real l22 = fc_sqrt(d), i2 = 1.0 / l22;
    fc_real l30 = p30 * i0;
    fc_real l31 = (p31 - l30 * l10) * i1;
    fc_real l32 = (p32 - l30 * l20 - l31 * l21) * i2;
    d = p33 - l30 * l30 - l31 * l31 - l32 * l32;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    fc_real l33 = fc_sqrt(d), i3 = 1.0 / l33;
    fc_real l40 = p40 * i0;
    fc_real l41 = (p41 - l40 * l10) * i1;
    fc_real l42 = (p42 - l40 * l20 - l41 * l21) * i2;
    fc_real l43 = (p43 - l40 * l30 - l41 * l31 - l42 * l32) * i3;
    d = p44 - l40 * l40 - l41 * l41 - l42 * l42 - l43 * l43;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    fc_real l44 = fc_sqrt(d);
    fc_real l50 = p50 * i0;
    fc_real l51 = (p51 - l50 * l10) * i1;
    fc_real l52 = (p52 - l50 * l20 - l51 * l21) * i2;
    fc_real l53 = (p53 - l50 * l30 - l51 * l31 - l52 * l32) * i3;
    fc_real l54 = (p54 - l50 * l40 - l51 * l41 - l52 * l42 - l53 * l43) / l44;
    d = p55 - l50 * l50 - l51 * l51 - l52 * l52 - l53 * l53 - l54 * l54;
    if (!(d > 0.0)) {
        psd_sqrt_columns(P, gamma, off);
        return;
    }
    fc_real g = gamma;
    const fc_real cols[6][6] = {
        {g * l00, g * l10, g * l20, g * l30, g * l40, g * l50},
        {0.0, g * l11, g * l21, g * l31, g * l41, g * l51},
        {0.0, 0.0, g * l22, g * l32, g * l42, g * l52},
        {0.0, 0.0, 0.0, g * l33, g * l43, g * l53},
        {0.0, 0.0, 0.0, 0.0, g * l44, g * l54},
        {0.0, 0.0, 0.0, 0.0, 0.0, g * fc_sqrt(d)},
    };
    memcpy(off, cols, sizeof cols);
}

/* cholesky3 / cholesky4: the packed lower factor, 0 when not positive definite */
int fc_paper_ukf_cholesky3(fc_real s00, fc_real s10, fc_real s11, fc_real s20, fc_real s21, fc_real s22,
                     fc_real L[6])
{
    if (!(s00 > 0.0)) {
        return 0;
    }
    fc_real l00 = fc_sqrt(s00), l10 = s10 / l00, d = s11 - l10 * l10;
    if (!(d > 0.0)) {
        return 0;
    }
    fc_real l11 = fc_sqrt(d), l20 = s20 / l00, l21 = (s21 - l20 * l10) / l11;
    d = s22 - l20 * l20 - l21 * l21;
    if (!(d > 0.0)) {
        return 0;
    }
    L[0] = l00;
    L[1] = l10;
    L[2] = l11;
    L[3] = l20;
    L[4] = l21;
    L[5] = fc_sqrt(d);
    return 1;
}

static int cholesky4(const fc_real S[10], fc_real L[10])  /* cholesky3, then the last row */
{
    if (!fc_paper_ukf_cholesky3(S[0], S[1], S[2], S[3], S[4], S[5], L)) {
        return 0;
    }
    fc_real l00 = L[0], l10 = L[1], l11 = L[2], l20 = L[3], l21 = L[4], l22 = L[5];
    fc_real l30 = S[6] / l00, l31 = (S[7] - l30 * l10) / l11;
    fc_real l32 = (S[8] - l30 * l20 - l31 * l21) / l22;
    fc_real d = S[9] - l30 * l30 - l31 * l31 - l32 * l32;
    if (!(d > 0.0)) {
        return 0;
    }
    L[6] = l30;
    L[7] = l31;
    L[8] = l32;
    L[9] = fc_sqrt(d);
    return 1;
}

/* general_update: K^T = S^-1 P_xz^T by Gauss-Jordan with partial pivoting; x and P in place */
static void general_update(fc_real x[6], fc_real P[21], const fc_real S[10],
                           const fc_real rows[6][4], const fc_real y[4])
{
    enum { M = 4, WIDTH = 4 + N_STATE + 1 };
    fc_real aug[M][WIDTH];
    for (int i = 0; i < M; i++) {
        for (int j = 0; j < M; j++) {
            aug[i][j] = S[fc_paper_ukf_packed(i, j)];
        }
        for (int k = 0; k < N_STATE; k++) {
            aug[i][M + k] = rows[k][i];
        }
        aug[i][WIDTH - 1] = y[i];
    }
    for (int col = 0; col < M; col++) {
        int pivot = col;
        for (int i = col + 1; i < M; i++) {
            if (fc_fabs(aug[i][col]) > fc_fabs(aug[pivot][col])) {
                pivot = i;
            }
        }
        if (aug[pivot][col] == 0.0) {
            return;  /* singular S: x and P as they were */
        }
        fc_real tmp[WIDTH];
        memcpy(tmp, aug[col], sizeof tmp);
        memcpy(aug[col], aug[pivot], sizeof tmp);
        memcpy(aug[pivot], tmp, sizeof tmp);
        fc_real inv = 1.0 / aug[col][col];
        for (int k = 0; k < WIDTH; k++) {
            aug[col][k] = aug[col][k] * inv;
        }
        for (int i = 0; i < M; i++) {
            if (i != col && aug[i][col] != 0.0) {
                fc_real f = aug[i][col];
                for (int k = 0; k < WIDTH; k++) {
                    aug[i][k] = aug[i][k] - f * aug[col][k];
                }
            }
        }
    }
    fc_real K[N_STATE][M], Siy[M], KSK[N_STATE][N_STATE];
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
            fc_real sum = 0.0;
            for (int k = 0; k < M; k++) {
                sum += K[i][k] * rows[j][k];
            }
            KSK[i][j] = sum;
        }
    }
    for (int i = 0; i < N_STATE; i++) {
        fc_real sum = 0.0;
        for (int k = 0; k < M; k++) {
            sum += rows[i][k] * Siy[k];
        }
        x[i] = x[i] + sum;
    }
    for (int i = 0; i < N_STATE; i++) {
        for (int j = 0; j <= i; j++) {
            P[fc_paper_ukf_packed(i, j)] = P[fc_paper_ukf_packed(i, j)] - 0.5 * (KSK[i][j] + KSK[j][i]);
        }
    }
}

/* kalman_update and consider_bias: x + K y, P - K S K^T (eq. 17); x and P in place */
static void kalman_update(fc_real x[6], fc_real P[21], const fc_real S[10], const fc_real rows[6][4],
                          const fc_real y[4], int learn_bias)
{
    fc_real x_old[6], P_old[21];
    memcpy(x_old, x, sizeof x_old);
    memcpy(P_old, P, sizeof P_old);
    fc_real L[10];
    if (!cholesky4(S, L)) {
        general_update(x, P, S, rows, y);
    } else {
        fc_real l00 = L[0], l10 = L[1], l11 = L[2], l20 = L[3], l21 = L[4], l22 = L[5];
        fc_real l30 = L[6], l31 = L[7], l32 = L[8], l33 = L[9];
        fc_real i0 = 1.0 / l00, i1 = 1.0 / l11, i2 = 1.0 / l22, i3 = 1.0 / l33;
        fc_real Y[7][4];
        for (int k = 0; k < 7; k++) {  /* forward substitution, L^-1 r, for each row and y */
            const fc_real *r = k < 6 ? rows[k] : y;
            fc_real y0 = r[0] * i0;
            fc_real y1 = (r[1] - l10 * y0) * i1;
            fc_real y2 = (r[2] - l20 * y0 - l21 * y1) * i2;
            Y[k][0] = y0;
            Y[k][1] = y1;
            Y[k][2] = y2;
            Y[k][3] = (r[3] - l30 * y0 - l31 * y1 - l32 * y2) * i3;
        }
        const fc_real *z = Y[6];
        for (int i = 0; i < 6; i++) {
            x[i] = x_old[i] + (Y[i][0] * z[0] + Y[i][1] * z[1] + Y[i][2] * z[2] + Y[i][3] * z[3]);
        }
        for (int i = 0; i < 6; i++) {
            for (int j = 0; j <= i; j++) {
                P[fc_paper_ukf_packed(i, j)] = P_old[fc_paper_ukf_packed(i, j)] - (Y[i][0] * Y[j][0] + Y[i][1] * Y[j][1]
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

void fc_paper_ukf_unscented_constants(fc_real alpha, fc_real beta, fc_real kappa, fc_real *gamma,
                                      fc_real *w, fc_real *w_mu)
{
    fc_real alpha2 = fc_pow(alpha, 2.0);
    fc_real lam = alpha2 * (N_STATE + kappa) - N_STATE;
    *gamma = fc_sqrt(N_STATE + lam);
    *w = 0.5 / (N_STATE + lam);
    *w_mu = beta - alpha2;
}

/* rotation_terms: c and d of phi(b) = c - M b (eq. 14) */
void fc_paper_ukf_rotation_terms(const fc_real prev[3], const fc_real g[3], fc_real dt,
                                 int trapezoid, fc_real terms[6])
{
    fc_real gx = g[0], gy = g[1], gz = g[2];
    if (trapezoid) {
        fc_real h0 = prev[0], h1 = prev[1], h2 = prev[2];
        fc_real k = dt * dt / 12.0, hdt = 0.5 * dt;
        terms[0] = hdt * (h0 + gx) + k * (h1 * gz - h2 * gy);
        terms[1] = hdt * (h1 + gy) + k * (h2 * gx - h0 * gz);
        terms[2] = hdt * (h2 + gz) + k * (h0 * gy - h1 * gx);
        terms[3] = k * (gx - h0);
        terms[4] = k * (gy - h1);
        terms[5] = k * (gz - h2);
    } else {
        terms[0] = gx * dt;
        terms[1] = gy * dt;
        terms[2] = gz * dt;
        terms[3] = terms[4] = terms[5] = 0.0;
    }
}

/* sigma_predict: every sigma point through X_{k+1} = fc_exp(-[phi]x) X_k (eq. 14-15) */
void fc_paper_ukf_sigma_predict(const fc_real x[6], const fc_real P[21], const fc_real terms[6],
                                fc_real dt, fc_real gamma, fc_real w, fc_real w_mu, int norm_row,
                                fc_ukf_prediction *pred)
{
    fc_real X0 = x[0], X1 = x[1], X2 = x[2], b0 = x[3], b1 = x[4], b2 = x[5];
    fc_real off[6][6];
    sigma_offsets(P, gamma, off);
    fc_real c0 = terms[0], c1 = terms[1], c2 = terms[2];
    fc_real d0 = terms[3], d1 = terms[4], d2 = terms[5];
    fc_real f0 = c0 - (dt * b0 - (d1 * b2 - d2 * b1));
    fc_real f1 = c1 - (dt * b1 - (d2 * b0 - d0 * b2));
    fc_real f2 = c2 - (dt * b2 - (d0 * b1 - d1 * b0));
    fc_real Xv[3] = {X0, X1, X2}, fv[3] = {f0, f1, f2}, Yc[3];
    fc_rotate_back(Xv, fv, Yc);
    fc_real Y0 = Yc[0], Y1 = Yc[1], Y2 = Yc[2];
    fc_real m0 = 0.0, m1 = 0.0, m2 = 0.0;
    fc_real e00 = 0.0, e10 = 0.0, e11 = 0.0, e20 = 0.0, e21 = 0.0, e22 = 0.0;
    fc_real x00 = 0.0, x01 = 0.0, x02 = 0.0, x10 = 0.0, x11 = 0.0, x12 = 0.0;
    fc_real x20 = 0.0, x21 = 0.0, x22 = 0.0;
    fc_real v_sum = 0.0, vv = 0.0, ev0 = 0.0, ev1 = 0.0, ev2 = 0.0, bv0 = 0.0, bv1 = 0.0,
        bv2 = 0.0;
    for (int j = 0; j < 6; j++) {
        fc_real s0 = off[j][0], s1 = off[j][1], s2 = off[j][2];
        fc_real s3 = off[j][3], s4 = off[j][4], s5 = off[j][5];
        fc_real t0 = dt * s3 - (d1 * s5 - d2 * s4);
        fc_real t1 = dt * s4 - (d2 * s3 - d0 * s5);
        fc_real t2 = dt * s5 - (d0 * s4 - d1 * s3);
        fc_real xp[3] = {X0 + s0, X1 + s1, X2 + s2}, fp[3] = {f0 - t0, f1 - t1, f2 - t2};
        fc_real xm[3] = {X0 - s0, X1 - s1, X2 - s2}, fm[3] = {f0 + t0, f1 + t1, f2 + t2};
        fc_real r[3];
        fc_rotate_back(xp, fp, r);
        fc_real ep0 = r[0] - Y0, ep1 = r[1] - Y1, ep2 = r[2] - Y2;
        fc_rotate_back(xm, fm, r);
        fc_real em0 = r[0] - Y0, em1 = r[1] - Y1, em2 = r[2] - Y2;
        m0 += ep0 + em0;
        m1 += ep1 + em1;
        m2 += ep2 + em2;
        e00 += ep0 * ep0 + em0 * em0;
        e10 += ep1 * ep0 + em1 * em0;
        e11 += ep1 * ep1 + em1 * em1;
        e20 += ep2 * ep0 + em2 * em0;
        e21 += ep2 * ep1 + em2 * em1;
        e22 += ep2 * ep2 + em2 * em2;
        fc_real u0 = ep0 - em0, u1 = ep1 - em1, u2 = ep2 - em2;
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
            fc_real a = 2.0 * (X0 * s0 + X1 * s1 + X2 * s2);
            fc_real q = s0 * s0 + s1 * s1 + s2 * s2;
            fc_real vp = q + a, vm = q - a;
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
    fc_real mu0 = w * m0, mu1 = w * m1, mu2 = w * m2;
    pred->X[0] = Y0 + mu0;
    pred->X[1] = Y1 + mu1;
    pred->X[2] = Y2 + mu2;
    pred->A[0] = w * e00 + w_mu * mu0 * mu0;
    pred->A[1] = w * e10 + w_mu * mu1 * mu0;
    pred->A[2] = w * e11 + w_mu * mu1 * mu1;
    pred->A[3] = w * e20 + w_mu * mu2 * mu0;
    pred->A[4] = w * e21 + w_mu * mu2 * mu1;
    pred->A[5] = w * e22 + w_mu * mu2 * mu2;
    pred->C[0] = w * x00;
    pred->C[1] = w * x01;
    pred->C[2] = w * x02;
    pred->C[3] = w * x10;
    pred->C[4] = w * x11;
    pred->C[5] = w * x12;
    pred->C[6] = w * x20;
    pred->C[7] = w * x21;
    pred->C[8] = w * x22;
    pred->mu[0] = mu0;
    pred->mu[1] = mu1;
    pred->mu[2] = mu2;
    pred->v_prior = X0 * X0 + X1 * X1 + X2 * X2;
    pred->v_sum = v_sum;
    pred->vv = vv;
    pred->ev[0] = ev0;
    pred->ev[1] = ev1;
    pred->ev[2] = ev2;
    pred->bv[0] = bv0;
    pred->bv[1] = bv1;
    pred->bv[2] = bv2;
}

/* predicted_covariance: with Q = qg (I - h h^T) for X and qb I for b (eq. 15) */
void fc_paper_ukf_predicted_covariance(const fc_ukf_prediction *pred, const fc_real P[21],
                                       const fc_real h[3], fc_real qg, fc_real qb, fc_real out[21])
{
    const fc_real *A = pred->A, *C = pred->C;
    fc_real h0 = h[0], h1 = h[1], h2 = h[2];
    fc_real Pn[21] = {
        A[0] + qg * (1.0 - h0 * h0),
        A[1] - qg * (h1 * h0), A[2] + qg * (1.0 - h1 * h1),
        A[3] - qg * (h2 * h0), A[4] - qg * (h2 * h1), A[5] + qg * (1.0 - h2 * h2),
        C[0], C[3], C[6], P[9] + qb,
        C[1], C[4], C[7], P[13], P[14] + qb,
        C[2], C[5], C[8], P[18], P[19], P[20] + qb,
    };
    memcpy(out, Pn, sizeof Pn);
}

/* measurement_update: z = [acc/g; 1], h = [X; |X|^2] (eq. 16-17) */
void fc_paper_ukf_measurement_update(const fc_ukf_prediction *pred, const fc_real b[3],
                                     fc_real P[21], const fc_real acc[3], fc_real r, fc_real w,
                                     fc_real w_mu, int has_norm, fc_real r_norm, int learn_bias,
                                     fc_real x[6])
{
    const fc_real *A = pred->A, *C = pred->C, *mu = pred->mu;
    fc_real mu_v = w * pred->v_sum;
    fc_real sv0 = w * pred->ev[0] + w_mu * mu[0] * mu_v;
    fc_real sv1 = w * pred->ev[1] + w_mu * mu[1] * mu_v;
    fc_real sv2 = w * pred->ev[2] + w_mu * mu[2] * mu_v;
    /* no pseudo-measurement: with its sums 0, s33 = 1 and a zero innovation the last row is
     * independent of the others and changes nothing (exactly) */
    fc_real s33 = 1.0, y3 = 0.0;
    if (has_norm) {
        s33 = w * pred->vv + w_mu * mu_v * mu_v + r_norm;
        y3 = 1.0 - (pred->v_prior + mu_v);
    }
    const fc_real S[10] = {A[0] + r, A[1], A[2] + r, A[3], A[4], A[5] + r, sv0, sv1, sv2, s33};
    const fc_real rows[6][4] = {
        {A[0], A[1], A[3], sv0}, {A[1], A[2], A[4], sv1}, {A[3], A[4], A[5], sv2},
        {C[0], C[3], C[6], w * pred->bv[0]}, {C[1], C[4], C[7], w * pred->bv[1]},
        {C[2], C[5], C[8], w * pred->bv[2]},
    };
    const fc_real innovation[4] = {
        acc[0] / FC_G - pred->X[0], acc[1] / FC_G - pred->X[1], acc[2] / FC_G - pred->X[2], y3,
    };
    x[0] = pred->X[0];
    x[1] = pred->X[1];
    x[2] = pred->X[2];
    x[3] = b[0];
    x[4] = b[1];
    x[5] = b[2];
    kalman_update(x, P, S, rows, innovation, learn_bias);
}

void fc_paper_ukf_configure(fc_paper_ukf *f)
{
    const fc_paper_ukf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    fc_paper_ukf_unscented_constants(p->alpha, p->beta, p->kappa, &f->gamma, &f->w, &f->w_mu);
    f->q_gyro = p->gyro_psd;
    f->q_bias = p->bias_psd;
    f->r_acc = fc_pow(p->acc_noise, 2.0);
    f->r_norm = fc_pow(p->norm_noise, 2.0);
    f->gate = p->acc_gate;
}

fc_estimate fc_paper_ukf_gravity_estimate(const fc_real x[6])
{
    fc_estimate e;
    memset(&e, 0, sizeof e);
    fc_accel_roll_pitch(x[0], x[1], x[2], &e.roll, &e.pitch);
    e.bias[0] = x[3];
    e.bias[1] = x[4];
    e.bias[2] = x[5];
    return e;
}

fc_estimate fc_paper_ukf_estimate(const fc_paper_ukf *f)
{
    return fc_paper_ukf_gravity_estimate(f->x);
}

void fc_paper_ukf_reset(fc_paper_ukf *f)
{
    fc_base_reset(&f->base);
    const fc_real x0[6] = {0.0, 0.0, 1.0, 0.0, 0.0, 0.0};
    memcpy(f->x, x0, sizeof x0);
    memset(f->P, 0, sizeof f->P);
    f->last = fc_paper_ukf_estimate(f);
}

FC_DEFINE_INIT(fc_paper_ukf)
FC_DEFINE_RESTORED(fc_paper_ukf)

static void first_sample(fc_paper_ukf *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    (void)g;
    fc_real n = fc_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    f->x[0] = a[0] / n;
    f->x[1] = a[1] / n;
    f->x[2] = a[2] / n;
    f->x[3] = f->x[4] = f->x[5] = 0.0;
    fc_real p_x = fc_pow(f->params.acc_noise, 2.0);
    fc_real p_b = fc_pow(f->params.init_bias_std, 2.0);
    memset(f->P, 0, sizeof f->P);
    f->P[0] = f->P[2] = f->P[5] = p_x;
    f->P[9] = f->P[14] = f->P[20] = p_b;
}

static void advance(fc_paper_ukf *f, const fc_real a[3], const fc_real g[3], fc_real dt)
{
    fc_real b[3] = {f->x[3], f->x[4], f->x[5]};
    fc_real norm = fc_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    int update = fc_fabs(norm / FC_G - 1.0) < f->gate && norm > 0.0;  /* rho < acc_gate */
    int norm_row = update && f->r_norm > 0.0;  /* the pseudo-measurement |X|^2 = 1 */
    fc_real terms[6];
    fc_paper_ukf_rotation_terms(f->base.gyro_prev, g, dt, f->base.trapezoid, terms);
    fc_ukf_prediction pred;
    fc_paper_ukf_sigma_predict(f->x, f->P, terms, dt, f->gamma, f->w, f->w_mu, norm_row, &pred);
    fc_real X0 = pred.X[0], X1 = pred.X[1], X2 = pred.X[2];
    fc_real n = fc_sqrt(X0 * X0 + X1 * X1 + X2 * X2);
    fc_real inv = 1.0 / n;
    fc_real h[3] = {X0 * inv, X1 * inv, X2 * inv}, P[21];
    fc_paper_ukf_predicted_covariance(&pred, f->P, h, f->q_gyro * dt, f->q_bias * dt, P);
    fc_real x[6] = {X0, X1, X2, b[0], b[1], b[2]};
    if (update) {
        fc_paper_ukf_measurement_update(&pred, b, P, a, f->r_acc, f->w, f->w_mu, norm_row,
                                        f->r_norm, 1, x);
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

FC_DEFINE_STEP_AND_RUN(fc_paper_ukf)

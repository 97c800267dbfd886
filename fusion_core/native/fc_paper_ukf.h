/* fc_paper_ukf.h: the paper's unscented Kalman filter on the gravity direction with three
 * gyro-bias states (fusion_core/papers/ukf.py, PaperUnscentedKalmanFilter), the C twin. Duong
 * Quoc et al. eq. 14-17; scaled sigma points after Wan & van der Merwe (2000); the identities
 * that spare the matrices are derived in the Python module's docstring. Its equations are
 * public: the recommended filter (fc_ukf.c) is built on them. */
#ifndef FC_PAPER_UKF_H
#define FC_PAPER_UKF_H

#include "fc_core.h"
#include "fc_params.h"

typedef struct fc_paper_ukf {
    fc_paper_ukf_params params;
    fc_base base;
    /* PaperUnscentedKalmanFilter.STATE */
    fc_real x[6];   /* X (the gravity direction, 3), b (the gyro bias, 3) */
    fc_real P[21];  /* the covariance's lower triangle, row by row */
    fc_estimate last;
    /* derived from params (PaperUnscentedKalmanFilter._configure) */
    fc_real gamma, w, w_mu, q_gyro, q_bias, r_acc, r_norm, gate;
} fc_paper_ukf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_paper_ukf);

/* papers/ukf.py's Prediction: the unscented transform of one sample's process model. */
typedef struct fc_ukf_prediction {
    fc_real X[3];   /* the predicted mean of X */
    fc_real A[6];   /* its covariance before Q, packed */
    fc_real C[9];   /* the weighted X-b cross terms x00, x01, x02, x10, ..., x22 */
    fc_real mu[3];  /* the mean deviation */
    fc_real v_prior, v_sum, vv, ev[3], bv[3];  /* the unit-norm pseudo-measurement's sums */
} fc_ukf_prediction;

/* The equations (papers/ukf.py's functions of the same names). */
void fc_paper_ukf_unscented_constants(fc_real alpha, fc_real beta, fc_real kappa, fc_real *gamma,
                                      fc_real *w, fc_real *w_mu);
void fc_paper_ukf_rotation_terms(const fc_real prev[3], const fc_real g[3], fc_real dt,
                                 int trapezoid, fc_real terms[6]);
void fc_paper_ukf_sigma_predict(const fc_real x[6], const fc_real P[21], const fc_real terms[6],
                                fc_real dt, fc_real gamma, fc_real w, fc_real w_mu, int norm_row,
                                fc_ukf_prediction *pred);
void fc_paper_ukf_predicted_covariance(const fc_ukf_prediction *pred, const fc_real P[21],
                                       const fc_real h[3], fc_real qg, fc_real qb, fc_real out[21]);
/* x (6) out: X and b after the update; P (21) in and out. has_norm 0: no pseudo-measurement. */
void fc_paper_ukf_measurement_update(const fc_ukf_prediction *pred, const fc_real b[3],
                                     fc_real P[21], const fc_real acc[3], fc_real r, fc_real w,
                                     fc_real w_mu, int has_norm, fc_real r_norm, int learn_bias,
                                     fc_real x[6]);
/* GravityDirectionState._estimate: roll, pitch and the bias from x = [X (3), b (3)]. */
fc_estimate fc_paper_ukf_gravity_estimate(const fc_real x[6]);
/* packed_index and cholesky3 (the packed lower factor of a 3x3 S; 0 where not positive
 * definite). */
int fc_paper_ukf_packed(int i, int j);
int fc_paper_ukf_cholesky3(fc_real s00, fc_real s10, fc_real s11, fc_real s20, fc_real s21,
                           fc_real s22, fc_real L[6]);

#endif /* FC_PAPER_UKF_H */

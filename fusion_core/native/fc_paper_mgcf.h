/* fc_paper_mgcf.h: the paper's modified-gain complementary filter
 * (fusion_core/papers/mgcf.py, PaperGainScheduledFilter), the C twin. Duong Quoc et al.
 * eq. 7-13, the PI law of Mahony et al. 2008. */
#ifndef FC_PAPER_MGCF_H
#define FC_PAPER_MGCF_H

#include "fc_core.h"
#include "fc_params.h"

typedef struct fc_paper_mgcf {
    fc_paper_mgcf_params params;
    fc_base base;
    /* PaperGainScheduledFilter.STATE */
    double q[4];
    double bias[3];
    double w0_now;
    fc_estimate last;
    /* derived from params (PaperGainScheduledFilter._configure) */
    double w0_fixed, two_zeta;
    int trapezoid;
} fc_paper_mgcf;

void fc_paper_mgcf_init(fc_paper_mgcf *f, const fc_paper_mgcf_params *params);
void fc_paper_mgcf_configure(fc_paper_mgcf *f);
void fc_paper_mgcf_reset(fc_paper_mgcf *f);
fc_status fc_paper_mgcf_step(fc_paper_mgcf *f, const double acc[3], const double gyro[3],
                             double dt, fc_estimate *out);
long fc_paper_mgcf_run(fc_paper_mgcf *f, long n, const double *acc, const double *gyro,
                       const double *dt, fc_estimate *out, unsigned char *rejected);
fc_estimate fc_paper_mgcf_estimate(const fc_paper_mgcf *f);
/* After a restore of the state fields (fc_state.h): recompute what follows from them. */
void fc_paper_mgcf_restored(fc_paper_mgcf *f);

/* quat_first_order: q + dt/2 q (x) (0, w), renormalised, in place (Mahony's reference code; the
 * recommended filter integrates mean samples with it too). */
void fc_paper_mgcf_quat_first_order(double q[4], double w0, double w1, double w2, double dt);

/* pi_step: one step of the PI law (papers/mgcf.py's pi_step): q and bias in place, from the
 * previous and this gyro sample, the specific force a of norm |a|, w0 and Kp; the integral
 * term learns only while learn_bias. */
void fc_paper_mgcf_pi_step(double q[4], double bias[3], const double prev[3], const double g[3],
                           const double a[3], double norm, double w0, double kp, double dt,
                           int trapezoid, int learn_bias);

#endif /* FC_PAPER_MGCF_H */

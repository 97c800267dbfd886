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
    fc_real q[4];
    fc_real bias[3];
    fc_real w0_now;
    fc_estimate last;
    /* derived from params (PaperGainScheduledFilter._configure) */
    fc_real w0_fixed, two_zeta;
} fc_paper_mgcf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_paper_mgcf);
/* The estimate of a quaternion's roll and pitch and a gyro bias (both mgcfs' _estimate). */
fc_estimate fc_paper_mgcf_quat_estimate(const fc_real q[4], const fc_real bias[3]);

/* quat_first_order: q + dt/2 q (x) (0, w), renormalised, in place (Mahony's reference code; the
 * recommended filter integrates mean samples with it too). */
void fc_paper_mgcf_quat_first_order(fc_real q[4], fc_real w0, fc_real w1, fc_real w2, fc_real dt);

/* pi_step: one step of the PI law (papers/mgcf.py's pi_step): q and bias in place, from the
 * previous and this gyro sample, the specific force a of norm |a|, w0 and Kp; the integral
 * term learns only while learn_bias. */
void fc_paper_mgcf_pi_step(fc_real q[4], fc_real bias[3], const fc_real prev[3], const fc_real g[3],
                           const fc_real a[3], fc_real norm, fc_real w0, fc_real kp, fc_real dt,
                           int trapezoid, int learn_bias);

#endif /* FC_PAPER_MGCF_H */

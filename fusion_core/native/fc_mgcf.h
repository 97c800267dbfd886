/* fc_mgcf.h: the recommended modified-gain complementary filter, a Mahony-style quaternion PI
 * filter (fusion_core/mgcf.py, GainScheduledComplementaryFilter), the C twin. Duong Quoc et al.
 * eq. 7-13 (fc_paper_mgcf.h) with a fixed gain and the mechanisms for real sensors. */
#ifndef FC_MGCF_H
#define FC_MGCF_H

#include "fc_core.h"
#include "fc_params.h"

typedef struct fc_mgcf {
    fc_mgcf_params params;
    fc_base base;
    /* GainScheduledComplementaryFilter.STATE */
    fc_real q[4];
    fc_real bias[3];
    fc_real w0_now;
    fc_real meas[FC_MEAS_SIZE];  /* the measured vector (acc_lowpass > 0; measured_vector) */
    fc_real rest[FC_REST_SIZE];
    fc_estimate last;
    /* derived from params (GainScheduledComplementaryFilter._configure) */
    fc_real w0, two_zeta, acc_tau, rest_time, rest_gyro, rest_acc, rest_bias_bound;
    fc_real r_ref, q_rotation, dist_tau, longest;  /* _adaptive */
    fc_meas_constants measure;  /* _measure */
    fc_real motion_gain, bias_lo2, bias_hi2;  /* _motion_gain, _bias_band2 */
} fc_mgcf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_mgcf);

#endif /* FC_MGCF_H */

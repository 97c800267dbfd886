/* fc_cf.h: the recommended complementary filter (fusion_core/complementary.py,
 * ComplementaryFilter), the C twin. Gui et al. 2015 eq. 1-2, Das & Mary eq. 1 (fc_paper_cf.h)
 * with the mechanisms for real sensors of the Python class's docstring. */
#ifndef FC_CF_H
#define FC_CF_H

#include "fc_core.h"
#include "fc_params.h"

typedef struct fc_cf {
    fc_cf_params params;
    fc_base base;
    /* ComplementaryFilter.STATE */
    fc_real roll, pitch;
    fc_real meas[FC_MEAS_SIZE];  /* the measured vector (acc_lowpass > 0; measured_vector) */
    fc_real q_att[4];
    fc_real bias[3];
    fc_real rest[FC_REST_SIZE];
    fc_estimate last;
    /* derived from params (ComplementaryFilter._configure) */
    fc_real tau, gate_low2, gate_high2, acc_tau;
    fc_real r_ref, q_rotation, dist_tau, longest;  /* ComplementaryFilter._adaptive */
    fc_meas_constants measure;  /* ComplementaryFilter._measure */
    fc_real bias_lo2, bias_hi2;  /* ComplementaryFilter._bias_band2 */
} fc_cf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_cf);

#endif /* FC_CF_H */

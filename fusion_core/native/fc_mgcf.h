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
    int trapezoid;
} fc_mgcf;

void fc_mgcf_init(fc_mgcf *f, const fc_mgcf_params *params);
void fc_mgcf_configure(fc_mgcf *f);
void fc_mgcf_reset(fc_mgcf *f);
fc_status fc_mgcf_step(fc_mgcf *f, const fc_real acc[3], const fc_real gyro[3], fc_real dt,
                       fc_estimate *out);
long fc_mgcf_run(fc_mgcf *f, long n, const fc_real *acc, const fc_real *gyro, const fc_real *dt,
                 fc_estimate *out, unsigned char *rejected);
long fc_mgcf_run_columns(fc_mgcf *f, long n, const fc_real *acc, const fc_real *gyro,
                         const fc_real *dt, fc_real *roll, fc_real *pitch, fc_real *bias,
                         fc_real *pos, fc_real *vel, unsigned char *rejected);
fc_estimate fc_mgcf_estimate(const fc_mgcf *f);
/* After a restore of the state fields (fc_state.h): recompute what follows from them. */
void fc_mgcf_restored(fc_mgcf *f);

#endif /* FC_MGCF_H */

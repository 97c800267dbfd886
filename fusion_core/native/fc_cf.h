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
    int trapezoid;
} fc_cf;

/* params (NULL: the defaults) in, a filter waiting for its first sample out. */
void fc_cf_init(fc_cf *f, const fc_cf_params *params);
/* Take a change of f->params (the state is kept). */
void fc_cf_configure(fc_cf *f);
/* Forget every sample. */
void fc_cf_reset(fc_cf *f);
/* One sample: acc [m/s^2], gyro [rad/s], dt [s]. FC_OK or FC_SKIPPED: *out is the estimate
 * (the last one when skipped); a rejection leaves the filter and *out as they were. */
fc_status fc_cf_step(fc_cf *f, const fc_real acc[3], const fc_real gyro[3], fc_real dt,
                     fc_estimate *out);
/* n samples (acc, gyro row-major [n][3], dt [n]): out[i] the estimate after sample i (the last
 * one for a rejected sample, rejected[i] = 1, counted in n_rejected). Returns the number of
 * rejected samples. */
long fc_cf_run(fc_cf *f, long n, const fc_real *acc, const fc_real *gyro, const fc_real *dt,
               fc_estimate *out, unsigned char *rejected);
long fc_cf_run_columns(fc_cf *f, long n, const fc_real *acc, const fc_real *gyro,
                       const fc_real *dt, fc_real *roll, fc_real *pitch, fc_real *bias,
                       fc_real *pos, fc_real *vel, unsigned char *rejected);
fc_estimate fc_cf_estimate(const fc_cf *f);
/* After a restore of the state fields (fc_state.h): recompute what follows from them. */
void fc_cf_restored(fc_cf *f);

#endif /* FC_CF_H */

/* fc_madgwick.h: Madgwick's gradient-descent filter, IMU form (fusion_core/madgwick.py,
 * MadgwickFilter), the C twin. Madgwick, Harrison, Vaidyanathan 2011; Madgwick 2010 eq. 12-34. */
#ifndef FC_MADGWICK_H
#define FC_MADGWICK_H

#include "fc_core.h"
#include "fc_params.h"

typedef struct fc_madgwick {
    fc_madgwick_params params;
    fc_base base;
    /* MadgwickFilter.STATE */
    fc_real q[4];
    fc_estimate last;
    /* derived from params (MadgwickFilter._configure) */
    fc_real beta;
    int trapezoid;
} fc_madgwick;

void fc_madgwick_init(fc_madgwick *f, const fc_madgwick_params *params);
void fc_madgwick_configure(fc_madgwick *f);
void fc_madgwick_reset(fc_madgwick *f);
fc_status fc_madgwick_step(fc_madgwick *f, const fc_real acc[3], const fc_real gyro[3], fc_real dt,
                           fc_estimate *out);
long fc_madgwick_run(fc_madgwick *f, long n, const fc_real *acc, const fc_real *gyro,
                     const fc_real *dt, fc_estimate *out, unsigned char *rejected);
long fc_madgwick_run_columns(fc_madgwick *f, long n, const fc_real *acc, const fc_real *gyro,
                             const fc_real *dt, fc_real *roll, fc_real *pitch, fc_real *bias,
                             fc_real *pos, fc_real *vel, unsigned char *rejected);
fc_estimate fc_madgwick_estimate(const fc_madgwick *f);
/* After a restore of the state fields (fc_state.h): recompute what follows from them. */
void fc_madgwick_restored(fc_madgwick *f);

#endif /* FC_MADGWICK_H */

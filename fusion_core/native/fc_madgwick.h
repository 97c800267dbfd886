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
} fc_madgwick;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_madgwick);

#endif /* FC_MADGWICK_H */

/* fc_paper_cf.h: the papers' complementary filter (fusion_core/papers/complementary.py,
 * PaperComplementaryFilter), the C twin. Gui et al. 2015 eq. 1-2, Das & Mary eq. 1. */
#ifndef FC_PAPER_CF_H
#define FC_PAPER_CF_H

#include "fc_core.h"
#include "fc_params.h"

typedef struct fc_paper_cf {
    fc_paper_cf_params params;
    fc_base base;
    /* PaperComplementaryFilter.STATE */
    fc_real roll, pitch;
    fc_estimate last;
    /* derived from params (PaperComplementaryFilter._configure) */
    fc_real tau, gate_low2, gate_high2;
} fc_paper_cf;

/* init, configure, reset, step, run, run_columns, estimate, restored (fc_core.h) */
FC_DECLARE_ESTIMATOR(fc_paper_cf);

#endif /* FC_PAPER_CF_H */

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
    int trapezoid;
} fc_paper_cf;

void fc_paper_cf_init(fc_paper_cf *f, const fc_paper_cf_params *params);
void fc_paper_cf_configure(fc_paper_cf *f);
void fc_paper_cf_reset(fc_paper_cf *f);
fc_status fc_paper_cf_step(fc_paper_cf *f, const fc_real acc[3], const fc_real gyro[3], fc_real dt,
                           fc_estimate *out);
long fc_paper_cf_run(fc_paper_cf *f, long n, const fc_real *acc, const fc_real *gyro,
                     const fc_real *dt, fc_estimate *out, unsigned char *rejected);
long fc_paper_cf_run_columns(fc_paper_cf *f, long n, const fc_real *acc, const fc_real *gyro,
                             const fc_real *dt, fc_real *roll, fc_real *pitch, fc_real *bias,
                             fc_real *pos, fc_real *vel, unsigned char *rejected);
fc_estimate fc_paper_cf_estimate(const fc_paper_cf *f);
/* After a restore of the state fields (fc_state.h): recompute what follows from them. */
void fc_paper_cf_restored(fc_paper_cf *f);

#endif /* FC_PAPER_CF_H */

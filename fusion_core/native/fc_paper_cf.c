/* fc_paper_cf.c: see fc_paper_cf.h; the twin of fusion_core/papers/complementary.py line by
 * line. */
#include "fc_paper_cf.h"

#include <string.h>

void fc_paper_cf_configure(fc_paper_cf *f)
{
    const fc_paper_cf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    f->tau = p->tau;
    fc_gate_bounds2(p->gate_low, p->gate_high, &f->gate_low2, &f->gate_high2);
}

fc_estimate fc_paper_cf_estimate(const fc_paper_cf *f)  /* _estimate: no bias state */
{
    fc_estimate e;
    memset(&e, 0, sizeof e);
    e.roll = f->roll;
    e.pitch = f->pitch;
    return e;
}

void fc_paper_cf_reset(fc_paper_cf *f)
{
    fc_base_reset(&f->base);
    f->roll = f->pitch = 0.0;
    f->last = fc_paper_cf_estimate(f);
}

FC_DEFINE_INIT(fc_paper_cf)
FC_DEFINE_RESTORED(fc_paper_cf)

static void first_sample(fc_paper_cf *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    (void)g;
    fc_accel_roll_pitch(a[0], a[1], a[2], &f->roll, &f->pitch);
}

static void advance(fc_paper_cf *f, const fc_real a[3], const fc_real g[3], fc_real dt)
{
    fc_real roll, pitch;
    if (f->base.trapezoid) {
        const fc_real *w0 = f->base.gyro_prev;
        fc_heun_euler_step(f->roll, f->pitch, w0[0], w0[1], w0[2], g[0], g[1], g[2], dt, NULL,
                           &roll, &pitch);
    } else {
        fc_euler_step(f->roll, f->pitch, g[0], g[1], g[2], dt, NULL, &roll, &pitch);
    }
    fc_real n2 = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    if (f->gate_low2 <= n2 && n2 <= f->gate_high2) {
        fc_real acc_roll, acc_pitch;
        fc_accel_roll_pitch(a[0], a[1], a[2], &acc_roll, &acc_pitch);
        fc_real k = dt / (f->tau + dt);  /* 1 - a, Gui et al. eq. 2 */
        fc_real y = acc_roll - roll;
        roll += k * (-FC_PI <= y && y <= FC_PI ? y : fc_wrap_angle(y));
        pitch += k * (acc_pitch - pitch);
    }
    f->roll = -FC_PI <= roll && roll <= FC_PI ? roll : fc_wrap_angle(roll);
    f->pitch = -FC_HALF_PI <= pitch && pitch <= FC_HALF_PI ? pitch : fc_clamp_pitch(pitch);
}

FC_DEFINE_STEP_AND_RUN(fc_paper_cf)

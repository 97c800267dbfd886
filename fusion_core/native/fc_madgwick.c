/* fc_madgwick.c: see fc_madgwick.h; the twin of fusion_core/madgwick.py line by line. */
#include "fc_madgwick.h"

void fc_madgwick_configure(fc_madgwick *f)
{
    const fc_madgwick_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    f->beta = p->beta;
}

fc_estimate fc_madgwick_estimate(const fc_madgwick *f)  /* _estimate: no bias state */
{
    fc_real roll, pitch;
    fc_quat_roll_pitch(f->q, &roll, &pitch);
    return fc_attitude_estimate(roll, pitch, 0.0, 0.0, 0.0);
}

void fc_madgwick_reset(fc_madgwick *f)
{
    fc_base_reset(&f->base);
    f->q[0] = 1.0;
    f->q[1] = f->q[2] = f->q[3] = 0.0;
    f->last = fc_madgwick_estimate(f);
}

FC_DEFINE_INIT(fc_madgwick)
FC_DEFINE_RESTORED(fc_madgwick)

static void first_sample(fc_madgwick *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    fc_real roll, pitch;
    (void)g;
    fc_accel_roll_pitch(a[0], a[1], a[2], &roll, &pitch);
    fc_quat_from_roll_pitch_yaw(roll, pitch, 0.0, f->q);
}

static void advance(fc_madgwick *f, const fc_real a[3], const fc_real g[3], fc_real dt)
{
    fc_real w = f->q[0], x = f->q[1], y = f->q[2], z = f->q[3];
    fc_real gx = g[0], gy = g[1], gz = g[2];
    if (f->base.trapezoid) {  /* the rate's mean over the interval, linear between the samples */
        const fc_real *p = f->base.gyro_prev;
        gx = 0.5 * (p[0] + gx);
        gy = 0.5 * (p[1] + gy);
        gz = 0.5 * (p[2] + gz);
    }
    /* eq. 12: q_dot = 0.5 q (x) (0, gx, gy, gz) */
    fc_real dw = 0.5 * (-x * gx - y * gy - z * gz);
    fc_real dx = 0.5 * (w * gx + y * gz - z * gy);
    fc_real dy = 0.5 * (w * gy - x * gz + z * gx);
    fc_real dz = 0.5 * (w * gz + x * gy - y * gx);
    if (f->base.trapezoid) {  /* the gradient taken at this sample's time: q turned first */
        w = w + dw * dt;
        x = x + dx * dt;
        y = y + dy * dt;
        z = z + dz * dt;
        fc_real np = fc_sqrt(w * w + x * x + y * y + z * z);
        w = w / np;
        x = x / np;
        y = y / np;
        z = z / np;
        dw = dx = dy = dz = 0.0;
    }
    fc_real norm = fc_sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (norm > 0.0) {
        fc_real ax = a[0] / norm, ay = a[1] / norm, az = a[2] / norm;
        /* eq. 25: the gravity direction q predicts in the body frame minus the measured one */
        fc_real f1 = 2.0 * (x * z - w * y) - ax;
        fc_real f2 = 2.0 * (w * x + y * z) - ay;
        fc_real f3 = 2.0 * (0.5 - x * x - y * y) - az;
        /* eq. 26 and 34: J^T f */
        fc_real sw = -2.0 * y * f1 + 2.0 * x * f2;
        fc_real sx = 2.0 * z * f1 + 2.0 * w * f2 - 4.0 * x * f3;
        fc_real sy = -2.0 * w * f1 + 2.0 * z * f2 - 4.0 * y * f3;
        fc_real sz = 2.0 * x * f1 + 2.0 * y * f2;
        fc_real step = fc_sqrt(sw * sw + sx * sx + sy * sy + sz * sz);
        if (step > 0.0) {  /* eq. 33: the normalised step, scaled by beta */
            fc_real k = f->beta / step;
            dw -= k * sw;
            dx -= k * sx;
            dy -= k * sy;
            dz -= k * sz;
        }
    }
    /* eq. 13, then back onto the unit sphere */
    w = w + dw * dt;
    x = x + dx * dt;
    y = y + dy * dt;
    z = z + dz * dt;
    fc_real n = fc_sqrt(w * w + x * x + y * y + z * z);
    f->q[0] = w / n;
    f->q[1] = x / n;
    f->q[2] = y / n;
    f->q[3] = z / n;
}

FC_DEFINE_STEP_AND_RUN(fc_madgwick)

/* fc_paper_mgcf.c: see fc_paper_mgcf.h; the twin of fusion_core/papers/mgcf.py line by line. */
#include "fc_paper_mgcf.h"

#include <math.h>
#include <string.h>

/* SCHEDULES by schedule (FC_PAPER_MGCF_SCHEDULE_SIMULATION, _EXPERIMENTAL): (rho upper bound,
 * w0 [rad/s]) rows; rho at or above the last bound: w0 = 0 */
static const fc_real SCHEDULES[2][3][2] = {
    {{0.01, 0.1}, {0.25, 0.07}, {0.35, 0.035}},
    {{0.025, 0.1}, {0.035, 0.07}, {0.05, 0.05}},
};

/* scheduled_w0: the table is chosen here, by its index, so the filter's struct holds no
 * pointer (fc_state.h) */
static fc_real scheduled_w0(fc_real rho, int schedule)
{
    for (int i = 0; i < 3; i++) {
        if (rho < SCHEDULES[schedule][i][0]) {
            return SCHEDULES[schedule][i][1];
        }
    }
    return 0.0;
}

void fc_paper_mgcf_quat_first_order(fc_real q[4], fc_real w0, fc_real w1, fc_real w2, fc_real dt)
{
    fc_real qw = q[0], qx = q[1], qy = q[2], qz = q[3];
    fc_real wx = 0.5 * dt * w0, wy = 0.5 * dt * w1, wz = 0.5 * dt * w2;
    fc_real rw = qw - qx * wx - qy * wy - qz * wz;
    fc_real rx = qx + qw * wx + qy * wz - qz * wy;
    fc_real ry = qy + qw * wy - qx * wz + qz * wx;
    fc_real rz = qz + qw * wz + qx * wy - qy * wx;
    fc_real n = 1.0 / fc_sqrt(rw * rw + rx * rx + ry * ry + rz * rz);
    q[0] = rw * n;
    q[1] = rx * n;
    q[2] = ry * n;
    q[3] = rz * n;
}

void fc_paper_mgcf_pi_step(fc_real q[4], fc_real bias[3], const fc_real prev[3], const fc_real g[3],
                           const fc_real a[3], fc_real norm, fc_real w0, fc_real kp, fc_real dt,
                           int trapezoid, int learn_bias)
{
    fc_real bx = bias[0], by = bias[1], bz = bias[2];
    fc_real gx = g[0], gy = g[1], gz = g[2];
    if (trapezoid) {
        fc_real phi[3];
        fc_rotation_increment(prev[0] - bx, prev[1] - by, prev[2] - bz, gx - bx, gy - by,
                              gz - bz, dt, phi);
        fc_quat_mul_rotvec(q, phi[0], phi[1], phi[2]);
    }
    fc_real ex = 0.0, ey = 0.0, ez = 0.0;
    if (w0 > 0.0) {  /* e = a/|a| x v, v = R(q)^T e_z */
        fc_real v[3];
        fc_quat_gravity_body(q, v);
        fc_real inv = 1.0 / norm;
        fc_real nx = a[0] * inv, ny = a[1] * inv, nz = a[2] * inv;
        ex = ny * v[2] - nz * v[1];
        ey = nz * v[0] - nx * v[2];
        ez = nx * v[1] - ny * v[0];
        if (learn_bias) {  /* b <- b - Ki e dt, Ki = w0^2 */
            fc_real ki_dt = w0 * w0 * dt;
            bx = bx - ki_dt * ex;
            by = by - ki_dt * ey;
            bz = bz - ki_dt * ez;
            bias[0] = bx;
            bias[1] = by;
            bias[2] = bz;
        }
    }
    if (!trapezoid) {
        fc_paper_mgcf_quat_first_order(q, gx + kp * ex - bx, gy + kp * ey - by,
                                       gz + kp * ez - bz, dt);
    } else if (w0 > 0.0) {
        fc_real kp_dt = kp * dt;
        fc_quat_mul_rotvec(q, kp_dt * ex, kp_dt * ey, kp_dt * ez);
    }
}

void fc_paper_mgcf_configure(fc_paper_mgcf *f)
{
    const fc_paper_mgcf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    f->w0_fixed = p->w0;
    f->two_zeta = 2.0 * p->zeta;
}

fc_estimate fc_paper_mgcf_quat_estimate(const fc_real q[4], const fc_real bias[3])
{
    fc_estimate e;
    memset(&e, 0, sizeof e);
    fc_quat_roll_pitch(q, &e.roll, &e.pitch);
    memcpy(e.bias, bias, sizeof e.bias);
    return e;
}

fc_estimate fc_paper_mgcf_estimate(const fc_paper_mgcf *f)
{
    return fc_paper_mgcf_quat_estimate(f->q, f->bias);
}

void fc_paper_mgcf_reset(fc_paper_mgcf *f)
{
    fc_base_reset(&f->base);
    f->q[0] = 1.0;
    f->q[1] = f->q[2] = f->q[3] = 0.0;
    memset(f->bias, 0, sizeof f->bias);
    f->w0_now = 0.0;
    f->last = fc_paper_mgcf_estimate(f);
}

FC_DEFINE_INIT(fc_paper_mgcf)
FC_DEFINE_RESTORED(fc_paper_mgcf)

static void first_sample(fc_paper_mgcf *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    (void)g;
    fc_real roll, pitch;
    fc_accel_roll_pitch(a[0], a[1], a[2], &roll, &pitch);
    fc_quat_from_roll_pitch_yaw(roll, pitch, 0.0, f->q);
}

static void advance(fc_paper_mgcf *f, const fc_real a[3], const fc_real g[3], fc_real dt)
{
    fc_real ax = a[0], ay = a[1], az = a[2];
    fc_real norm = fc_sqrt(ax * ax + ay * ay + az * az);
    int schedule = f->params.schedule;
    int scheduled = schedule == FC_PAPER_MGCF_SCHEDULE_SIMULATION ||
                    schedule == FC_PAPER_MGCF_SCHEDULE_EXPERIMENTAL;
    fc_real w0 = scheduled ? scheduled_w0(fc_fabs(norm / FC_G - 1.0), schedule) : f->w0_fixed;
    if (!(norm > 0.0)) {  /* no gravity direction in this sample: gyro only */
        w0 = 0.0;
    }
    f->w0_now = w0;
    fc_paper_mgcf_pi_step(f->q, f->bias, f->base.gyro_prev, g, a, norm, w0, f->two_zeta * w0, dt,
                          f->base.trapezoid, 1);
}

FC_DEFINE_STEP_AND_RUN(fc_paper_mgcf)

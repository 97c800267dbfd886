/* fc_poskf.c: see fc_poskf.h; the twin of fusion_core/position.py line by line. */
#include "fc_poskf.h"

#include "fc_paper_poskf.h"

#include <math.h>
#include <string.h>

void fc_poskf_configure(fc_poskf *f)
{
    const fc_poskf_params *p = &f->params;
    fc_base_configure(&f->base, &p->input);
    /* the tilt stage: the papers' kf with the TILT_PARAMS given */
    fc_paper_kf_params tp;
    fc_paper_kf_params_default(&tp);
    tp.Q_angle = p->Q_angle;
    tp.Q_bias = p->Q_bias;
    tp.R_measure = p->R_measure;
    tp.R_loop_time = p->R_loop_time;
    tp.gate_low = p->gate_low;
    tp.gate_high = p->gate_high;
    tp.input.gyro_sampling = p->input.gyro_sampling;
    tp.input.max_dt = p->input.max_dt;
    tp.input.max_rate = p->input.max_rate;
    f->tilt.params = tp;
    fc_paper_kf_configure(&f->tilt);
    /* the attitude output: the recommended kf */
    fc_kf_params ap;
    fc_kf_params_default(&ap);
    ap.input.gyro_sampling = p->input.gyro_sampling;
    ap.input.max_dt = p->input.max_dt;
    ap.input.max_rate = p->input.max_rate;
    ap.input.gyro_range = p->input.gyro_range;
    f->att.params = ap;
    fc_kf_configure(&f->att);
    f->acc_var_density = p->acc_psd;
    f->zupt_var = fc_pow(p->zupt_noise, 2.0);
    f->gyro_var_density = p->gyro_psd;
    f->Q_dt = 0.0;
}

fc_estimate fc_poskf_estimate(const fc_poskf *f)
{
    fc_estimate e = f->att.last;  /* the attitude kf's own output (in the sensor frame) */
    fc_paper_poskf_put_axes(f->x, &e);
    return e;
}

void fc_poskf_reset(fc_poskf *f)
{
    fc_base_reset(&f->base);
    fc_paper_kf_reset(&f->tilt);
    fc_kf_reset(&f->att);
    f->yaw = 0.0;
    memset(f->x, 0, sizeof f->x);
    memset(f->P, 0, sizeof f->P);
    f->quiet_time = 0.0;
    f->stationary = 0;
    f->pending_head = f->pending_count = 0;
    f->turned[0] = f->turned[1] = 0.0;
    memset(f->f_mean, 0, sizeof f->f_mean);
    f->aligned = 0;
    f->sines[0] = f->sines[1] = NAN;  /* tilt_sines: none yet */
    f->last = fc_poskf_estimate(f);
}

FC_DEFINE_INIT(fc_poskf)

void fc_poskf_restored(fc_poskf *f)  /* the nested filters' last estimates too (_restored) */
{
    fc_paper_kf_restored(&f->tilt);
    fc_kf_restored(&f->att);
    f->last = fc_poskf_estimate(f);
    fc_base_output(&f->base, &f->last);
}

static void first_sample(fc_poskf *f, const fc_real a[3], const fc_real g[3])  /* _init */
{
    fc_paper_poskf_first_axis_states(&f->tilt, a, g, f->params.input.max_dt, f->acc_var_density,
                                     f->x, f->P);
    fc_kf_step_prepared(&f->att, a, g, f->params.input.max_dt, f->base.clipped, NULL);
    memcpy(f->f_mean, a, sizeof f->f_mean);
}

/* _tilt_sines: sin and cos of the tilt stage's roll and pitch, computed once per pair */
static const fc_real *tilt_sines(fc_poskf *f, fc_real roll, fc_real pitch)
{
    fc_real *c = f->sines;
    if (!(c[0] == roll && c[1] == pitch)) {
        c[0] = roll;
        c[1] = pitch;
        fc_roll_pitch_sines(roll, pitch, c + 2);
    }
    return c + 2;
}

static int slow_enough(const fc_poskf *f)  /* _slow_enough */
{
    const fc_real *x = f->x;
    fc_real speed = fc_sqrt(x[1] * x[1] + x[4] * x[4] + x[7] * x[7]);
    fc_real sigma = fc_sqrt(f->P[3] + f->zupt_var);
    fc_real bound = 5.0 * sigma > f->params.zupt_speed ? 5.0 * sigma : f->params.zupt_speed;
    return speed <= bound;
}

static void advance(fc_poskf *f, const fc_real a[3], const fc_real g[3], fc_real dt)
{
    const fc_poskf_params *p = &f->params;
    fc_paper_kf *tilt = &f->tilt;
    fc_real ax = a[0], ay = a[1], az = a[2], gx = g[0], gy = g[1], gz = g[2];
    /* 1. stationary detector */
    fc_real mx = f->f_mean[0], my = f->f_mean[1], mz = f->f_mean[2];
    fc_real dx = ax - mx, dy = ay - my, dz = az - mz;
    fc_real wx = gx - tilt->bias_x, wy = gy - tilt->bias_y;
    fc_real roll = tilt->roll, pitch = tilt->pitch, l[3];
    const fc_real *sc = tilt_sines(f, roll, pitch);
    fc_paper_poskf_level_acceleration(ax, ay, az, sc[0], sc[1], sc[2], sc[3], 0.0, 1.0, l);
    int quiet = fc_sqrt(dx * dx + dy * dy + dz * dz) < p->zupt_acc
        && fc_sqrt(l[0] * l[0] + l[1] * l[1] + l[2] * l[2]) < p->zupt_level_acc
        && fc_sqrt(wx * wx + wy * wy + gz * gz) < p->zupt_gyro;
    fc_real window = p->zupt_window;
    fc_real k = window > 0.0 ? dt / window : 1.0;
    if (k > 1.0) {
        k = 1.0;
    }
    f->f_mean[0] = mx + k * dx;
    f->f_mean[1] = my + k * dy;
    f->f_mean[2] = mz + k * dz;
    fc_real quiet_time = f->quiet_time = quiet ? f->quiet_time + dt : 0.0;
    int stationary = f->stationary = quiet && quiet_time >= window
        && (quiet_time >= p->zupt_force_after || slow_enough(f));
    /* 2. tilt stage */
    fc_paper_kf_propagate(tilt, f->base.gyro_prev, g, dt, sc);
    fc_real d_roll = tilt->roll - roll;
    fc_real turned_roll = f->turned[0], turned_pitch = f->turned[1];
    turned_roll += -FC_PI <= d_roll && d_roll <= FC_PI ? d_roll : fc_wrap_angle(d_roll);
    turned_pitch = turned_pitch + tilt->pitch - pitch;
    f->turned[0] = turned_roll;
    f->turned[1] = turned_pitch;
    fc_real n2 = ax * ax + ay * ay + az * az;
    if (!quiet) {
        f->pending_head = f->pending_count = 0;
    } else {
        if (stationary && fc_paper_kf_accel_trusted(tilt, n2)) {
            if (f->pending_count >= FC_POSKF_PENDING_MAX) {  /* full: drop the oldest */
                f->pending_head = (f->pending_head + 1) % FC_POSKF_PENDING_MAX;
                f->pending_count--;
            }
            fc_real *e = f->pending[(f->pending_head + f->pending_count) % FC_POSKF_PENDING_MAX];
            e[0] = quiet_time;
            fc_accel_roll_pitch(ax, ay, az, &e[1], &e[2]);
            e[3] = turned_roll;
            e[4] = turned_pitch;
            f->pending_count++;
        }
        while (f->pending_count && quiet_time - f->pending[f->pending_head][0] >= window) {
            const fc_real *e = f->pending[f->pending_head];
            fc_real acc_roll = e[1], acc_pitch = e[2], then_roll = e[3], then_pitch = e[4];
            f->pending_head = (f->pending_head + 1) % FC_POSKF_PENDING_MAX;
            f->pending_count--;
            fc_paper_kf_correct_innovation(
                tilt, fc_wrap_angle(acc_roll - tilt->roll + turned_roll - then_roll),
                acc_pitch - tilt->pitch + turned_pitch - then_pitch);
            f->aligned = 1;
        }
    }
    if (stationary) {
        fc_paper_kf_correct_bias(tilt, gx, gy, f->gyro_var_density / dt);
    }
    fc_paper_kf_took_sample(tilt, g);
    fc_kf_step_prepared(&f->att, a, g, dt, f->base.clipped, NULL);
    if (!f->aligned) {  /* until the first confirmed rest: the attitude filter's levelling */
        tilt->roll = f->att.last.roll;
        tilt->pitch = f->att.last.pitch;
    }
    /* 3. yaw from the gyro, the level-frame acceleration with the new attitude */
    fc_real acc[3];
    fc_paper_poskf_yaw_and_level_acceleration(tilt->roll, tilt->pitch, &f->yaw, wy, gz, a, dt,
                                              tilt_sines(f, tilt->roll, tilt->pitch), acc);
    /* 4. [p, v, a] filter per axis (eq. 20-29) */
    if (dt != f->Q_dt) {
        fc_paper_poskf_process_noise(FC_PAPER_POSKF_QR_FORM_WHITE_JERK, p->q, dt, f->Q);
        f->R = f->acc_var_density / dt;
        f->Q_dt = dt;
    }
    fc_paper_poskf_axis_filters(f->x, f->P, f->Q, dt, acc, f->R, stationary, f->zupt_var);
}

FC_DEFINE_STEP_AND_RUN(fc_poskf)

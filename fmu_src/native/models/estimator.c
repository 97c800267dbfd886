/* estimator.c: an estimator of fusion_core's C twin as an FMU model (fmu_model.h), written once
 * for all five. config.h, generated from the FMU's variable table, names the twin (FC_T and its
 * functions), the value references (VR_*), the variable table and how the parameter values fill
 * the twin's params struct.
 *
 * Sample semantics as the pythonfmu FMUs (fmu_src/estimator.py): the inputs set before
 * doStep(t, h) are one IMU sample; the first valid one initialises the filter; a rejected
 * sample (NaN/inf, dt outside (0, max_dt], a rate above max_rate) leaves the filter state as it
 * was, counts in invalid_samples and is logged as a warning; the outputs after doStep are the
 * estimate for the sample.
 */
#include <stdio.h>
#include <string.h>

#include "config.h"
#include "fc_state_layouts.h"
#include "fmu_model.h"

typedef struct model_data {
    FC_T filter;
} model_data;

static void setup(void *data, double *values, double t)
{
    model_data *m = (model_data *)data;
    (void)t;
    FC_PARAMS p;
    memset(&p, 0, sizeof p);  /* no stack garbage in its padding: a state is compared bytewise */
    params_from_values(&p, values);
    FC_INIT(&m->filter, &p);
}

static void tune(void *data, const double *values)
{
    model_data *m = (model_data *)data;
    params_from_values(&m->filter.params, values);
    FC_CONFIGURE(&m->filter);
}

static const char *rejection(fc_status status)
{
    switch (status) {
    case FC_BAD_ACC: return "an accelerometer value is NaN or infinite";
    case FC_BAD_GYRO: return "a gyro value is NaN or infinite";
    case FC_BAD_DT: return "dt is NaN, infinite or outside (0, max_dt]";
    case FC_BAD_RATE: return "the gyro reading is above max_rate";
    default: return "bad sample";
    }
}

static int step(void *data, double *v, double t, double h, char *message, size_t size)
{
    model_data *m = (model_data *)data;
    const double acc[3] = {v[VR_acc_x], v[VR_acc_y], v[VR_acc_z]};
    const double gyro[3] = {v[VR_gyro_x], v[VR_gyro_y], v[VR_gyro_z]};
    fc_estimate e;
    fc_status status = FC_STEP(&m->filter, acc, gyro, v[VR_dt], &e);
    if (status > FC_SKIPPED) {
        v[VR_invalid_samples] += 1.0;
        snprintf(message, size, "sample at t = %.9g s rejected, the filter state is kept: %s "
                 "(%.0f rejected so far)", t + h, rejection(status), v[VR_invalid_samples]);
        return 1;
    }
    v[VR_roll] = e.roll;
    v[VR_pitch] = e.pitch;
    v[VR_bias_x] = e.bias[0];
    v[VR_bias_y] = e.bias[1];
    v[VR_bias_z] = e.bias[2];
#if HAS_POSITION
    v[VR_pos_x] = e.pos[0];
    v[VR_pos_y] = e.pos[1];
    v[VR_pos_z] = e.pos[2];
    v[VR_vel_x] = e.vel[0];
    v[VR_vel_y] = e.vel[1];
    v[VR_vel_z] = e.vel[2];
#endif
    return 0;
}

static void restored(void *data)
{
    FC_RESTORED(&((model_data *)data)->filter);
}

/* The twin is model_data's first member: its layout's offsets are the data's. */
const fmu_model FMU_MODEL = {
    MODEL_IDENTIFIER, MODEL_TOKEN, VARIABLES, N_VARIABLES, sizeof(model_data), &FC_LAYOUT,
    setup, tune, step, restored,
};

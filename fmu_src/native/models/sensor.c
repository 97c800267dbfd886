/* sensor.c: the MEMS IMU error model (fc_sensor.h, the twin of fusion_core.sensor) as an FMU
 * model (fmu_model.h). Inputs: the true body rates omega_* and specific force f_*; after
 * doStep(t, h) the outputs are the IMU sample of the inputs (acc_*, gyro_*, dt) and the gyro's
 * true bias then (true_bias_*); inputs_at says whether the inputs hold at t+h or at t.
 * config.h, generated from the FMU's variable table, gives the value references and how the
 * parameter values fill fc_sensor_params. */
#include <string.h>

#include "config.h"
#include "fc_sensor.h"
#include "fc_state_layouts.h"
#include "fmu_model.h"

typedef struct model_data {
    fc_sensor sensor;
} model_data;

static void setup(void *data, double *values, double t)
{
    fc_sensor_params p;
    (void)t;
    memset(&p, 0, sizeof p);  /* no stack garbage in its padding: a state is compared bytewise */
    params_from_values(&p, values);
    fc_sensor_init(&((model_data *)data)->sensor, &p);
}

static void tune(void *data, const double *values)
{
    /* The model reads its tunable parameters at every sample, as the Python model does. */
    params_from_values(&((model_data *)data)->sensor.params, values);
}

static int step(void *data, double *v, double t, double h, char *message, size_t size)
{
    fc_sensor *s = &((model_data *)data)->sensor;
    const double omega[3] = {v[VR_omega_x], v[VR_omega_y], v[VR_omega_z]};
    const double f[3] = {v[VR_f_x], v[VR_f_y], v[VR_f_z]};
    double acc[3], gyro[3], dt, bias[3];
    /* the interval the sample covers: h where the inputs hold at t+h (inputs_at = end), the
     * step before where they hold at t (start; the first sample: h) */
    double interval = v[VR_inputs_at] == 1.0 || !(v[VR_last_step] > 0.0) ? h : v[VR_last_step];
    (void)t;
    (void)message;
    (void)size;
    if (fc_sensor_sample(s, omega, f, interval, acc, gyro, &dt) != 0) {
        return 0;  /* unreachable: the plumbing refuses h <= 0 */
    }
    fc_sensor_gyro_bias(s, bias);
    v[VR_acc_x] = acc[0];
    v[VR_acc_y] = acc[1];
    v[VR_acc_z] = acc[2];
    v[VR_gyro_x] = gyro[0];
    v[VR_gyro_y] = gyro[1];
    v[VR_gyro_z] = gyro[2];
    v[VR_dt] = dt;
    v[VR_true_bias_x] = bias[0];
    v[VR_true_bias_y] = bias[1];
    v[VR_true_bias_z] = bias[2];
    v[VR_last_step] = h;
    return 0;
}

/* The sensor is model_data's first member: its layout's offsets are the data's. */
const fmu_model FMU_MODEL = {
    MODEL_IDENTIFIER, MODEL_TOKEN, VARIABLES, N_VARIABLES, sizeof(model_data), &FC_SENSOR_LAYOUT,
    setup, tune, step, NULL,
};

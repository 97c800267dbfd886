/* native_floor.c: the benchmark's floor model for the native FMUs (fmu_src/native/fmu_model.h):
 * the estimator FMUs' inputs and outputs, and a step that does nothing. Timing it times the host
 * and the FMI plumbing only: no native estimator FMU can step faster. */
#include "config.h"
#include "fmu_model.h"

static void setup(void *data, double *values, double t)
{
    (void)data;
    (void)values;
    (void)t;
}

static void tune(void *data, const double *values)
{
    (void)data;
    (void)values;
}

static int step(void *data, double *values, double t, double h, char *message, size_t size)
{
    (void)data;
    (void)values;
    (void)t;
    (void)h;
    (void)message;
    (void)size;
    return 0;
}

const fmu_model FMU_MODEL = {
    MODEL_IDENTIFIER, MODEL_TOKEN, VARIABLES, N_VARIABLES, 1, NULL, setup, tune, step, NULL,
};

/* plant.c: the testbench plant (fc_plant.h, the twin of fusion_core.scenarios) as an FMU model
 * (fmu_model.h). After doStep(t, h) the outputs are the truth at t+h of the scenario the fixed
 * parameter `scenario` chooses; before the first step, from the moment the start time or the
 * scenario is set, they are its truth at the start time (a Jacobi master passes them on to the
 * sensor before any step: they must be the truth, not a start value). config.h, generated from the FMU's variable table, gives the
 * value references and TRUTH_VR, the output of each truth value in fc_plant_truth's order. */
#include "config.h"
#include "fc_plant.h"
#include "fmu_model.h"

typedef struct model_data {
    int scenario;
} model_data;

static void write_truth(int scenario, double t, double *v)
{
    double truth[FC_TRUTH_SIZE];
    int i;
    if (fc_plant_truth(scenario, t, truth) != 0) {
        return;  /* unreachable: `scenario` is checked against its range when it is set */
    }
    for (i = 0; i < FC_TRUTH_SIZE; i++) {
        v[TRUTH_VR[i]] = truth[i];
    }
}

static void setup(void *data, double *values, double t)
{
    model_data *m = (model_data *)data;
    m->scenario = (int)values[VR_scenario];
    write_truth(m->scenario, t, values);
}

static void tune(void *data, const double *values)
{
    (void)data;
    (void)values;  /* the plant has no tunable parameter */
}

static int step(void *data, double *v, double t, double h, char *message, size_t size)
{
    (void)message;
    (void)size;
    write_truth(((model_data *)data)->scenario, t + h, v);
    return 0;
}

/* No state: the truth is a function of time, and the scenario a parameter. */
const fmu_model FMU_MODEL = {
    MODEL_IDENTIFIER, MODEL_TOKEN, VARIABLES, N_VARIABLES, sizeof(model_data), NULL, setup, tune,
    step, NULL,
};

/* fmi2Functions.c: the FMI 2.0 co-simulation interface, written once for every model.
 *
 * Every call is checked against the FMI 2.0 state machine (the states each function is allowed
 * in, as in the standard's state diagram and the Reference-FMUs' masks); a call in the wrong
 * state, an unknown value reference, a value out of range, a step size <= 0 or bytes that are
 * not this FMU's state return fmi2Error with a log line naming the call, and leave the instance
 * as it was, so the next correct call sequence still works. Model-exchange functions return
 * fmi2Error: these are co-simulation FMUs. Nothing a host passes (NULL pointers aside, where the
 * standard allows them) may crash the process.
 */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_model.h"

#define MASK_ANY FMU_ANY_STATE
#define MASK_GET (FMU_INITIALIZATION | FMU_STEP | FMU_TERMINATED)
#define MASK_SET (FMU_INSTANTIATED | FMU_INITIALIZATION | FMU_STEP)

static void emit(const fmu_instance *inst, int status, const char *category, const char *message)
{
    const fmi2CallbackFunctions *cb = inst->callbacks;
    char escaped[2048];
    size_t i, j = 0;
    if (!cb || !cb->logger) {
        return;
    }
    /* The logger takes the message as a printf format: a '%' in it must be doubled. */
    for (i = 0; message[i] && j + 2 < sizeof escaped; i++) {
        if (message[i] == '%') {
            escaped[j++] = '%';
        }
        escaped[j++] = message[i];
    }
    escaped[j] = '\0';
    cb->logger(cb->componentEnvironment, inst->name, (fmi2Status)status, category, escaped);
}

#define INSTANCE(c, call, mask)                                                               \
    fmu_instance *inst = (fmu_instance *)(c);                                                 \
    if (!inst) {                                                                              \
        return fmi2Error;                                                                     \
    }                                                                                         \
    if (fmu_allow(inst, (mask), (call)) != FMU_OK) {                                          \
        return fmi2Error;                                                                     \
    }

const char *fmi2GetTypesPlatform(void)
{
    return fmi2TypesPlatform;
}

const char *fmi2GetVersion(void)
{
    return fmi2Version;
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    INSTANCE(c, "fmi2SetDebugLogging", MASK_ANY)
    (void)categories;
    (void)nCategories;
    inst->logging_on = loggingOn ? 1 : 0;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    fmu_instance probe;
    (void)fmuResourceLocation;
    (void)visible;
    /* A stand-in instance to log through before the real one exists. */
    memset(&probe, 0, sizeof probe);
    probe.name = (char *)(instanceName ? instanceName : "?");
    probe.emit = emit;
    probe.callbacks = functions;
    if (!instanceName || !instanceName[0]) {
        fmu_log(&probe, FMU_ERROR, "fmi2Instantiate: the instance name must not be empty");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        fmu_log(&probe, FMU_ERROR, "fmi2Instantiate: %s is a co-simulation FMU only "
                "(fmuType %d refused)", FMU_MODEL.name, (int)fmuType);
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, FMU_MODEL.token) != 0) {
        fmu_log(&probe, FMU_ERROR, "fmi2Instantiate: GUID %s is not this FMU's (%s %s): was the "
                "modelDescription.xml of another FMU read?", fmuGUID ? fmuGUID : "NULL",
                FMU_MODEL.name, FMU_MODEL.token);
        return NULL;
    }
    return fmu_instance_new(instanceName, emit, functions, NULL,
                            functions ? functions->componentEnvironment : NULL, loggingOn);
}

void fmi2FreeInstance(fmi2Component c)
{
    fmu_instance_free((fmu_instance *)c);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    INSTANCE(c, "fmi2SetupExperiment", FMU_INSTANTIATED)
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    inst->time = startTime;
    fmu_instance_setup(inst);  /* the plant's outputs: its truth at startTime */
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    INSTANCE(c, "fmi2EnterInitializationMode", FMU_INSTANTIATED)
    inst->state = FMU_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    INSTANCE(c, "fmi2ExitInitializationMode", FMU_INITIALIZATION)
    return (fmi2Status)fmu_exit_initialization(inst);
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    INSTANCE(c, "fmi2Terminate", FMU_STEP)
    inst->state = FMU_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    INSTANCE(c, "fmi2Reset", MASK_ANY)
    fmu_instance_reset(inst);
    return fmi2OK;
}

/* ----- values ------------------------------------------------------------------------------- */

#define REAL_TYPES FMU_TYPE_BIT(FMU_REAL)
#define INTEGER_TYPES (FMU_TYPE_BIT(FMU_INTEGER) | FMU_TYPE_BIT(FMU_ENUMERATION))
#define BOOLEAN_TYPES FMU_TYPE_BIT(FMU_BOOLEAN)
#define BATCH 64  /* values converted per chunk, so that no call allocates */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    INSTANCE(c, "fmi2GetReal", MASK_GET)
    return (fmi2Status)fmu_get(inst, "fmi2GetReal", vr, nvr, REAL_TYPES, value);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    INSTANCE(c, "fmi2SetReal", MASK_SET)
    return (fmi2Status)fmu_set(inst, "fmi2SetReal", vr, nvr, REAL_TYPES, value);
}

/* Integer and Boolean values go through the double value table in chunks. */
#define GET_CONVERTED(call, types, T, convert)                                                \
    size_t i, k;                                                                              \
    double buf[BATCH];                                                                        \
    INSTANCE(c, call, MASK_GET)                                                               \
    if (nvr > 0 && (!vr || !value)) {                                                         \
        fmu_log(inst, FMU_ERROR, "%s: NULL value references or values", call);                \
        return fmi2Error;                                                                     \
    }                                                                                         \
    for (i = 0; i < nvr; i += BATCH) {                                                        \
        size_t n = nvr - i < BATCH ? nvr - i : BATCH;                                         \
        if (fmu_get(inst, call, vr + i, n, types, buf) != FMU_OK) {                           \
            return fmi2Error;                                                                 \
        }                                                                                     \
        for (k = 0; k < n; k++) {                                                             \
            value[i + k] = (T)convert(buf[k]);                                                \
        }                                                                                     \
    }                                                                                         \
    return fmi2OK;

#define SET_CONVERTED(call, types)                                                            \
    size_t i, k;                                                                              \
    double buf[BATCH];                                                                        \
    INSTANCE(c, call, MASK_SET)                                                               \
    if (nvr > 0 && (!vr || !value)) {                                                         \
        fmu_log(inst, FMU_ERROR, "%s: NULL value references or values", call);                \
        return fmi2Error;                                                                     \
    }                                                                                         \
    for (i = 0; i < nvr; i += BATCH) {                                                        \
        size_t n = nvr - i < BATCH ? nvr - i : BATCH;                                         \
        for (k = 0; k < n; k++) {                                                             \
            buf[k] = (double)value[i + k];                                                    \
        }                                                                                     \
        if (fmu_set(inst, call, vr + i, n, types, buf) != FMU_OK) {                           \
            return fmi2Error;                                                                 \
        }                                                                                     \
    }                                                                                         \
    return fmi2OK;

#define AS_INTEGER(x) (x)
#define AS_BOOLEAN(x) ((x) != 0.0 ? fmi2True : fmi2False)

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    GET_CONVERTED("fmi2GetInteger", INTEGER_TYPES, fmi2Integer, AS_INTEGER)
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    GET_CONVERTED("fmi2GetBoolean", BOOLEAN_TYPES, fmi2Boolean, AS_BOOLEAN)
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    SET_CONVERTED("fmi2SetInteger", INTEGER_TYPES)
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    SET_CONVERTED("fmi2SetBoolean", BOOLEAN_TYPES)
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    INSTANCE(c, "fmi2GetString", MASK_GET)
    (void)value;
    return (fmi2Status)fmu_no_variables(inst, "fmi2GetString", "String", vr, nvr);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    INSTANCE(c, "fmi2SetString", MASK_SET)
    (void)value;
    return (fmi2Status)fmu_no_variables(inst, "fmi2SetString", "String", vr, nvr);
}

/* ----- FMU state (fmu_instance.c) ---------------------------------------------------------- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    INSTANCE(c, "fmi2GetFMUstate", MASK_ANY)
    return (fmi2Status)fmu_state_get(inst, "fmi2GetFMUstate", (void **)FMUstate);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    INSTANCE(c, "fmi2SetFMUstate", MASK_ANY)
    return (fmi2Status)fmu_state_read(inst, "fmi2SetFMUstate", FMUstate, fmu_state_size());
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    INSTANCE(c, "fmi2FreeFMUstate", MASK_ANY)
    fmu_state_free((void **)FMUstate);
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    INSTANCE(c, "fmi2SerializedFMUstateSize", MASK_ANY)
    (void)FMUstate;
    return (fmi2Status)fmu_state_size_of(inst, "fmi2SerializedFMUstateSize", size);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    INSTANCE(c, "fmi2SerializeFMUstate", MASK_ANY)
    return (fmi2Status)fmu_state_serialize(inst, "fmi2SerializeFMUstate", FMUstate,
                                           serializedState, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    INSTANCE(c, "fmi2DeSerializeFMUstate", MASK_ANY)
    return (fmi2Status)fmu_state_deserialize(inst, "fmi2DeSerializeFMUstate", serializedState,
                                             size, (void **)FMUstate);
}

/* ----- co-simulation ------------------------------------------------------------------------ */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    INSTANCE(c, "fmi2DoStep", FMU_STEP)
    (void)noSetFMUStatePriorToCurrentPoint;
    return (fmi2Status)fmu_do_step(inst, currentCommunicationPoint, communicationStepSize);
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    INSTANCE(c, "fmi2CancelStep", FMU_STEP)
    fmu_log(inst, FMU_ERROR, "fmi2CancelStep: doStep never returns fmi2Pending here");
    return fmi2Error;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    INSTANCE(c, "fmi2SetRealInputDerivatives", MASK_SET)
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    fmu_log(inst, FMU_ERROR, "fmi2SetRealInputDerivatives: canInterpolateInputs is false");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[])
{
    INSTANCE(c, "fmi2GetRealOutputDerivatives", MASK_GET)
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    fmu_log(inst, FMU_ERROR, "fmi2GetRealOutputDerivatives: maxOutputDerivativeOrder is 0");
    return fmi2Error;
}

static fmi2Status no_status(fmu_instance *inst, const char *call)
{
    fmu_log(inst, FMU_ERROR, "%s: doStep never returns fmi2Pending, so there is no asynchronous "
            "status to ask for", call);
    return fmi2Discard;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    INSTANCE(c, "fmi2GetStatus", FMU_STEP | FMU_TERMINATED)
    (void)s;
    (void)value;
    return no_status(inst, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    INSTANCE(c, "fmi2GetRealStatus", FMU_STEP | FMU_TERMINATED)
    if (s == fmi2LastSuccessfulTime && value) {
        *value = inst->time;
        return fmi2OK;
    }
    return no_status(inst, "fmi2GetRealStatus");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    INSTANCE(c, "fmi2GetIntegerStatus", FMU_STEP | FMU_TERMINATED)
    (void)s;
    (void)value;
    return no_status(inst, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    INSTANCE(c, "fmi2GetBooleanStatus", FMU_STEP | FMU_TERMINATED)
    if (s == fmi2Terminated && value) {
        *value = fmi2False;  /* the FMU never asks the master to stop */
        return fmi2OK;
    }
    return no_status(inst, "fmi2GetBooleanStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    INSTANCE(c, "fmi2GetStringStatus", FMU_STEP | FMU_TERMINATED)
    (void)s;
    (void)value;
    return no_status(inst, "fmi2GetStringStatus");
}

/* ----- not a model-exchange FMU, no directional derivatives -------------------------------- */

static fmi2Status not_provided(fmi2Component c, const char *call)
{
    fmu_instance *inst = (fmu_instance *)c;
    if (inst) {
        fmu_log(inst, FMU_ERROR, "%s: this is a co-simulation FMU without model exchange or "
                "directional derivatives", call);
    }
    return fmi2Error;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return not_provided(c, "fmi2GetDirectionalDerivative");
}

fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    return not_provided(c, "fmi2EnterEventMode");
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *fmi2eventInfo)
{
    (void)fmi2eventInfo;
    return not_provided(c, "fmi2NewDiscreteStates");
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    return not_provided(c, "fmi2EnterContinuousTimeMode");
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c,
                                       fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode,
                                       fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return not_provided(c, "fmi2CompletedIntegratorStep");
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    (void)time;
    return not_provided(c, "fmi2SetTime");
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    (void)x;
    (void)nx;
    return not_provided(c, "fmi2SetContinuousStates");
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    (void)derivatives;
    (void)nx;
    return not_provided(c, "fmi2GetDerivatives");
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    (void)eventIndicators;
    (void)ni;
    return not_provided(c, "fmi2GetEventIndicators");
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    (void)x;
    (void)nx;
    return not_provided(c, "fmi2GetContinuousStates");
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    (void)x_nominal;
    (void)nx;
    return not_provided(c, "fmi2GetNominalsOfContinuousStates");
}

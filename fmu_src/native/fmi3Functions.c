/* fmi3Functions.c: the FMI 3.0 co-simulation interface, written once for every model.
 *
 * The same rules as fmi2Functions.c: every call is checked against the FMI 3.0 state machine
 * (the states each function is allowed in, as in the standard and the Reference-FMUs' masks);
 * a call in the wrong state, an unknown value reference, a value of the wrong type or out of
 * range, a step size <= 0 or bytes that are not this FMU's state return fmi3Error with a log
 * line and leave the instance as it was. Variables are scalars with the pythonfmu FMUs' names
 * and value references: Real -> Float64, Integer -> Int32, Enumeration -> Int64 (as FMI 3.0
 * reads and writes enumerations), Boolean -> Boolean. Model exchange, scheduled execution,
 * event mode, clocks and derivatives are not provided: their functions return fmi3Error.
 */
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "fmu_model.h"

#define MASK_ANY FMU_ANY_STATE
#define MASK_GET (FMU_CONFIGURATION | FMU_INITIALIZATION | FMU_STEP | FMU_TERMINATED)
#define MASK_SET (FMU_INSTANTIATED | FMU_CONFIGURATION | FMU_INITIALIZATION | FMU_STEP | \
                  FMU_TERMINATED)

static void emit(const fmu_instance *inst, int status, const char *category, const char *message)
{
    fmi3LogMessageCallback log = (fmi3LogMessageCallback)inst->log_message;
    if (log) {
        log(inst->environment, (fmi3Status)status, category, message);
    }
}

#define INSTANCE(c, call, mask)                                                               \
    fmu_instance *inst = (fmu_instance *)(c);                                                 \
    if (!inst) {                                                                              \
        return fmi3Error;                                                                     \
    }                                                                                         \
    if (fmu_allow(inst, (mask), (call)) != FMU_OK) {                                          \
        return fmi3Error;                                                                     \
    }

const char *fmi3GetVersion(void)
{
    return fmi3Version;
}

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    INSTANCE(instance, "fmi3SetDebugLogging", MASK_ANY)
    (void)nCategories;
    (void)categories;
    inst->logging_on = loggingOn ? 1 : 0;
    return fmi3OK;
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    fmu_instance probe, *inst;
    (void)resourcePath;
    (void)visible;
    (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    memset(&probe, 0, sizeof probe);
    probe.name = (char *)(instanceName ? instanceName : "?");
    probe.emit = emit;
    probe.log_message = (void (*)(void))logMessage;
    probe.environment = instanceEnvironment;
    if (!instanceName || !instanceName[0]) {
        fmu_log(&probe, FMU_ERROR, "fmi3InstantiateCoSimulation: the instance name must not be "
                "empty");
        return NULL;
    }
    if (!instantiationToken || strcmp(instantiationToken, FMU_MODEL.token) != 0) {
        fmu_log(&probe, FMU_ERROR, "fmi3InstantiateCoSimulation: instantiationToken %s is not "
                "this FMU's (%s %s): was the modelDescription.xml of another FMU read?",
                instantiationToken ? instantiationToken : "NULL", FMU_MODEL.name,
                FMU_MODEL.token);
        return NULL;
    }
    if (eventModeUsed || nRequiredIntermediateVariables > 0) {
        fmu_log(&probe, FMU_ERROR, "fmi3InstantiateCoSimulation: %s has no event mode and no "
                "intermediate variables (hasEventMode and providesIntermediateUpdate are false)",
                FMU_MODEL.name);
        return NULL;
    }
    inst = fmu_instance_new(instanceName, emit, NULL, (void (*)(void))logMessage,
                            instanceEnvironment, loggingOn);
    if (inst) {
        inst->time_vr = (int)FMU_MODEL.n_variables;  /* `time`, after the model's variables */
    }
    return inst;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    if (logMessage) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateModelExchange: this is a co-simulation FMU only");
    }
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    if (logMessage) {
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: this is a co-simulation FMU only");
    }
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    fmu_instance_free((fmu_instance *)instance);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    INSTANCE(instance, "fmi3EnterInitializationMode", FMU_INSTANTIATED)
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    inst->time = startTime;
    fmu_instance_setup(inst);  /* the plant's outputs: its truth at startTime */
    inst->state = FMU_INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    INSTANCE(instance, "fmi3ExitInitializationMode", FMU_INITIALIZATION)
    return (fmi3Status)fmu_exit_initialization(inst);
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    INSTANCE(instance, "fmi3EnterConfigurationMode", FMU_INSTANTIATED)
    inst->state = FMU_CONFIGURATION;
    return fmi3OK;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    INSTANCE(instance, "fmi3ExitConfigurationMode", FMU_CONFIGURATION)
    inst->state = FMU_INSTANTIATED;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    INSTANCE(instance, "fmi3Terminate", FMU_STEP)
    inst->state = FMU_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    INSTANCE(instance, "fmi3Reset", MASK_ANY)
    fmu_instance_reset(inst);
    return fmi3OK;
}

/* ----- values ------------------------------------------------------------------------------- */

#define BATCH 64  /* values converted per chunk, so that no call allocates */

static int counts_match(fmu_instance *inst, const char *call, size_t nvr, size_t nValues,
                        const void *vr, const void *values)
{
    if (nvr != nValues) {
        fmu_log(inst, FMU_ERROR, "%s: %lu values for %lu value references: every variable is a "
                "scalar", call, (unsigned long)nValues, (unsigned long)nvr);
        return 0;
    }
    if (nvr > 0 && (!vr || !values)) {
        fmu_log(inst, FMU_ERROR, "%s: NULL value references or values", call);
        return 0;
    }
    return 1;
}

#define GETTER(Name, T, types)                                                                \
    fmi3Status fmi3Get##Name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                             T values[], size_t nValues)                                      \
    {                                                                                         \
        size_t i, k;                                                                          \
        double buf[BATCH];                                                                    \
        INSTANCE(instance, "fmi3Get" #Name, MASK_GET)                                         \
        if (!counts_match(inst, "fmi3Get" #Name, nvr, nValues, vr, values)) {                 \
            return fmi3Error;                                                                 \
        }                                                                                     \
        for (i = 0; i < nvr; i += BATCH) {                                                    \
            size_t n = nvr - i < BATCH ? nvr - i : BATCH;                                     \
            if (fmu_get(inst, "fmi3Get" #Name, vr + i, n, (types), buf) != FMU_OK) {          \
                return fmi3Error;                                                             \
            }                                                                                 \
            for (k = 0; k < n; k++) {                                                         \
                values[i + k] = (T)buf[k];                                                    \
            }                                                                                 \
        }                                                                                     \
        return fmi3OK;                                                                        \
    }

#define SETTER(Name, T, types)                                                                \
    fmi3Status fmi3Set##Name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, \
                             const T values[], size_t nValues)                                \
    {                                                                                         \
        size_t i, k;                                                                          \
        double buf[BATCH];                                                                    \
        INSTANCE(instance, "fmi3Set" #Name, MASK_SET)                                         \
        if (!counts_match(inst, "fmi3Set" #Name, nvr, nValues, vr, values)) {                 \
            return fmi3Error;                                                                 \
        }                                                                                     \
        for (i = 0; i < nvr; i += BATCH) {                                                    \
            size_t n = nvr - i < BATCH ? nvr - i : BATCH;                                     \
            for (k = 0; k < n; k++) {                                                         \
                buf[k] = (double)values[i + k];                                               \
            }                                                                                 \
            if (fmu_set(inst, "fmi3Set" #Name, vr + i, n, (types), buf) != FMU_OK) {          \
                return fmi3Error;                                                             \
            }                                                                                 \
        }                                                                                     \
        return fmi3OK;                                                                        \
    }

/* A type this FMU has no variables of: any value reference is unknown to it. */
#define NO_VARIABLES(Kind, Name, T, qualifier)                                                \
    fmi3Status fmi3##Kind##Name(fmi3Instance instance, const fmi3ValueReference vr[],         \
                                size_t nvr, qualifier T values[], size_t nValues)             \
    {                                                                                         \
        INSTANCE(instance, "fmi3" #Kind #Name, Kind##_MASK)                                   \
        (void)values;                                                                         \
        (void)nValues;                                                                        \
        return (fmi3Status)fmu_no_variables(inst, "fmi3" #Kind #Name, #Name, vr, nvr);       \
    }
#define Get_MASK MASK_GET
#define Set_MASK MASK_SET

GETTER(Float64, fmi3Float64, FMU_TYPE_BIT(FMU_REAL))
SETTER(Float64, fmi3Float64, FMU_TYPE_BIT(FMU_REAL))
GETTER(Int32, fmi3Int32, FMU_TYPE_BIT(FMU_INTEGER))
SETTER(Int32, fmi3Int32, FMU_TYPE_BIT(FMU_INTEGER))
GETTER(Int64, fmi3Int64, FMU_TYPE_BIT(FMU_ENUMERATION))
SETTER(Int64, fmi3Int64, FMU_TYPE_BIT(FMU_ENUMERATION))
GETTER(Boolean, fmi3Boolean, FMU_TYPE_BIT(FMU_BOOLEAN))
SETTER(Boolean, fmi3Boolean, FMU_TYPE_BIT(FMU_BOOLEAN))

NO_VARIABLES(Get, Float32, fmi3Float32, )
NO_VARIABLES(Set, Float32, fmi3Float32, const)
NO_VARIABLES(Get, Int8, fmi3Int8, )
NO_VARIABLES(Set, Int8, fmi3Int8, const)
NO_VARIABLES(Get, UInt8, fmi3UInt8, )
NO_VARIABLES(Set, UInt8, fmi3UInt8, const)
NO_VARIABLES(Get, Int16, fmi3Int16, )
NO_VARIABLES(Set, Int16, fmi3Int16, const)
NO_VARIABLES(Get, UInt16, fmi3UInt16, )
NO_VARIABLES(Set, UInt16, fmi3UInt16, const)
NO_VARIABLES(Get, UInt32, fmi3UInt32, )
NO_VARIABLES(Set, UInt32, fmi3UInt32, const)
NO_VARIABLES(Get, UInt64, fmi3UInt64, )
NO_VARIABLES(Set, UInt64, fmi3UInt64, const)
NO_VARIABLES(Get, String, fmi3String, )
NO_VARIABLES(Set, String, fmi3String, const)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    INSTANCE(instance, "fmi3GetBinary", MASK_GET)
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return (fmi3Status)fmu_no_variables(inst, "fmi3GetBinary", "Binary", vr, nvr);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues)
{
    INSTANCE(instance, "fmi3SetBinary", MASK_SET)
    (void)valueSizes;
    (void)values;
    (void)nValues;
    return (fmi3Status)fmu_no_variables(inst, "fmi3SetBinary", "Binary", vr, nvr);
}

/* ----- FMU state (fmu_instance.c) ---------------------------------------------------------- */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    INSTANCE(instance, "fmi3GetFMUState", MASK_ANY)
    return (fmi3Status)fmu_state_get(inst, "fmi3GetFMUState", (void **)FMUState);
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    INSTANCE(instance, "fmi3SetFMUState", MASK_ANY)
    return (fmi3Status)fmu_state_read(inst, "fmi3SetFMUState", FMUState, fmu_state_size());
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    INSTANCE(instance, "fmi3FreeFMUState", MASK_ANY)
    fmu_state_free((void **)FMUState);
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    INSTANCE(instance, "fmi3SerializedFMUStateSize", MASK_ANY)
    (void)FMUState;
    return (fmi3Status)fmu_state_size_of(inst, "fmi3SerializedFMUStateSize", size);
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size)
{
    INSTANCE(instance, "fmi3SerializeFMUState", MASK_ANY)
    return (fmi3Status)fmu_state_serialize(inst, "fmi3SerializeFMUState", FMUState,
                                           serializedState, size);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance,
                                   const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState)
{
    INSTANCE(instance, "fmi3DeserializeFMUState", MASK_ANY)
    return (fmi3Status)fmu_state_deserialize(inst, "fmi3DeserializeFMUState", serializedState,
                                             size, (void **)FMUState);
}

/* ----- co-simulation ------------------------------------------------------------------------ */

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    int status;
    INSTANCE(instance, "fmi3DoStep", FMU_STEP)
    (void)noSetFMUStatePriorToCurrentPoint;
    status = fmu_do_step(inst, currentCommunicationPoint, communicationStepSize);
    if (eventHandlingNeeded) {
        *eventHandlingNeeded = fmi3False;
    }
    if (terminateSimulation) {
        *terminateSimulation = fmi3False;
    }
    if (earlyReturn) {
        *earlyReturn = fmi3False;
    }
    if (lastSuccessfulTime) {
        *lastSuccessfulTime = inst->time;
    }
    return (fmi3Status)status;
}

/* ----- what these FMUs do not provide -------------------------------------------------------- */

static fmi3Status not_provided(fmi3Instance instance, const char *call)
{
    fmu_instance *inst = (fmu_instance *)instance;
    if (inst) {
        fmu_log(inst, FMU_ERROR, "%s: this co-simulation FMU has no event mode, clocks, model "
                "exchange, dependencies or derivatives", call);
    }
    return fmi3Error;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EnterEventMode");
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EnterStepMode");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[])
{
    (void)vr;
    (void)nvr;
    (void)values;
    return not_provided(instance, "fmi3GetClock");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[])
{
    (void)vr;
    (void)nvr;
    (void)values;
    return not_provided(instance, "fmi3SetClock");
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr,
                                               size_t *nDependencies)
{
    (void)vr;
    (void)nDependencies;
    return not_provided(instance, "fmi3GetNumberOfVariableDependencies");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    (void)dependent;
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    (void)nDependencies;
    return not_provided(instance, "fmi3GetVariableDependencies");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return not_provided(instance, "fmi3GetDirectionalDerivative");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return not_provided(instance, "fmi3GetAdjointDerivative");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
                                  size_t nvr, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[])
{
    (void)vr;
    (void)nvr;
    (void)intervals;
    (void)qualifiers;
    return not_provided(instance, "fmi3GetIntervalDecimal");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return not_provided(instance, "fmi3GetIntervalFraction");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               fmi3Float64 shifts[])
{
    (void)vr;
    (void)nvr;
    (void)shifts;
    return not_provided(instance, "fmi3GetShiftDecimal");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    return not_provided(instance, "fmi3GetShiftFraction");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
                                  size_t nvr, const fmi3Float64 intervals[])
{
    (void)vr;
    (void)nvr;
    (void)intervals;
    return not_provided(instance, "fmi3SetIntervalDecimal");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t nvr, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    return not_provided(instance, "fmi3SetIntervalFraction");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[])
{
    (void)vr;
    (void)nvr;
    (void)shifts;
    return not_provided(instance, "fmi3SetShiftDecimal");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr;
    (void)nvr;
    (void)counters;
    (void)resolutions;
    return not_provided(instance, "fmi3SetShiftFraction");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EvaluateDiscreteStates");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    (void)discreteStatesNeedUpdate;
    (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined;
    (void)nextEventTime;
    return not_provided(instance, "fmi3UpdateDiscreteStates");
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return not_provided(instance, "fmi3EnterContinuousTimeMode");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return not_provided(instance, "fmi3CompletedIntegratorStep");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    return not_provided(instance, "fmi3SetTime");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates;
    (void)nContinuousStates;
    return not_provided(instance, "fmi3SetContinuousStates");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    (void)derivatives;
    (void)nContinuousStates;
    return not_provided(instance, "fmi3GetContinuousStateDerivatives");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators)
{
    (void)eventIndicators;
    (void)nEventIndicators;
    return not_provided(instance, "fmi3GetEventIndicators");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates;
    (void)nContinuousStates;
    return not_provided(instance, "fmi3GetContinuousStates");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    (void)nominals;
    (void)nContinuousStates;
    return not_provided(instance, "fmi3GetNominalsOfContinuousStates");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators)
{
    (void)nEventIndicators;
    return not_provided(instance, "fmi3GetNumberOfEventIndicators");
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates)
{
    (void)nContinuousStates;
    return not_provided(instance, "fmi3GetNumberOfContinuousStates");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues)
{
    (void)vr;
    (void)nvr;
    (void)orders;
    (void)values;
    (void)nValues;
    return not_provided(instance, "fmi3GetOutputDerivatives");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference;
    (void)activationTime;
    return not_provided(instance, "fmi3ActivateModelPartition");
}

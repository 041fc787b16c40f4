/*
 * FMI 3.0 interface of the native wheelterrain FMUs: model exchange and co-simulation.
 *
 * The FMI 3 functions are a thin layer over the FMI 2 wrapper (fmi2_native.c, included here
 * with its fmi2 functions kept internal): one state machine, one set of value checks, the same
 * CasADi-generated model and hooks, so both standards give the same numbers. What FMI 3
 * changes is mapped here: the instantiation token (the model's GUID), the log callback (no
 * format string), typed getters and setters (Float64 for the Reals, Int32 for counts and
 * mode switches, Int64 too, Boolean), the independent variable `time` (value reference
 * TIME_VR = N_VARS), the step mode of co-simulation and the event update of model exchange.
 * Clocks, scheduled execution, Float32, the unsigned and 8/16-bit integers, String and
 * Binary are not used by the model: those calls return fmi3Error with a logged reason.
 */
#define WHEELTERRAIN_FMI2_INTERNAL /* fmi2_native.c: types only, its functions not exported */
#include "fmi2_native.inc"          /* fmi2_native.c, as the FMU's sources/ ship it */

#include <ctype.h>

#include "fmi3Functions.h"

#define TIME_VR N_VARS /* the independent variable of the FMI 3 modelDescription */

typedef struct {
    fmi2Component inner; /* the FMI 2 instance (Instance *) doing the work */
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log;
    fmi2Type type; /* model exchange or co-simulation: which fmi3Instantiate* the user called */
} Instance3;

#define INNER(instance) (((Instance3 *)(instance))->inner)
#define CORE(instance) ((Instance *)INNER(instance))

/* What the FMI 2 layer's messages name, as FMI 3 names it: the functions whose FMI 3
   counterpart is not the same name with fmi3 for fmi2, and the GUID. Any other fmi2 name
   becomes its fmi3 twin (fmi2DoStep -> fmi3DoStep). */
static const char *const RENAMED[][2] = {
    {"fmi2GetReal", "fmi3GetFloat64"},
    {"fmi2SetReal", "fmi3SetFloat64"},
    {"fmi2GetInteger", "fmi3GetInt32"}, /* the only integer type (no Int64 variables) */
    {"fmi2SetInteger", "fmi3SetInt32"},
    {"fmi2GetDerivatives", "fmi3GetContinuousStateDerivatives"},
    {"fmi2SetupExperiment", "fmi3EnterInitializationMode"},
    {"fmi2GetFMUstate", "fmi3GetFMUState"},
    {"fmi2SetFMUstate", "fmi3SetFMUState"},
    {"fmi2FreeFMUstate", "fmi3FreeFMUState"},
    {"fmi2SerializeFMUstate", "fmi3SerializeFMUState"},
    {"fmi2DeSerializeFMUstate", "fmi3DeserializeFMUState"},
    {"fmi2SerializedFMUstateSize", "fmi3SerializedFMUStateSize"},
    {"fmi2NewDiscreteStates", "fmi3UpdateDiscreteStates"},
    {"fmi2GetRealOutputDerivatives", "fmi3GetOutputDerivatives"},
    {"GUID", "instantiation token"},
};

/* Append ``text`` to ``out`` (capacity ``size``, ``*j`` used). */
static void append(char *out, size_t size, size_t *j, const char *text) {
    while (*text != '\0' && *j + 1 < size) out[(*j)++] = *text++;
}

/* The FMI 2 layer logs a format string (its '%' doubled) in FMI 2's words; FMI 3 logs plain
   text in its own. */
static void forward_log(fmi2ComponentEnvironment environment, fmi2String name, fmi2Status status,
                        fmi2String category, fmi2String message, ...) {
    Instance3 *w = (Instance3 *)environment;
    char plain[MAX_MESSAGE * 4];
    size_t j = 0, i = 0;
    (void)name;
    if (w == NULL || w->log == NULL) return;
    while (message[i] != '\0' && j + 1 < sizeof plain) {
        size_t word = 0, k;
        if (message[i] == '%' && message[i + 1] == '%') i++;
        if (strncmp(message + i, "fmi2", 4) == 0 || strncmp(message + i, "GUID", 4) == 0) {
            while (isalnum((unsigned char)message[i + word])) word++;
        }
        if (word == 0) {
            plain[j++] = message[i++];
            continue;
        }
        for (k = 0; k < sizeof RENAMED / sizeof RENAMED[0]; k++) {
            if (strlen(RENAMED[k][0]) == word && strncmp(message + i, RENAMED[k][0], word) == 0)
                break;
        }
        if (strncmp(message + i, "fmi2Instantiate", word) == 0 && word == 15) {
            append(plain, sizeof plain, &j, w->type == fmi2ModelExchange
                                                ? "fmi3InstantiateModelExchange"
                                                : "fmi3InstantiateCoSimulation");
        } else if (k < sizeof RENAMED / sizeof RENAMED[0]) {
            append(plain, sizeof plain, &j, RENAMED[k][1]);
        } else if (message[i] == 'f') { /* fmi2X -> fmi3X */
            append(plain, sizeof plain, &j, "fmi3");
            for (k = 4; k < word && j + 1 < sizeof plain; k++) plain[j++] = message[i + k];
        } else { /* a word that only starts like GUID: as it is */
            for (k = 0; k < word && j + 1 < sizeof plain; k++) plain[j++] = message[i + k];
        }
        i += word;
    }
    plain[j] = '\0';
    w->log(w->environment, (fmi3Status)status, category, plain);
}

static void log3(fmi3Instance instance, const char *fmt, const char *function) {
    if (instance != NULL) LOG_ERROR(CORE(instance), fmt, function, MODEL_NAME);
}

static fmi3Instance instantiate(fmi3String name, fmi3String token, fmi3Boolean loggingOn,
                                fmi3InstanceEnvironment environment, fmi3LogMessageCallback log,
                                fmi2Type type) {
    Instance3 *w = (Instance3 *)calloc(1, sizeof(Instance3));
    fmi2CallbackFunctions callbacks = {forward_log, calloc, free, NULL, NULL};
    if (w == NULL) return NULL;
    w->environment = environment;
    w->log = log;
    w->type = type;
    callbacks.componentEnvironment = w;
    w->inner = fmi2Instantiate(name, type, token, "", &callbacks, fmi2False, loggingOn);
    if (w->inner == NULL) {
        free(w);
        return NULL;
    }
    return w;
}

/* ---- common functions ------------------------------------------------------------------- */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2SetDebugLogging(INNER(instance), loggingOn, nCategories, categories);
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)resourcePath, (void)visible;
    return instantiate(instanceName, instantiationToken, loggingOn, instanceEnvironment,
                       logMessage, fmi2ModelExchange);
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)resourcePath, (void)visible, (void)eventModeUsed, (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables, (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate; /* no events, no early return: steps are taken whole */
    return instantiate(instanceName, instantiationToken, loggingOn, instanceEnvironment,
                       logMessage, fmi2CoSimulation);
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible;
    (void)loggingOn, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    if (logMessage != NULL)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   MODEL_NAME " has no scheduled-execution interface");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    if (instance == NULL) return;
    fmi2FreeInstance(INNER(instance));
    free(instance);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    fmi2Status status;
    if (instance == NULL) return fmi3Error;
    status = fmi2SetupExperiment(INNER(instance), toleranceDefined, tolerance, startTime,
                                 stopTimeDefined, stopTime);
    if (status != fmi2OK) return (fmi3Status)status;
    return (fmi3Status)fmi2EnterInitializationMode(INNER(instance));
}

/* calls that take only the instance and mean the same in FMI 2 */
#define FORWARD(NAME3, NAME2)                                                              \
    fmi3Status NAME3(fmi3Instance instance) {                                                \
        if (instance == NULL) return fmi3Error;                                               \
        return (fmi3Status)NAME2(INNER(instance));                                            \
    }
FORWARD(fmi3ExitInitializationMode, fmi2ExitInitializationMode)

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    if (instance == NULL) return fmi3Error;
    if (!CORE(instance)->model_exchange) {
        LOG_ERROR(CORE(instance), "fmi3EnterEventMode: %s steps without events", MODEL_NAME);
        return fmi3Error;
    }
    return (fmi3Status)fmi2EnterEventMode(INNER(instance));
}

FORWARD(fmi3Terminate, fmi2Terminate)

FORWARD(fmi3Reset, fmi2Reset)

/* ---- get and set ------------------------------------------------------------------------ */

static int scalar_sizes(fmi3Instance instance, const char *function, size_t nvr, size_t nv) {
    if (nvr == nv) return 1;
    LOG_ERROR(CORE(instance), "%s: %zu values for %zu value references (%s has scalars only)",
              function, nv, nvr, MODEL_NAME);
    return 0;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues) {
    fmi3Status status = fmi3OK;
    if (instance == NULL) return fmi3Error;
    if (!scalar_sizes(instance, "fmi3GetFloat64", nvr, nValues)) return fmi3Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi3Status one;
        if (vr[i] == TIME_VR) {
            values[i] = CORE(instance)->b.time;
            continue;
        }
        one = (fmi3Status)fmi2GetReal(INNER(instance), &vr[i], 1, &values[i]);
        if (one > status) status = one;
        if (status > fmi3Warning) return status;
    }
    return status;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    if (instance == NULL) return fmi3Error;
    if (!scalar_sizes(instance, "fmi3SetFloat64", nvr, nValues)) return fmi3Error;
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == TIME_VR) {
            LOG_ERROR(CORE(instance), "fmi3SetFloat64: time is the independent variable and "
                      "cannot be set");
            return fmi3Error;
        }
    }
    return (fmi3Status)fmi2SetReal(INNER(instance), vr, nvr, values);
}

/* Int32 (counts, mode switches) is the FMI 2 layer's Integer. The description has no Int64 or
   Enumeration variable (build_fmi3 refuses to write one this file cannot serve), so
   fmi3Get/SetInt64 have no variable to serve: refused below as the other absent types. */
#define INTEGER_GET(NAME, TYPE)                                                              \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,         \
                    TYPE values[], size_t nValues) {                                          \
        if (instance == NULL) return fmi3Error;                                               \
        if (!scalar_sizes(instance, #NAME, nvr, nValues)) return fmi3Error;                   \
        for (size_t i = 0; i < nvr; i++) {                                                    \
            fmi2Integer value;                                                                \
            fmi2Status status = fmi2GetInteger(INNER(instance), &vr[i], 1, &value);           \
            if (status != fmi2OK) return (fmi3Status)status;                                  \
            values[i] = (TYPE)value;                                                          \
        }                                                                                     \
        return fmi3OK;                                                                        \
    }
#define INTEGER_SET(NAME, TYPE)                                                              \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,         \
                    const TYPE values[], size_t nValues) {                                    \
        fmi3Status status = fmi3OK;                                                           \
        if (instance == NULL) return fmi3Error;                                               \
        if (!scalar_sizes(instance, #NAME, nvr, nValues)) return fmi3Error;                   \
        for (size_t i = 0; i < nvr; i++) {                                                    \
            fmi2Integer value = (fmi2Integer)values[i];                                       \
            if ((TYPE)value != values[i]) {                                                   \
                LOG_ERROR(CORE(instance), "%s: value reference %u: %lld is out of range",     \
                          #NAME, vr[i], (long long)values[i]);                                \
                status = fmi3Error;                                                           \
                continue;                                                                     \
            }                                                                                 \
            if (fmi2SetInteger(INNER(instance), &vr[i], 1, &value) != fmi2OK)                 \
                status = fmi3Error;                                                           \
        }                                                                                     \
        return status;                                                                        \
    }
INTEGER_GET(fmi3GetInt32, fmi3Int32)
INTEGER_SET(fmi3SetInt32, fmi3Int32)

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Boolean values[], size_t nValues) {
    if (instance == NULL) return fmi3Error;
    if (!scalar_sizes(instance, "fmi3GetBoolean", nvr, nValues)) return fmi3Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2Boolean value;
        fmi2Status status = fmi2GetBoolean(INNER(instance), &vr[i], 1, &value);
        if (status != fmi2OK) return (fmi3Status)status;
        values[i] = value != fmi2False;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues) {
    fmi3Status status = fmi3OK;
    if (instance == NULL) return fmi3Error;
    if (!scalar_sizes(instance, "fmi3SetBoolean", nvr, nValues)) return fmi3Error;
    for (size_t i = 0; i < nvr; i++) {
        fmi2Boolean value = values[i] ? fmi2True : fmi2False;
        if (fmi2SetBoolean(INNER(instance), &vr[i], 1, &value) != fmi2OK) status = fmi3Error;
    }
    return status;
}

/* The types the model has no variable of: refused with the reason. */
#define NO_SUCH_GET(NAME, TYPE)                                                              \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,         \
                    TYPE values[], size_t nValues) {                                          \
        (void)vr, (void)values, (void)nValues;                                                \
        if (nvr == 0) return fmi3OK;                                                          \
        log3(instance, "%s: %s has no variables of this type", #NAME);                        \
        return fmi3Error;                                                                     \
    }
#define NO_SUCH_SET(NAME, TYPE)                                                              \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,         \
                    const TYPE values[], size_t nValues) {                                    \
        (void)vr, (void)values, (void)nValues;                                                \
        if (nvr == 0) return fmi3OK;                                                          \
        log3(instance, "%s: %s has no variables of this type", #NAME);                        \
        return fmi3Error;                                                                     \
    }
NO_SUCH_GET(fmi3GetFloat32, fmi3Float32)
NO_SUCH_GET(fmi3GetInt8, fmi3Int8)
NO_SUCH_GET(fmi3GetUInt8, fmi3UInt8)
NO_SUCH_GET(fmi3GetInt16, fmi3Int16)
NO_SUCH_GET(fmi3GetUInt16, fmi3UInt16)
NO_SUCH_GET(fmi3GetUInt32, fmi3UInt32)
NO_SUCH_GET(fmi3GetInt64, fmi3Int64)
NO_SUCH_GET(fmi3GetUInt64, fmi3UInt64)
NO_SUCH_GET(fmi3GetString, fmi3String)
NO_SUCH_SET(fmi3SetFloat32, fmi3Float32)
NO_SUCH_SET(fmi3SetInt8, fmi3Int8)
NO_SUCH_SET(fmi3SetUInt8, fmi3UInt8)
NO_SUCH_SET(fmi3SetInt16, fmi3Int16)
NO_SUCH_SET(fmi3SetUInt16, fmi3UInt16)
NO_SUCH_SET(fmi3SetUInt32, fmi3UInt32)
NO_SUCH_SET(fmi3SetInt64, fmi3Int64)
NO_SUCH_SET(fmi3SetUInt64, fmi3UInt64)
NO_SUCH_SET(fmi3SetString, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)vr, (void)valueSizes, (void)values, (void)nValues;
    if (nvr == 0) return fmi3OK;
    log3(instance, "%s: %s has no variables of this type", "fmi3GetBinary");
    return fmi3Error;
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)vr, (void)valueSizes, (void)values, (void)nValues;
    if (nvr == 0) return fmi3OK;
    log3(instance, "%s: %s has no variables of this type", "fmi3SetBinary");
    return fmi3Error;
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[]) {
    (void)vr, (void)values;
    if (nvr == 0) return fmi3OK;
    log3(instance, "%s: %s has no clocks", "fmi3GetClock");
    return fmi3Error;
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[]) {
    (void)vr, (void)values;
    if (nvr == 0) return fmi3OK;
    log3(instance, "%s: %s has no clocks", "fmi3SetClock");
    return fmi3Error;
}

/* ---- dependencies, FMU state, derivatives ----------------------------------------------- */

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference, (void)nDependencies;
    log3(instance, "%s: %s declares its dependencies in the modelDescription only",
         "fmi3GetNumberOfVariableDependencies");
    return fmi3Error;
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)dependent, (void)elementIndicesOfDependent, (void)independents;
    (void)elementIndicesOfIndependents, (void)dependencyKinds, (void)nDependencies;
    log3(instance, "%s: %s declares its dependencies in the modelDescription only",
         "fmi3GetVariableDependencies");
    return fmi3Error;
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2GetFMUstate(INNER(instance), FMUState);
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2SetFMUstate(INNER(instance), FMUState);
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2FreeFMUstate(INNER(instance), FMUState);
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState,
                                      size_t *size) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2SerializedFMUstateSize(INNER(instance), FMUState, size);
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2SerializeFMUstate(INNER(instance), FMUState,
                                             (fmi2Byte *)serializedState, size);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2DeSerializeFMUstate(INNER(instance), (const fmi2Byte *)serializedState,
                                               size, FMUState);
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    log3(instance, "%s: not provided by %s (use the CasADi Jacobian Functions of wheelterrain)",
         "fmi3GetDirectionalDerivative");
    return fmi3Error;
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    log3(instance, "%s: not provided by %s (use the CasADi Jacobian Functions of wheelterrain)",
         "fmi3GetAdjointDerivative");
    return fmi3Error;
}

/* ---- configuration mode and clocks: not used by the model ---------------------------------- */

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    log3(instance, "%s: %s has no structural parameters", "fmi3EnterConfigurationMode");
    return fmi3Error;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    log3(instance, "%s: %s has no structural parameters", "fmi3ExitConfigurationMode");
    return fmi3Error;
}

#define NO_CLOCK(NAME, ...)                                                                  \
    fmi3Status NAME(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,         \
                    __VA_ARGS__) {                                                            \
        (void)vr, (void)nvr;                                                                  \
        log3(instance, "%s: %s has no clocks", #NAME);                                        \
        return fmi3Error;                                                                     \
    }
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wunused-parameter"
NO_CLOCK(fmi3GetIntervalDecimal, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
NO_CLOCK(fmi3GetIntervalFraction, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
         fmi3IntervalQualifier qualifiers[])
NO_CLOCK(fmi3GetShiftDecimal, fmi3Float64 shifts[])
NO_CLOCK(fmi3GetShiftFraction, fmi3UInt64 counters[], fmi3UInt64 resolutions[])
NO_CLOCK(fmi3SetIntervalDecimal, const fmi3Float64 intervals[])
NO_CLOCK(fmi3SetIntervalFraction, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
NO_CLOCK(fmi3SetShiftDecimal, const fmi3Float64 shifts[])
NO_CLOCK(fmi3SetShiftFraction, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
#pragma GCC diagnostic pop

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    if (instance == NULL) return fmi3Error;
    return fmi3OK; /* no discrete states */
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    fmi2EventInfo info;
    fmi2Status status;
    if (instance == NULL) return fmi3Error;
    if (!CORE(instance)->model_exchange) { /* co-simulation without events: nothing to do */
        info.newDiscreteStatesNeeded = info.terminateSimulation = fmi2False;
        info.nominalsOfContinuousStatesChanged = info.valuesOfContinuousStatesChanged = fmi2False;
        info.nextEventTimeDefined = fmi2False;
        info.nextEventTime = 0.0;
        status = fmi2OK;
    } else {
        status = fmi2NewDiscreteStates(INNER(instance), &info);
    }
    *discreteStatesNeedUpdate = info.newDiscreteStatesNeeded != fmi2False;
    *terminateSimulation = info.terminateSimulation != fmi2False;
    *nominalsOfContinuousStatesChanged = info.nominalsOfContinuousStatesChanged != fmi2False;
    *valuesOfContinuousStatesChanged = info.valuesOfContinuousStatesChanged != fmi2False;
    *nextEventTimeDefined = info.nextEventTimeDefined != fmi2False;
    *nextEventTime = info.nextEventTime;
    return (fmi3Status)status;
}

/* ---- model exchange ------------------------------------------------------------------------ */

FORWARD(fmi3EnterContinuousTimeMode, fmi2EnterContinuousTimeMode)

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation) {
    fmi2Boolean event = fmi2False, stop = fmi2False;
    fmi2Status status;
    if (instance == NULL) return fmi3Error;
    status = fmi2CompletedIntegratorStep(INNER(instance), noSetFMUStatePriorToCurrentPoint,
                                         &event, &stop);
    *enterEventMode = event != fmi2False;
    *terminateSimulation = stop != fmi2False;
    return (fmi3Status)status;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2SetTime(INNER(instance), time);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2SetContinuousStates(INNER(instance), continuousStates,
                                               nContinuousStates);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2GetDerivatives(INNER(instance), derivatives, nContinuousStates);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2GetEventIndicators(INNER(instance), eventIndicators,
                                              nEventIndicators);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2GetContinuousStates(INNER(instance), continuousStates,
                                               nContinuousStates);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    if (instance == NULL) return fmi3Error;
    return (fmi3Status)fmi2GetNominalsOfContinuousStates(INNER(instance), nominals,
                                                         nContinuousStates);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    if (instance == NULL) return fmi3Error;
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    if (instance == NULL) return fmi3Error;
    *nContinuousStates = N_CONTINUOUS;
    return fmi3OK;
}

/* ---- co-simulation ---------------------------------------------------------------------- */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    if (instance == NULL) return fmi3Error;
    if (CORE(instance)->b.mode != S_STEP_COMPLETE) {
        LOG_ERROR(CORE(instance), "fmi3EnterStepMode: illegal call sequence (the instance is "
                  "in %s)", mode_name(CORE(instance)->b.mode));
        return fmi3Error;
    }
    return fmi3OK; /* without event mode the instance is in step mode after initialisation */
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    (void)vr, (void)nvr, (void)orders, (void)values, (void)nValues;
    log3(instance, "%s: not provided by %s", "fmi3GetOutputDerivatives");
    return fmi3Error;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    fmi2Status status;
    if (instance == NULL) return fmi3Error;
    status = fmi2DoStep(INNER(instance), currentCommunicationPoint, communicationStepSize,
                        noSetFMUStatePriorToCurrentPoint);
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = CORE(instance)->b.terminated ? fmi3True : fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = CORE(instance)->b.time;
    return (fmi3Status)status;
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference, (void)activationTime;
    log3(instance, "%s: %s has no scheduled-execution interface", "fmi3ActivateModelPartition");
    return fmi3Error;
}

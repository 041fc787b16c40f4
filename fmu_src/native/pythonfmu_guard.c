/*
 * The guard in front of a pythonfmu FMU's Linux library (wheelterrain build, pythonfmu flavour).
 *
 * pythonfmu 0.7's library (shipped beside this one as <model>_pythonfmu.so) cannot see the
 * GUID, keeps no call sequence, decodes only %20 in the resource URI (a non-ASCII unzip path
 * crashed the host), answers an unknown value reference with OK, and deserialises any bytes as
 * its state. Its Python API allows no fix (fmu_src/README.md). This library is the FMU's
 * binary instead: it checks what pythonfmu cannot and forwards every call to pythonfmu's
 * library, which does the work:
 *   - fmi2Instantiate: co-simulation only, the GUID, a file: resource URI decoded whole
 *     (every %XX) before pythonfmu sees it;
 *   - the FMI 2 co-simulation call sequence (fmi2Error and a logged reason when violated);
 *   - value references: each must name a variable of the called type; outputs cannot be set;
 *   - Real and Integer values against the declared ranges (fmi2Error, as the native flavour);
 *     a value refused at set time makes fmi2ExitInitializationMode refuse too;
 *   - serialized FMU states carry this model's GUID; another model's are refused.
 * Compiled with the generated guard_vars.h (GUARD_NAME, GUARD_GUID, GUARD_VARS: the same
 * variable table as the modelDescription).
 */
#define _GNU_SOURCE /* dladdr */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

typedef enum { G_REAL, G_INTEGER, G_BOOLEAN } GuardType;
typedef enum { G_PARAMETER, G_INPUT, G_OUTPUT } GuardCausality;

typedef struct {
    const char *name;
    GuardType type;
    GuardCausality causality;
    int has_range;
    double min, max;
    const char *unit;
} GuardVar;

#include "guard_vars.h" /* GUARD_NAME, GUARD_GUID, GUARD_N_VARS, GUARD_VARS */

enum {
    M_INSTANTIATED = 1,
    M_INITIALIZATION = 2,
    M_STEP_COMPLETE = 4,
    M_TERMINATED = 8,
};
#define M_ANY (M_INSTANTIATED | M_INITIALIZATION | M_STEP_COMPLETE | M_TERMINATED)
#define M_SETTABLE (M_INSTANTIATED | M_INITIALIZATION | M_STEP_COMPLETE)
#define M_GETTABLE (M_INITIALIZATION | M_STEP_COMPLETE | M_TERMINATED)

#define STATE_TAG "wheelterrain pythonfmu state "
#define STATE_HEADER 128 /* the tag and the GUID, zero-padded */

typedef struct {
    fmi2Component real;
    int mode;
    fmi2CallbackFunctions cb;
    char name[128];
    unsigned char invalid[GUARD_N_VARS];
    double refused[GUARD_N_VARS]; /* the refused value, for the message */
} Guard;

/* ---- pythonfmu's library -------------------------------------------------------------- */

static struct {
    void *handle;
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetDebugLoggingTYPE *set_debug_logging;
    fmi2SetupExperimentTYPE *setup_experiment;
    fmi2EnterInitializationModeTYPE *enter_initialization;
    fmi2ExitInitializationModeTYPE *exit_initialization;
    fmi2TerminateTYPE *terminate;
    fmi2ResetTYPE *reset;
    fmi2GetRealTYPE *get_real;
    fmi2GetIntegerTYPE *get_integer;
    fmi2GetBooleanTYPE *get_boolean;
    fmi2SetRealTYPE *set_real;
    fmi2SetIntegerTYPE *set_integer;
    fmi2SetBooleanTYPE *set_boolean;
    fmi2GetFMUstateTYPE *get_state;
    fmi2SetFMUstateTYPE *set_state;
    fmi2FreeFMUstateTYPE *free_state;
    fmi2SerializedFMUstateSizeTYPE *state_size;
    fmi2SerializeFMUstateTYPE *serialize;
    fmi2DeSerializeFMUstateTYPE *deserialize;
    fmi2DoStepTYPE *do_step;
    fmi2GetStatusTYPE *get_status;
    fmi2GetRealStatusTYPE *get_real_status;
    fmi2GetIntegerStatusTYPE *get_integer_status;
    fmi2GetBooleanStatusTYPE *get_boolean_status;
    fmi2GetStringStatusTYPE *get_string_status;
} F;

/* Load pythonfmu's library from beside this one, once; NULL on success, else the reason. */
static const char *load_library(void) {
    static char reason[6144];
    Dl_info self;
    char path[4096];
    const char *slash;
    if (F.handle) return NULL;
    if (!dladdr((void *)&load_library, &self) || self.dli_fname == NULL) {
        return "cannot locate this library's folder";
    }
    slash = strrchr(self.dli_fname, '/');
    snprintf(path, sizeof path, "%.*s/%s_pythonfmu.so",
             slash ? (int)(slash - self.dli_fname) : 1, slash ? self.dli_fname : ".",
             GUARD_NAME);
    F.handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!F.handle) {
        snprintf(reason, sizeof reason, "cannot load pythonfmu's library %s: %s (a C host "
                 "needs libpython preloaded: fmu_src/README.md)", path, dlerror());
        return reason;
    }
#define LOAD(field, symbol)                                                                  \
    if (!(*(void **)&F.field = dlsym(F.handle, symbol))) {                                   \
        snprintf(reason, sizeof reason, "pythonfmu's library %s lacks %s", path, symbol);    \
        dlclose(F.handle);                                                                   \
        F.handle = NULL;                                                                     \
        return reason;                                                                       \
    }
    LOAD(instantiate, "fmi2Instantiate")
    LOAD(free_instance, "fmi2FreeInstance")
    LOAD(set_debug_logging, "fmi2SetDebugLogging")
    LOAD(setup_experiment, "fmi2SetupExperiment")
    LOAD(enter_initialization, "fmi2EnterInitializationMode")
    LOAD(exit_initialization, "fmi2ExitInitializationMode")
    LOAD(terminate, "fmi2Terminate")
    LOAD(reset, "fmi2Reset")
    LOAD(get_real, "fmi2GetReal")
    LOAD(get_integer, "fmi2GetInteger")
    LOAD(get_boolean, "fmi2GetBoolean")
    LOAD(set_real, "fmi2SetReal")
    LOAD(set_integer, "fmi2SetInteger")
    LOAD(set_boolean, "fmi2SetBoolean")
    LOAD(get_state, "fmi2GetFMUstate")
    LOAD(set_state, "fmi2SetFMUstate")
    LOAD(free_state, "fmi2FreeFMUstate")
    LOAD(state_size, "fmi2SerializedFMUstateSize")
    LOAD(serialize, "fmi2SerializeFMUstate")
    LOAD(deserialize, "fmi2DeSerializeFMUstate")
    LOAD(do_step, "fmi2DoStep")
    LOAD(get_status, "fmi2GetStatus")
    LOAD(get_real_status, "fmi2GetRealStatus")
    LOAD(get_integer_status, "fmi2GetIntegerStatus")
    LOAD(get_boolean_status, "fmi2GetBooleanStatus")
    LOAD(get_string_status, "fmi2GetStringStatus")
#undef LOAD
    return NULL;
}

/* ---- logging ------------------------------------------------------------------------- */

/* An error through the host's logger (always: errors reach the host whatever the logging
   flag), the text's '%' doubled (the logger's message is a format string). */
static void log_error(const fmi2CallbackFunctions *cb, const char *name, const char *fmt, ...) {
    char text[1024], escaped[2048];
    size_t j = 0;
    va_list ap;
    if (cb == NULL || cb->logger == NULL) return;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    for (size_t i = 0; text[i] != '\0' && j + 2 < sizeof escaped; i++) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError", escaped);
}

#define GUARD_ERROR(g, ...) log_error(&(g)->cb, (g)->name, __VA_ARGS__)

static const char *mode_name(int mode) {
    switch (mode) {
    case M_INSTANTIATED: return "instantiated";
    case M_INITIALIZATION: return "initialization mode";
    case M_STEP_COMPLETE: return "step complete";
    default: return "terminated";
    }
}

/* The guard of ``c`` if the call is legal in its mode; else NULL (logged). */
static Guard *legal(fmi2Component c, const char *function, int modes) {
    Guard *g = (Guard *)c;
    if (g == NULL) return NULL;
    if (g->mode & modes) return g;
    GUARD_ERROR(g, "%s: %s: illegal call sequence (the instance is in %s)", GUARD_NAME,
                function, mode_name(g->mode));
    return NULL;
}

/* 1 if every reference names a variable of ``type`` (settable ones when ``set``). */
static int references_ok(Guard *g, const char *function, const fmi2ValueReference vr[],
                         size_t n, GuardType type, int set) {
    for (size_t i = 0; i < n; i++) {
        if (vr[i] >= GUARD_N_VARS || GUARD_VARS[vr[i]].type != type) {
            GUARD_ERROR(g, "%s: %s: no variable of this type with value reference %u",
                        GUARD_NAME, function, (unsigned)vr[i]);
            return 0;
        }
        if (set && GUARD_VARS[vr[i]].causality == G_OUTPUT) {
            GUARD_ERROR(g, "%s: %s: %s is computed by the model and cannot be set", GUARD_NAME,
                        function, GUARD_VARS[vr[i]].name);
            return 0;
        }
    }
    return 1;
}

/* Record (and log) whether ``value`` is inside the declared range of ``vr``; 1 if it is. */
static int value_ok(Guard *g, fmi2ValueReference vr, double value) {
    const GuardVar *v = &GUARD_VARS[vr];
    int ok = isfinite(value) && (!v->has_range || (value >= v->min && value <= v->max));
    g->invalid[vr] = (unsigned char)!ok;
    g->refused[vr] = value;
    if (!ok)
        GUARD_ERROR(g, "%s: %s = %g is %s; valid range [%g, %g] %s", GUARD_NAME, v->name, value,
                    isfinite(value) ? "out of range" : "not finite", v->min, v->max, v->unit);
    return ok;
}

/* ---- decoding the resource URI --------------------------------------------------------- */

static int hex(char c) {
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* "file:///p%C3%A4th" (or file:/p, file://localhost/p) -> "file:///päth" in ``out``: what
   pythonfmu (which decodes only %20) reads right. 0 if it is not a local file URI. */
static int decode_uri(const char *uri, char *out, size_t size) {
    const char *p;
    size_t j;
    if (uri == NULL || strncmp(uri, "file:", 5) != 0) return 0;
    p = uri + 5;
    if (strncmp(p, "//", 2) == 0) {
        p += 2;
        if (strncmp(p, "localhost", 9) == 0) p += 9;
        if (*p != '/') return 0; /* another host */
    }
    j = (size_t)snprintf(out, size, "file://");
    for (; *p != '\0' && j + 1 < size; p++) {
        if (*p == '%' && hex(p[1]) >= 0 && hex(p[2]) >= 0) {
            out[j++] = (char)(hex(p[1]) * 16 + hex(p[2]));
            p += 2;
        } else {
            out[j++] = *p;
        }
    }
    out[j] = '\0';
    return *p == '\0';
}

/* ---- the FMI 2 functions --------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *callbacks,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    char uri[4096];
    const char *problem;
    Guard *g;
    name = name ? name : "";
    if (callbacks == NULL) return NULL;
    if (type != fmi2CoSimulation) {
        log_error(callbacks, name, "fmi2Instantiate: %s (pythonfmu flavour) is a co-simulation "
                  "FMU only; the native flavour has model exchange", GUARD_NAME);
        return NULL;
    }
    if (guid == NULL || strcmp(guid, GUARD_GUID) != 0) {
        log_error(callbacks, name, "fmi2Instantiate: wrong GUID '%s' for %s (expected '%s')",
                  guid ? guid : "(null)", GUARD_NAME, GUARD_GUID);
        return NULL;
    }
    if (!decode_uri(resources, uri, sizeof uri)) {
        log_error(callbacks, name, "fmi2Instantiate: %s needs its resources folder as a local "
                  "file URI (file:///...), got '%s'", GUARD_NAME, resources ? resources : "");
        return NULL;
    }
    if ((problem = load_library()) != NULL) {
        log_error(callbacks, name, "fmi2Instantiate: %s: %s", GUARD_NAME, problem);
        return NULL;
    }
    g = (Guard *)calloc(1, sizeof(Guard));
    if (g == NULL) return NULL;
    g->cb = *callbacks;
    snprintf(g->name, sizeof g->name, "%s", name);
    g->real = F.instantiate(name, type, guid, uri, callbacks, visible, loggingOn);
    if (g->real == NULL) {
        free(g);
        return NULL;
    }
    g->mode = M_INSTANTIATED;
    return g;
}

void fmi2FreeInstance(fmi2Component c) {
    Guard *g = (Guard *)c;
    if (g == NULL) return;
    F.free_instance(g->real);
    free(g);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n,
                               const fmi2String categories[]) {
    Guard *g = legal(c, "fmi2SetDebugLogging", M_ANY);
    return g ? F.set_debug_logging(g->real, on, n, categories) : fmi2Error;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Guard *g = legal(c, "fmi2SetupExperiment", M_INSTANTIATED);
    return g ? F.setup_experiment(g->real, toleranceDefined, tolerance, startTime,
                                  stopTimeDefined, stopTime)
             : fmi2Error;
}

/* ``status`` of a call that moves the instance to ``mode`` when it succeeds. */
static fmi2Status moved(Guard *g, fmi2Status status, int mode) {
    if (status <= fmi2Warning) g->mode = mode;
    return status;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Guard *g = legal(c, "fmi2EnterInitializationMode", M_INSTANTIATED);
    return g ? moved(g, F.enter_initialization(g->real), M_INITIALIZATION) : fmi2Error;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Guard *g = legal(c, "fmi2ExitInitializationMode", M_INITIALIZATION);
    if (g == NULL) return fmi2Error;
    for (int k = 0; k < GUARD_N_VARS; k++) {
        if (g->invalid[k]) {
            GUARD_ERROR(g, "fmi2ExitInitializationMode: %s = %g is invalid (valid range [%g, "
                        "%g] %s); set it right and call fmi2ExitInitializationMode again",
                        GUARD_VARS[k].name, g->refused[k], GUARD_VARS[k].min,
                        GUARD_VARS[k].max, GUARD_VARS[k].unit);
            return fmi2Error;
        }
    }
    return moved(g, F.exit_initialization(g->real), M_STEP_COMPLETE);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    Guard *g = legal(c, "fmi2Terminate", M_STEP_COMPLETE);
    return g ? moved(g, F.terminate(g->real), M_TERMINATED) : fmi2Error;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Guard *g = legal(c, "fmi2Reset", M_ANY);
    fmi2Status status;
    if (g == NULL) return fmi2Error;
    status = moved(g, F.reset(g->real), M_INSTANTIATED);
    if (status <= fmi2Warning) memset(g->invalid, 0, sizeof g->invalid);
    return status;
}

#define GETTER(NAME, TYPE, GTYPE, FIELD)                                                     \
    fmi2Status NAME(fmi2Component c, const fmi2ValueReference vr[], size_t n, TYPE value[]) { \
        Guard *g = legal(c, #NAME, M_GETTABLE);                                              \
        if (g == NULL || !references_ok(g, #NAME, vr, n, GTYPE, 0)) return fmi2Error;        \
        return F.FIELD(g->real, vr, n, value);                                               \
    }
GETTER(fmi2GetReal, fmi2Real, G_REAL, get_real)
GETTER(fmi2GetInteger, fmi2Integer, G_INTEGER, get_integer)
GETTER(fmi2GetBoolean, fmi2Boolean, G_BOOLEAN, get_boolean)
#undef GETTER

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         fmi2String value[]) {
    Guard *g = legal(c, "fmi2GetString", M_GETTABLE);
    (void)value;
    if (g != NULL && n > 0)
        GUARD_ERROR(g, "fmi2GetString: %s has no String variable (value reference %u)",
                    GUARD_NAME, (unsigned)vr[0]);
    return g != NULL && n == 0 ? fmi2OK : fmi2Error;
}

/* Set Real or Integer values: every reference checked first, then each value against its
   range; the values are passed on whatever their range (the slave keeps and reports them as
   the native flavour does), and a refused one makes the call fmi2Error. */
#define SETTER(NAME, TYPE, GTYPE, FIELD)                                                     \
    fmi2Status NAME(fmi2Component c, const fmi2ValueReference vr[], size_t n,                \
                    const TYPE value[]) {                                                    \
        Guard *g = legal(c, #NAME, M_SETTABLE);                                              \
        int ok = 1;                                                                          \
        fmi2Status status;                                                                   \
        if (g == NULL || !references_ok(g, #NAME, vr, n, GTYPE, 1)) return fmi2Error;        \
        for (size_t i = 0; i < n; i++) ok &= value_ok(g, vr[i], (double)value[i]);           \
        status = F.FIELD(g->real, vr, n, value);                                             \
        return ok ? status : fmi2Error;                                                      \
    }
SETTER(fmi2SetReal, fmi2Real, G_REAL, set_real)
SETTER(fmi2SetInteger, fmi2Integer, G_INTEGER, set_integer)
#undef SETTER

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean value[]) {
    Guard *g = legal(c, "fmi2SetBoolean", M_SETTABLE);
    if (g == NULL || !references_ok(g, "fmi2SetBoolean", vr, n, G_BOOLEAN, 1)) return fmi2Error;
    return F.set_boolean(g->real, vr, n, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                         const fmi2String value[]) {
    Guard *g = legal(c, "fmi2SetString", M_SETTABLE);
    (void)value;
    if (g != NULL && n > 0)
        GUARD_ERROR(g, "fmi2SetString: %s has no String variable (value reference %u)",
                    GUARD_NAME, (unsigned)vr[0]);
    return g != NULL && n == 0 ? fmi2OK : fmi2Error;
}

/* ---- FMU state ------------------------------------------------------------------------- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Guard *g = legal(c, "fmi2GetFMUstate", M_ANY);
    return g ? F.get_state(g->real, state) : fmi2Error;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    Guard *g = legal(c, "fmi2SetFMUstate", M_ANY);
    return g ? F.set_state(g->real, state) : fmi2Error;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Guard *g = legal(c, "fmi2FreeFMUstate", M_ANY);
    return g ? F.free_state(g->real, state) : fmi2Error;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    Guard *g = legal(c, "fmi2SerializedFMUstateSize", M_ANY);
    fmi2Status status;
    if (g == NULL) return fmi2Error;
    status = F.state_size(g->real, state, size);
    if (status <= fmi2Warning) *size += STATE_HEADER;
    return status;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size) {
    Guard *g = legal(c, "fmi2SerializeFMUstate", M_ANY);
    if (g == NULL) return fmi2Error;
    if (size < STATE_HEADER) {
        GUARD_ERROR(g, "fmi2SerializeFMUstate: %u bytes is too small (see "
                    "fmi2SerializedFMUstateSize)", (unsigned)size);
        return fmi2Error;
    }
    memset(bytes, 0, STATE_HEADER);
    snprintf(bytes, STATE_HEADER, "%s%s", STATE_TAG, GUARD_GUID);
    return F.serialize(g->real, state, bytes + STATE_HEADER, size - STATE_HEADER);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state) {
    Guard *g = legal(c, "fmi2DeSerializeFMUstate", M_ANY);
    char expected[STATE_HEADER];
    if (g == NULL) return fmi2Error;
    memset(expected, 0, sizeof expected);
    snprintf(expected, sizeof expected, "%s%s", STATE_TAG, GUARD_GUID);
    if (size < STATE_HEADER || memcmp(bytes, expected, STATE_HEADER) != 0) {
        GUARD_ERROR(g, "fmi2DeSerializeFMUstate: these %u bytes are not a state of %s (GUID "
                    "%s): another model's, another build's, or not a state", (unsigned)size,
                    GUARD_NAME, GUARD_GUID);
        return fmi2Error;
    }
    return F.deserialize(g->real, bytes + STATE_HEADER, size - STATE_HEADER, state);
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknown[],
                                        size_t n_unknown, const fmi2ValueReference known[],
                                        size_t n_known, const fmi2Real dv_known[],
                                        fmi2Real dv_unknown[]) {
    Guard *g = (Guard *)c;
    (void)unknown, (void)n_unknown, (void)known, (void)n_known, (void)dv_known,
        (void)dv_unknown;
    if (g) GUARD_ERROR(g, "fmi2GetDirectionalDerivative: not provided by %s", GUARD_NAME);
    return fmi2Error;
}

/* ---- co-simulation ---------------------------------------------------------------------- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                       size_t n, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    Guard *g = (Guard *)c;
    (void)vr, (void)n, (void)order, (void)value;
    if (g) GUARD_ERROR(g, "fmi2SetRealInputDerivatives: %s does not interpolate inputs",
                       GUARD_NAME);
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[],
                                        fmi2Real value[]) {
    Guard *g = (Guard *)c;
    (void)vr, (void)n, (void)order, (void)value;
    if (g) GUARD_ERROR(g, "fmi2GetRealOutputDerivatives: not provided by %s", GUARD_NAME);
    return fmi2Error;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Guard *g = legal(c, "fmi2DoStep", M_STEP_COMPLETE);
    return g ? F.do_step(g->real, t, h, noSetPrior) : fmi2Error;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    Guard *g = (Guard *)c;
    if (g) GUARD_ERROR(g, "fmi2CancelStep: %s steps synchronously", GUARD_NAME);
    return fmi2Error;
}

/* The status queries, legal in every mode, forwarded as they are. */
#define STATUS_QUERY(NAME, TYPE, FIELD)                                                      \
    fmi2Status NAME(fmi2Component c, const fmi2StatusKind s, TYPE *value) {                  \
        Guard *g = legal(c, #NAME, M_ANY);                                                   \
        return g ? F.FIELD(g->real, s, value) : fmi2Error;                                   \
    }
STATUS_QUERY(fmi2GetStatus, fmi2Status, get_status)
STATUS_QUERY(fmi2GetRealStatus, fmi2Real, get_real_status)
STATUS_QUERY(fmi2GetIntegerStatus, fmi2Integer, get_integer_status)
STATUS_QUERY(fmi2GetBooleanStatus, fmi2Boolean, get_boolean_status)
STATUS_QUERY(fmi2GetStringStatus, fmi2String, get_string_status)
#undef STATUS_QUERY

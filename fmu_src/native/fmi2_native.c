/*
 * FMI 2.0 wrapper of the native wheelterrain FMUs: co-simulation and model exchange.
 *
 * One translation unit per FMU: this file includes model_vars.h, which `wheelterrain build
 * --flavor native` generates for WheelTerrain or SingleWheelRig (the variable table, the GUID,
 * the sizes and value references the hooks use, and the C that CasADi generates from the very
 * Functions the Python flavour calls, wheelterrain.fmu.functions), and model_hooks.inc, the
 * model's hooks (terrain_hooks.c or state_hooks.c beside this file: model_work, model_reset,
 * model_initialize, model_refresh, model_step, copying values in and out of those Functions,
 * and MODEL_CHECKS_AT_STEP_END, see fmi2DoStep).
 * No arithmetic of the model is written by hand.
 *
 * Model exchange: the continuous states are the ones the co-simulation step advances (the
 * rig's states, the terrain's wheel angle); model_refresh computes their derivatives with the
 * outputs, from the same Functions (rig_rates, or the wheel speed), listed in model_vars.h
 * (STATE_VRS, DER_VRS, NOMINALS). No event indicators, no discrete states.
 *
 * What this wrapper adds: the FMI 2 call-sequence state machine, the GUID check, logging
 * categories (errors are always reported, whether logging is on or not), checks of every set
 * value against its declared range (fmi2Error and a logged reason naming the variable and the
 * range), fmi2Discard with the reason when a step cannot be taken, get/set/serialize of the
 * whole instance state, and no global mutable state (any number of instances).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* glibc 2.29 gave exp, exp2, log, log2 and pow new symbol versions. `wheelterrain build`
 * defines WHEELTERRAIN_PORTABLE_LIBM to bind them to the versions every x86_64 glibc has
 * (2.2.5), so the shipped binary loads on glibc >= 2.17 systems (RHEL/CentOS 7 and 8, Ubuntu
 * 18.04, Debian 10); same mathematics, the newer ones are faster. A build of sources/ on the
 * machine that runs it needs nothing (and a build without -lm could not bind versions). */
#if defined(__GLIBC__) && defined(__x86_64__) && defined(WHEELTERRAIN_PORTABLE_LIBM)
__asm__(".symver exp,exp@GLIBC_2.2.5");
__asm__(".symver exp2,exp2@GLIBC_2.2.5");
__asm__(".symver log,log@GLIBC_2.2.5");
__asm__(".symver log2,log2@GLIBC_2.2.5");
__asm__(".symver pow,pow@GLIBC_2.2.5");
#endif

#ifdef WHEELTERRAIN_FMI2_INTERNAL
/* included by fmi3_native.c: the FMI 2 types only, so the fmi2 functions stay internal to the
   FMI 3 binary (not exported) */
#include "fmi2FunctionTypes.h"
#define fmi2Version "2.0"
#else
#include "fmi2Functions.h"
#endif

typedef enum { T_REAL, T_INTEGER, T_BOOLEAN } VarType;
typedef enum { C_PARAMETER, C_INPUT, C_OUTPUT, C_LOCAL } Causality;

typedef struct {
    const char *name;
    VarType type;
    Causality causality;
    double start;
    int has_range;
    double min, max;
    const char *unit;
    const char *description;
} VarInfo;

typedef enum {
    S_INSTANTIATED = 1,
    S_INITIALIZATION = 2,
    S_STEP_COMPLETE = 4,
    S_TERMINATED = 8,
    S_ERROR = 16,
    S_EVENT = 32,      /* model exchange: event mode */
    S_CONTINUOUS = 64, /* model exchange: continuous-time mode */
} ModeBit;

#define MAX_MESSAGE 512

#include "model_vars.h" /* VARS, N_VARS, N_STATES, MODEL_NAME, MODEL_GUID, CasADi functions */

/* The instance state that get/set/serialize FMU state carries, as one plain block. */
typedef struct {
    unsigned magic;
    char guid[48]; /* the model's GUID: a state of another FMU (or build) is refused */
    double v[N_VARS];
    int invalid[N_VARS];
    double s[AT_LEAST_ONE(N_STATES)];
    int dirty;
    int operating_error;
    int mode;
    double time;
    int terminated; /* a refusal the model cannot leave: fmi2Terminated, until a reset or an
                       earlier FMU state */
    int has_point;  /* the model has been evaluated at a valid operating point (the outputs
                       are its results, not their start values) */
    char operating_message[MAX_MESSAGE];
} Block;

#define BLOCK_MAGIC 0x57544632u /* "WTF2" */

/* An FMU state this instance made (fmi2GetFMUstate, fmi2DeSerializeFMUstate) and has not
   freed: the host's fmi2FMUstate points at one of these. A pointer that is not in the
   instance's list (freed, made by another instance or FMU, or never made) is refused without
   being read. */
typedef struct StateNode {
    Block b;
    struct StateNode *next;
} StateNode;

/* A serialized state: SERIAL_TAG and the model's GUID (zero-padded to SERIAL_ID bytes), the
   body's length and an FNV-1a checksum of the body (8 bytes each, little-endian), then the
   body, the Block. Another model's, a truncated or an altered state is refused. */
#define SERIAL_TAG "wheelterrain native state "
#define SERIAL_ID 96
#define SERIAL_HEADER (SERIAL_ID + 16)
#define SERIAL_SIZE (SERIAL_HEADER + sizeof(Block))

typedef struct Instance {
    Block b;
    StateNode *states; /* the FMU states this instance made and has not freed */
    fmi2CallbackFunctions cb;
    char *name;
    int model_exchange; /* instantiated as fmi2ModelExchange (else co-simulation) */
    int logging_on;
    int log_categories; /* bit k: category k enabled */
    casadi_int *iw;
    casadi_real *w;
    const casadi_real **arg;
    casadi_real **res;
} Instance;

/* Grow the work sizes to cover one more CasADi Function (its generated <name>_work). */
typedef int (*WorkSizes)(casadi_int *, casadi_int *, casadi_int *, casadi_int *);
static void cover(WorkSizes f, casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw,
                  casadi_int *sz_w) {
    casadi_int a = 0, r = 0, i = 0, w = 0;
    f(&a, &r, &i, &w);
    if (a > *sz_arg) *sz_arg = a;
    if (r > *sz_res) *sz_res = r;
    if (i > *sz_iw) *sz_iw = i;
    if (w > *sz_w) *sz_w = w;
}

#include "model_hooks.inc"

/* Exactly the categories the modelDescription declares; any other name is refused. */
static const char *CATEGORIES[] = {"logStatusWarning", "logStatusDiscard", "logStatusError",
                                   "logStatusFatal", "logAll"};
#define N_CATEGORIES 5

static void log_message(Instance *c, fmi2Status status, int category, const char *fmt, ...) {
    char text[MAX_MESSAGE * 2];
    va_list ap;
    int with_status = status != fmi2OK;
    if (c == NULL || c->cb.logger == NULL) return;
    /* the message of a status returned (a warning, discard or error: every call of this file
       with a status other than OK returns it) always reaches the host, as FMI's status rules
       ask; other messages when logging is on and their category is enabled */
    if (!with_status && !(c->logging_on && (c->log_categories & (1 << category)))) return;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    /* The logger's message is a format string (FMI 2.0, 2.1.5): pass the finished text with any
       '%' doubled, and no arguments, so formatting and non-formatting hosts both print it. */
    {
        char escaped[sizeof text * 2];
        size_t j = 0;
        for (size_t i = 0; text[i] != '\0' && j + 2 < sizeof escaped; i++) {
            if (text[i] == '%') escaped[j++] = '%';
            escaped[j++] = text[i];
        }
        escaped[j] = '\0';
        c->cb.logger(c->cb.componentEnvironment, c->name, status, CATEGORIES[category],
                     escaped);
    }
}

#define LOG_ERROR(c, ...) log_message((c), fmi2Error, 2, __VA_ARGS__)
#define LOG_DISCARD(c, ...) log_message((c), fmi2Discard, 1, __VA_ARGS__)

static const char *mode_name(int mode) {
    switch (mode) {
    case S_INSTANTIATED: return "instantiated";
    case S_INITIALIZATION: return "initialization mode";
    case S_STEP_COMPLETE: return "step complete";
    case S_TERMINATED: return "terminated";
    default: return "error";
    }
}

/* 1 if the call is allowed in the current mode, else log and 0. */
static int allowed(Instance *c, const char *function, int modes) {
    if (c == NULL) return 0;
    if (c->b.mode & modes) return 1;
    LOG_ERROR(c, "%s: illegal call sequence (the instance is in %s)", function,
              mode_name(c->b.mode));
    return 0;
}

/* ---- value checks ------------------------------------------------------------------------- */

static int check_value(Instance *c, fmi2ValueReference vr, double value) {
    const VarInfo *v = &VARS[vr];
    if (v->type == T_BOOLEAN) return 1;
    if (!isfinite(value)) {
        LOG_ERROR(c, "%s: %s = %g must be finite; valid range [%g, %g] %s", MODEL_NAME, v->name,
                  value, v->min, v->max, v->unit);
        return 0;
    }
    if (v->has_range && (value < v->min || value > v->max)) {
        LOG_ERROR(c, "%s: %s = %g is out of range; valid range [%g, %g] %s", MODEL_NAME, v->name,
                  value, v->min, v->max, v->unit);
        return 0;
    }
    return 1;
}

static int any_invalid(Instance *c, int report) {
    int bad = 0;
    for (int k = 0; k < N_VARS; k++) {
        if (c->b.invalid[k]) {
            bad = 1;
            if (report)
                LOG_DISCARD(c, "%s: step refused: %s = %g is invalid (see the error logged when "
                            "it was set); valid range [%g, %g] %s", MODEL_NAME, VARS[k].name,
                            c->b.v[k], VARS[k].min, VARS[k].max, VARS[k].unit);
        }
    }
    return bad;
}

static void refresh(Instance *c) {
    double dx[AT_LEAST_ONE(N_CONTINUOUS)];
    if (!c->b.dirty || any_invalid(c, 0)) return;
    c->b.dirty = 0;
    c->b.operating_error = 0;
    if (model_refresh(c, dx, c->b.operating_message) != 0) {
        c->b.operating_error = 1;
        LOG_ERROR(c, "%s: %s", MODEL_NAME, c->b.operating_message);
        return;
    }
    c->b.has_point = 1;
    for (int k = 0; k < N_CONTINUOUS; k++) c->b.v[DER_VRS[k]] = dx[k];
}

/* ---- common functions ------------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component comp, fmi2Boolean loggingOn, size_t n,
                               const fmi2String categories[]) {
    Instance *c = (Instance *)comp;
    if (c == NULL) return fmi2Error;
    c->logging_on = loggingOn;
    if (n == 0) {
        c->log_categories = loggingOn ? ~0 : 0;
        return fmi2OK;
    }
    for (size_t i = 0; i < n; i++) {
        int found = 0;
        for (int k = 0; k < N_CATEGORIES; k++) {
            if (strcmp(categories[i], CATEGORIES[k]) == 0) {
                if (loggingOn) c->log_categories |= 1 << k;
                else c->log_categories &= ~(1 << k);
                found = 1;
            }
        }
        if (!found) {
            LOG_ERROR(c, "fmi2SetDebugLogging: unknown log category '%s'", categories[i]);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

static void set_defaults(Instance *c) {
    memset(&c->b, 0, sizeof c->b);
    c->b.magic = BLOCK_MAGIC;
    snprintf(c->b.guid, sizeof c->b.guid, "%s", MODEL_GUID);
    for (int k = 0; k < N_VARS; k++) c->b.v[k] = VARS[k].start;
    c->b.dirty = 1;
    c->b.mode = S_INSTANTIATED;
    model_reset(c);
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    Instance *c;
    casadi_int sz_arg, sz_res, sz_iw, sz_w;
    (void)resourceLocation;
    (void)visible;
    if (functions == NULL || functions->allocateMemory == NULL || functions->freeMemory == NULL)
        return NULL;
    c = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (c == NULL) return NULL;
    c->cb = *functions;
    c->name = (char *)functions->allocateMemory(strlen(name ? name : "") + 1, 1);
    if (c->name == NULL) {
        functions->freeMemory(c);
        return NULL;
    }
    strcpy(c->name, name ? name : "");
    c->logging_on = loggingOn;
    c->log_categories = loggingOn ? ~0 : 0;
    c->model_exchange = type == fmi2ModelExchange;
    if (type != fmi2CoSimulation && type != fmi2ModelExchange) {
        LOG_ERROR(c, "fmi2Instantiate: %s has no interface of fmuType %d", MODEL_NAME,
                  (int)type);
        functions->freeMemory(c->name);
        functions->freeMemory(c);
        return NULL;
    }
    if (guid == NULL || strcmp(guid, MODEL_GUID) != 0) {
        LOG_ERROR(c, "fmi2Instantiate: wrong GUID '%s' for %s (expected '%s')",
                  guid ? guid : "(null)", MODEL_NAME, MODEL_GUID);
        functions->freeMemory(c->name);
        functions->freeMemory(c);
        return NULL;
    }
    sz_arg = sz_res = sz_iw = sz_w = 0;
    model_work(&sz_arg, &sz_res, &sz_iw, &sz_w);
    c->iw = (casadi_int *)functions->allocateMemory((size_t)(sz_iw > 0 ? sz_iw : 1),
                                                    sizeof(casadi_int));
    c->w = (casadi_real *)functions->allocateMemory((size_t)(sz_w > 0 ? sz_w : 1),
                                                    sizeof(casadi_real));
    c->arg = (const casadi_real **)functions->allocateMemory((size_t)sz_arg,
                                                            sizeof(casadi_real *));
    c->res = (casadi_real **)functions->allocateMemory((size_t)sz_res, sizeof(casadi_real *));
    if (!c->iw || !c->w || !c->arg || !c->res) {
        LOG_ERROR(c, "fmi2Instantiate: out of memory");
        if (c->iw) functions->freeMemory(c->iw);
        if (c->w) functions->freeMemory(c->w);
        if (c->arg) functions->freeMemory((void *)c->arg);
        if (c->res) functions->freeMemory(c->res);
        functions->freeMemory(c->name);
        functions->freeMemory(c);
        return NULL;
    }
    set_defaults(c);
    return c;
}

void fmi2FreeInstance(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (c == NULL) return;
    while (c->states != NULL) { /* the states the host did not free go with the instance */
        StateNode *next = c->states->next;
        c->cb.freeMemory(c->states);
        c->states = next;
    }
    c->cb.freeMemory(c->iw);
    c->cb.freeMemory(c->w);
    c->cb.freeMemory((void *)c->arg);
    c->cb.freeMemory(c->res);
    c->cb.freeMemory(c->name);
    c->cb.freeMemory(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component comp, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Instance *c = (Instance *)comp;
    (void)toleranceDefined, (void)tolerance, (void)stopTimeDefined, (void)stopTime;
    if (!allowed(c, "fmi2SetupExperiment", S_INSTANTIATED)) return fmi2Error;
    c->b.time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2EnterInitializationMode", S_INSTANTIATED)) return fmi2Error;
    c->b.mode = S_INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2ExitInitializationMode", S_INITIALIZATION)) return fmi2Error;
    /* a value refused while it was set is refused here too, not first at the first step: the
       instance stays in initialisation mode, where the value can be set right */
    for (int k = 0; k < N_VARS; k++) {
        if (c->b.invalid[k]) {
            LOG_ERROR(c, "fmi2ExitInitializationMode: %s = %g is invalid (valid range [%g, %g] "
                      "%s); set it right and call fmi2ExitInitializationMode again",
                      VARS[k].name, c->b.v[k], VARS[k].min, VARS[k].max, VARS[k].unit);
            return fmi2Error;
        }
    }
    c->b.mode = c->model_exchange ? S_EVENT : S_STEP_COMPLETE;
    model_initialize(c);
    c->b.dirty = 1;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2Terminate", S_STEP_COMPLETE | S_EVENT | S_CONTINUOUS | S_ERROR))
        return fmi2Error;
    c->b.mode = S_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (c == NULL) return fmi2Error;
    set_defaults(c);
    return fmi2OK;
}

/* ---- get and set ------------------------------------------------------------------------ */

#define GETTABLE (S_INITIALIZATION | S_STEP_COMPLETE | S_EVENT | S_CONTINUOUS | S_TERMINATED | \
                  S_ERROR)
#define SETTABLE (S_INSTANTIATED | S_INITIALIZATION | S_STEP_COMPLETE | S_EVENT | S_CONTINUOUS)

static int check_vr(Instance *c, const char *function, fmi2ValueReference vr, VarType type) {
    if (vr >= N_VARS || VARS[vr].type != type) {
        LOG_ERROR(c, "%s: no variable of this type with value reference %u", function, vr);
        return 0;
    }
    return 1;
}

static fmi2Status get_values(Instance *c, const char *function, const fmi2ValueReference vr[],
                             size_t n, VarType type, double *out) {
    int stale = 0;
    if (!allowed(c, function, GETTABLE)) return fmi2Error;
    refresh(c);
    for (size_t i = 0; i < n; i++) {
        if (!check_vr(c, function, vr[i], type)) return fmi2Error;
        out[i] = c->b.v[vr[i]];
        if (VARS[vr[i]].causality == C_OUTPUT || VARS[vr[i]].causality == C_LOCAL) stale = 1;
    }
    /* model exchange has no last step: outputs at a refused point are an error */
    if (stale && c->model_exchange && (c->b.operating_error || any_invalid(c, 0))) {
        LOG_ERROR(c, "%s: %s: the outputs at this point are refused: %s", MODEL_NAME, function,
                  c->b.operating_error ? c->b.operating_message : "an invalid value");
        return fmi2Error;
    }
    /* outputs while the current inputs are refused are those of the last valid point, or,
       where there has been none, their start values: served, but not as OK (fmi2Warning, with
       which of the two and the reason) */
    if (stale && (c->b.operating_error || any_invalid(c, 0))) {
        log_message(c, fmi2Warning, 0, "%s: %s: %s; the current one is refused: %s", MODEL_NAME,
                    function, c->b.has_point ? "outputs are those of the last valid operating "
                    "point" : "no valid operating point yet: the outputs are their start "
                    "values, not results of the model",
                    c->b.operating_error ? c->b.operating_message : "an invalid value");
        return fmi2Warning;
    }
    /* an output with no value at this point (e.g. the paper's slip with the carriage at
       rest) is NaN, served as fmi2Warning, never as OK (its description says where) */
    for (size_t i = 0; i < n; i++) {
        if (out[i] != out[i]) {
            log_message(c, fmi2Warning, 0, "%s: %s: %s is undefined at this operating point "
                        "(NaN): %s", MODEL_NAME, function, VARS[vr[i]].name,
                        VARS[vr[i]].description);
            return fmi2Warning;
        }
    }
    return fmi2OK;
}

static fmi2Status set_value(Instance *c, const char *function, fmi2ValueReference vr,
                            VarType type, double value) {
    if (!check_vr(c, function, vr, type)) return fmi2Error;
    if (VARS[vr].causality == C_OUTPUT || VARS[vr].causality == C_LOCAL) {
        LOG_ERROR(c, "%s: %s is computed by the model and cannot be set", function,
                  VARS[vr].name);
        return fmi2Error;
    }
    c->b.v[vr] = value;
    c->b.dirty = 1;
    c->b.invalid[vr] = !check_value(c, vr, value);
    return c->b.invalid[vr] ? fmi2Error : fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                       fmi2Real value[]) {
    return get_values((Instance *)comp, "fmi2GetReal", vr, n, T_REAL, value);
}

fmi2Status fmi2GetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Integer value[]) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetInteger", GETTABLE)) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        if (!check_vr(c, "fmi2GetInteger", vr[i], T_INTEGER)) return fmi2Error;
        value[i] = (fmi2Integer)c->b.v[vr[i]];
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          fmi2Boolean value[]) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetBoolean", GETTABLE)) return fmi2Error;
    for (size_t i = 0; i < n; i++) {
        if (!check_vr(c, "fmi2GetBoolean", vr[i], T_BOOLEAN)) return fmi2Error;
        value[i] = c->b.v[vr[i]] != 0.0;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                         fmi2String value[]) {
    Instance *c = (Instance *)comp;
    (void)vr, (void)value;
    if (n == 0) return fmi2OK;
    LOG_ERROR(c, "fmi2GetString: %s has no String variables", MODEL_NAME);
    return fmi2Error;
}

fmi2Status fmi2SetReal(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real value[]) {
    Instance *c = (Instance *)comp;
    fmi2Status status = fmi2OK;
    if (!allowed(c, "fmi2SetReal", SETTABLE)) return fmi2Error;
    for (size_t i = 0; i < n; i++)
        if (set_value(c, "fmi2SetReal", vr[i], T_REAL, value[i]) != fmi2OK) status = fmi2Error;
    return status;
}

fmi2Status fmi2SetInteger(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          const fmi2Integer value[]) {
    Instance *c = (Instance *)comp;
    fmi2Status status = fmi2OK;
    if (!allowed(c, "fmi2SetInteger", SETTABLE)) return fmi2Error;
    for (size_t i = 0; i < n; i++)
        if (set_value(c, "fmi2SetInteger", vr[i], T_INTEGER, (double)value[i]) != fmi2OK)
            status = fmi2Error;
    return status;
}

fmi2Status fmi2SetBoolean(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean value[]) {
    Instance *c = (Instance *)comp;
    fmi2Status status = fmi2OK;
    if (!allowed(c, "fmi2SetBoolean", SETTABLE)) return fmi2Error;
    for (size_t i = 0; i < n; i++)
        if (set_value(c, "fmi2SetBoolean", vr[i], T_BOOLEAN, value[i] ? 1.0 : 0.0) != fmi2OK)
            status = fmi2Error;
    return status;
}

fmi2Status fmi2SetString(fmi2Component comp, const fmi2ValueReference vr[], size_t n,
                         const fmi2String value[]) {
    Instance *c = (Instance *)comp;
    (void)vr, (void)value;
    if (n == 0) return fmi2OK;
    LOG_ERROR(c, "fmi2SetString: %s has no String variables", MODEL_NAME);
    return fmi2Error;
}

/* ---- FMU state ------------------------------------------------------------------------------ */

/* The instance's node ``state`` points at, else NULL: compared, never read. */
static StateNode *own_state(Instance *c, fmi2FMUstate state) {
    for (StateNode *n = c->states; n != NULL; n = n->next)
        if ((void *)n == (void *)state) return n;
    return NULL;
}

/* The node of ``state`` if this instance made it and has not freed it; else NULL (logged). */
static StateNode *checked_state(Instance *c, const char *function, fmi2FMUstate state) {
    StateNode *n = own_state(c, state);
    if (n == NULL)
        LOG_ERROR(c, "%s: the FMU state %p was not made by this instance of %s, or has been "
                  "freed (fmi2FreeFMUstate)", function, (void *)state, MODEL_NAME);
    return n;
}

/* A new node in the instance's list holding ``block``; NULL when out of memory (logged). */
static StateNode *new_state(Instance *c, const char *function, const Block *block) {
    StateNode *n = (StateNode *)c->cb.allocateMemory(1, sizeof(StateNode));
    if (n == NULL) {
        LOG_ERROR(c, "%s: out of memory", function);
        return NULL;
    }
    n->b = *block;
    n->next = c->states;
    c->states = n;
    return n;
}

/* FNV-1a, 64 bits, of ``n`` bytes. */
static unsigned long long checksum(const unsigned char *bytes, size_t n) {
    unsigned long long h = 1469598103934665603ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= bytes[i];
        h *= 1099511628211ULL;
    }
    return h;
}

static void put_u64(unsigned char *out, unsigned long long v) {
    for (int k = 0; k < 8; k++) out[k] = (unsigned char)(v >> (8 * k));
}

static unsigned long long get_u64(const unsigned char *in) {
    unsigned long long v = 0;
    for (int k = 7; k >= 0; k--) v = (v << 8) | in[k];
    return v;
}

/* The id a serialized state of this model starts with: SERIAL_TAG, the GUID, zeros. */
static void serial_id(unsigned char id[SERIAL_ID]) {
    memset(id, 0, SERIAL_ID);
    snprintf((char *)id, SERIAL_ID, "%s%s", SERIAL_TAG, MODEL_GUID);
}

fmi2Status fmi2GetFMUstate(fmi2Component comp, fmi2FMUstate *state) {
    Instance *c = (Instance *)comp;
    StateNode *n;
    if (!allowed(c, "fmi2GetFMUstate", SETTABLE | S_TERMINATED | S_ERROR)) return fmi2Error;
    if (state == NULL) {
        LOG_ERROR(c, "fmi2GetFMUstate: no place for the state (NULL)");
        return fmi2Error;
    }
    if (*state != NULL) { /* an earlier state of this instance, overwritten */
        if ((n = checked_state(c, "fmi2GetFMUstate", *state)) == NULL) return fmi2Error;
        n->b = c->b;
        return fmi2OK;
    }
    if ((n = new_state(c, "fmi2GetFMUstate", &c->b)) == NULL) return fmi2Error;
    *state = n;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component comp, fmi2FMUstate state) {
    Instance *c = (Instance *)comp;
    StateNode *n;
    if (!allowed(c, "fmi2SetFMUstate", SETTABLE | S_TERMINATED | S_ERROR)) return fmi2Error;
    if ((n = checked_state(c, "fmi2SetFMUstate", state)) == NULL) return fmi2Error;
    c->b = n->b;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component comp, fmi2FMUstate *state) {
    Instance *c = (Instance *)comp;
    StateNode **at;
    if (c == NULL || state == NULL) return fmi2Error;
    if (*state == NULL) return fmi2OK;
    for (at = &c->states; *at != NULL; at = &(*at)->next) {
        if ((void *)*at == (void *)*state) {
            StateNode *n = *at;
            *at = n->next;
            c->cb.freeMemory(n);
            *state = NULL;
            return fmi2OK;
        }
    }
    checked_state(c, "fmi2FreeFMUstate", *state); /* logs why */
    return fmi2Error;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component comp, fmi2FMUstate state, size_t *size) {
    Instance *c = (Instance *)comp;
    if (c == NULL || size == NULL) return fmi2Error;
    if (checked_state(c, "fmi2SerializedFMUstateSize", state) == NULL) return fmi2Error;
    *size = SERIAL_SIZE;
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component comp, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size) {
    Instance *c = (Instance *)comp;
    StateNode *n;
    unsigned char *out = (unsigned char *)bytes;
    if (c == NULL) return fmi2Error;
    if ((n = checked_state(c, "fmi2SerializeFMUstate", state)) == NULL) return fmi2Error;
    if (bytes == NULL || size < SERIAL_SIZE) {
        LOG_ERROR(c, "fmi2SerializeFMUstate: buffer of %zu bytes, %zu needed", size,
                  (size_t)SERIAL_SIZE);
        return fmi2Error;
    }
    serial_id(out);
    put_u64(out + SERIAL_ID, sizeof(Block));
    memcpy(out + SERIAL_HEADER, &n->b, sizeof(Block));
    put_u64(out + SERIAL_ID + 8, checksum(out + SERIAL_HEADER, sizeof(Block)));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component comp, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state) {
    Instance *c = (Instance *)comp;
    const unsigned char *in = (const unsigned char *)bytes;
    unsigned char id[SERIAL_ID];
    Block block;
    StateNode *n;
    if (c == NULL || state == NULL) return fmi2Error;
    serial_id(id);
    if (bytes == NULL || size < SERIAL_HEADER || memcmp(in, id, SERIAL_ID) != 0) {
        LOG_ERROR(c, "fmi2DeSerializeFMUstate: not a serialized state of %s (GUID %s)",
                  MODEL_NAME, MODEL_GUID);
        return fmi2Error;
    }
    if (get_u64(in + SERIAL_ID) != sizeof(Block) || size < SERIAL_SIZE) {
        /* a longer buffer is allowed (the host's size is its buffer's): the state is whole */
        LOG_ERROR(c, "fmi2DeSerializeFMUstate: a state of %s holds %zu bytes; this one says "
                  "%llu and has %zu (truncated, or of another build)", MODEL_NAME,
                  (size_t)SERIAL_SIZE, (unsigned long long)get_u64(in + SERIAL_ID) +
                  SERIAL_HEADER, size);
        return fmi2Error;
    }
    if (get_u64(in + SERIAL_ID + 8) != checksum(in + SERIAL_HEADER, sizeof(Block))) {
        LOG_ERROR(c, "fmi2DeSerializeFMUstate: the state's checksum does not match its body "
                  "(the bytes were altered after fmi2SerializeFMUstate wrote them)");
        return fmi2Error;
    }
    memcpy(&block, in + SERIAL_HEADER, sizeof(Block));
    if (block.magic != BLOCK_MAGIC || strncmp(block.guid, MODEL_GUID, sizeof block.guid) != 0) {
        LOG_ERROR(c, "fmi2DeSerializeFMUstate: not a serialized state of %s (GUID %s)",
                  MODEL_NAME, MODEL_GUID);
        return fmi2Error;
    }
    if ((n = new_state(c, "fmi2DeSerializeFMUstate", &block)) == NULL) return fmi2Error;
    *state = n;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component comp, const fmi2ValueReference u[],
                                        size_t nu, const fmi2ValueReference z[], size_t nz,
                                        const fmi2Real dv[], fmi2Real dz[]) {
    (void)u, (void)nu, (void)z, (void)nz, (void)dv, (void)dz;
    LOG_ERROR((Instance *)comp, "fmi2GetDirectionalDerivative: not provided by %s (use the "
              "CasADi Jacobian Functions of wheelterrain)", MODEL_NAME);
    return fmi2Error;
}

/* ---- co-simulation ---------------------------------------------------------------------- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                       size_t n, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    (void)vr, (void)n, (void)order, (void)value;
    LOG_ERROR((Instance *)comp, "fmi2SetRealInputDerivatives: %s does not interpolate inputs",
              MODEL_NAME);
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component comp, const fmi2ValueReference vr[],
                                        size_t n, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)vr, (void)n, (void)order, (void)value;
    LOG_ERROR((Instance *)comp, "fmi2GetRealOutputDerivatives: not provided by %s", MODEL_NAME);
    return fmi2Error;
}

fmi2Status fmi2DoStep(fmi2Component comp, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Instance *c = (Instance *)comp;
    (void)noSetPrior;
    if (!allowed(c, "fmi2DoStep", S_STEP_COMPLETE)) return fmi2Error;
    if (!(h > 0.0) || !isfinite(h) || !isfinite(t)) {
        LOG_ERROR(c, "fmi2DoStep: communication step %g at t = %g must be finite and > 0", h, t);
        return fmi2Error;
    }
    if (fabs(t - c->b.time) > 1e-9 * fmax(1.0, fabs(t))) {
        LOG_ERROR(c, "fmi2DoStep: the step starts at t = %.17g but the last one ended at "
                  "t = %.17g; steps must continue from the last step's end", t, c->b.time);
        return fmi2Error;
    }
    if (MODEL_CHECKS_AT_STEP_END && c->b.dirty && !any_invalid(c, 0)) {
        /* Not evaluated since the last set: step, then evaluate once, at the step's end (what
           the master reads next), so a set + doStep + get costs one evaluation. The model's
           refusals depend on its inputs, not on its state; a refused step is not taken. */
        double start[AT_LEAST_ONE(N_STATES)];
        memcpy(start, c->b.s, sizeof start);
        model_step(c, t, h);
        refresh(c);
        if (c->b.operating_error) {
            memcpy(c->b.s, start, sizeof start);
            LOG_DISCARD(c, "%s: step refused: %s", MODEL_NAME, c->b.operating_message);
            return fmi2Discard;
        }
        c->b.time = t + h;
        return fmi2OK;
    }
    refresh(c);
    if (any_invalid(c, 1)) return fmi2Discard;
    if (c->b.operating_error) {
        /* a refusal from the model's own state (MODEL_STATE_REFUSALS_ARE_FINAL) comes back at
           every later step: the simulation cannot go on, and fmi2Terminated says so (a master
           that only retries a Discard would retry forever) */
        c->b.terminated = MODEL_STATE_REFUSALS_ARE_FINAL;
        LOG_DISCARD(c, "%s: step refused%s: %s", MODEL_NAME,
                    c->b.terminated ? " and the simulation terminated (reset, or set an "
                                      "earlier FMU state, to go on)" : "",
                    c->b.operating_message);
        return fmi2Discard;
    }
    model_step(c, t, h);
    c->b.time = t + h;
    c->b.dirty = 1;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component comp) {
    LOG_ERROR((Instance *)comp, "fmi2CancelStep: %s steps synchronously", MODEL_NAME);
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Status *value) {
    (void)comp, (void)s;
    *value = fmi2OK;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Real *value) {
    Instance *c = (Instance *)comp;
    if (s == fmi2LastSuccessfulTime) {
        *value = c->b.time;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Integer *v) {
    (void)comp, (void)s, (void)v;
    return fmi2Discard;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component comp, const fmi2StatusKind s, fmi2Boolean *v) {
    Instance *c = (Instance *)comp;
    if (s == fmi2Terminated && c != NULL) {
        *v = c->b.terminated ? fmi2True : fmi2False;
        return fmi2OK;
    }
    return fmi2Discard;
}

fmi2Status fmi2GetStringStatus(fmi2Component comp, const fmi2StatusKind s, fmi2String *v) {
    (void)comp, (void)s, (void)v;
    return fmi2Discard;
}

/* ---- model exchange ------------------------------------------------------------------------ */

#define ME_MODES (S_EVENT | S_CONTINUOUS)

static int check_size(Instance *c, const char *function, size_t n, size_t expected) {
    if (n == expected) return 1;
    LOG_ERROR(c, "%s: %s has %u continuous states (and no event indicators); %u asked for",
              function, MODEL_NAME, (unsigned)expected, (unsigned)n);
    return 0;
}

fmi2Status fmi2EnterEventMode(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2EnterEventMode", ME_MODES)) return fmi2Error;
    c->b.mode = S_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component comp, fmi2EventInfo *info) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2NewDiscreteStates", S_EVENT)) return fmi2Error;
    info->newDiscreteStatesNeeded = fmi2False;
    info->terminateSimulation = fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = fmi2False;
    info->nextEventTimeDefined = fmi2False;
    info->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component comp) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2EnterContinuousTimeMode", S_EVENT)) return fmi2Error;
    c->b.mode = S_CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component comp, fmi2Boolean noSetPrior,
                                       fmi2Boolean *enterEventMode,
                                       fmi2Boolean *terminateSimulation) {
    Instance *c = (Instance *)comp;
    (void)noSetPrior;
    if (!allowed(c, "fmi2CompletedIntegratorStep", S_CONTINUOUS)) return fmi2Error;
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component comp, fmi2Real time) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SetTime", S_INSTANTIATED | S_INITIALIZATION | ME_MODES))
        return fmi2Error;
    if (!isfinite(time)) {
        LOG_ERROR(c, "fmi2SetTime: time %g must be finite", time);
        return fmi2Error;
    }
    c->b.time = time; /* the model is autonomous: time changes no value */
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component comp, const fmi2Real x[], size_t nx) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2SetContinuousStates", S_INITIALIZATION | ME_MODES)) return fmi2Error;
    if (!check_size(c, "fmi2SetContinuousStates", nx, N_CONTINUOUS)) return fmi2Error;
    for (size_t k = 0; k < nx; k++) {
        if (!isfinite(x[k])) {
            LOG_ERROR(c, "fmi2SetContinuousStates: %s = %g must be finite",
                      VARS[STATE_VRS[k]].name, x[k]);
            return fmi2Error;
        }
    }
    for (size_t k = 0; k < nx; k++) c->b.s[k] = x[k];
    c->b.dirty = 1;
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component comp, fmi2Real dx[], size_t nx) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetDerivatives", GETTABLE)) return fmi2Error;
    if (!check_size(c, "fmi2GetDerivatives", nx, N_CONTINUOUS)) return fmi2Error;
    refresh(c);
    if (any_invalid(c, 0) || c->b.operating_error) {
        LOG_ERROR(c, "%s: fmi2GetDerivatives: refused: %s", MODEL_NAME,
                  c->b.operating_error ? c->b.operating_message
                                       : "a value set is invalid (see the error logged then)");
        return fmi2Error;
    }
    for (size_t k = 0; k < nx; k++) dx[k] = c->b.v[DER_VRS[k]];
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component comp, fmi2Real indicators[], size_t ni) {
    Instance *c = (Instance *)comp;
    (void)indicators;
    if (!allowed(c, "fmi2GetEventIndicators", GETTABLE)) return fmi2Error;
    if (ni != 0) {
        LOG_ERROR(c, "fmi2GetEventIndicators: %s has no event indicators; %u asked for",
                  MODEL_NAME, (unsigned)ni);
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component comp, fmi2Real x[], size_t nx) {
    Instance *c = (Instance *)comp;
    if (!allowed(c, "fmi2GetContinuousStates", GETTABLE)) return fmi2Error;
    if (!check_size(c, "fmi2GetContinuousStates", nx, N_CONTINUOUS)) return fmi2Error;
    for (size_t k = 0; k < nx; k++) x[k] = c->b.s[k];
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component comp, fmi2Real x_nominal[],
                                             size_t nx) {
    Instance *c = (Instance *)comp;
    if (c == NULL) return fmi2Error;
    if (!check_size(c, "fmi2GetNominalsOfContinuousStates", nx, N_CONTINUOUS)) return fmi2Error;
    for (size_t k = 0; k < nx; k++) x_nominal[k] = NOMINALS[k];
    return fmi2OK;
}

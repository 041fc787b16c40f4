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
 *     (every %XX) before pythonfmu sees it, naming this FMU's resources folder (pythonfmu
 *     crashed the host on a folder that does not exist or is not resources/);
 *   - the FMI 2 co-simulation call sequence (fmi2Error and a logged reason when violated);
 *   - value references: each must name a variable of the called type; outputs cannot be set;
 *   - Real and Integer values against the declared ranges (fmi2Error, as the native flavour);
 *     a value refused at set time makes fmi2ExitInitializationMode refuse too;
 *   - doStep: a finite step h > 0 from the end of the last step (fmi2Error otherwise);
 *     fmi2Terminated only where a refusal is final (the state models' own state);
 *   - outputs: a non-finite value is never served as fmi2OK (fmi2Warning, with the reason);
 *   - messages: pythonfmu logs through the guard, which passes warnings, discards and errors
 *     to the host whatever its logging flag (FMI's status rules), other messages when on;
 *   - FMU states: the guard owns them (a pointer it did not make is refused); serialized
 *     states carry this model's GUID, their length and a checksum, so another model's, a
 *     truncated or an overwritten state is refused before pythonfmu reads it;
 *   - fmi2Fatal (a Python exception escaped the slave): every later call but fmi2FreeInstance
 *     is refused with the reason (pythonfmu's next call crashed the host);
 *   - process exit: a host that exits without freeing its instances (a C host whose
 *     interpreter pythonfmu started) gets them freed before CasADi's static destructors run.
 * Compiled with the generated guard_vars.h (GUARD_NAME, GUARD_GUID, GUARD_VARS: the same
 * variable table as the modelDescription).
 */
#define _GNU_SOURCE /* dladdr */
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

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
    const char *undefined; /* an output the model leaves undefined (NaN) at some points: its
                              description, which says where; else NULL */
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
#define STATE_ID 128 /* the tag and the GUID, zero-padded */
/* A serialized state: the id, then the body's length and an FNV-1a checksum of what follows
   them (the guard's time and terminated flag, then pythonfmu's bytes), all little-endian. */
#define STATE_HEADER (STATE_ID + 8 + 8 + 8 + 8)

typedef struct Guard {
    fmi2Component real;
    int mode;
    fmi2CallbackFunctions cb;     /* the host's */
    fmi2CallbackFunctions py_cb;  /* what pythonfmu gets: its messages pass through the guard */
    int logging_on;               /* the host's debug logging flag */
    int fatal;                    /* a call ended in fmi2Fatal: only fmi2FreeInstance is legal */
    char name[128];
    unsigned char invalid[GUARD_N_VARS];
    double refused[GUARD_N_VARS]; /* the refused value, for the message */
    double time;                  /* the end of the last step (the next one starts there) */
    int terminated;               /* a final refusal: fmi2Terminated */
    char reason[512];             /* the last error or discard pythonfmu logged */
    struct Guard *next;           /* the live instances of this library */
} Guard;

/* A state the guard made: pythonfmu's, plus what the guard itself keeps. */
typedef struct GuardState {
    fmi2FMUstate real;
    double time;
    int terminated;
    struct GuardState *next; /* every state this library made and has not freed */
} GuardState;

static Guard *live_instances;
static GuardState *live_states;
/* the two lists above are the library's, shared by its instances, which a host may call from
   several threads */
static pthread_mutex_t lists = PTHREAD_MUTEX_INITIALIZER;

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

/* A message that goes with the status returned through the host's logger (always: a warning
   or an error reaches the host whatever the logging flag), the text's '%' doubled (the
   logger's message is a format string). */
static void pass_text(const fmi2CallbackFunctions *cb, const char *name, fmi2Status status,
                      const char *category, const char *text) {
    char escaped[2048];
    size_t j = 0;
    if (cb == NULL || cb->logger == NULL) return;
    for (size_t i = 0; text[i] != '\0' && j + 2 < sizeof escaped; i++) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    cb->logger(cb->componentEnvironment, name, status, category, escaped);
}

static void vlog_status(const fmi2CallbackFunctions *cb, const char *name, fmi2Status status,
                        const char *fmt, va_list ap) {
    char text[1024];
    vsnprintf(text, sizeof text, fmt, ap);
    pass_text(cb, name, status, status == fmi2Warning ? "logStatusWarning" : "logStatusError",
              text);
}

static void log_error(const fmi2CallbackFunctions *cb, const char *name, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vlog_status(cb, name, fmi2Error, fmt, ap);
    va_end(ap);
}

static void log_warning(const fmi2CallbackFunctions *cb, const char *name, const char *fmt,
                        ...) {
    va_list ap;
    va_start(ap, fmt);
    vlog_status(cb, name, fmi2Warning, fmt, ap);
    va_end(ap);
}

#define GUARD_ERROR(g, ...) log_error(&(g)->cb, (g)->name, __VA_ARGS__)
#define GUARD_WARNING(g, ...) log_warning(&(g)->cb, (g)->name, __VA_ARGS__)

/* pythonfmu's messages, on their way to the host: pythonfmu logs everything to the guard (its
   logging is kept on), the guard passes a warning, discard or error always and any other
   message when the host turned logging on; it keeps the last error or discard (the reason a
   step was refused) for its own messages. */
static void relay(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                  fmi2String category, fmi2String message, ...) {
    Guard *g = (Guard *)env;
    if (g == NULL || message == NULL) return;
    if (status == fmi2Error || status == fmi2Discard || status == fmi2Fatal)
        snprintf(g->reason, sizeof g->reason, "%s", message);
    if (status == fmi2OK && !g->logging_on) return;
    pass_text(&g->cb, name, status, category, message); /* pythonfmu's text, '%' doubled */
}

static const char *mode_name(int mode) {
    switch (mode) {
    case M_INSTANTIATED: return "instantiated";
    case M_INITIALIZATION: return "initialization mode";
    case M_STEP_COMPLETE: return "step complete";
    default: return "terminated";
    }
}

/* The status pythonfmu returned, remembered when fmi2Fatal (a Python exception escaped the
   slave: its state is unknown, and pythonfmu's next call crashed the host). */
static fmi2Status kept(Guard *g, fmi2Status status) {
    if (status == fmi2Fatal) g->fatal = 1;
    return status;
}

/* The guard of ``c`` if the call is legal in its mode; else NULL (logged). After fmi2Fatal no
   call but fmi2FreeInstance reaches pythonfmu (FMI 2, 2.1.3: the instance cannot go on). */
static Guard *legal(fmi2Component c, const char *function, int modes) {
    Guard *g = (Guard *)c;
    if (g == NULL) return NULL;
    if (g->fatal) {
        GUARD_ERROR(g, "%s: %s: an earlier call ended in fmi2Fatal (%s); the instance cannot "
                    "go on: free it (fmi2FreeInstance) and instantiate a new one", GUARD_NAME,
                    function, g->reason[0] ? g->reason : "no reason given");
        return NULL;
    }
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

/* 1 if ``folder`` is a pythonfmu FMU's resources folder as pythonfmu reads it: a folder
   holding a readable slavemodule.txt and the slave script it names; else 0, the reason in
   ``why``. pythonfmu 0.7 does not check it and crashed the host (SIGSEGV) in fmi2Instantiate
   on a folder that does not exist or is another (the unzip root given instead). */
static int resources_ok(const char *folder, char *why, size_t size) {
    struct stat st;
    char path[4400], module[256];
    size_t n;
    FILE *f;
    if (stat(folder, &st) != 0) {
        snprintf(why, size, "the resource folder %s does not exist", folder);
        return 0;
    }
    if (!S_ISDIR(st.st_mode)) {
        snprintf(why, size, "the resource location %s is not a folder", folder);
        return 0;
    }
    snprintf(path, sizeof path, "%s/slavemodule.txt", folder);
    if ((f = fopen(path, "r")) == NULL) {
        snprintf(why, size, "%s holds no readable slavemodule.txt: it is not this FMU's "
                 "resources folder (give the unzipped FMU's resources/ folder)", folder);
        return 0;
    }
    n = fread(module, 1, sizeof module - 1, f);
    fclose(f);
    while (n > 0 && (module[n - 1] == '\n' || module[n - 1] == '\r' || module[n - 1] == ' '))
        n--;
    module[n] = '\0';
    snprintf(path, sizeof path, "%s/%s.py", folder, module);
    if (n == 0 || access(path, R_OK) != 0) {
        snprintf(why, size, "the slave script %s.py named by %s/slavemodule.txt is missing or "
                 "unreadable", module, folder);
        return 0;
    }
    return 1;
}

/* ---- the FMI 2 functions --------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

/* At process exit, free the instances the host did not free, while the interpreter pythonfmu
   started and CasADi are whole. Registered at the first instantiation, after pythonfmu's
   library and (through Python) CasADi were loaded, so it runs before their static destructors
   (exit runs handlers in the reverse order of registration); a host that exits without
   fmi2FreeInstance aborted there ("pure virtual method called"). A Python host has finalised
   its interpreter before: the instances are then left as they are. */
static void free_at_exit(void) {
    int (*initialized)(void) = NULL;
    *(void **)&initialized = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    if (initialized == NULL || !initialized()) return;
    for (;;) {
        Guard *g;
        pthread_mutex_lock(&lists);
        g = live_instances;
        if (g != NULL) live_instances = g->next;
        pthread_mutex_unlock(&lists);
        if (g == NULL) return;
        F.free_instance(g->real);
        free(g);
    }
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *callbacks,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    static int exit_handler;
    char uri[4096], why[8600];
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
    if (strstr(uri, "%20") != NULL) {
        log_error(callbacks, name, "fmi2Instantiate: %s cannot run from %s: the folder's name "
                  "contains the text '%%20', which pythonfmu 0.7 reads as a space; unzip the "
                  "FMU into a folder whose path has no '%%20' (or use the native flavour)",
                  GUARD_NAME, uri + 7);
        return NULL;
    }
    if (!resources_ok(uri + 7, why, sizeof why)) {
        log_error(callbacks, name, "fmi2Instantiate: %s: %s (resource location '%s')",
                  GUARD_NAME, why, resources);
        return NULL;
    }
    if ((problem = load_library()) != NULL) {
        log_error(callbacks, name, "fmi2Instantiate: %s: %s", GUARD_NAME, problem);
        return NULL;
    }
    g = (Guard *)calloc(1, sizeof(Guard));
    if (g == NULL) return NULL;
    g->cb = *callbacks;
    g->py_cb = *callbacks;
    g->py_cb.logger = relay;
    g->py_cb.componentEnvironment = g;
    g->logging_on = loggingOn;
    snprintf(g->name, sizeof g->name, "%s", name);
    /* pythonfmu's logging stays on: the guard decides what reaches the host (relay) */
    g->real = F.instantiate(name, type, guid, uri, &g->py_cb, visible, fmi2True);
    if (g->real == NULL) {
        free(g);
        return NULL;
    }
    g->mode = M_INSTANTIATED;
    pthread_mutex_lock(&lists);
    g->next = live_instances;
    live_instances = g;
    if (!exit_handler) exit_handler = atexit(free_at_exit) == 0;
    pthread_mutex_unlock(&lists);
    return g;
}

void fmi2FreeInstance(fmi2Component c) {
    Guard *g = (Guard *)c;
    if (g == NULL) return;
    pthread_mutex_lock(&lists);
    for (Guard **p = &live_instances; *p != NULL; p = &(*p)->next) {
        if (*p == g) {
            *p = g->next;
            break;
        }
    }
    pthread_mutex_unlock(&lists);
    F.free_instance(g->real);
    free(g);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n,
                               const fmi2String categories[]) {
    Guard *g = legal(c, "fmi2SetDebugLogging", M_ANY);
    if (g == NULL) return fmi2Error;
    g->logging_on = on;
    /* logging off for the host: pythonfmu still logs every category to the guard (relay) */
    return on ? kept(g, F.set_debug_logging(g->real, on, n, categories))
              : kept(g, F.set_debug_logging(g->real, fmi2True, 0, NULL));
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    Guard *g = legal(c, "fmi2SetupExperiment", M_INSTANTIATED);
    if (g == NULL) return fmi2Error;
    if (!isfinite(startTime)) {
        GUARD_ERROR(g, "fmi2SetupExperiment: start time %g must be finite", startTime);
        return fmi2Error;
    }
    g->time = startTime;
    return kept(g, F.setup_experiment(g->real, toleranceDefined, tolerance, startTime,
                                      stopTimeDefined, stopTime));
}

/* ``status`` of a call that moves the instance to ``mode`` when it succeeds. */
static fmi2Status moved(Guard *g, fmi2Status status, int mode) {
    if (status <= fmi2Warning) g->mode = mode;
    return status;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Guard *g = legal(c, "fmi2EnterInitializationMode", M_INSTANTIATED);
    return g ? moved(g, kept(g, F.enter_initialization(g->real)), M_INITIALIZATION)
             : fmi2Error;
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
    return moved(g, kept(g, F.exit_initialization(g->real)), M_STEP_COMPLETE);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    Guard *g = legal(c, "fmi2Terminate", M_STEP_COMPLETE);
    return g ? moved(g, kept(g, F.terminate(g->real)), M_TERMINATED) : fmi2Error;
}

fmi2Status fmi2Reset(fmi2Component c) {
    Guard *g = legal(c, "fmi2Reset", M_ANY);
    fmi2Status status;
    if (g == NULL) return fmi2Error;
    status = moved(g, kept(g, F.reset(g->real)), M_INSTANTIATED);
    if (status <= fmi2Warning) {
        memset(g->invalid, 0, sizeof g->invalid);
        g->time = 0.0;
        g->terminated = 0;
    }
    return status;
}

#define GETTER(NAME, TYPE, GTYPE, FIELD)                                                     \
    fmi2Status NAME(fmi2Component c, const fmi2ValueReference vr[], size_t n, TYPE value[]) { \
        Guard *g = legal(c, #NAME, M_GETTABLE);                                              \
        if (g == NULL || !references_ok(g, #NAME, vr, n, GTYPE, 0)) return fmi2Error;        \
        return kept(g, F.FIELD(g->real, vr, n, value));                                      \
    }
GETTER(fmi2GetInteger, fmi2Integer, G_INTEGER, get_integer)
GETTER(fmi2GetBoolean, fmi2Boolean, G_BOOLEAN, get_boolean)
#undef GETTER

/* Real values: a value that is not finite is never served as fmi2OK. An output the model
   leaves undefined at this point (e.g. the paper's slip with the carriage at rest) is NaN with
   fmi2Warning and its description (logged by the slave); any other is NaN only where the
   model has had no valid operating point yet (every evaluation so far refused; pythonfmu
   keeps the last valid outputs once there is one): fmi2Warning, saying so and why. */
fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       fmi2Real value[]) {
    Guard *g = legal(c, "fmi2GetReal", M_GETTABLE);
    fmi2Status status;
    if (g == NULL || !references_ok(g, "fmi2GetReal", vr, n, G_REAL, 0)) return fmi2Error;
    status = kept(g, F.get_real(g->real, vr, n, value));
    if (status > fmi2Warning) return status;
    for (size_t i = 0; i < n; i++) {
        const GuardVar *v = &GUARD_VARS[vr[i]];
        if (isfinite(value[i])) continue;
        if (v->undefined != NULL && isnan(value[i])) {
            /* the slave logged why (its getter's warning, relayed to the host) */
        } else {
            GUARD_WARNING(g, "%s: fmi2GetReal: %s has no value (%g): no valid operating point "
                          "yet, every evaluation so far was refused%s%s", GUARD_NAME, v->name,
                          value[i], g->reason[0] ? "; the last reason: " : "", g->reason);
        }
        status = fmi2Warning;
        break;
    }
    return status;
}

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
        status = kept(g, F.FIELD(g->real, vr, n, value));                                    \
        return ok ? status : fmi2Error;                                                      \
    }
SETTER(fmi2SetReal, fmi2Real, G_REAL, set_real)
SETTER(fmi2SetInteger, fmi2Integer, G_INTEGER, set_integer)
#undef SETTER

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Boolean value[]) {
    Guard *g = legal(c, "fmi2SetBoolean", M_SETTABLE);
    if (g == NULL || !references_ok(g, "fmi2SetBoolean", vr, n, G_BOOLEAN, 1)) return fmi2Error;
    return kept(g, F.set_boolean(g->real, vr, n, value));
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

/* ``state`` if this library made it and has not freed it (found by its address alone: a
   pointer of another model's library, or a freed one, is never read); else NULL. */
static GuardState *own_state(fmi2FMUstate state) {
    GuardState *found = NULL;
    pthread_mutex_lock(&lists);
    for (GuardState *s = live_states; s != NULL && found == NULL; s = s->next)
        if ((void *)s == state) found = s;
    pthread_mutex_unlock(&lists);
    return found;
}

static GuardState *new_state(void) {
    GuardState *s = (GuardState *)calloc(1, sizeof(GuardState));
    if (s == NULL) return NULL;
    pthread_mutex_lock(&lists);
    s->next = live_states;
    live_states = s;
    pthread_mutex_unlock(&lists);
    return s;
}

static void drop_state(GuardState *s) {
    pthread_mutex_lock(&lists);
    for (GuardState **p = &live_states; *p != NULL; p = &(*p)->next) {
        if (*p == s) {
            *p = s->next;
            break;
        }
    }
    pthread_mutex_unlock(&lists);
    free(s);
}

/* The guard's state of ``state`` for ``function``, or NULL (logged): another model's state, a
   freed one, or not a state at all. */
static GuardState *known_state(Guard *g, const char *function, fmi2FMUstate state) {
    GuardState *s = own_state(state);
    if (s == NULL)
        GUARD_ERROR(g, "%s: this FMU state was not made by %s's fmi2GetFMUstate or "
                    "fmi2DeSerializeFMUstate, or has been freed (another model's state?)",
                    function, GUARD_NAME);
    return s;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Guard *g = legal(c, "fmi2GetFMUstate", M_ANY);
    GuardState *s;
    fmi2Status status;
    if (g == NULL || state == NULL) return fmi2Error;
    if (*state != NULL) { /* update a state made before */
        if ((s = known_state(g, "fmi2GetFMUstate", *state)) == NULL) return fmi2Error;
    } else if ((s = new_state()) == NULL) {
        GUARD_ERROR(g, "fmi2GetFMUstate: out of memory");
        return fmi2Error;
    }
    status = kept(g, F.get_state(g->real, &s->real));
    if (status > fmi2Warning) {
        if (*state == NULL) drop_state(s);
        return status;
    }
    s->time = g->time;
    s->terminated = g->terminated;
    *state = s;
    return status;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    Guard *g = legal(c, "fmi2SetFMUstate", M_ANY);
    GuardState *s;
    fmi2Status status;
    if (g == NULL || (s = known_state(g, "fmi2SetFMUstate", state)) == NULL) return fmi2Error;
    status = kept(g, F.set_state(g->real, s->real));
    if (status <= fmi2Warning) {
        g->time = s->time;
        g->terminated = s->terminated;
    }
    return status;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    Guard *g = legal(c, "fmi2FreeFMUstate", M_ANY);
    GuardState *s;
    fmi2Status status;
    if (g == NULL || state == NULL) return fmi2Error;
    if (*state == NULL) return fmi2OK; /* nothing to free */
    if ((s = known_state(g, "fmi2FreeFMUstate", *state)) == NULL) return fmi2Error;
    status = kept(g, F.free_state(g->real, &s->real));
    drop_state(s);
    *state = NULL;
    return status;
}

static void put_u64(fmi2Byte *p, unsigned long long x) {
    for (int k = 0; k < 8; k++) p[k] = (fmi2Byte)((x >> (8 * k)) & 0xffu);
}

static unsigned long long get_u64(const fmi2Byte *p) {
    unsigned long long x = 0;
    for (int k = 0; k < 8; k++) x |= (unsigned long long)(unsigned char)p[k] << (8 * k);
    return x;
}

/* FNV-1a, 64 bits: a checksum that finds a changed or truncated byte (not a defence against
   forgery: a host that rewrites a state on purpose owns the result). */
static unsigned long long checksum(const fmi2Byte *p, size_t n) {
    unsigned long long h = 14695981039346656037ull;
    for (size_t i = 0; i < n; i++) {
        h ^= (unsigned char)p[i];
        h *= 1099511628211ull;
    }
    return h;
}

static void state_id(char id[STATE_ID]) {
    memset(id, 0, STATE_ID);
    snprintf(id, STATE_ID, "%s%s", STATE_TAG, GUARD_GUID);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    Guard *g = legal(c, "fmi2SerializedFMUstateSize", M_ANY);
    GuardState *s;
    fmi2Status status;
    if (g == NULL || size == NULL) return fmi2Error;
    if ((s = known_state(g, "fmi2SerializedFMUstateSize", state)) == NULL) return fmi2Error;
    status = kept(g, F.state_size(g->real, s->real, size));
    if (status <= fmi2Warning) *size += STATE_HEADER;
    return status;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                 size_t size) {
    Guard *g = legal(c, "fmi2SerializeFMUstate", M_ANY);
    GuardState *s;
    size_t body;
    fmi2Status status;
    if (g == NULL || (s = known_state(g, "fmi2SerializeFMUstate", state)) == NULL)
        return fmi2Error;
    if (kept(g, F.state_size(g->real, s->real, &body)) > fmi2Warning) return fmi2Error;
    if (bytes == NULL || size < body + STATE_HEADER) {
        GUARD_ERROR(g, "fmi2SerializeFMUstate: %u bytes given for a state of %u bytes (see "
                    "fmi2SerializedFMUstateSize)", (unsigned)size,
                    (unsigned)(body + STATE_HEADER));
        return fmi2Error;
    }
    state_id(bytes);
    put_u64(bytes + STATE_ID, (unsigned long long)body);
    memcpy(bytes + STATE_ID + 16, &s->time, 8);
    put_u64(bytes + STATE_ID + 24, (unsigned long long)s->terminated);
    status = kept(g, F.serialize(g->real, s->real, bytes + STATE_HEADER, body));
    put_u64(bytes + STATE_ID + 8, checksum(bytes + STATE_ID + 16, 16 + body));
    return status;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                   fmi2FMUstate *state) {
    Guard *g = legal(c, "fmi2DeSerializeFMUstate", M_ANY);
    char expected[STATE_ID];
    GuardState *s, *reused = NULL;
    unsigned long long body;
    fmi2Status status;
    if (g == NULL || state == NULL) return fmi2Error;
    state_id(expected);
    if (bytes == NULL || size < STATE_HEADER || memcmp(bytes, expected, STATE_ID) != 0) {
        GUARD_ERROR(g, "fmi2DeSerializeFMUstate: these %u bytes are not a state of %s (GUID "
                    "%s): another model's, another build's, or not a state", (unsigned)size,
                    GUARD_NAME, GUARD_GUID);
        return fmi2Error;
    }
    body = get_u64(bytes + STATE_ID);
    if (body > size - STATE_HEADER) {
        GUARD_ERROR(g, "fmi2DeSerializeFMUstate: the state of %s is %llu bytes long and %u "
                    "were given: truncated", GUARD_NAME, body + STATE_HEADER, (unsigned)size);
        return fmi2Error;
    }
    if (get_u64(bytes + STATE_ID + 8) != checksum(bytes + STATE_ID + 16, 16 + (size_t)body)) {
        GUARD_ERROR(g, "fmi2DeSerializeFMUstate: the state's bytes do not match its checksum "
                    "(changed since fmi2SerializeFMUstate wrote them)");
        return fmi2Error;
    }
    if (*state != NULL && (reused = known_state(g, "fmi2DeSerializeFMUstate", *state)) == NULL)
        return fmi2Error;
    if ((s = reused ? reused : new_state()) == NULL) {
        GUARD_ERROR(g, "fmi2DeSerializeFMUstate: out of memory");
        return fmi2Error;
    }
    if (reused && s->real != NULL) {
        kept(g, F.free_state(g->real, &s->real));
        s->real = NULL;
    }
    status = kept(g, F.deserialize(g->real, bytes + STATE_HEADER, (size_t)body, &s->real));
    if (status > fmi2Warning) {
        drop_state(s);
        if (reused) *state = NULL;
        return status;
    }
    memcpy(&s->time, bytes + STATE_ID + 16, 8);
    s->terminated = get_u64(bytes + STATE_ID + 24) != 0;
    *state = s;
    return status;
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

/* A step the host asks for wrongly is an error of the host (fmi2Error); a step the model
   refuses is fmi2Discard, and final (fmi2Terminated) only where it comes from the model's own
   state with every value valid: a state model's, as the native flavour. */
fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Guard *g = legal(c, "fmi2DoStep", M_STEP_COMPLETE);
    fmi2Status status;
    int invalid = 0;
    if (g == NULL) return fmi2Error;
    if (!(h > 0.0) || !isfinite(h) || !isfinite(t)) {
        GUARD_ERROR(g, "fmi2DoStep: communication step %g at t = %g must be finite and > 0", h,
                    t);
        return fmi2Error;
    }
    if (fabs(t - g->time) > 1e-9 * fmax(1.0, fabs(t))) {
        GUARD_ERROR(g, "fmi2DoStep: the step starts at t = %.17g but the last one ended at "
                    "t = %.17g; steps must continue from the last step's end", t, g->time);
        return fmi2Error;
    }
    g->reason[0] = '\0';
    status = kept(g, F.do_step(g->real, t, h, noSetPrior));
    if (status <= fmi2Warning) {
        g->time = t + h;
        g->terminated = 0;
    } else if (status == fmi2Discard) {
        for (int k = 0; k < GUARD_N_VARS; k++) invalid |= g->invalid[k];
        g->terminated = GUARD_STATE_REFUSALS_ARE_FINAL && !invalid;
    }
    return status;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    Guard *g = (Guard *)c;
    if (g) GUARD_ERROR(g, "fmi2CancelStep: %s steps synchronously", GUARD_NAME);
    return fmi2Error;
}

/* The status queries, legal in every mode: fmi2Terminated and fmi2LastSuccessfulTime from the
   guard (pythonfmu answered Terminated true after any refused step, even one the next step
   recovers from), the rest forwarded as they are. */
#define STATUS_QUERY(NAME, TYPE, FIELD)                                                      \
    fmi2Status NAME(fmi2Component c, const fmi2StatusKind s, TYPE *value) {                  \
        Guard *g = legal(c, #NAME, M_ANY);                                                   \
        return g ? kept(g, F.FIELD(g->real, s, value)) : fmi2Error;                          \
    }
STATUS_QUERY(fmi2GetStatus, fmi2Status, get_status)
STATUS_QUERY(fmi2GetIntegerStatus, fmi2Integer, get_integer_status)
STATUS_QUERY(fmi2GetStringStatus, fmi2String, get_string_status)
#undef STATUS_QUERY

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    Guard *g = legal(c, "fmi2GetRealStatus", M_ANY);
    if (g == NULL || value == NULL) return fmi2Error;
    if (s != fmi2LastSuccessfulTime) return kept(g, F.get_real_status(g->real, s, value));
    *value = g->time;
    return fmi2OK;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    Guard *g = (Guard *)c;
    if (g != NULL && g->fatal && s == fmi2Terminated && value != NULL) {
        *value = fmi2True; /* the one question a host may still ask after fmi2Fatal */
        return fmi2OK;
    }
    g = legal(c, "fmi2GetBooleanStatus", M_ANY);
    if (g == NULL || value == NULL) return fmi2Error;
    if (s != fmi2Terminated) return kept(g, F.get_boolean_status(g->real, s, value));
    *value = g->terminated ? fmi2True : fmi2False;
    return fmi2OK;
}

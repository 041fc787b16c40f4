/*
 * A minimal FMI co-simulation host for the native FMUs' binaries, compiled for Linux (dlopen)
 * and cross-compiled for Windows (LoadLibrary; run under Wine) by
 * tests/test_native_platforms.py, so the same steps run through both binaries of an FMU.
 *
 *   fmi_host LIBRARY GUID STEPS H SET RAMP GET [FMI [time]]
 *
 * With FMI = 3 the library is an FMI 3.0 binary (the GUID is its instantiation token); else
 * FMI 2.0. With "time" (FMI 2) nothing is printed per step: the host prints the wall time per
 * step (set, doStep, get) and a checksum of the outputs (benchmarks/fmus.py).
 * SET  "vr=value,..." Real values set before initialisation ("-" for none); "bvr=1" sets
 *      a Boolean (e.g. WheelTerrain's quasi_static), "ivr=0" an Integer (FMI 3: Int32, e.g.
 *      model.contact_form);
 * RAMP "vr=start+slope,..." Real inputs set to start + slope*t before every step ("-");
 * GET  "vr,..." Real values printed after every step, with t, as %.17g.
 * FMI_HOST_RESOURCES, if set, is the resource location passed to instantiate (a file: URI;
 * pythonfmu FMUs need it); else "".
 * FMI_HOST_EXIT (FMI 2) "terminate": return from main after fmi2Terminate without
 * fmi2FreeInstance; "none": without either (as hosts that leave cleanup to the process exit);
 * else both.
 * FMI_HOST_RELOAD (FMI 2), if set: after the first instance is initialised, the library is
 * closed and opened again (as ecos does between two instances of one FMU, the first one alive)
 * and a second instance runs beside the first; every step both must give the same values.
 * Exit status 0 if every call returned fmi2OK, else 1 (the failing call is printed).
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"

#ifdef _WIN32
#include <windows.h>
typedef HMODULE Library;
static Library open_library(const char *path) { return LoadLibraryA(path); }
static void close_library(Library lib) { FreeLibrary(lib); }
static void *symbol(Library lib, const char *name) { return (void *)GetProcAddress(lib, name); }
static double now(void) {
    LARGE_INTEGER count, frequency;
    QueryPerformanceCounter(&count);
    QueryPerformanceFrequency(&frequency);
    return (double)count.QuadPart / (double)frequency.QuadPart;
}
#else
#include <dlfcn.h>
#include <time.h>
typedef void *Library;
static Library open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void close_library(Library lib) { dlclose(lib); }
static void *symbol(Library lib, const char *name) { return dlsym(lib, name); }
static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
#endif

#define MAX_VARS 64

enum { SET_REAL, SET_BOOLEAN, SET_INTEGER }; /* what a SET entry is: "vr=x", "bvr=x", "ivr=x" */

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    fprintf(stderr, "[%s] %s (status %d): %s\n", category, name, (int)status, message);
}

/* "vr=a+b,vr=c+d" or "vr=a,..." or "vr,vr": value references and up to two numbers each */
static int parse(const char *text, fmi2ValueReference *vr, double *a, double *b, int *kind) {
    int n = 0;
    const char *p = text;
    if (strcmp(text, "-") == 0) return 0;
    while (*p && n < MAX_VARS) {
        char *end;
        kind[n] = *p == 'b' ? SET_BOOLEAN : *p == 'i' ? SET_INTEGER : SET_REAL;
        if (kind[n] != SET_REAL) p++;
        vr[n] = (fmi2ValueReference)strtoul(p, &end, 10);
        p = end;
        if (*p == '=') {
            a[n] = strtod(p + 1, &end);
            p = end;
            if (*p == '+') {
                b[n] = strtod(p + 1, &end);
                p = end;
            }
        }
        n++;
        if (*p == ',') p++;
    }
    return n;
}

#define CHECK(call)                                                                          \
    do {                                                                                     \
        if ((int)(call) != 0) { /* fmi2OK, fmi3OK */                                     \
            fprintf(stderr, "%s failed\n", #call);                                           \
            return 1;                                                                        \
        }                                                                                    \
    } while (0)

/* The inputs of a step: start + slope*t. */
static void ramp_at(double t, int n, const double *start, const double *slope, double *values) {
    for (int i = 0; i < n; i++) values[i] = start[i] + slope[i] * t;
}

/* One line of output: t and the values got after the step. */
static void print_row(double t, int n, const double *values) {
    printf("%.17g", t);
    for (int i = 0; i < n; i++) printf(" %.17g", values[i]);
    printf("\n");
}

/* The resource location the host passes: FMI_HOST_RESOURCES or "". */
static const char *resources(void) {
    const char *uri = getenv("FMI_HOST_RESOURCES");
    return uri ? uri : "";
}

static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                    fmi3String message) {
    (void)env;
    fprintf(stderr, "[%s] (status %d): %s\n", category, (int)status, message);
}

/* The same run through the FMI 3.0 API. */
static int run3(Library lib, const char *token, int steps, double h, int n_set,
                const fmi3ValueReference *set_vr, const double *set_value, const int *kind,
                int n_ramp, const fmi3ValueReference *ramp_vr, const double *ramp_start,
                const double *ramp_slope, int n_get, const fmi3ValueReference *get_vr) {
    fmi3InstantiateCoSimulationTYPE *instantiate =
        (fmi3InstantiateCoSimulationTYPE *)symbol(lib, "fmi3InstantiateCoSimulation");
    fmi3EnterInitializationModeTYPE *enter =
        (fmi3EnterInitializationModeTYPE *)symbol(lib, "fmi3EnterInitializationMode");
    fmi3ExitInitializationModeTYPE *leave =
        (fmi3ExitInitializationModeTYPE *)symbol(lib, "fmi3ExitInitializationMode");
    fmi3SetFloat64TYPE *set_real = (fmi3SetFloat64TYPE *)symbol(lib, "fmi3SetFloat64");
    fmi3SetBooleanTYPE *set_boolean = (fmi3SetBooleanTYPE *)symbol(lib, "fmi3SetBoolean");
    fmi3SetInt32TYPE *set_integer = (fmi3SetInt32TYPE *)symbol(lib, "fmi3SetInt32");
    fmi3GetFloat64TYPE *get_real = (fmi3GetFloat64TYPE *)symbol(lib, "fmi3GetFloat64");
    fmi3DoStepTYPE *do_step = (fmi3DoStepTYPE *)symbol(lib, "fmi3DoStep");
    fmi3TerminateTYPE *terminate = (fmi3TerminateTYPE *)symbol(lib, "fmi3Terminate");
    fmi3FreeInstanceTYPE *free_instance = (fmi3FreeInstanceTYPE *)symbol(lib,
                                                                         "fmi3FreeInstance");
    fmi3Instance c;
    double out[MAX_VARS], t = 0.0;
    if (!instantiate || !enter || !leave || !set_real || !set_boolean || !set_integer ||
        !get_real || !do_step || !terminate || !free_instance) {
        fprintf(stderr, "the library lacks an fmi3 function\n");
        return 1;
    }
    c = instantiate("host", token, resources(), fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0,
                    NULL, logger3, NULL);
    if (!c) {
        fprintf(stderr, "fmi3InstantiateCoSimulation failed\n");
        return 1;
    }
    CHECK(enter(c, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    for (int i = 0; i < n_set; i++) {
        fmi3Boolean on = set_value[i] != 0.0;
        fmi3Int32 whole = (fmi3Int32)set_value[i];
        if (kind[i] == SET_BOOLEAN) CHECK(set_boolean(c, &set_vr[i], 1, &on, 1));
        else if (kind[i] == SET_INTEGER) CHECK(set_integer(c, &set_vr[i], 1, &whole, 1));
        else CHECK(set_real(c, &set_vr[i], 1, &set_value[i], 1));
    }
    CHECK(leave(c));
    for (int k = 0; k < steps; k++) {
        double ramp[MAX_VARS], last;
        fmi3Boolean event, stop, early;
        ramp_at(t, n_ramp, ramp_start, ramp_slope, ramp);
        if (n_ramp) CHECK(set_real(c, ramp_vr, (size_t)n_ramp, ramp, (size_t)n_ramp));
        CHECK(do_step(c, t, h, fmi3True, &event, &stop, &early, &last));
        t = (k + 1) * h;
        CHECK(get_real(c, get_vr, (size_t)n_get, out, (size_t)n_get));
        print_row(t, n_get, out);
    }
    CHECK(terminate(c));
    free_instance(c);
    return 0;
}

/* The FMI 2 functions the host calls. */
typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *leave;
    fmi2SetRealTYPE *set_real;
    fmi2SetBooleanTYPE *set_boolean;
    fmi2SetIntegerTYPE *set_integer;
    fmi2GetRealTYPE *get_real;
    fmi2DoStepTYPE *do_step;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_instance;
} Fmi2;

/* 1 if ``lib`` has every function of Fmi2. */
static int load2(Library lib, Fmi2 *f) {
    f->instantiate = (fmi2InstantiateTYPE *)symbol(lib, "fmi2Instantiate");
    f->setup = (fmi2SetupExperimentTYPE *)symbol(lib, "fmi2SetupExperiment");
    f->enter = (fmi2EnterInitializationModeTYPE *)symbol(lib, "fmi2EnterInitializationMode");
    f->leave = (fmi2ExitInitializationModeTYPE *)symbol(lib, "fmi2ExitInitializationMode");
    f->set_real = (fmi2SetRealTYPE *)symbol(lib, "fmi2SetReal");
    f->set_boolean = (fmi2SetBooleanTYPE *)symbol(lib, "fmi2SetBoolean");
    f->set_integer = (fmi2SetIntegerTYPE *)symbol(lib, "fmi2SetInteger");
    f->get_real = (fmi2GetRealTYPE *)symbol(lib, "fmi2GetReal");
    f->do_step = (fmi2DoStepTYPE *)symbol(lib, "fmi2DoStep");
    f->terminate = (fmi2TerminateTYPE *)symbol(lib, "fmi2Terminate");
    f->free_instance = (fmi2FreeInstanceTYPE *)symbol(lib, "fmi2FreeInstance");
    return f->instantiate && f->setup && f->enter && f->leave && f->set_real &&
           f->set_boolean && f->set_integer && f->get_real && f->do_step && f->terminate &&
           f->free_instance;
}

#define CHECK_NULL(call)                                                                     \
    do {                                                                                     \
        if ((int)(call) != 0) {                                                              \
            fprintf(stderr, "%s failed\n", #call);                                           \
            return NULL;                                                                     \
        }                                                                                    \
    } while (0)

/* An instance, initialised with the SET values; NULL (said) if a call failed. */
static fmi2Component instantiate2(const Fmi2 *f, const char *name, const char *guid,
                                  const fmi2CallbackFunctions *callbacks, int n_set,
                                  const fmi2ValueReference *set_vr, const double *set_value,
                                  const int *kind) {
    fmi2Component c = f->instantiate(name, fmi2CoSimulation, guid, resources(), callbacks,
                                     fmi2False, fmi2False);
    if (!c) {
        fprintf(stderr, "fmi2Instantiate failed\n");
        return NULL;
    }
    CHECK_NULL(f->setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));
    CHECK_NULL(f->enter(c));
    for (int i = 0; i < n_set; i++) {
        fmi2Boolean on = set_value[i] != 0.0;
        fmi2Integer whole = (fmi2Integer)set_value[i];
        if (kind[i] == SET_BOOLEAN) CHECK_NULL(f->set_boolean(c, &set_vr[i], 1, &on));
        else if (kind[i] == SET_INTEGER) CHECK_NULL(f->set_integer(c, &set_vr[i], 1, &whole));
        else CHECK_NULL(f->set_real(c, &set_vr[i], 1, &set_value[i]));
    }
    CHECK_NULL(f->leave(c));
    return c;
}

int main(int argc, char **argv) {
    const char *exit_mode = getenv("FMI_HOST_EXIT");
    int leave_at_exit = exit_mode == NULL              ? 0
                        : strcmp(exit_mode, "terminate") == 0 ? 1
                        : strcmp(exit_mode, "none") == 0      ? 2
                                                              : 0;
    fmi2ValueReference set_vr[MAX_VARS], ramp_vr[MAX_VARS], get_vr[MAX_VARS];
    double set_value[MAX_VARS], ramp_start[MAX_VARS], ramp_slope[MAX_VARS], unused[MAX_VARS];
    double out[MAX_VARS], t = 0.0, h;
    int n_set, n_ramp, n_get, steps, kind[MAX_VARS], timed;
    double started, checksum = 0.0;
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    Library lib;
    fmi2Component c;

    if (argc < 8 || argc > 10) {
        fprintf(stderr, "usage: %s LIBRARY GUID STEPS H SET RAMP GET [FMI [time]]\n", argv[0]);
        return 2;
    }
    timed = argc == 10 && strcmp(argv[9], "time") == 0;
    lib = open_library(argv[1]);
    if (!lib) {
        fprintf(stderr, "cannot load %s\n", argv[1]);
        return 1;
    }
    steps = atoi(argv[3]);
    h = strtod(argv[4], NULL);
    n_ramp = parse(argv[6], ramp_vr, ramp_start, ramp_slope, kind);
    n_get = parse(argv[7], get_vr, unused, unused, kind);
    n_set = parse(argv[5], set_vr, set_value, unused, kind);
    if (argc >= 9 && strcmp(argv[8], "3") == 0)
        return run3(lib, argv[2], steps, h, n_set, set_vr, set_value, kind, n_ramp, ramp_vr,
                    ramp_start, ramp_slope, n_get, get_vr);
    {
        Fmi2 f;
        fmi2Component c2 = NULL;
        double out2[MAX_VARS];
        if (!load2(lib, &f)) {
            fprintf(stderr, "%s lacks an fmi2 function\n", argv[1]);
            return 1;
        }
        c = instantiate2(&f, "host", argv[2], &callbacks, n_set, set_vr, set_value, kind);
        if (!c) return 1;
        if (getenv("FMI_HOST_RELOAD")) {
            close_library(lib);
            lib = open_library(argv[1]);
            if (!lib || !load2(lib, &f)) {
                fprintf(stderr, "cannot load %s again\n", argv[1]);
                return 1;
            }
            c2 = instantiate2(&f, "host2", argv[2], &callbacks, n_set, set_vr, set_value, kind);
            if (!c2) return 1;
        }
        started = now();
        for (int k = 0; k < steps; k++) {
            double ramp[MAX_VARS];
            ramp_at(t, n_ramp, ramp_start, ramp_slope, ramp);
            if (n_ramp) CHECK(f.set_real(c, ramp_vr, (size_t)n_ramp, ramp));
            CHECK(f.do_step(c, t, h, fmi2True));
            if (c2) {
                if (n_ramp) CHECK(f.set_real(c2, ramp_vr, (size_t)n_ramp, ramp));
                CHECK(f.do_step(c2, t, h, fmi2True));
            }
            t = (k + 1) * h;
            CHECK(f.get_real(c, get_vr, (size_t)n_get, out));
            if (c2) {
                CHECK(f.get_real(c2, get_vr, (size_t)n_get, out2));
                for (int i = 0; i < n_get; i++) {
                    if (out2[i] != out[i]) {
                        fprintf(stderr, "the second instance differs at t = %g: %.17g != "
                                "%.17g\n", t, out2[i], out[i]);
                        return 1;
                    }
                }
            }
            if (timed) {
                for (int i = 0; i < n_get; i++) checksum += out[i];
                continue;
            }
            print_row(t, n_get, out);
        }
        if (timed) printf("%.9g %.17g\n", (now() - started) / steps, checksum);
        if (leave_at_exit == 2) return 0; /* neither fmi2Terminate nor fmi2FreeInstance */
        CHECK(f.terminate(c));
        if (c2) CHECK(f.terminate(c2));
        if (leave_at_exit == 1) return 0; /* terminated, never freed */
        f.free_instance(c);
        if (c2) f.free_instance(c2);
    }
    return 0;
}

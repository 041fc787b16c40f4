/* The rig-terrain co-simulation loop of wheelterrain.cosim.master in C: the same FMI 2 calls in
 * the same order as the master's Python loop (_cosimulate_direct), on the functions and
 * instances fmpy loaded, the FMUs reading and writing the rows of the master's record in place.
 * Compiled once per machine into the cache (wheelterrain.compiled.cached_source); where no C
 * compiler is at hand the master keeps its Python loop, with the same numbers.
 *
 * Per step k (time k*h), the calls in order (CALL_*):
 *   rig's fmi2GetReal of its state outputs into row k of xs,
 *   terrain's fmi2SetReal of its inputs from that row,
 *   terrain's fmi2GetReal of its forces into row k of ys,
 *   rig's fmi2SetReal of its inputs from that row,
 *   below n: rig's fmi2DoStep, then the terrain's.
 * A call that returns more than fmi2Warning stops the loop: the return value is
 * 6*k + call, which the master makes again through fmpy's wrapper (which raises with the FMU's
 * reason) and, if that goes through, resumes at the next call; -1 when all n steps are done. */

#include <stddef.h>

typedef int (*get_real)(void *, const unsigned int *, size_t, double *);
typedef int (*set_real)(void *, const unsigned int *, size_t, const double *);
typedef int (*do_step)(void *, double, double, int);

enum { CALL_RIG_GET, CALL_TER_SET, CALL_TER_GET, CALL_RIG_SET, CALL_RIG_STEP, CALL_TER_STEP,
       CALLS };
#define WARNING 1 /* fmi2Warning: the highest status the master accepts */

long couple(void *rig, get_real rig_get, set_real rig_set, do_step rig_step,
            void *ter, get_real ter_get, set_real ter_set, do_step ter_step,
            const unsigned int *rig_out, size_t n_x, const unsigned int *ter_in, size_t n_in,
            const unsigned int *ter_out, size_t n_y, const unsigned int *rig_in, size_t n_f,
            double *xs, size_t row_x, double *ys, size_t row_y, long n, double h,
            long resume) {
    long k, call;
    for (k = resume / CALLS; k <= n; k++) {
        double *x = xs + k * row_x, *y = ys + k * row_y, t = k * h;
        for (call = k == resume / CALLS ? resume % CALLS : 0; call < CALLS; call++) {
            int status = 0;
            switch (call) {
            case CALL_RIG_GET: status = rig_get(rig, rig_out, n_x, x); break;
            case CALL_TER_SET: status = ter_set(ter, ter_in, n_in, x); break;
            case CALL_TER_GET: status = ter_get(ter, ter_out, n_y, y); break;
            case CALL_RIG_SET: status = rig_set(rig, rig_in, n_f, y); break;
            case CALL_RIG_STEP: if (k < n) status = rig_step(rig, t, h, 1); break;
            case CALL_TER_STEP: if (k < n) status = ter_step(ter, t, h, 1); break;
            }
            if (status > WARNING) return k * CALLS + call;
        }
    }
    return -1;
}

/* The model hooks of a state-space FMU (SingleWheelRig, RoverChassis, Terrain) for fmi2_native.c
 * (copied into the FMU as sources/model_hooks.inc).
 *
 * Values in and out of the CasADi Functions <prefix>_step / _outputs / _initial / _rates
 * (wheelterrain.fmu.functions.StateModel; MODEL_FN(name) names them). States 0..N_X-1 are the
 * model's states (the first N_CONTINUOUS of them the continuous states of model exchange: all
 * of a rig's or a rover's, none of the Terrain's rut profile); states N_X..N_X+N_MEM-1 hold the
 * memory of the last step (the motors' torques). Sizes, value references, the domain check and
 * its messages come from the generated model_vars.h: IN_VRS, OUT_VRS, P_VRS, N_X, N_U, N_P,
 * N_OUT, N_MEM, X_DEPTH, DEPTH_LIMIT, X_NONFINITE_0..2, MESSAGE_DEPTH, MESSAGE_NONFINITE (the
 * last five undefined for a model without states, Terrain: nothing to check). */

/* The model's refusals depend on its state: each step is checked at its start (fmi2DoStep). */
#define MODEL_CHECKS_AT_STEP_END 0
/* the model refuses only a state outside its domain (a depth beyond its range, a non-finite
   state): nothing the master sets brings it back */
#define MODEL_STATE_REFUSALS_ARE_FINAL 1

#define MODEL_FN_CAT2(a, b) a##_##b
#define MODEL_FN_CAT(a, b) MODEL_FN_CAT2(a, b)
#define MODEL_FN(name) MODEL_FN_CAT(MODEL_PREFIX, name)

static void model_work(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw,
                       casadi_int *sz_w) {
    cover(MODEL_FN(step_work), sz_arg, sz_res, sz_iw, sz_w);
    cover(MODEL_FN(outputs_work), sz_arg, sz_res, sz_iw, sz_w);
    cover(MODEL_FN(initial_work), sz_arg, sz_res, sz_iw, sz_w);
    cover(MODEL_FN(rates_work), sz_arg, sz_res, sz_iw, sz_w);
}

static void load_params(Instance *c, casadi_real *p) {
    for (int k = 0; k < N_P; k++) p[k] = c->b.v[P_VRS[k]];
}

/* The arguments <prefix>_outputs and <prefix>_step share: arg[0] the state, arg[1] the inputs
   u, arg[2] the parameters p (u and p are the caller's buffers, filled here). */
static void bind_state_inputs_params(Instance *c, casadi_real *u, casadi_real *p) {
    for (int k = 0; k < N_U; k++) u[k] = c->b.v[IN_VRS[k]];
    load_params(c, p);
    c->arg[0] = c->b.s;
    c->arg[1] = u;
    c->arg[2] = p;
}

static void model_initialize(Instance *c) {
    casadi_real p[N_P];
    load_params(c, p);
    c->arg[0] = p;
    c->res[0] = c->b.s;
    MODEL_FN(initial)(c->arg, c->res, c->iw, c->w, 0);
    for (int k = 0; k < N_MEM; k++) c->b.s[N_X + k] = 0.0;
}

static void model_reset(Instance *c) { model_initialize(c); }

/* The model's own domain (wheelterrain.fmu.functions.StateModel.problem, same checks and
   messages): a state that is not finite, or the depth state beyond DEPTH_LIMIT. */
static int state_problem(const Instance *c, char *message) {
#ifdef X_DEPTH
    const casadi_real *s = c->b.s;
    int k;
    for (k = 0; k < N_X; k++) {
        if (!(fabs(s[k]) < FINITE_LIMIT)) {
            snprintf(message, MAX_MESSAGE, MESSAGE_NONFINITE, s[X_NONFINITE_0],
                     s[X_NONFINITE_1], s[X_NONFINITE_2]);
            return 1;
        }
    }
    if (fabs(s[X_DEPTH]) > DEPTH_LIMIT) {
        snprintf(message, MAX_MESSAGE, MESSAGE_DEPTH, s[X_DEPTH], DEPTH_LIMIT, DEPTH_LIMIT);
        return 1;
    }
#else /* a model without states (X_DEPTH undefined): nothing to check */
    (void)c;
    (void)message;
#endif
    return 0;
}

/* The outputs (<prefix>_outputs) and the derivatives of the states (<prefix>_rates) at the
   current state, inputs and parameters, loaded once. In model exchange the memory (the motor
   torques) is the one of this state and these commands (set from <prefix>_rates first); in
   co-simulation it stays that of the last step. */
static int model_refresh(Instance *c, double *dx, char *message) {
    casadi_real u[N_U], p[N_P], y[N_OUT], memory[AT_LEAST_ONE(N_MEM)];
    casadi_real xdot[AT_LEAST_ONE(N_X)];
    int k;
    if (state_problem(c, message)) return 1;
    bind_state_inputs_params(c, u, p);
    c->res[0] = xdot;
    c->res[1] = memory;
    MODEL_FN(rates)(c->arg, c->res, c->iw, c->w, 0);
    /* the continuous states are the first N_CONTINUOUS (all of a rig's or a rover's; none of
       the Terrain's rut profile, which only a co-simulation step changes) */
    for (k = 0; k < N_CONTINUOUS; k++) dx[k] = xdot[k];
    if (c->model_exchange)
        for (k = 0; k < N_MEM; k++) c->b.s[N_X + k] = memory[k];
    c->arg[3] = &c->b.s[N_X];
    c->res[0] = y;
    MODEL_FN(outputs)(c->arg, c->res, c->iw, c->w, 0);
    for (k = 0; k < N_OUT; k++) c->b.v[OUT_VRS[k]] = y[k];
    return 0;
}

static void model_step(Instance *c, double t, double h) {
    casadi_real u[N_U], p[N_P], x_next[AT_LEAST_ONE(N_X)], memory[AT_LEAST_ONE(N_MEM)];
    int k;
    (void)t;
    bind_state_inputs_params(c, u, p);
    c->arg[3] = &h;
    c->res[0] = x_next;
    c->res[1] = memory;
    MODEL_FN(step)(c->arg, c->res, c->iw, c->w, 0);
    for (k = 0; k < N_X; k++) c->b.s[k] = x_next[k];
    for (k = 0; k < N_MEM; k++) c->b.s[N_X + k] = memory[k];
}

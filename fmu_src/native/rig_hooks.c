/* SingleWheelRig's model hooks for fmi2_native.c (copied into the FMU as
 * sources/model_hooks.inc).
 *
 * Values in and out of the CasADi Functions rig_step / rig_outputs / rig_initial
 * (wheelterrain.model.rig, wheelterrain.fmu.functions). States 0..N_X-1 are the rig's states
 * (wheelterrain.model.rig.RIG_STATES, the continuous states of model exchange); state N_X holds the motor torque of the last step. Sizes and
 * value references come from the generated model_vars.h: IN_VRS, OUT_VRS, P_VRS, N_X, N_U, N_P,
 * N_OUT. */

/* The rig's refusals depend on its state: each step is checked at its start (fmi2DoStep). */
#define MODEL_CHECKS_AT_STEP_END 0
/* the rig refuses only a state outside its domain (sinkage beyond the rig's range,
   a non-finite state): nothing the master sets brings it back */
#define MODEL_STATE_REFUSALS_ARE_FINAL 1

static void model_work(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw,
                       casadi_int *sz_w) {
    cover(rig_step_work, sz_arg, sz_res, sz_iw, sz_w);
    cover(rig_outputs_work, sz_arg, sz_res, sz_iw, sz_w);
    cover(rig_initial_work, sz_arg, sz_res, sz_iw, sz_w);
    cover(rig_rates_work, sz_arg, sz_res, sz_iw, sz_w);
}

static void load_params(Instance *c, casadi_real *p) {
    for (int k = 0; k < N_P; k++) p[k] = c->b.v[P_VRS[k]];
}

/* The arguments rig_outputs and rig_step share: arg[0] the state, arg[1] the inputs u,
   arg[2] the parameters p (u and p are the caller's buffers, filled here). */
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
    rig_initial(c->arg, c->res, c->iw, c->w, 0);
    c->b.s[N_X] = 0.0;
}

static void model_reset(Instance *c) { model_initialize(c); }

/* The rig's own domain (wheelterrain.fmu.functions.rig_state_problem, same checks and
   messages): a state that is not finite, or a sinkage beyond RIG_SINKAGE_LIMIT. */
static int state_problem(const Instance *c, char *message) {
    const casadi_real *s = c->b.s;
    int k;
    for (k = 0; k < N_X; k++) {
        if (!(fabs(s[k]) < FINITE_LIMIT)) {
            snprintf(message, MAX_MESSAGE, MESSAGE_RIG_NONFINITE, s[X_SINKAGE],
                     s[X_WHEEL_SPEED], s[X_CARRIAGE_SPEED]);
            return 1;
        }
    }
    if (fabs(s[X_SINKAGE]) > RIG_SINKAGE_LIMIT) {
        snprintf(message, MAX_MESSAGE, MESSAGE_RIG_DEPTH, s[X_SINKAGE], RIG_SINKAGE_LIMIT,
                 RIG_SINKAGE_LIMIT);
        return 1;
    }
    return 0;
}

/* The outputs (rig_outputs) and the derivatives of the states (rig_rates:
   wheelterrain.model.rig.rates) at the current state, inputs and parameters, loaded once. In
   model exchange the motor torque output is the one of this state and these commands (state
   N_X, set from rig_rates first); in co-simulation it stays the torque of the last step. */
static int model_refresh(Instance *c, double *dx, char *message) {
    casadi_real u[N_U], p[N_P], y[N_OUT], torque;
    int k;
    if (state_problem(c, message)) return 1;
    bind_state_inputs_params(c, u, p);
    c->res[0] = dx;
    c->res[1] = &torque;
    rig_rates(c->arg, c->res, c->iw, c->w, 0);
    if (c->model_exchange) c->b.s[N_X] = torque;
    c->arg[3] = &c->b.s[N_X];
    c->res[0] = y;
    rig_outputs(c->arg, c->res, c->iw, c->w, 0);
    for (k = 0; k < N_OUT; k++) c->b.v[OUT_VRS[k]] = y[k];
    return 0;
}

static void model_step(Instance *c, double t, double h) {
    casadi_real u[N_U], p[N_P], x_next[N_X], torque;
    int k;
    (void)t;
    bind_state_inputs_params(c, u, p);
    c->arg[3] = &h;
    c->res[0] = x_next;
    c->res[1] = &torque;
    rig_step(c->arg, c->res, c->iw, c->w, 0);
    for (k = 0; k < N_X; k++) c->b.s[k] = x_next[k];
    c->b.s[N_X] = torque;
}

/* WheelTerrain's model hooks for fmi2_native.c (copied into the FMU as sources/model_hooks.inc).
 *
 * Values in and out of the CasADi Functions terrain_dynamic / terrain_quasi_static
 * (wheelterrain.fmu.functions); the wheel angle (state 0) is integrated from wheel_speed, so the
 * grouser ripple follows the wheel's rotation; the plastic sinkage (state 1) is the soil's
 * memory under the wheel, advanced by terrain_memory (co-simulation) or integrated from the
 * plastic_rate of terrain_dynamic (model exchange). Everything model-specific that is a list of names
 * (value references, sizes, status codes and their messages) comes from the generated
 * model_vars.h, itself generated from the one variables table: IN_VRS, OUT_VRS, P_VRS, N_IN,
 * N_OUT, N_P, N_GROUND, GROUND_VRS, GROUND_P, VR_*, STATUS_*, MESSAGE_*. The wheel angle and
 * the plastic sinkage are the continuous states of model exchange. */

/* The terrain's refusals (slip, burial, load, convergence) depend on its inputs, not on the
   wheel angle: a step with unevaluated inputs is evaluated once, at its end (fmi2DoStep). */
#define MODEL_CHECKS_AT_STEP_END 1
/* the terrain refuses inputs (speeds, sinkage, load): the master can set others */
#define MODEL_STATE_REFUSALS_ARE_FINAL 0

static void model_work(casadi_int *sz_arg, casadi_int *sz_res, casadi_int *sz_iw,
                       casadi_int *sz_w) {
    cover(terrain_dynamic_work, sz_arg, sz_res, sz_iw, sz_w);
    cover(terrain_quasi_static_work, sz_arg, sz_res, sz_iw, sz_w);
    cover(terrain_memory_work, sz_arg, sz_res, sz_iw, sz_w);
}

static void model_reset(Instance *c) {
    c->b.s[0] = 0.0;
    c->b.s[1] = 0.0;
}

/* the model's parameter vector: the parameters, the soil from the ground.* inputs if so set */
static void model_parameters(Instance *c, casadi_real *p) {
    int k;
    for (k = 0; k < N_P; k++) p[k] = c->b.v[P_VRS[k]];
    if (c->b.v[VR_SOIL_FROM_INPUTS] != 0.0)
        for (k = 0; k < N_GROUND; k++) p[GROUND_P[k]] = c->b.v[GROUND_VRS[k]];
}

static void model_initialize(Instance *c) { (void)c; }

/* The outputs at the current inputs, wheel angle and plastic sinkage, and the states' rates
   d(wheel_angle)/dt = wheel_speed, d(plastic_sinkage)/dt = plastic_rate (model exchange; the
   co-simulation step advances them). */
static int model_refresh(Instance *c, double *dx, char *message) {
    casadi_real u[N_IN], p[N_P], y[N_OUT], status = 0.0, info = 0.0, angle = c->b.s[0];
    casadi_real plastic = c->b.s[1], plastic_rate = 0.0;
    /* quasi-static warm start: Newton from the last solved sinkage (0: cold) */
    casadi_real guess = c->b.v[VR_WARM_START] != 0.0 ? c->b.v[VR_CONTACT_SINKAGE] : 0.0;
    int k;
    for (k = 0; k < N_IN; k++) u[k] = c->b.v[IN_VRS[k]];
    /* the soil under the wheel from a terrain map's query point (ground.* inputs) */
    model_parameters(c, p);
    c->res[0] = y;
    c->res[1] = &status;
    c->res[2] = &info;
    if (c->b.v[VR_QUASI_STATIC] != 0.0) {
        c->arg[0] = u;
        c->arg[1] = p;
        c->arg[2] = &guess;
        if (terrain_quasi_static(c->arg, c->res, c->iw, c->w, 0)) status = -1.0;
    } else {
        c->res[3] = &plastic_rate;
        c->arg[0] = u;
        c->arg[1] = &angle;
        c->arg[2] = &plastic;
        c->arg[3] = p;
        if (terrain_dynamic(c->arg, c->res, c->iw, c->w, 0)) status = -1.0;
    }
    if (status == STATUS_SLIP) {
        snprintf(message, MAX_MESSAGE, MESSAGE_SLIP, c->b.v[VR_WHEEL_SPEED],
                 c->b.v[VR_CARRIAGE_SPEED], info);
        return 1;
    }
    if (status == STATUS_LOAD) {
        snprintf(message, MAX_MESSAGE, MESSAGE_LOAD, c->b.v[VR_LOAD], info, info);
        return 1;
    }
    if (status == STATUS_BURIED) {
        snprintf(message, MAX_MESSAGE, MESSAGE_BURIED, c->b.v[VR_SINKAGE], info);
        return 1;
    }
    if (status == STATUS_ANGLE) {
        snprintf(message, MAX_MESSAGE, MESSAGE_ANGLE, c->b.v[VR_SLIP_ANGLE], info, info);
        return 1;
    }
    if (status == STATUS_TURN) {
        snprintf(message, MAX_MESSAGE, MESSAGE_TURN, c->b.v[VR_YAW_RATE],
                 c->b.v[VR_CARRIAGE_SPEED], info, info);
        return 1;
    }
    if (status == STATUS_NONFINITE) {
        snprintf(message, MAX_MESSAGE, MESSAGE_NONFINITE, c->b.v[VR_SINKAGE],
                 c->b.v[VR_WHEEL_SPEED], c->b.v[VR_CARRIAGE_SPEED], c->b.v[VR_LOAD]);
        return 1;
    }
    if (status != STATUS_OK) {
        snprintf(message, MAX_MESSAGE, MESSAGE_UNCONVERGED, c->b.v[VR_LOAD]);
        return 1;
    }
    for (k = 0; k < N_OUT; k++) c->b.v[OUT_VRS[k]] = y[k];
    c->b.v[VR_WHEEL_ANGLE] = c->b.s[0];
    c->b.v[VR_PLASTIC_SINKAGE] = c->b.s[1];
    dx[0] = c->b.v[VR_WHEEL_SPEED];
    dx[1] = plastic_rate;  /* 0 in quasi-static mode: the state is held */
    return 0;
}

/* A co-simulation step: the wheel turns, and the soil under it yields and is replaced by the
   soil ahead (terrain_memory), the inputs held. */
static void model_step(Instance *c, double t, double h) {
    casadi_real u[N_IN], p[N_P], plastic = c->b.s[1], next = c->b.s[1], step = h;
    int k;
    (void)t;
    c->b.s[0] += c->b.v[VR_WHEEL_SPEED] * h;
    if (c->b.v[VR_QUASI_STATIC] != 0.0) return;
    for (k = 0; k < N_IN; k++) u[k] = c->b.v[IN_VRS[k]];
    model_parameters(c, p);
    c->arg[0] = u;
    c->arg[1] = &plastic;
    c->arg[2] = p;
    c->arg[3] = &step;
    c->res[0] = &next;
    if (terrain_memory(c->arg, c->res, c->iw, c->w, 0) == 0) c->b.s[1] = next;
}

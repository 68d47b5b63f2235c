/* body_rk45 (fmus/README.md): a free rigid body on a line, driven by the force F acting with the opposite sign,
 * in a gravity field if asked:  m x'' = -F - (inGravityField ? m g dir : 0),  dir = +1 (down) or -1 (up).
 *
 * Written in the style of a modelling tool's binary export with an embedded variable-step solver: value
 * references counted per type from 0 (Real 0 is m, Boolean 0 inGravityField, Integer 0 nSteps, String 0
 * solverType), typed parameters, and outputs computed only by fmi2DoStep and at the end of initialisation, from
 * the input held over the step (no direct feedthrough: setting F changes a only at the next step).  The solver
 * (solverType "RK45": Dormand-Prince 5(4) with step-size control, "RK4": classical Runge-Kutta with nSteps steps)
 * is in dopri45.h.  The instance is one struct without pointers besides the callbacks (strings are copied into
 * its own buffers), so an FMU state is a copy of it (state.h), the RK45 step size to try next included: a
 * restored step repeats bit for bit.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"
#include "state.h"
#include "dopri45.h"

#define MODEL_GUID "{b80a3d6b-ecdb-456c-ad34-3dc440750adb}"
#define RK45_ATOL 1e-14 /* the absolute part of the RK45 error scale, in m and m/s */

/* value references, counted per type */
enum { R_M, R_G, R_F, R_X, R_V, R_A, R_TOL, NREAL };
enum { B_GRAVITY, NBOOLEAN };
enum { I_NSTEPS, I_DIRECTION, NINTEGER }; /* Enumerations are read and written as Integers */
enum { S_SOLVER, NSTRING };

static const char *const real_names[NREAL] = {"m", "g", "F", "x", "v", "a", "tolerance"};
static const char *const integer_names[NINTEGER] = {"nSteps", "gravityDirection"};

enum { DOWN = 1, UP = 2 }; /* the items of the enumeration GravityDirection */
enum { INSTANTIATED, INITIALIZATION, STEPPING, TERMINATED };

#define STRING_CAPACITY 32

typedef struct {
    double r[NREAL];
    fmi2Boolean gravity;
    fmi2Integer nsteps, direction;
    char solver[STRING_CAPACITY];
    double h; /* RK45: the step size to try first in the next step (0: not chosen yet) */
    double time;
    int mode;
    fmi2CallbackFunctions cb;
    char name[64];
} Instance;

/* A message through the logger; the logger takes a format, so a '%' of the text goes as "%%". */
static void logf_(Instance *c, fmi2Status status, const char *category, const char *fmt, ...) {
    char text[512], escaped[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(text, sizeof text, fmt, ap);
    va_end(ap);
    size_t j = 0;
    for (size_t i = 0; text[i] && j + 2 < sizeof escaped; i++) {
        if (text[i] == '%') escaped[j++] = '%';
        escaped[j++] = text[i];
    }
    escaped[j] = '\0';
    if (c->cb.logger) c->cb.logger(c->cb.componentEnvironment, c->name, status, category, escaped);
}

static void defaults(Instance *c) {
    double r[NREAL] = {400.0, 9.81, 0.0, 0.0, 0.0, 0.0, 1e-10};
    memcpy(c->r, r, sizeof r);
    c->gravity = fmi2False;
    c->nsteps = 10;
    c->direction = DOWN;
    snprintf(c->solver, sizeof c->solver, "%s", "RK45");
    c->h = 0;
    c->time = 0;
    c->mode = INSTANTIATED;
}

/* the body's acceleration under the force F (it does not depend on the state: a free body) */
static double acceleration(const Instance *c, double F) {
    double gravity = c->gravity ? c->r[R_G] * (c->direction == UP ? -1.0 : 1.0) : 0.0;
    return -F / c->r[R_M] - gravity;
}

typedef struct {
    const Instance *c;
    double F; /* the input held over the step */
} Rhs;

static void rhs(const void *ctx, const double *y, double *f) {
    const Rhs *p = (const Rhs *)ctx;
    f[0] = y[1];
    f[1] = acceleration(p->c, p->F);
}

static int before_initialized(const Instance *c) { return c->mode == INSTANTIATED || c->mode == INITIALIZATION; }

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    (void)c; (void)on; (void)n; (void)cat; return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging) {
    (void)location; (void)visible; (void)logging;
    if (type != fmi2CoSimulation || guid == NULL || strcmp(guid, MODEL_GUID) != 0) return NULL;
    Instance *c = (Instance *)calloc(1, sizeof(Instance));
    if (!c) return NULL;
    if (cb) c->cb = *cb;
    snprintf(c->name, sizeof c->name, "%s", name ? name : "");
    defaults(c);
    return c;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolDefined, fmi2Real tol, fmi2Real start,
                               fmi2Boolean stopDefined, fmi2Real stop) {
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop; /* the solver keeps its own tolerance */
    ((Instance *)c)->time = start;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Instance *i = (Instance *)c;
    if (i->mode != INSTANTIATED) return fmi2Error;
    i->mode = INITIALIZATION;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *i = (Instance *)c;
    if (i->mode != INITIALIZATION) return fmi2Error;
    if (strcmp(i->solver, "RK45") != 0 && strcmp(i->solver, "RK4") != 0) {
        logf_(i, fmi2Error, "logStatusError",
              "solverType \"%s\" is not supported: the allowed values are \"RK4\" and \"RK45\"", i->solver);
        return fmi2Error;
    }
    if (!(i->r[R_M] > 0) || !(i->r[R_TOL] > 0) || i->nsteps < 1 || (i->direction != DOWN && i->direction != UP)) {
        logf_(i, fmi2Error, "logStatusError",
              "bad parameters: m = %g and tolerance = %g must be positive, nSteps = %d at least 1, "
              "gravityDirection = %d one of 1 (down), 2 (up)",
              i->r[R_M], i->r[R_TOL], (int)i->nsteps, (int)i->direction);
        return fmi2Error;
    }
    i->r[R_A] = acceleration(i, i->r[R_F]);
    i->h = 0;
    i->mode = STEPPING;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) { ((Instance *)c)->mode = TERMINATED; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component c) { defaults((Instance *)c); return fmi2OK; }

/* -- values ---------------------------------------------------------------------------------------------------- */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= NREAL) {
            logf_(i, fmi2Error, "logStatusError", "fmi2GetReal: no Real variable has value reference %u", vr[k]);
            return fmi2Error;
        }
        v[k] = i->r[vr[k]];
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= NREAL) {
            logf_(i, fmi2Error, "logStatusError", "fmi2SetReal: no Real variable has value reference %u", vr[k]);
            return fmi2Error;
        }
        /* the input at any time; the parameters and the start values of x and v before initialisation ends */
        int settable = vr[k] == R_F || (vr[k] != R_A && before_initialized(i));
        if (!settable) {
            logf_(i, fmi2Error, "logStatusError", "fmi2SetReal: %s cannot be set %s", real_names[vr[k]],
                  vr[k] == R_A ? "(a calculated output)" : "after initialisation");
            return fmi2Error;
        }
        i->r[vr[k]] = v[k];
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        switch (vr[k]) {
        case I_NSTEPS: v[k] = i->nsteps; break;
        case I_DIRECTION: v[k] = i->direction; break;
        default:
            logf_(i, fmi2Error, "logStatusError", "fmi2GetInteger: no Integer variable has value reference %u", vr[k]);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= NINTEGER) {
            logf_(i, fmi2Error, "logStatusError", "fmi2SetInteger: no Integer variable has value reference %u", vr[k]);
            return fmi2Error;
        }
        if (!before_initialized(i)) {
            logf_(i, fmi2Error, "logStatusError", "fmi2SetInteger: %s cannot be set after initialisation",
                  integer_names[vr[k]]);
            return fmi2Error;
        }
        if (vr[k] == I_DIRECTION && v[k] != DOWN && v[k] != UP) {
            logf_(i, fmi2Error, "logStatusError",
                  "fmi2SetInteger: gravityDirection = %d is not an item of GravityDirection (1 down, 2 up)", (int)v[k]);
            return fmi2Error;
        }
        if (vr[k] == I_NSTEPS) i->nsteps = v[k];
        else i->direction = v[k];
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != B_GRAVITY) {
            logf_(i, fmi2Error, "logStatusError", "fmi2GetBoolean: no Boolean variable has value reference %u", vr[k]);
            return fmi2Error;
        }
        v[k] = i->gravity;
    }
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != B_GRAVITY) {
            logf_(i, fmi2Error, "logStatusError", "fmi2SetBoolean: no Boolean variable has value reference %u", vr[k]);
            return fmi2Error;
        }
        if (!before_initialized(i)) {
            logf_(i, fmi2Error, "logStatusError", "fmi2SetBoolean: inGravityField cannot be set after initialisation");
            return fmi2Error;
        }
        i->gravity = v[k] ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

/* the strings returned point into the instance: valid until the next call that changes them */
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != S_SOLVER) {
            logf_(i, fmi2Error, "logStatusError", "fmi2GetString: no String variable has value reference %u", vr[k]);
            return fmi2Error;
        }
        v[k] = i->solver;
    }
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != S_SOLVER) {
            logf_(i, fmi2Error, "logStatusError", "fmi2SetString: no String variable has value reference %u", vr[k]);
            return fmi2Error;
        }
        if (!before_initialized(i)) {
            logf_(i, fmi2Error, "logStatusError", "fmi2SetString: solverType cannot be set after initialisation");
            return fmi2Error;
        }
        if (v[k] == NULL || strlen(v[k]) >= sizeof i->solver) {
            logf_(i, fmi2Error, "logStatusError", "fmi2SetString: solverType must be a string of at most %d characters",
                  (int)sizeof i->solver - 1);
            return fmi2Error;
        }
        memcpy(i->solver, v[k], strlen(v[k]) + 1);
    }
    return fmi2OK;
}

/* -- states: the instance itself (state.h) ---------------------------------------------------------------------- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    return state_save(c, s, sizeof(Instance)) ? fmi2Error : fmi2OK;
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    return state_restore(c, s, sizeof(Instance)) ? fmi2Error : fmi2OK;
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) {
    (void)c; state_free(s); return fmi2OK;
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    (void)c; (void)s; *size = sizeof(Instance); return fmi2OK;
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t size) {
    (void)c; return state_serialize(s, b, size, sizeof(Instance)) ? fmi2Error : fmi2OK;
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte b[], size_t size, fmi2FMUstate *s) {
    if (state_deserialize(b, size, s, sizeof(Instance))) return fmi2Error;
    ((Instance *)*s)->cb = ((Instance *)c)->cb; /* the callbacks of the running instance */
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dz[], fmi2Real du[]) {
    (void)c; (void)u; (void)nu; (void)z; (void)nz; (void)dz; (void)du; return fmi2Error;
}

/* -- stepping --------------------------------------------------------------------------------------------------- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real v[]) {
    (void)vr; (void)order; (void)v;
    if (n) logf_((Instance *)c, fmi2Error, "logStatusError", "the input is held over a step: no input derivatives");
    return n ? fmi2Error : fmi2OK;
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real v[]) {
    (void)c; (void)vr; (void)order; (void)v; return n ? fmi2Error : fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real H, fmi2Boolean noSetPrior) {
    Instance *i = (Instance *)c;
    (void)noSetPrior;
    if (i->mode != STEPPING) {
        logf_(i, fmi2Error, "logStatusError", "fmi2DoStep: the unit is not initialised");
        return fmi2Error;
    }
    if (!(H > 0)) {
        logf_(i, fmi2Error, "logStatusError", "fmi2DoStep: the communication step size must be positive (%g)", H);
        return fmi2Error;
    }
    Rhs ctx = {i, i->r[R_F]};
    double y[2] = {i->r[R_X], i->r[R_V]};
    if (strcmp(i->solver, "RK4") == 0) {
        rk4(rhs, &ctx, 2, y, H, (int)i->nsteps);
    } else {
        int rejected = 0;
        if (dopri45(rhs, &ctx, 2, y, H, i->r[R_TOL], RK45_ATOL, &i->h, &rejected) < 0) {
            logf_(i, fmi2Error, "logStatusError", "RK45: the step from t = %.17g could not meet the tolerance %g", t,
                  i->r[R_TOL]);
            return fmi2Error;
        }
    }
    i->r[R_X] = y[0];
    i->r[R_V] = y[1];
    i->r[R_A] = acceleration(i, ctx.F);
    i->time = t + H;
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) { (void)c; return fmi2Error; }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *v) {
    (void)c; (void)s; *v = fmi2OK; return fmi2OK;
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *v) {
    if (s == fmi2LastSuccessfulTime) { *v = ((Instance *)c)->time; return fmi2OK; }
    return fmi2Discard;
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *v) {
    (void)c; (void)s; (void)v; return fmi2Discard;
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *v) {
    (void)c; (void)s; (void)v; return fmi2Discard;
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *v) {
    (void)c; (void)s; (void)v; return fmi2Discard;
}

/* faulty (fmus/README.md): the force-driven oscillator of fmus/msd (its model.c: exact integration for polynomial
 * inputs) behind an FMI 2.0 interface that fails on purpose, as the Integer parameter `fault` selects, in every
 * communication step that starts at or after the tunable parameter `fault_time`:
 *
 *   0 none                      1 fmi2Warning (the step is taken)      2 fmi2Discard ("step rejected: ...")
 *   3 fmi2Error                 4 fmi2Fatal                            5 the acceleration output NaN after the step
 *   6 the position output +Inf  7 fmi2DoStep never returns             8 fmi2DoStep crashes the process (SIGSEGV)
 *   9 fmi2SetFMUstate restores all but a count of the steps taken, which adds 1e-6 m a step to the position output
 *  10 fmi2ExitInitializationMode refuses (fmi2Error, "no licence")
 *  11 fmi2DoStep reads noSetFMUStatePriorToCurrentPoint = false as "integrate the last step again from its start"
 *     (where it started is kept outside the saved state), as OSP's quarter-truck units do: with false on every
 *     step it stands still; with true it is msd
 *  12 as 11, and after a step with the flag true fmi2SetFMUstate does nothing (it returns fmi2OK)
 *
 * Every message goes through the fmi2CallbackLogger with the instance name.  Otherwise the unit is msd: input
 * derivatives, saved states (a copy of the instance, state.h), the x_set/v_set hooks and fail_time.
 */
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "fmi2Functions.h"
#include "model.h"
#include "state.h"
#include "step.h"

enum { I_FAULT, NINTEGER };
enum {
    FAULT_NONE, FAULT_WARNING, FAULT_DISCARD, FAULT_ERROR, FAULT_FATAL, FAULT_NAN, FAULT_INF, FAULT_HANG,
    FAULT_CRASH, FAULT_ROLLBACK, FAULT_LICENCE, FAULT_FLAG, FAULT_FLAG_RESTORE, NFAULT
};

typedef struct {
    Model m;                              /* msd's variables and state (model.h) */
    double time;
    double der[NINPUT * (MAX_ORDER + 1)]; /* derivatives of the inputs at the step start */
    double fault_time;
    fmi2Integer fault;
    double steps;         /* fault 9: steps taken since instantiation, kept by fmi2SetFMUstate */
    int nan_a, inf_x;     /* faults 5 and 6: the last step spoiled the acceleration or the position output */
    double last_x, last_v; /* faults 11 and 12: where the last step started, kept by fmi2SetFMUstate */
    int has_last, last_final; /* and whether it was taken with noSetFMUStatePriorToCurrentPoint true */
    int initialized;
    fmi2CallbackFunctions cb;
    char name[64];
} Instance;

/* the messages hold no '%' of their own: the text goes as the logger's format */
static void logmsg(Instance *c, fmi2Status s, const char *category, const char *msg) {
    if (c->cb.logger) c->cb.logger(c->cb.componentEnvironment, c->name, s, category, msg);
}

static void step_message(Instance *c, fmi2Status s, const char *category, const char *what, double t) {
    char msg[256];
    snprintf(msg, sizeof msg, what, t);
    logmsg(c, s, category, msg);
}

static int input_index(unsigned vr) {
    for (int k = 0; k < NINPUT; k++)
        if (input_vrs[k] == vr) return k;
    return -1;
}

static void defaults(Instance *i) {
    model_defaults(&i->m);
    memset(i->der, 0, sizeof i->der);
    i->time = 0;
    i->fault_time = 0;
    i->fault = FAULT_NONE;
    i->steps = 0;
    i->nan_a = i->inf_x = 0;
    i->last_x = i->last_v = 0;
    i->has_last = i->last_final = 0;
    i->initialized = 0;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cat[]) {
    (void)c; (void)on; (void)n; (void)cat; return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging) {
    (void)location; (void)visible; (void)logging;
    if (type != fmi2CoSimulation || (guid && strcmp(guid, MODEL_GUID) != 0)) return NULL;
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
    (void)tolDefined; (void)tol; (void)stopDefined; (void)stop;
    ((Instance *)c)->time = start;
    return fmi2OK;
}
fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *i = (Instance *)c;
    if (i->fault == FAULT_LICENCE) {
        logmsg(i, fmi2Error, "logStatusError", "faulty: initialisation refused: no licence for this unit");
        return fmi2Error;
    }
    model_initialize(&i->m);
    i->initialized = 1;
    return fmi2OK;
}
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) { defaults((Instance *)c); return fmi2OK; }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= NREAL) return fmi2Error;
        if (vr[k] == VR_FAULT_TIME) v[k] = i->fault_time;
        else if (vr[k] == VR_A && i->nan_a) v[k] = NAN;
        else if (vr[k] == VR_X && i->inf_x) v[k] = INFINITY;
        else v[k] = model_get(&i->m, vr[k]);
        if (vr[k] == VR_X && i->fault == FAULT_ROLLBACK) v[k] += 1e-6 * i->steps;
    }
    return fmi2OK;
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] == VR_FAULT_TIME) {
            i->fault_time = v[k];
        } else if (vr[k] >= NREAL || model_set(&i->m, vr[k], v[k]) != 0) {
            logmsg(i, fmi2Error, "logStatusError", "fmi2SetReal: this variable cannot be set");
            return fmi2Error;
        }
    }
    return fmi2OK;
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != I_FAULT) return fmi2Error;
        v[k] = i->fault;
    }
    return fmi2OK;
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] != I_FAULT) return fmi2Error;
        if (i->initialized) {
            logmsg(i, fmi2Error, "logStatusError", "fmi2SetInteger: fault is fixed: it cannot be set after initialisation");
            return fmi2Error;
        }
        if (v[k] < 0 || v[k] >= NFAULT) {
            logmsg(i, fmi2Error, "logStatusError", "fmi2SetInteger: fault must be one of 0 to 10");
            return fmi2Error;
        }
        i->fault = v[k];
    }
    return fmi2OK;
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2String v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2String v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}

/* the state is the instance itself (state.h), but for fault 9 the count of steps taken survives a restore */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) {
    return state_save(c, s, sizeof(Instance)) ? fmi2Error : fmi2OK;
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) {
    Instance *i = (Instance *)c;
    double steps = i->steps, last_x = i->last_x, last_v = i->last_v;
    int rollback = i->fault == FAULT_ROLLBACK, has_last = i->has_last, last_final = i->last_final;
    int flag = i->fault == FAULT_FLAG || i->fault == FAULT_FLAG_RESTORE;
    if (i->fault == FAULT_FLAG_RESTORE && last_final) return fmi2OK; /* fault 12: nothing is restored */
    if (state_restore(c, s, sizeof(Instance))) return fmi2Error;
    if (rollback) i->steps = steps;
    if (flag) {
        i->last_x = last_x, i->last_v = last_v;
        i->has_last = has_last, i->last_final = last_final;
    }
    return fmi2OK;
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

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        int in = input_index(vr[k]);
        if (in < 0 || order[k] < 1 || order[k] > MAX_ORDER) {
            logmsg(i, fmi2Error, "logStatusError", "input derivative of an unknown input or beyond the highest order");
            return fmi2Error;
        }
        i->der[in * (MAX_ORDER + 1) + order[k]] = v[k];
    }
    return fmi2OK;
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                        const fmi2Integer order[], fmi2Real v[]) {
    (void)c; (void)vr; (void)order; (void)v; return n ? fmi2Error : fmi2OK;
}

static volatile int hang = 1; /* fault 7 spins on it: a volatile read each turn, so the loop stays */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Instance *i = (Instance *)c;
    int fault = t >= i->fault_time ? (int)i->fault : FAULT_NONE;
    switch (fault) {
    case FAULT_DISCARD:
        step_message(i, fmi2Discard, "logStatusDiscard",
                     "step rejected: the unit refuses the step from t = %.17g (fault 2)", t);
        return fmi2Discard;
    case FAULT_ERROR:
        step_message(i, fmi2Error, "logStatusError", "faulty: the step from t = %.17g failed (fault 3)", t);
        return fmi2Error;
    case FAULT_FATAL:
        step_message(i, fmi2Fatal, "logStatusFatal",
                     "faulty: fatal failure in the step from t = %.17g, the instance is lost (fault 4)", t);
        return fmi2Fatal;
    case FAULT_HANG:
        while (hang) {
        }
        return fmi2Error;
    case FAULT_CRASH:
        step_message(i, fmi2Fatal, "logStatusFatal", "faulty: the step from t = %.17g crashes the process (fault 8)", t);
        raise(SIGSEGV);
        return fmi2Fatal;
    case FAULT_FLAG:
    case FAULT_FLAG_RESTORE:
        if (noSetPrior || !i->has_last) {
            i->last_x = i->m.x, i->last_v = i->m.v;
            i->has_last = 1;
        } else { /* false read as a rejected last step: from its start again */
            i->m.x = i->last_x, i->m.v = i->last_v;
        }
        i->last_final = noSetPrior != fmi2False;
        break;
    default:
        break;
    }
    int refused = unit_step(&i->m, i->der, t, h);
    if (refused > 0) logmsg(i, fmi2Discard, "logStatusDiscard", STEP_REFUSED);
    if (refused) return refused > 0 ? fmi2Discard : fmi2Error;
    memset(i->der, 0, sizeof i->der); /* derivatives hold for one step (they are set before each) */
    i->time = t + h;
    i->nan_a = fault == FAULT_NAN;
    i->inf_x = fault == FAULT_INF;
    if (fault == FAULT_ROLLBACK) i->steps += 1;
    if (fault == FAULT_WARNING) {
        step_message(i, fmi2Warning, "logStatusWarning",
                     "faulty: a warning in the step from t = %.17g; the step is taken (fault 1)", t);
        return fmi2Warning;
    }
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

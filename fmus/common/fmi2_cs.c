/* FMI 2.0 co-simulation interface shared by the test units of icosim (fmus/README.md).
 *
 * A unit supplies model.h: NREAL real variables addressed by value reference, NINPUT continuous inputs INPUT_VRS
 * (whose derivatives fmi2SetRealInputDerivatives accepts up to order MAX_ORDER) and, through unit.h, FAIL_TIME_VR
 * (a parameter: a step starting at or after it is refused) and model_defaults/model_set/model_get/model_step
 * (der[k * (MAX_ORDER + 1) + j]: j-th derivative of input k).  The whole instance is one struct, so
 * fmi2GetFMUstate and fmi2SetFMUstate are a copy of it (state.h): a restored step repeats bit for bit.
 */
#include <stdlib.h>
#include <string.h>
#include <stdio.h>
#include "fmi2Functions.h"
#include "model.h"
#include "state.h"
#include "step.h"

static int input_index(unsigned vr) {
    for (int k = 0; k < NINPUT; k++)
        if (input_vrs[k] == vr) return k;
    return -1;
}

typedef struct {
    Model m;                      /* the unit's variables and state (model.h) */
    double time;
    double der[NINPUT * (MAX_ORDER + 1)];  /* derivatives of the inputs at the step start (model.h) */
    fmi2CallbackFunctions cb;
    char name[64];
} Instance;

static void logmsg(Instance *c, fmi2Status s, const char *msg) {
    if (c->cb.logger) c->cb.logger(c->cb.componentEnvironment, c->name, s, "error", msg);
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
    model_defaults(&c->m);
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
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { model_initialize(&((Instance *)c)->m); return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }
fmi2Status fmi2Reset(fmi2Component c) {
    Instance *i = (Instance *)c;
    model_defaults(&i->m);
    memset(i->der, 0, sizeof i->der);
    i->time = 0;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Real v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= NREAL) return fmi2Error;
        v[k] = model_get(&i->m, vr[k]);
    }
    return fmi2OK;
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Real v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        if (vr[k] >= NREAL || model_set(&i->m, vr[k], v[k]) != 0) {
            logmsg(i, fmi2Error, "fmi2SetReal: this variable cannot be set");
            return fmi2Error;
        }
    }
    return fmi2OK;
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, fmi2Integer v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[]) {
    (void)c; (void)vr; (void)v; return n ? fmi2Error : fmi2OK;
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

/* the state is the instance itself (state.h) */
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
    /* the callbacks belong to the running instance, not to the serialised one */
    ((Instance *)*s)->cb = ((Instance *)c)->cb;
    return fmi2OK;
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference u[], size_t nu,
                                        const fmi2ValueReference z[], size_t nz, const fmi2Real dz[], fmi2Real du[]) {
#ifdef MODEL_DIRECTIONAL /* a unit whose model gives its partial derivatives (providesDirectionalDerivative) */
    return model_directional(&((Instance *)c)->m, u, nu, z, nz, dz, du) ? fmi2Error : fmi2OK;
#else
    (void)c; (void)u; (void)nu; (void)z; (void)nz; (void)dz; (void)du; return fmi2Error;
#endif
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                       const fmi2Integer order[], const fmi2Real v[]) {
    Instance *i = (Instance *)c;
    for (size_t k = 0; k < n; k++) {
        int in = input_index(vr[k]);
        if (in < 0 || order[k] < 1 || order[k] > MAX_ORDER) {
            logmsg(i, fmi2Error, "input derivative of an unknown input or beyond the highest order");
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

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean noSetPrior) {
    Instance *i = (Instance *)c;
    (void)noSetPrior;
    int refused = unit_step(&i->m, i->der, t, h);
    if (refused > 0) logmsg(i, fmi2Discard, STEP_REFUSED);
    if (refused) return refused > 0 ? fmi2Discard : fmi2Error;
    memset(i->der, 0, sizeof i->der);  /* derivatives hold for one step (they are set before each) */
    i->time = t + h;
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

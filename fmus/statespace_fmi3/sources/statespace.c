/* statespace_fmi3 (fmus/README.md): a linear time-invariant system as an FMI 3.0 co-simulation unit, in the
 * style of the Modelica Reference-FMUs' StateSpace,
 *
 *     x' = A x + B u,    y = C x + D u,
 *
 * with m inputs, n states and r outputs, structural parameters (at most MAX_DIM each) that set the sizes of the
 * arrays A (n x n), B (n x m), C (r x n), D (r x m), x0 (n), u (m) and y (r), read and written whole, row major.
 * The structural parameters are set in Configuration Mode; on leaving it, the entries outside the new sizes are
 * zeroed.  A communication step holds u and is exact: one matrix exponential (expm.h) of the system augmented by
 * the constant input, [x; u]' = [A B; 0 0] [x; u].  y follows u at once (direct feedthrough through D).  The
 * arrays are sized for MAX_DIM inside the instance, which holds no pointers besides the callbacks: a saved state
 * is a copy of it (state.h).
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "fmi3Functions.h"
#include "expm.h"
#include "state.h"

#define INSTANTIATION_TOKEN "{e3320f92-08d8-4541-9a25-72eeb260ca44}"
#define MAX_DIM 5

enum { VR_TIME, VR_M, VR_N, VR_R, VR_A, VR_B, VR_C, VR_D, VR_X0, VR_U, VR_Y, NVR };
static const char *const names[NVR] = {"time", "m", "n", "r", "A", "B", "C", "D", "x0", "u", "y"};

enum { INSTANTIATED, CONFIGURATION, INITIALIZATION, STEP, TERMINATED };

typedef struct {
    fmi3UInt64 m, n, r; /* inputs, states, outputs */
    double A[MAX_DIM][MAX_DIM], B[MAX_DIM][MAX_DIM], C[MAX_DIM][MAX_DIM], D[MAX_DIM][MAX_DIM];
    double x0[MAX_DIM], u[MAX_DIM], x[MAX_DIM];
    double time;
    int mode;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
} Instance;

static void logmsg(Instance *c, const char *fmt, ...) {
    char msg[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    if (c->log) c->log(c->env, fmi3Error, "logStatusError", msg);
}

/* the defaults: the mass-spring-damper m = 1 kg, c = 1000 N/m, d = 2 N s/m driven by the force u[0];
 * y = (position, velocity, acceleration) */
static void defaults(Instance *c) {
    memset(c->A, 0, sizeof c->A); memset(c->B, 0, sizeof c->B);
    memset(c->C, 0, sizeof c->C); memset(c->D, 0, sizeof c->D);
    memset(c->x0, 0, sizeof c->x0); memset(c->u, 0, sizeof c->u); memset(c->x, 0, sizeof c->x);
    c->m = 1; c->n = 2; c->r = 3;
    c->A[0][1] = 1; c->A[1][0] = -1000; c->A[1][1] = -2;
    c->B[1][0] = 1;
    c->C[0][0] = 1; c->C[1][1] = 1; c->C[2][0] = -1000; c->C[2][1] = -2;
    c->D[2][0] = 1;
    c->time = 0;
    c->mode = INSTANTIATED;
}

/* the rows and columns of a variable's value (1 x 1 for a scalar, rows x 1 for a vector); 0 if unknown */
static int shape(const Instance *c, fmi3ValueReference vr, size_t *rows, size_t *cols) {
    size_t m = (size_t)c->m, n = (size_t)c->n, r = (size_t)c->r;
    size_t s[NVR][2] = {{1, 1}, {1, 1}, {1, 1}, {1, 1}, {n, n}, {n, m}, {r, n}, {r, m}, {n, 1}, {m, 1}, {r, 1}};
    if (vr >= NVR) return 0;
    *rows = s[vr][0];
    *cols = s[vr][1];
    return 1;
}

/* the state the outputs see: x0 until initialisation ends, then x */
static const double *state(const Instance *c) { return c->mode == INSTANTIATED || c->mode == INITIALIZATION ? c->x0 : c->x; }

static double output(const Instance *c, size_t i) {
    const double *x = state(c);
    double y = 0;
    for (size_t j = 0; j < c->n; j++) y += c->C[i][j] * x[j];
    for (size_t j = 0; j < c->m; j++) y += c->D[i][j] * c->u[j];
    return y;
}

/* element (i, j) of a Float64 variable other than time and y */
static double *element(Instance *c, fmi3ValueReference vr, size_t i, size_t j) {
    switch (vr) {
    case VR_A: return &c->A[i][j];
    case VR_B: return &c->B[i][j];
    case VR_C: return &c->C[i][j];
    case VR_D: return &c->D[i][j];
    case VR_X0: return &c->x0[i];
    case VR_U: return &c->u[i];
    default: return NULL;
    }
}

/* nValues must be the sum of the sizes of the variables: -1 (logged) when it is not or a variable is not Float64 */
static int float64_count(Instance *c, const fmi3ValueReference vr[], size_t nvr, size_t nValues, const char *fn) {
    size_t total = 0, rows, cols;
    for (size_t k = 0; k < nvr; k++) {
        if (!shape(c, vr[k], &rows, &cols) || vr[k] == VR_M || vr[k] == VR_N || vr[k] == VR_R) {
            logmsg(c, "%s: no Float64 variable has value reference %u", fn, vr[k]);
            return -1;
        }
        total += rows * cols;
    }
    if (total != nValues) {
        logmsg(c, "%s: %zu values given, but the variables have %zu (arrays whole, row major)", fn, nValues, total);
        return -1;
    }
    return 0;
}

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories, const fmi3String categories[]) { (void)instance; (void)loggingOn; (void)nCategories; (void)categories; return fmi3OK; }

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[], size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)instanceName; (void)resourcePath; (void)visible; (void)loggingOn; (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables; (void)nRequiredIntermediateVariables; (void)intermediateUpdate;
    if (instantiationToken == NULL || strcmp(instantiationToken, INSTANTIATION_TOKEN) != 0) return NULL;
    if (eventModeUsed) { /* the unit has no events: no Event Mode */
        if (logMessage) logMessage(instanceEnvironment, fmi3Error, "logStatusError", "statespace_fmi3 has no event mode");
        return NULL;
    }
    Instance *c = (Instance *)calloc(1, sizeof(Instance));
    if (!c) return NULL;
    c->env = instanceEnvironment;
    c->log = logMessage;
    defaults(c);
    return c;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (c->mode != INSTANTIATED) {
        logmsg(c, "fmi3EnterConfigurationMode: only from the state Instantiated (the structural parameters are fixed)");
        return fmi3Error;
    }
    c->mode = CONFIGURATION;
    return fmi3OK;
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (c->mode != CONFIGURATION) return fmi3Error;
    for (size_t i = 0; i < MAX_DIM; i++) { /* the arrays resized: what lies outside them is zero */
        for (size_t j = 0; j < MAX_DIM; j++) {
            if (i >= c->n || j >= c->n) c->A[i][j] = 0;
            if (i >= c->n || j >= c->m) c->B[i][j] = 0;
            if (i >= c->r || j >= c->n) c->C[i][j] = 0;
            if (i >= c->r || j >= c->m) c->D[i][j] = 0;
        }
        if (i >= c->n) c->x0[i] = c->x[i] = 0;
        if (i >= c->m) c->u[i] = 0;
    }
    c->mode = INSTANTIATED;
    return fmi3OK;
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance, fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    Instance *c = (Instance *)instance;
    (void)toleranceDefined; (void)tolerance; (void)stopTimeDefined; (void)stopTime;
    if (c->mode != INSTANTIATED) return fmi3Error;
    c->time = startTime;
    c->mode = INITIALIZATION;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    Instance *c = (Instance *)instance;
    if (c->mode != INITIALIZATION) return fmi3Error;
    memcpy(c->x, c->x0, sizeof c->x);
    c->mode = STEP;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) { (void)instance; return fmi3Error; } /* no event mode */

fmi3Status fmi3Terminate(fmi3Instance instance) { ((Instance *)instance)->mode = TERMINATED; return fmi3OK; }

fmi3Status fmi3Reset(fmi3Instance instance) { defaults((Instance *)instance); return fmi3OK; }

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 values[], size_t nValues) {
    Instance *c = (Instance *)instance;
    if (c->mode == CONFIGURATION) {
        logmsg(c, "fmi3GetFloat64: not in Configuration Mode (the arrays are being resized)");
        return fmi3Error;
    }
    if (float64_count(c, valueReferences, nValueReferences, nValues, "fmi3GetFloat64")) return fmi3Error;
    size_t q = 0, rows, cols;
    for (size_t k = 0; k < nValueReferences; k++) {
        fmi3ValueReference vr = valueReferences[k];
        shape(c, vr, &rows, &cols);
        for (size_t i = 0; i < rows; i++)
            for (size_t j = 0; j < cols; j++)
                values[q++] = vr == VR_TIME ? c->time : vr == VR_Y ? output(c, i) : *element(c, vr, i, j);
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 values[], size_t nValues) {
    Instance *c = (Instance *)instance;
    if (float64_count(c, valueReferences, nValueReferences, nValues, "fmi3SetFloat64")) return fmi3Error;
    int before = c->mode == INSTANTIATED || c->mode == INITIALIZATION;
    for (size_t k = 0; k < nValueReferences; k++) {
        fmi3ValueReference vr = valueReferences[k];
        /* the input before initialisation and in Step Mode; the (fixed) parameters before initialisation */
        int settable = vr == VR_U ? before || c->mode == STEP : vr != VR_TIME && vr != VR_Y && before;
        if (!settable) {
            logmsg(c, "fmi3SetFloat64: %s cannot be set in this state", names[vr]);
            return fmi3Error;
        }
    }
    size_t q = 0, rows, cols;
    for (size_t k = 0; k < nValueReferences; k++) {
        shape(c, valueReferences[k], &rows, &cols);
        for (size_t i = 0; i < rows; i++)
            for (size_t j = 0; j < cols; j++) *element(c, valueReferences[k], i, j) = values[q++];
    }
    return fmi3OK;
}

static fmi3UInt64 *structural(Instance *c, fmi3ValueReference vr) {
    return vr == VR_M ? &c->m : vr == VR_N ? &c->n : vr == VR_R ? &c->r : NULL;
}

fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 values[], size_t nValues) {
    Instance *c = (Instance *)instance;
    if (nValues != nValueReferences) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; k++) {
        fmi3UInt64 *p = structural(c, valueReferences[k]);
        if (!p) {
            logmsg(c, "fmi3GetUInt64: no UInt64 variable has value reference %u", valueReferences[k]);
            return fmi3Error;
        }
        values[k] = *p;
    }
    return fmi3OK;
}

fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 values[], size_t nValues) {
    Instance *c = (Instance *)instance;
    if (nValues != nValueReferences) return fmi3Error;
    for (size_t k = 0; k < nValueReferences; k++) {
        fmi3UInt64 *p = structural(c, valueReferences[k]);
        if (!p) {
            logmsg(c, "fmi3SetUInt64: no UInt64 variable has value reference %u", valueReferences[k]);
            return fmi3Error;
        }
        if (c->mode != CONFIGURATION) {
            logmsg(c, "fmi3SetUInt64: the structural parameter %s is set in Configuration Mode only",
                   names[valueReferences[k]]);
            return fmi3Error;
        }
        if (values[k] > MAX_DIM) {
            logmsg(c, "fmi3SetUInt64: %s = %llu is beyond the largest size, %d", names[valueReferences[k]],
                   (unsigned long long)values[k], MAX_DIM);
            return fmi3Error;
        }
    }
    for (size_t k = 0; k < nValueReferences; k++) *structural(c, valueReferences[k]) = values[k];
    return fmi3OK;
}

/* the state is the instance itself (state.h) */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState* FMUState) { return state_save(instance, FMUState, sizeof(Instance)) ? fmi3Error : fmi3OK; }

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) { return state_restore(instance, FMUState, sizeof(Instance)) ? fmi3Error : fmi3OK; }

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState* FMUState) { (void)instance; state_free(FMUState); return fmi3OK; }

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t* size) { (void)instance; (void)FMUState; *size = sizeof(Instance); return fmi3OK; }

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) { (void)instance; return state_serialize(FMUState, serializedState, size, sizeof(Instance)) ? fmi3Error : fmi3OK; }

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size, fmi3FMUState* FMUState) {
    if (state_deserialize(serializedState, size, FMUState, sizeof(Instance))) return fmi3Error;
    ((Instance *)*FMUState)->env = ((Instance *)instance)->env; /* the callbacks of the running instance */
    ((Instance *)*FMUState)->log = ((Instance *)instance)->log;
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* eventHandlingNeeded, fmi3Boolean* terminateSimulation, fmi3Boolean* earlyReturn, fmi3Float64* lastSuccessfulTime) {
    Instance *c = (Instance *)instance;
    double t = currentCommunicationPoint, h = communicationStepSize;
    (void)noSetFMUStatePriorToCurrentPoint;
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = c->time;
    if (c->mode != STEP || !(h > 0)) {
        logmsg(c, "fmi3DoStep: only in Step Mode, with a positive step size");
        return fmi3Error;
    }
    /* exp(h [A B; 0 0]) = [Phi Gamma; 0 I]: x(t + h) = Phi x(t) + Gamma u */
    int n = (int)c->n, N = (int)(c->n + c->m);
    double M[EXPM_MAX * EXPM_MAX] = {0}, E[EXPM_MAX * EXPM_MAX], x[MAX_DIM];
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) M[i * N + j] = h * c->A[i][j];
        for (int j = 0; j < (int)c->m; j++) M[i * N + n + j] = h * c->B[i][j];
    }
    if (N > 0) expm(N, M, E);
    for (int i = 0; i < n; i++) {
        double s = 0;
        for (int j = 0; j < n; j++) s += E[i * N + j] * c->x[j];
        for (int j = 0; j < (int)c->m; j++) s += E[i * N + n + j] * c->u[j];
        x[i] = s;
    }
    memcpy(c->x, x, n * sizeof *x);
    c->time = t + h;
    *lastSuccessfulTime = c->time;
    return fmi3OK;
}

/* what a co-simulation unit without events, clocks or derivatives need not offer */

fmi3Status fmi3GetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float32 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int8 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt8 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int16 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt16 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int32 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt32 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Int64 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Boolean values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3String values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)valueSizes; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Clock values[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; return fmi3Error; }

fmi3Status fmi3SetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float32 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int8 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt8 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int16 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt16 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt32 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int64 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Boolean values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3String values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)valueSizes; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Clock values[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)values; return fmi3Error; }

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference, size_t* nDependencies) { (void)instance; (void)valueReference; (void)nDependencies; return fmi3Error; }

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent, size_t elementIndicesOfDependent[], fmi3ValueReference independents[], size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[], size_t nDependencies) { (void)instance; (void)dependent; (void)elementIndicesOfDependent; (void)independents; (void)elementIndicesOfIndependents; (void)dependencyKinds; (void)nDependencies; return fmi3Error; }

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) { (void)instance; (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity; (void)nSensitivity; return fmi3Error; }

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns, const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[], size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) { (void)instance; (void)unknowns; (void)nUnknowns; (void)knowns; (void)nKnowns; (void)seed; (void)nSeed; (void)sensitivity; (void)nSensitivity; return fmi3Error; }

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)intervals; (void)qualifiers; return fmi3Error; }

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions; (void)qualifiers; return fmi3Error; }

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3Float64 shifts[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)shifts; return fmi3Error; }

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions; return fmi3Error; }

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 intervals[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)intervals; return fmi3Error; }

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions; return fmi3Error; }

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Float64 shifts[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)shifts; return fmi3Error; }

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)counters; (void)resolutions; return fmi3Error; }

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) { (void)instance; return fmi3Error; }

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean* discreteStatesNeedUpdate, fmi3Boolean* terminateSimulation, fmi3Boolean* nominalsOfContinuousStatesChanged, fmi3Boolean* valuesOfContinuousStatesChanged, fmi3Boolean* nextEventTimeDefined, fmi3Float64* nextEventTime) { (void)instance; (void)discreteStatesNeedUpdate; (void)terminateSimulation; (void)nominalsOfContinuousStatesChanged; (void)valuesOfContinuousStatesChanged; (void)nextEventTimeDefined; (void)nextEventTime; return fmi3Error; }

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) { (void)instance; return fmi3Error; }

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean* enterEventMode, fmi3Boolean* terminateSimulation) { (void)instance; (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation; return fmi3Error; }

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) { (void)instance; (void)time; return fmi3Error; }

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[], size_t nContinuousStates) { (void)instance; (void)continuousStates; (void)nContinuousStates; return fmi3Error; }

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t nContinuousStates) { (void)instance; (void)derivatives; (void)nContinuousStates; return fmi3Error; }

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) { (void)instance; (void)eventIndicators; (void)nEventIndicators; return fmi3Error; }

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) { (void)instance; (void)continuousStates; (void)nContinuousStates; return fmi3Error; }

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nContinuousStates) { (void)instance; (void)nominals; (void)nContinuousStates; return fmi3Error; }

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t* nEventIndicators) { (void)instance; (void)nEventIndicators; return fmi3Error; }

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t* nContinuousStates) { (void)instance; (void)nContinuousStates; return fmi3Error; }

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues) { (void)instance; (void)valueReferences; (void)nValueReferences; (void)orders; (void)values; (void)nValues; return fmi3Error; }

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime) { (void)instance; (void)clockReference; (void)activationTime; return fmi3Error; }

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage) { (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn; (void)instanceEnvironment; (void)logMessage; return NULL; }

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate, fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption) { (void)instanceName; (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn; (void)instanceEnvironment; (void)logMessage; (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption; return NULL; }

fmi3Status fmi3EnterEventMode(fmi3Instance instance) { (void)instance; return fmi3Error; }

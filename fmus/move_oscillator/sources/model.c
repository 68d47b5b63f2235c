/* The Move-driven oscillator (model.h): m2 x2'' = -k3 x2 - c3 x2' - F with F = k2 (x2 - x1) + c2 (x2' - v1), the
 * inputs x1, v1 polynomials over the step given by their derivatives at its start; they ride along as states
 * (w_j' = w_j+1) and the end state is one matrix exponential of the augmented linear system.  The acceleration a1
 * moves the massless driven point only: nothing in the unit depends on it (as in Move). */
#include "model.h"
#include "expm.h"

#define FIELDS(X) X(VR_K2, k2) X(VR_C2, c2) X(VR_K3, k3) X(VR_C3, c3) X(VR_M2, m2) X(VR_X20, x20) X(VR_FAIL, fail)

void model_defaults(Model *m) {
    m->k2 = 10.0; m->c2 = 0.5; m->k3 = 20.0; m->c3 = 0.3; m->m2 = 1.0; m->x20 = 0.5;
    m->x1 = m->v1 = m->a1 = 0.0; m->x2 = m->v2 = 0.0; m->fail = -1.0;
}

void model_initialize(Model *m) { m->x2 = m->x20; m->v2 = 0.0; }

double model_get(const Model *m, unsigned vr) {
    switch (vr) {
    FIELDS(UNIT_GET)
    INPUT_FIELDS(UNIT_GET)
    case VR_X2: return m->x2;
    case VR_V2: return m->v2;
    case VR_F: return m->k2 * (m->x2 - m->x1) + m->c2 * (m->v2 - m->v1);
    default: return 0.0;
    }
}

int model_set(Model *m, unsigned vr, double value) {
    switch (vr) {
    FIELDS(UNIT_SET)
    INPUT_FIELDS(UNIT_SET)
    default: return -1; /* outputs */
    }
}

void model_step(Model *m, const double *der, int max_order, double h) {
    const double *dx = der, *dv = der + (max_order + 1), *da = der + 2 * (max_order + 1);
    int n = 0; /* highest derivative given of x1 and v1 */
    for (int j = 1; j <= max_order; j++)
        if (dx[j] != 0 || dv[j] != 0) n = j;
    if (n > (EXPM_MAX - 4) / 2 - 1) n = (EXPM_MAX - 4) / 2 - 1;
    int N = 2 + 2 * (n + 1), X = 2, V = 3 + n;
    double A[EXPM_MAX * EXPM_MAX] = {0}, E[EXPM_MAX * EXPM_MAX];
    A[0 * N + 1] = h;
    A[1 * N + 0] = -(m->k2 + m->k3) / m->m2 * h;
    A[1 * N + 1] = -(m->c2 + m->c3) / m->m2 * h;
    A[1 * N + X] = m->k2 / m->m2 * h;
    A[1 * N + V] = m->c2 / m->m2 * h;
    for (int j = 0; j < n; j++) {
        A[(X + j) * N + X + j + 1] = h;
        A[(V + j) * N + V + j + 1] = h;
    }
    expm(N, A, E);
    double z[EXPM_MAX] = {m->x2, m->v2};
    for (int j = 0; j <= n; j++) {
        z[X + j] = dx[j];
        z[V + j] = dv[j];
    }
    double x2 = 0, v2 = 0, x1 = 0, v1 = 0;
    for (int k = 0; k < N; k++) {
        x2 += E[0 * N + k] * z[k];
        v2 += E[1 * N + k] * z[k];
        x1 += E[X * N + k] * z[k];
        v1 += E[V * N + k] * z[k];
    }
    double a1 = 0.0, p = 1.0; /* a1 at the step end from its own derivatives */
    for (int j = 0; j <= max_order; j++) {
        a1 += da[j] * p;
        p *= h / (j + 1);
    }
    m->x2 = x2; m->v2 = v2; m->x1 = x1; m->v1 = v1; m->a1 = a1; /* the inputs at the step end */
}

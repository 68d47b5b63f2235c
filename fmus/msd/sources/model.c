/* The force-driven oscillator, integrated exactly over a step for a polynomial force (fmus/README.md):
 * the force's derivatives at the step start w_0 .. w_n ride along as states (w_j' = w_j+1), and the
 * end state is one matrix exponential of the augmented linear system. */
#include "model.h"
#include "expm.h"

void model_defaults(Model *m) {
    m->m = 1.0; m->c = 1000.0; m->d = 2.0; m->x0 = 0.0; m->v0 = 0.0;
    m->lambda = 0.0; m->x = 0.0; m->v = 0.0; m->fail = -1.0;
}

void model_initialize(Model *m) { m->x = m->x0; m->v = m->v0; }

double model_get(const Model *m, unsigned vr) {
    switch (vr) {
    case VR_M: return m->m;
    case VR_C: return m->c;
    case VR_D: return m->d;
    case VR_X0: return m->x0;
    case VR_V0: return m->v0;
    case VR_LAMBDA: return m->lambda;
    case VR_X: case VR_XSET: return m->x;
    case VR_V: case VR_VSET: return m->v;
    case VR_A: return (-m->c * m->x - m->d * m->v + m->lambda) / m->m;
    case VR_FAIL: return m->fail;
    default: return 0.0;
    }
}

int model_set(Model *m, unsigned vr, double value) {
    switch (vr) {
    case VR_M: m->m = value; return 0;
    case VR_C: m->c = value; return 0;
    case VR_D: m->d = value; return 0;
    case VR_X0: m->x0 = value; return 0;
    case VR_V0: m->v0 = value; return 0;
    case VR_LAMBDA: m->lambda = value; return 0;
    case VR_XSET: m->x = value; return 0;
    case VR_VSET: m->v = value; return 0;
    case VR_FAIL: m->fail = value; return 0;
    default: return -1; /* outputs */
    }
}

void model_step(Model *m, const double *der, int max_order, double h) {
    int n = 0; /* highest derivative given */
    for (int j = 1; j <= max_order; j++)
        if (der[j] != 0) n = j;
    int N = 3 + n;
    double A[EXPM_MAX * EXPM_MAX] = {0}, E[EXPM_MAX * EXPM_MAX];
    A[0 * N + 1] = h;
    A[1 * N + 0] = -m->c / m->m * h;
    A[1 * N + 1] = -m->d / m->m * h;
    A[1 * N + 2] = h / m->m;
    for (int j = 0; j < n; j++) A[(2 + j) * N + 3 + j] = h;
    expm(N, A, E);
    double z[EXPM_MAX] = {m->x, m->v};
    for (int j = 0; j <= n; j++) z[2 + j] = der[j];
    double x = 0, v = 0, u = 0;
    for (int k = 0; k < N; k++) {
        x += E[0 * N + k] * z[k];
        v += E[1 * N + k] * z[k];
        u += E[2 * N + k] * z[k];
    }
    m->x = x; m->v = v; m->lambda = u; /* the input at the step end: the polynomial's value there */
}

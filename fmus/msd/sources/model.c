/* The force-driven oscillator, integrated exactly over a step for a polynomial force (fmus/README.md):
 * the force's derivatives at the step start w_0 .. w_n ride along as states (w_j' = w_j+1), and the
 * end state is one matrix exponential of the augmented linear system. */
#include "msd.h"
#include "expm.h"

static double msd_output(const Model *m, unsigned vr) {
    return vr == VR_A ? (-m->c * m->x - m->d * m->v + m->u) / m->m : 0.0;
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
    m->x = x; m->v = v; m->u = u; /* the input at the step end: the polynomial's value there */
}

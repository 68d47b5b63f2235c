/* msd in engineering units (fmus/README.md): the values come and go in mm, kN, N/mm and N.s/mm; a step converts
 * them to SI, integrates exactly as fmus/msd does (the force's derivatives ride along as states, one matrix
 * exponential of the augmented linear system) and converts the end state back. */
#include "model.h"
#include "expm.h"

/* SI value = factor * value in the unit's units (the factors of the BaseUnits in modelDescription.xml); lengths
 * (mm, mm/s, mm/s2: factor 1e-3) go to SI divided by 1000, correctly rounded, and come back multiplied by 1000 */
#define KN 1e3   /* kN -> N */
#define N_MM 1e3 /* N/mm -> N/m, N.s/mm -> N.s/m */

static double to_m(double mm) { return mm / 1000.0; }
static double to_mm(double m) { return m * 1000.0; }

void model_defaults(Model *m) {
    m->m = 1.0; m->c = 1.0; m->d = 0.002; m->x0 = 0.0; m->v0 = 0.0;
    m->u = 0.0; m->x = 0.0; m->v = 0.0; m->fail = -1.0;
}

void model_initialize(Model *m) { m->x = m->x0; m->v = m->v0; }

double model_get(const Model *m, unsigned vr) {
    switch (vr) {
    MODEL_FIELDS(UNIT_GET)
    case VR_X: return m->x;
    case VR_V: return m->v;
    case VR_A: /* in SI as msd computes it, then in mm/s2 */
        return to_mm((-m->c * N_MM * to_m(m->x) - m->d * N_MM * to_m(m->v) + m->u * KN) / m->m);
    default: return 0.0;
    }
}

int model_set(Model *m, unsigned vr, double value) {
    switch (vr) {
    MODEL_FIELDS(UNIT_SET)
    default: return -1; /* outputs */
    }
}

void model_step(Model *m, const double *der, int max_order, double h) {
    double mass = m->m, c = m->c * N_MM, d = m->d * N_MM;
    int n = 0; /* highest derivative given */
    for (int j = 1; j <= max_order; j++)
        if (der[j] != 0) n = j;
    int N = 3 + n;
    double A[EXPM_MAX * EXPM_MAX] = {0}, E[EXPM_MAX * EXPM_MAX];
    A[0 * N + 1] = h;
    A[1 * N + 0] = -c / mass * h;
    A[1 * N + 1] = -d / mass * h;
    A[1 * N + 2] = h / mass;
    for (int j = 0; j < n; j++) A[(2 + j) * N + 3 + j] = h;
    expm(N, A, E);
    double z[EXPM_MAX] = {to_m(m->x), to_m(m->v)};
    for (int j = 0; j <= n; j++) z[2 + j] = der[j] * KN; /* kN/s^j -> N/s^j */
    double x = 0, v = 0, u = 0;
    for (int k = 0; k < N; k++) {
        x += E[0 * N + k] * z[k];
        v += E[1 * N + k] * z[k];
    }
    for (int j = 0; j <= n; j++) u += E[2 * N + 2 + j] * der[j]; /* the polynomial's Taylor weights */
    m->x = to_mm(x); m->v = to_mm(v); m->u = u; /* the input at the step end, in kN */
}

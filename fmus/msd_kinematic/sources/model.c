/* The kinematically driven oscillator: x'' = a_in(t), a polynomial over the step given by its
 * derivatives at the step start, integrated exactly (Taylor sums); the reaction force follows
 * from the equation of motion (fmus/README.md). */
#include "model.h"

void model_defaults(Model *m) {
    m->m = 1.0; m->c = 1000.0; m->d = 2.0; m->x0 = 0.0; m->v0 = 0.0;
    m->a_in = 0.0; m->x = 0.0; m->v = 0.0; m->fail = -1.0;
}

void model_initialize(Model *m) { m->x = m->x0; m->v = m->v0; }

double model_get(const Model *m, unsigned vr) {
    switch (vr) {
    case VR_M: return m->m;
    case VR_C: return m->c;
    case VR_D: return m->d;
    case VR_X0: return m->x0;
    case VR_V0: return m->v0;
    case VR_AIN: case VR_A: return m->a_in;
    case VR_X: case VR_XSET: return m->x;
    case VR_V: case VR_VSET: return m->v;
    case VR_F: return m->m * m->a_in + m->c * m->x + m->d * m->v;
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
    case VR_AIN: m->a_in = value; return 0;
    case VR_XSET: m->x = value; return 0;
    case VR_VSET: m->v = value; return 0;
    case VR_FAIL: m->fail = value; return 0;
    default: return -1; /* outputs */
    }
}

void model_step(Model *m, const double *der, int max_order, double h) {
    /* a(s) = sum_j der[j] s^j / j!:  v(h) = v + sum_j der[j] h^(j+1)/(j+1)!,
     * x(h) = x + v h + sum_j der[j] h^(j+2)/(j+2)!,  a(h) = sum_j der[j] h^j / j! */
    double x = m->x + m->v * h, v = m->v, a = 0.0;
    double p = 1.0; /* h^j / j! */
    for (int j = 0; j <= max_order; j++) {
        a += der[j] * p;
        v += der[j] * p * h / (j + 1);
        x += der[j] * p * h * h / ((j + 1) * (j + 2));
        p *= h / (j + 1);
    }
    m->x = x; m->v = v; m->a_in = a;
}

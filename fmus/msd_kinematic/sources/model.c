/* The kinematically driven oscillator: x'' = a_in(t), a polynomial over the step given by its
 * derivatives at the step start, integrated exactly (Taylor sums); the reaction force follows
 * from the equation of motion (fmus/README.md). */
#include "msd.h"

static double msd_output(const Model *m, unsigned vr) {
    switch (vr) {
    case VR_A: return m->u;
    case VR_F: return m->m * m->u + m->c * m->x + m->d * m->v;
    default: return 0.0;
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
    m->x = x; m->v = v; m->u = a;
}

/* The static map (fmus/README.md): no state; its outputs y and w follow its input at once, z does not depend on it,
 * and a step only moves the input to its polynomial's value at the step end. */
#include <math.h>

#include "model.h"
#include "poly.h"

void model_defaults(Model *m) { m->a = 1.0; m->b = 0.0; m->c = 0.0; m->q = 0.0; m->u = 0.0; m->fail = -1.0; }

void model_initialize(Model *m) { (void)m; }

double model_get(const Model *m, unsigned vr) {
    switch (vr) {
    INPUT_FIELDS(UNIT_GET)
    case VR_A: return m->a;
    case VR_B: return m->b;
    case VR_C: return m->c;
    case VR_Q: return m->q;
    case VR_FAIL: return m->fail;
    case VR_Y:
    case VR_W: return m->a * m->u + m->b + m->c * sin(m->u) + m->q * m->u * m->u * m->u;
    case VR_Z: return m->b;
    default: return 0.0;
    }
}

int model_set(Model *m, unsigned vr, double value) {
    switch (vr) {
    INPUT_FIELDS(UNIT_SET)
    case VR_A: m->a = value; return 0;
    case VR_B: m->b = value; return 0;
    case VR_C: m->c = value; return 0;
    case VR_Q: m->q = value; return 0;
    case VR_FAIL: m->fail = value; return 0;
    default: return -1; /* an output */
    }
}

void model_step(Model *m, const double *der, int max_order, double h) { m->u = poly_input(der, 0, max_order, h); }

int model_directional(const Model *m, const unsigned *unknowns, size_t n_unknowns, const unsigned *knowns,
                      size_t n_knowns, const double *seed, double *out) {
    double dy = m->a + m->c * cos(m->u) + 3.0 * m->q * m->u * m->u;
    for (size_t j = 0; j < n_unknowns; j++) {
        out[j] = 0.0;
        for (size_t k = 0; k < n_knowns; k++) {
            if (knowns[k] != VR_U) return -1;
            if (unknowns[j] == VR_Y || unknowns[j] == VR_W) out[j] += dy * seed[k];
            else if (unknowns[j] != VR_Z) return -1;
        }
    }
    return 0;
}

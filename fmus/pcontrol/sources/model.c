/* The proportional controller (fmus/README.md): no state; its output follows its inputs at once, and a step only
 * moves the inputs to their polynomials' values at the step end. */
#include "model.h"
#include "poly.h"

void model_defaults(Model *m) { m->kp = 1.0; m->r = 0.0; m->y = 0.0; m->fail = -1.0; }

void model_initialize(Model *m) { (void)m; }

double model_get(const Model *m, unsigned vr) {
    switch (vr) {
    INPUT_FIELDS(UNIT_GET)
    case VR_KP: return m->kp;
    case VR_FAIL: return m->fail;
    case VR_U: return m->kp * (m->r - m->y);
    default: return 0.0;
    }
}

int model_set(Model *m, unsigned vr, double value) {
    switch (vr) {
    INPUT_FIELDS(UNIT_SET)
    case VR_KP: m->kp = value; return 0;
    case VR_FAIL: m->fail = value; return 0;
    default: return -1; /* the output */
    }
}

void model_step(Model *m, const double *der, int max_order, double h) {
    m->r = poly_input(der, 0, max_order, h);
    m->y = poly_input(der, 1, max_order, h);
}

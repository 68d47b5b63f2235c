/* The oscillator units' shared code (msd, msd_kinematic; fmus/README.md), included by their model.c: the
 * parameters, the state x, v with its set hooks x_set, v_set, the input u (the unit's INPUT_FIELDS names its value
 * reference), all of model_defaults, model_initialize and model_set, and model_get but for the unit's own outputs. */
#ifndef ICOSIM_MSD_H
#define ICOSIM_MSD_H
#include "model.h"

#define MSD_FIELDS(X) X(VR_M, m) X(VR_C, c) X(VR_D, d) X(VR_X0, x0) X(VR_V0, v0) X(VR_FAIL, fail)

static double msd_output(const Model *m, unsigned vr); /* the unit's own outputs (its model.c), else 0 */

void model_defaults(Model *m) {
    m->m = 1.0; m->c = 1000.0; m->d = 2.0; m->x0 = 0.0; m->v0 = 0.0;
    m->u = 0.0; m->x = 0.0; m->v = 0.0; m->fail = -1.0;
}

void model_initialize(Model *m) { m->x = m->x0; m->v = m->v0; }

double model_get(const Model *m, unsigned vr) {
    switch (vr) {
    MSD_FIELDS(UNIT_GET)
    INPUT_FIELDS(UNIT_GET)
    case VR_X: case VR_XSET: return m->x;
    case VR_V: case VR_VSET: return m->v;
    default: return msd_output(m, vr);
    }
}

int model_set(Model *m, unsigned vr, double value) {
    switch (vr) {
    MSD_FIELDS(UNIT_SET)
    INPUT_FIELDS(UNIT_SET)
    case VR_XSET: m->x = value; return 0;
    case VR_VSET: m->v = value; return 0;
    default: return -1; /* outputs */
    }
}
#endif

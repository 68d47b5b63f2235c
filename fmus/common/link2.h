/* Link 2's shared code (pendulum_link2, pendulum_link2_kinematic; docs/pendulum.md), included by their model.c
 * after the unit's rhs: a free body with the state z = (x, y, phi, vx, vy, omega) of its centre, its joint point
 * the end at -(l/2) e2; all of model_defaults, model_initialize and model_step, and the joint point's position
 * and velocity (the unit's link2_output gives the rest, from the state's derivative f under the current inputs). */
#ifndef ICOSIM_LINK2_H
#define ICOSIM_LINK2_H
#define LINK2_FIELDS(X) X(VR_X0, x0) X(VR_Y0, y0) X(VR_VX0, vx0) X(VR_VY0, vy0) /* in the unit's MODEL_FIELDS */
#include "link.h"

static link_rhs rhs;
static double link2_output(const Model *m, unsigned vr, const double *f);

void model_defaults(Model *m) {
    link_defaults(m);
    m->x0 = 0.0; m->y0 = 0.0; m->vx0 = m->vy0 = 0.0;
    memset(m->z, 0, sizeof m->z);
}

void model_initialize(Model *m) {
    double z[6] = {m->x0, m->y0, m->phi0, m->vx0, m->vy0, m->omega0};
    memcpy(m->z, z, sizeof z);
}

static double link_output(const Model *m, unsigned vr) {
    const double *z = m->z;
    double c = cos(z[2]), s = sin(z[2]), h = m->l / 2, w = z[5], f[6];
    switch (vr) {
    case VR_PX: return z[0] - h * c;
    case VR_PY: return z[1] - h * s;
    case VR_VX: return z[3] + h * w * s;
    case VR_VY: return z[4] - h * w * c;
    default: rhs(m, z, m->ux, m->uy, f); return link2_output(m, vr, f);
    }
}

void model_step(Model *m, const double *der, int max_order, double h) { link_step(m, rhs, 6, m->z, der, max_order, h); }
#endif

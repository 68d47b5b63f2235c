/* Link 2 of the double pendulum (docs/pendulum.md), a free body whose joint point is driven kinematically: its
 * acceleration (a_x, a_y) is prescribed; outputs the joint point's position and velocity, the prescribed
 * acceleration and the joint force (Fx, Fy) that realises it. */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{8c4e810f-3df3-4a00-8276-176fa3c9f013}"
enum {
    VR_M, VR_L, VR_J, VR_G, VR_D, VR_X0, VR_Y0, VR_PHI0, VR_VX0, VR_VY0, VR_OMEGA0, VR_AXIN, VR_AYIN,
    VR_PX, VR_PY, VR_VX, VR_VY, VR_AX, VR_AY, VR_FX, VR_FY, VR_FAIL, VR_NSTEPS, NREAL
};
#define NINPUT 2
#define INPUT_VRS {VR_AXIN, VR_AYIN}
#define MODEL_FIELDS(X) LINK2_FIELDS(X) X(VR_AXIN, ux) X(VR_AYIN, uy) /* besides the links' common ones (link.h) */

typedef struct {
    double m, l, J, g, d, x0, y0, phi0, vx0, vy0, omega0, ux, uy, fail, nsteps; /* (ux, uy): the acceleration */
    double z[6]; /* x, y, phi, vx, vy, omega */
} Model;

#include "unit.h"
#endif

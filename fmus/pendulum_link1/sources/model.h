/* Link 1 of the double pendulum (docs/pendulum.md), pinned to the ground, driven by the joint force
 * (lambda_x, lambda_y) at its tip; outputs the joint point's position, velocity and acceleration. */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{8c4e810f-3df3-4a00-8276-176fa3c9f011}"
enum {
    VR_M, VR_L, VR_J, VR_G, VR_D, VR_PHI0, VR_OMEGA0, VR_LX, VR_LY,
    VR_PX, VR_PY, VR_VX, VR_VY, VR_AX, VR_AY, VR_FAIL, VR_NSTEPS, NREAL
};
#define NINPUT 2
#define INPUT_VRS {VR_LX, VR_LY}
#define MODEL_FIELDS(X) X(VR_LX, ux) X(VR_LY, uy) /* besides the links' common ones (link.h) */

typedef struct {
    double m, l, J, g, d, phi0, omega0, ux, uy, fail, nsteps; /* (ux, uy): the joint force */
    double z[2]; /* phi, omega */
} Model;

#include "unit.h"
#endif

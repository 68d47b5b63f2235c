/* A point driven by its position, velocity and acceleration (inputs x1, v1, a1, as Modelica's
 * Translational.Sources.Move), a spring-damper (k2, c2) from it to the mass m2 and a spring-damper (k3, c3) from
 * the mass to the ground; output F, the force sensed at the driven point (OMSimulator's
 * DualMassOscillator.System2; fmus/README.md). */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{8c4e810f-3df3-4a00-8276-176fa3c9f010}"
enum { VR_K2, VR_C2, VR_K3, VR_C3, VR_M2, VR_X20, VR_X1, VR_V1, VR_A1, VR_F, VR_X2, VR_V2, VR_FAIL, NREAL };
#define NINPUT 3
#define INPUT_VRS {VR_X1, VR_V1, VR_A1}
#define INPUT_FIELDS(X) X(VR_X1, x1) X(VR_V1, v1) X(VR_A1, a1)

typedef struct {
    double k2, c2, k3, c3, m2, x20, x1, v1, a1, x2, v2, fail;
} Model;

#include "unit.h"
#endif

/* A proportional controller: u = kp (r - y), the reference r and the measurement y its inputs (fmus/README.md). */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{8c4e810f-3df3-4a00-8276-176fa3c9f010}"
enum { VR_KP, VR_R, VR_Y, VR_U, VR_FAIL, NREAL };
#define NINPUT 2
#define INPUT_VRS {VR_R, VR_Y}
#define INPUT_FIELDS(X) X(VR_R, r) X(VR_Y, y)

typedef struct {
    double kp, r, y, fail;
} Model;

#include "unit.h"
#endif

/* The force-driven oscillator of fmus/msd (its model.c, through uses.txt) with the value reference of fault_time
 * added; faulty.c is the FMI 2.0 interface that injects the faults (fmus/README.md). */
#ifndef ICOSIM_MODEL_H
#define ICOSIM_MODEL_H

#define MODEL_GUID "{91f656dd-0835-41ec-bf9f-fc4f7427a411}"
enum { VR_M, VR_C, VR_D, VR_X0, VR_V0, VR_LAMBDA, VR_X, VR_V, VR_A, VR_XSET, VR_VSET, VR_FAIL, VR_FAULT_TIME, NREAL };
#define NINPUT 1
#define INPUT_VRS {VR_LAMBDA}
#define INPUT_FIELDS(X) X(VR_LAMBDA, u)

typedef struct {
    double m, c, d, x0, v0, u, x, v, fail; /* u: the force lambda */
} Model;

#include "unit.h"
#endif

/* What every unit's model.h declares besides its own variables (fmus/README.md), included at its end after the
 * Model struct: the functions fmi2_cs.c and fmi3_cs.c call, and the cases of model_get/model_set that read or write
 * a variable as it is (a unit lists them as X(value reference, field) pairs, e.g. MODEL_FIELDS(UNIT_GET)). */
#ifndef ICOSIM_UNIT_H
#define ICOSIM_UNIT_H

#define MAX_ORDER 12          /* the highest input derivative accepted (the engine's k <= 12) */
#define FAIL_TIME_VR VR_FAIL  /* the tunable parameter fail_time: a step starting at or after it is refused */

#define UNIT_GET(vr, field) case vr: return m->field;
#define UNIT_SET(vr, field) case vr: m->field = value; return 0;

void model_defaults(Model *m);
void model_initialize(Model *m);
double model_get(const Model *m, unsigned vr);
int model_set(Model *m, unsigned vr, double value); /* 0, or -1 for a variable that cannot be set */
/* the step of size h, der[k * (max_order + 1) + j] the j-th derivative of input k at its start (the 0th: the
 * input's value); afterwards the inputs hold their values at the step end */
void model_step(Model *m, const double *der, int max_order, double h);
#ifdef MODEL_DIRECTIONAL
#include <stddef.h>
/* out[j] = sum_k d unknowns[j] / d knowns[k] seed[k] at the present values (fmi2GetDirectionalDerivative); 0, or -1
 * for a pair the model does not give */
int model_directional(const Model *m, const unsigned *unknowns, size_t n_unknowns, const unsigned *knowns,
                      size_t n_knowns, const double *seed, double *out);
#endif
#endif

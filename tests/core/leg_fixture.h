/* Shared set-up for the core tests: a sim of the compiled-in leg, the stand
 * pose, and independent measures (energy, whole-leg balance) computed here
 * from the model description, not by the solver. */
#ifndef LEG_FIXTURE_H
#define LEG_FIXTURE_H

#include "legsim/legsim.h"
#include "legsim/models.h"

#define NQ 18
#define NJ 8
#define NA 2

typedef struct fixture_storage {
  _Alignas(16) unsigned char bytes[64 * 1024];
} fixture_storage;

/* A sim of the given variant, assembled at the stand pose (asserts on failure). */
legsim_sim *leg_at_stand(fixture_storage *st, const legsim_model_desc *model, legsim_options opt);
/* Kinetic + gravitational potential - sum of F_a * l_a (constant actuator forces). */
double leg_energy(const legsim_sim *sim, const double *actuator_force);
/* Position of a body-fixed point (xi, eta) of body b in the state q. */
void body_point(const legsim_real *q, int b, double xi, double eta, double *xy);
double max_abs_diff(const legsim_real *a, const legsim_real *b, int n);

#endif

/* The FMU's variable table, shared by the FMU (legsim_fmu.c) and the program that writes
 * its modelDescription.xml (describe.c). */
#ifndef LEGSIM_FMU_H
#define LEGSIM_FMU_H

#include "legsim/legsim.h"

/* changes with the variable table: the FMU refuses an instantiation with another token */
#define LEGSIM_FMU_TOKEN "{legsim-" LEGSIM_FMU_NAME "-1}"

typedef enum { LEGSIM_FMU_TIME, LEGSIM_FMU_PARAMETER, LEGSIM_FMU_INPUT, LEGSIM_FMU_OUTPUT } legsim_fmu_kind;

typedef struct legsim_fmu_var {
  unsigned vr;
  legsim_fmu_kind kind;
  int is_int; /* Int32 (else Float64) */
  char name[2 * LEGSIM_NAME_LEN + 16];
} legsim_fmu_var;

const legsim_model_desc *legsim_fmu_model(void);
/* variable index (0, 1, ...) -> its entry; 0 past the last */
int legsim_fmu_variable(int index, legsim_fmu_var *v);
/* the lengths of the model's first pose (a robot's: standing); 0 if it does not assemble */
int legsim_fmu_stand_lengths(double *len);

#endif

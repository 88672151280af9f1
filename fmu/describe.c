/* Writes the FMU's modelDescription.xml (FMI 3.0, co-simulation) from its variable table
 * (legsim_fmu.c), with each start value the FMU itself starts from.
 *   legsim_fmu_describe OUT.xml */
#include <stdio.h>
#include <string.h>

#include "fmi3Functions.h"
#include "legsim/version.h"
#include "legsim_fmu.h"

/* the start value of a parameter or input: what a fresh instance holds */
static int start_of(fmi3Instance c, const legsim_fmu_var *v, char *buf, size_t n) {
  if (v->is_int) {
    fmi3Int32 x;
    if (fmi3GetInt32(c, &v->vr, 1, &x, 1) != fmi3OK) return 0;
    snprintf(buf, n, "%d", (int)x);
  } else {
    fmi3Float64 x;
    if (fmi3GetFloat64(c, &v->vr, 1, &x, 1) != fmi3OK) return 0;
    snprintf(buf, n, "%.17g", x);
  }
  return 1;
}

static const char *unit_of(const char *name) {
  const char *dot = strrchr(name, '.');
  const char *s = dot ? dot + 1 : name;
  size_t l = strlen(s);
  if (l > 2 && strcmp(s + l - 2, "_m") == 0) return "m";
  if (l > 4 && strcmp(s + l - 4, "_rad") == 0) return "rad";
  if (l > 3 && strcmp(s + l - 3, "_nm") == 0) return "N.m";
  if (l > 2 && strcmp(s + l - 2, "_n") == 0) return "N";
  if (strcmp(s, "step_s") == 0 || strcmp(s, "time") == 0) return "s";
  return NULL;
}

int main(int argc, char **argv) {
  if (argc != 2) {
    fprintf(stderr, "usage: legsim_fmu_describe OUT.xml\n");
    return 2;
  }
  fmi3Instance c = fmi3InstantiateCoSimulation("describe", LEGSIM_FMU_TOKEN, NULL, 0, 0, 0, 0,
                                               NULL, 0, NULL, NULL, NULL);
  double len[LEGSIM_MAX_ACTUATORS];
  if (!c || !legsim_fmu_stand_lengths(len)) {
    fprintf(stderr, "legsim_fmu_describe: the model's first pose does not assemble\n");
    return 1;
  }
  FILE *f = fopen(argv[1], "w");
  if (!f) {
    perror(argv[1]);
    return 1;
  }
  const legsim_model_desc *m = legsim_fmu_model();
  legsim_options o = legsim_default_options();
  fprintf(f,
          "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
          "<fmiModelDescription fmiVersion=\"3.0\" modelName=\"legsim_%s\"\n"
          "  description=\"legsim: %s (%d bodies, %d joints, %d actuators, %d contacts) at its fixed "
          "step, through the C API legsim.h\"\n"
          "  generationTool=\"legsim fmu/describe.c\" version=\"%s\"\n"
          "  instantiationToken=\"%s\" variableNamingConvention=\"flat\">\n"
          "  <CoSimulation modelIdentifier=\"legsim_%s\" canHandleVariableCommunicationStepSize=\"true\"\n"
          "    fixedInternalStepSize=\"%.17g\" canReturnEarlyAfterIntermediateUpdate=\"false\"\n"
          "    providesIntermediateUpdate=\"false\" hasEventMode=\"false\"/>\n"
          "  <UnitDefinitions>\n"
          "    <Unit name=\"m\"><BaseUnit m=\"1\"/></Unit>\n"
          "    <Unit name=\"s\"><BaseUnit s=\"1\"/></Unit>\n"
          "    <Unit name=\"rad\"><BaseUnit rad=\"1\"/></Unit>\n"
          "    <Unit name=\"N\"><BaseUnit kg=\"1\" m=\"1\" s=\"-2\"/></Unit>\n"
          "    <Unit name=\"N.m\"><BaseUnit kg=\"1\" m=\"2\" s=\"-2\"/></Unit>\n"
          "  </UnitDefinitions>\n"
          "  <DefaultExperiment startTime=\"0\" stopTime=\"0.1\" stepSize=\"%.17g\"/>\n"
          "  <ModelVariables>\n",
          LEGSIM_FMU_NAME, m->name, m->n_bodies, m->n_joints, m->n_actuators, m->n_contacts,
          LEGSIM_VERSION_STRING, LEGSIM_FMU_TOKEN, LEGSIM_FMU_NAME, o.step_s, o.step_s);
  legsim_fmu_var v;
  unsigned outputs[4096];
  int n_out = 0;
  for (int i = 0; legsim_fmu_variable(i, &v); ++i) {
    const char *unit = unit_of(v.name);
    char unit_attr[32] = "";
    if (unit && !v.is_int) snprintf(unit_attr, sizeof unit_attr, " unit=\"%s\"", unit);
    const char *type = v.is_int ? "Int32" : "Float64";
    char start[64];
    switch (v.kind) {
      case LEGSIM_FMU_TIME:
        fprintf(f, "    <Float64 name=\"time\" valueReference=\"%u\" causality=\"independent\" "
                   "variability=\"continuous\"%s/>\n", v.vr, unit_attr);
        break;
      case LEGSIM_FMU_PARAMETER:
        if (!start_of(c, &v, start, sizeof start)) return 1;
        fprintf(f, "    <%s name=\"%s\" valueReference=\"%u\" causality=\"parameter\" "
                   "variability=\"fixed\"%s start=\"%s\"/>\n", type, v.name, v.vr, unit_attr, start);
        break;
      case LEGSIM_FMU_INPUT:
        if (!start_of(c, &v, start, sizeof start)) return 1;
        fprintf(f, "    <%s name=\"%s\" valueReference=\"%u\" causality=\"input\" "
                   "variability=\"continuous\"%s start=\"%s\"/>\n", type, v.name, v.vr, unit_attr, start);
        break;
      case LEGSIM_FMU_OUTPUT:
        fprintf(f, "    <%s name=\"%s\" valueReference=\"%u\" causality=\"output\" "
                   "variability=\"continuous\"%s/>\n", type, v.name, v.vr, unit_attr);
        outputs[n_out++] = v.vr;
        break;
    }
  }
  fprintf(f, "  </ModelVariables>\n  <ModelStructure>\n");
  for (int k = 0; k < n_out; ++k) fprintf(f, "    <Output valueReference=\"%u\"/>\n", outputs[k]);
  for (int k = 0; k < n_out; ++k)
    fprintf(f, "    <InitialUnknown valueReference=\"%u\"/>\n", outputs[k]);
  fprintf(f, "  </ModelStructure>\n</fmiModelDescription>\n");
  fmi3FreeInstance(c);
  return fclose(f) == 0 ? 0 : 1;
}

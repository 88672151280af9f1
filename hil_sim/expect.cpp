// hil_sim_expect: the in-process expectation of a lockstep run, straight on the C API (no
// CAN, none of hil_sim's code): reset as hil_sim's RESET does, then steps, printing the
// state every K steps as JSON lines (%.17g). tests/hil compares hil_sim's CAN states to it.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "legsim/legsim.h"
#include "legsim/models.h"

namespace {

const char kUsage[] =
    "usage: hil_sim_expect [--variant revolute|slot] [--integrator rk4|generalized_alpha]\n"
    "                      [--step-ns N] [--steps N] [--every K] [--hold-length] [--disable N]\n"
    "Prints the state after the assembly of pose 0 and then every K steps up to N (JSON lines).\n";

void print_array(const char *name, const legsim_real *v, int n) {
  std::printf("\"%s\": [", name);
  for (int i = 0; i < n; ++i) std::printf("%s%.17g", i ? ", " : "", static_cast<double>(v[i]));
  std::printf("], ");
}

int print_state(const legsim_sim *sim) {
  legsim_real q[3 * LEGSIM_MAX_BODIES], qd[3 * LEGSIM_MAX_BODIES], len[LEGSIM_MAX_ACTUATORS],
      rate[LEGSIM_MAX_ACTUATORS], force[LEGSIM_MAX_ACTUATORS], phi[LEGSIM_MAX_ROWS], res = 0;
  legsim_reaction r[LEGSIM_MAX_JOINTS];
  const int nc = legsim_n_coords(sim), na = legsim_n_actuators(sim), nj = legsim_n_joints(sim);
  if (legsim_get_q(sim, q) || legsim_get_qd(sim, qd) || legsim_actuator_lengths(sim, len, rate) ||
      legsim_actuator_forces(sim, force) || legsim_constraints(sim, phi, &res))
    return 1;
  bool have_reactions = legsim_reactions(sim, r) == LEGSIM_OK;
  legsim_real flat[3 * LEGSIM_MAX_JOINTS] = {};
  for (int j = 0; j < nj && have_reactions; ++j) {
    flat[3 * j] = r[j].force_n[0];
    flat[3 * j + 1] = r[j].force_n[1];
    flat[3 * j + 2] = r[j].moment_nm;
  }
  std::printf("{\"step_count\": %llu, \"t\": %.17g, ",
              static_cast<unsigned long long>(legsim_step_count(sim)), legsim_time(sim));
  print_array("q", q, nc);
  print_array("qd", qd, nc);
  print_array("lengths", len, na);
  print_array("rates", rate, na);
  print_array("forces", force, na);
  print_array("reactions", flat, 3 * nj);
  std::printf("\"residual\": %.17g}\n", static_cast<double>(res));
  return 0;
}

}  // namespace

int main(int argc, char **argv) {
  const legsim_model_desc *model = &legsim_model_leg_revolute;
  legsim_options opt = legsim_default_options();
  unsigned long step_ns = 1000000, steps = 0, every = 0;
  bool hold = false;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    const char *v = i + 1 < argc ? argv[i + 1] : nullptr;
    if (a == "-h" || a == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    } else if (a == "--hold-length") {
      hold = true;
      continue;
    } else if (v == nullptr) {
      std::fprintf(stderr, "hil_sim_expect: bad arguments\n%s", kUsage);
      return 2;
    }
    ++i;
    std::string s = v;
    if (a == "--variant" && (s == "revolute" || s == "slot"))
      model = s == "slot" ? &legsim_model_leg_slot : &legsim_model_leg_revolute;
    else if (a == "--integrator" && (s == "rk4" || s == "generalized_alpha"))
      opt.integrator = s == "rk4" ? LEGSIM_INTEGRATOR_RK4 : LEGSIM_INTEGRATOR_GENERALIZED_ALPHA;
    else if (a == "--step-ns")
      step_ns = std::strtoul(v, nullptr, 10);
    else if (a == "--steps")
      steps = std::strtoul(v, nullptr, 10);
    else if (a == "--every")
      every = std::strtoul(v, nullptr, 10);
    else if (a == "--disable")
      opt.disable = static_cast<uint32_t>(std::strtoul(v, nullptr, 10));
    else {
      std::fprintf(stderr, "hil_sim_expect: bad argument %s %s\n%s", argv[i - 1], v, kUsage);
      return 2;
    }
  }
  if (every == 0) every = steps > 0 ? steps : 1;
  opt.step_s = static_cast<double>(step_ns) / 1e9;

  size_t bytes = (legsim_sim_size() + LEGSIM_STORAGE_ALIGN - 1) / LEGSIM_STORAGE_ALIGN *
                 LEGSIM_STORAGE_ALIGN;
  void *storage = std::aligned_alloc(LEGSIM_STORAGE_ALIGN, bytes);
  legsim_sim *sim = nullptr;
  legsim_status st = legsim_init(storage, bytes, model, &opt, &sim);
  if (st == LEGSIM_OK) st = legsim_assemble_pose(sim, 0);
  legsim_real len[LEGSIM_MAX_ACTUATORS], rate[LEGSIM_MAX_ACTUATORS];
  if (st == LEGSIM_OK && hold) st = legsim_actuator_lengths(sim, len, rate);
  for (int a = 0; a < legsim_n_actuators(sim) && st == LEGSIM_OK; ++a)
    st = hold ? legsim_command_length(sim, a, len[a]) : legsim_command_force(sim, a, 0);
  if (st != LEGSIM_OK || print_state(sim) != 0) {
    std::fprintf(stderr, "hil_sim_expect: %s\n", legsim_status_str(st));
    return 1;
  }
  for (unsigned long done = 0; done < steps;) {
    unsigned long n = steps - done < every ? steps - done : every;
    st = legsim_step(sim, static_cast<int32_t>(n));
    if (st != LEGSIM_OK) {
      std::fprintf(stderr, "hil_sim_expect: step %llu: %s\n",
                   static_cast<unsigned long long>(legsim_step_count(sim)), legsim_status_str(st));
      return 1;
    }
    done += n;
    print_state(sim);
  }
  std::free(storage);
  return 0;
}

// Fuzz target: the run-time model loader (firmware_core/host/model_toml.cpp), TOML text in.
//
// Every input must give a clean status with a message, never a crash or undefined
// behaviour (toml++ included). A model the loader accepts must pass legsim_model_check,
// be accepted by legsim_init, and then keep the C API's promises with it: after each call
// that returns LEGSIM_OK (assembling each pose, statics, RK4 and generalized-alpha steps)
// the state, the report, the reactions and the actuator figures are finite; after a
// refused call the report is still finite (issue 10, sections 1 and 2).
//
// A robot file names its leg files relative to its own folder, and the text is parsed as
// if it were a file of a seed folder (kSeedFolders, absolute: whatever the working
// directory): models/ (robot.toml's "leg.toml"), then tests/model/fixtures/ (the robot
// fixtures' "../../../models/leg.toml") when a leg file cannot be read from the first.
// A robot that loads is also put on its ground and stepped with its feet in contact.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "legsim/legsim.h"
#include "model_toml.hpp"
#include "reach.h"

FUZZ_REACH_DEFINE

namespace {

// "FOLDER/fuzz.toml": the source name, whose folder the loader reads leg files from.
const char *const kSeedFolders[] = {LEGSIM_FUZZ_SOURCE_DIR "/models/fuzz.toml",
                                    LEGSIM_FUZZ_SOURCE_DIR "/tests/model/fixtures/fuzz.toml"};

[[noreturn]] void violated(const std::string &what) {
  std::fprintf(stderr, "fuzz_model: invariant violated: %s\n", what.c_str());
  std::abort();
}

void finite(const legsim_real *v, int n, const std::string &what) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(static_cast<double>(v[i])))
      violated(what + "[" + std::to_string(i) + "] = " + std::to_string(static_cast<double>(v[i])));
}

void report_finite(const legsim_sim *sim, const std::string &after) {
  legsim_report rep;
  if (legsim_get_report(sim, &rep) != LEGSIM_OK) violated("legsim_get_report refused after " + after);
  finite(&rep.residual, 1, "report.residual after " + after);
  finite(&rep.condition, 1, "report.condition after " + after);
}

// After a call returned OK: everything the sim reports is finite.
void outputs_finite(const legsim_sim *sim, const std::string &after) {
  report_finite(sim, after);
  const int nq = legsim_n_coords(sim), nc = legsim_n_constraints(sim), nj = legsim_n_joints(sim),
            na = legsim_n_actuators(sim);
  legsim_real v[3 * LEGSIM_MAX_BODIES + 3 * LEGSIM_MAX_JOINTS];
  if (legsim_get_q(sim, v) == LEGSIM_OK) finite(v, nq, "q after " + after);
  if (legsim_get_qd(sim, v) == LEGSIM_OK) finite(v, nq, "qd after " + after);
  if (legsim_get_qdd(sim, v) == LEGSIM_OK) finite(v, nq, "qdd after " + after);
  legsim_real max_abs = 0;
  if (legsim_constraints(sim, v, &max_abs) == LEGSIM_OK) {
    finite(v, nc, "Phi after " + after);
    finite(&max_abs, 1, "max |Phi| after " + after);
  }
  if (legsim_multipliers(sim, v) == LEGSIM_OK) finite(v, nc, "multipliers after " + after);
  legsim_reaction r[LEGSIM_MAX_JOINTS];
  if (nj > 0 && legsim_reactions(sim, r) == LEGSIM_OK)
    for (int j = 0; j < nj; ++j) {
      finite(r[j].force_n, 2, "reaction force after " + after);
      finite(&r[j].moment_nm, 1, "reaction moment after " + after);
    }
  if (na > 0) {
    legsim_real len[LEGSIM_MAX_ACTUATORS], rate[LEGSIM_MAX_ACTUATORS];
    if (legsim_actuator_lengths(sim, len, rate) == LEGSIM_OK) {
      finite(len, na, "actuator lengths after " + after);
      finite(rate, na, "actuator rates after " + after);
    }
    if (legsim_actuator_forces(sim, len) == LEGSIM_OK) finite(len, na, "actuator forces after " + after);
  }
  legsim_real xy[2];
  if (legsim_foot_position(sim, xy) == LEGSIM_OK) finite(xy, 2, "foot after " + after);
}

void check_message(legsim_status st, const char *msg, size_t cap) {
  if (std::memchr(msg, '\0', cap) == nullptr) violated("message not terminated");
  if (st != LEGSIM_OK && msg[0] == '\0')
    violated(std::string("status ") + legsim_status_str(st) + " without a message");
}

void *storage() {
  static void *p = std::aligned_alloc(LEGSIM_STORAGE_ALIGN,
                                      (legsim_sim_size() + LEGSIM_STORAGE_ALIGN - 1) /
                                          LEGSIM_STORAGE_ALIGN * LEGSIM_STORAGE_ALIGN);
  return p;
}

// The loaded model in use: init, each pose (at most 2), statics, a few steps of each
// integrator.
void exercise(const legsim_model_desc &m) {
  char msg[256];
  std::memset(msg, 'x', sizeof msg);  // a message must end inside msg
  msg[0] = '\0';
  legsim_status st = legsim_model_check(&m, msg, sizeof msg);
  check_message(st, msg, sizeof msg);
  if (st != LEGSIM_OK) violated(std::string("the loader accepted a model legsim_model_check refuses: ") + msg);
  legsim_options opt = legsim_default_options();
  legsim_sim *sim = nullptr;
  const size_t bytes = (legsim_sim_size() + LEGSIM_STORAGE_ALIGN - 1) / LEGSIM_STORAGE_ALIGN * LEGSIM_STORAGE_ALIGN;
  st = legsim_init(storage(), bytes, &m, &opt, &sim);
  if (st != LEGSIM_OK) violated(std::string("legsim_init refused a loaded model: ") + legsim_status_str(st));
  const int n_poses = m.n_poses < 2 ? m.n_poses : 2;
  for (int p = 0; p < n_poses; ++p) {
    const std::string pose = "pose " + std::to_string(p);
    opt.integrator = LEGSIM_INTEGRATOR_RK4;
    if (legsim_set_options(sim, &opt) != LEGSIM_OK) violated("default options refused");
    st = legsim_assemble_pose(sim, p);
    report_finite(sim, "assembling " + pose);
    if (st != LEGSIM_OK) continue;
    outputs_finite(sim, "assembling " + pose);
    if (m.n_actuators > 0) {
      legsim_real f[LEGSIM_MAX_ACTUATORS];
      st = legsim_statics(sim, f);
      report_finite(sim, "statics in " + pose);
      if (st == LEGSIM_OK) {
        finite(f, m.n_actuators, "statics forces in " + pose);
        outputs_finite(sim, "statics in " + pose);
      }
    }
    for (int integrator = 0; integrator < 2; ++integrator) {
      const std::string what = std::string(integrator ? "generalized-alpha" : "RK4") + " steps from " + pose;
      opt.integrator = integrator ? LEGSIM_INTEGRATOR_GENERALIZED_ALPHA : LEGSIM_INTEGRATOR_RK4;
      if (legsim_set_options(sim, &opt) != LEGSIM_OK) violated("integrator option refused");
      for (int k = 0; k < 5; ++k) {
        st = legsim_step(sim, 1);
        report_finite(sim, what);
        if (st != LEGSIM_OK) break;
        outputs_finite(sim, what);
      }
    }
  }
  if (m.n_contacts > 0) {  // the robot: on its ground, feet stuck, then stepped
    fuzz_reach::robot();
    opt.integrator = LEGSIM_INTEGRATOR_RK4;
    if (legsim_set_options(sim, &opt) != LEGSIM_OK) violated("default options refused");
    if (n_poses > 0 && legsim_assemble_pose(sim, 0) != LEGSIM_OK) return;
    st = legsim_assemble_on_ground(sim, nullptr, 0);
    report_finite(sim, "assembling on the ground");
    if (st != LEGSIM_OK) return;
    outputs_finite(sim, "assembling on the ground");
    legsim_contact c[LEGSIM_CONTACT_SLOTS];
    if (legsim_contacts(sim, c) != LEGSIM_OK) violated("legsim_contacts refused after assembling on the ground");
    for (int k = 0; k < m.n_contacts; ++k)
      if (c[k].state != LEGSIM_CONTACT_STUCK) violated("a foot not stuck after assembling on the ground");
    for (int k = 0; k < 10; ++k) {
      st = legsim_step(sim, 1);
      report_finite(sim, "steps on the ground");
      if (st != LEGSIM_OK) break;
      outputs_finite(sim, "steps on the ground");
      if (legsim_contacts(sim, c) != LEGSIM_OK) violated("legsim_contacts refused after an OK step");
      for (int j = 0; j < m.n_contacts; ++j) {
        finite(&c[j].normal_n, 1, "contact normal force");
        finite(&c[j].tangential_n, 1, "contact tangential force");
        finite(c[j].position, 2, "contact position");
      }
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  fuzz_reach::input("fuzz_model");
  const char *text = reinterpret_cast<const char *>(data);
  for (const char *variant : {static_cast<const char *>(nullptr), "slot"}) {
    legsim_model_desc m;
    char msg[1024];
    legsim_status st = LEGSIM_OK;
    for (const char *source : kSeedFolders) {
      std::memset(msg, 'x', sizeof msg);  // a message must end inside msg
      msg[0] = '\0';
      st = legsim_model_parse_toml(text, size, source, variant, &m, msg, sizeof msg);
      check_message(st, msg, sizeof msg);
      if (!(st == LEGSIM_ERR_BAD_INPUT && std::strstr(msg, ": cannot read: ") != nullptr)) break;
    }
    if (st != LEGSIM_OK) {
      if (st != LEGSIM_ERR_MODEL && st != LEGSIM_ERR_CAPACITY && st != LEGSIM_ERR_BAD_INPUT)
        violated(std::string("unexpected status ") + legsim_status_str(st) + ": " + msg);
      continue;
    }
    exercise(m);
  }
  return 0;
}

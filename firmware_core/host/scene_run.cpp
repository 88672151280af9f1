// Running a bound scene's analysis through the C API, handing each sample to a writer.
// Host only.
#include "scene_text.hpp"
#include "scene_toml.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

namespace legsim_host {
namespace {

using scene_text::num;
using scene_text::q;

struct Storage {
  void *p = nullptr;
  explicit Storage(size_t n) {
    const size_t a = LEGSIM_STORAGE_ALIGN;
    p = std::aligned_alloc(a, (n + a - 1) / a * a);
  }
  ~Storage() { std::free(p); }
  Storage(const Storage &) = delete;
  Storage &operator=(const Storage &) = delete;
};

std::string q_name(const legsim_model_desc &m, int32_t k) { return q(scene_text::name_of(m.contact[k].name)); }

std::string call_failed(const std::string &what, legsim_status st) {
  return what + ": " + status_enum_name(st) + " (" + legsim_status_str(st) + ")";
}

// Reads the sim's state into a sample; forces: from the analysis (or NULL: the sim's).
void record(legsim_sim *sim, const legsim_model_desc &m, double t, const legsim_real *forces,
            Sample &s) {
  s = Sample{};
  s.t = t;
  const int32_t nq = legsim_n_coords(sim), na = legsim_n_actuators(sim), nj = legsim_n_joints(sim),
                nc = legsim_n_constraints(sim);
  std::vector<legsim_real> buf(std::max({nq, na, 3 * nj, nc, 1}));
  legsim_get_q(sim, buf.data());
  s.q.assign(buf.begin(), buf.begin() + nq);
  if (na > 0) {
    std::vector<legsim_real> len(na), rate(na), f(na);
    legsim_actuator_lengths(sim, len.data(), rate.data());
    if (forces)
      std::copy(forces, forces + na, f.begin());
    else
      legsim_actuator_forces(sim, f.data());
    s.length.assign(len.begin(), len.end());
    s.rate.assign(rate.begin(), rate.end());
    s.force.assign(f.begin(), f.end());
  }
  std::vector<legsim_reaction> r(std::max(nj, 1));
  if (nj > 0 && legsim_reactions(sim, r.data()) == LEGSIM_OK) {
    s.has_reactions = true;
    for (int32_t j = 0; j < nj; ++j) {
      s.reaction.push_back(r[j].force_n[0]);
      s.reaction.push_back(r[j].force_n[1]);
      s.reaction.push_back(r[j].moment_nm);
    }
  }
  if (m.foot_body >= 0) {
    legsim_real xy[2];
    if (legsim_foot_position(sim, xy) == LEGSIM_OK) {
      s.has_foot = true;
      s.foot[0] = xy[0];
      s.foot[1] = xy[1];
    }
  }
  if (const int32_t nk = legsim_n_contacts(sim); nk > 0) {
    s.contacts.resize(nk);
    if (legsim_contacts(sim, s.contacts.data()) != LEGSIM_OK) s.contacts.clear();
  }
  legsim_real max_abs = 0;
  if (legsim_constraints(sim, buf.data(), &max_abs) == LEGSIM_OK) s.residual = max_abs;
  legsim_report rep;
  if (legsim_get_report(sim, &rep) == LEGSIM_OK) {
    s.iterations = rep.iterations;
    s.condition = rep.condition;
    s.events = rep.events;
  }
  legsim_clear_events(sim);
}

// [start]: the stance moved rigidly (turned by tilt about the box's centre, raised by lift
// along the ground's normal, every body moving with the box), then each foot's state: on
// the ground (|gap| <= newton_tol) stuck by default, above it free; a [[contact]] state that
// the start cannot honour (stuck or sliding off the ground, stuck while moving, a foot below
// the ground, a foot on the ground and moving without a state) is refused, never adjusted.
}  // namespace

bool start_length_in_stroke(const legsim_model_desc &m, int32_t a, double l) {
  const legsim_actuator_desc &ad = m.actuator[a];
  return l >= ad.stroke_min_m && l <= ad.stroke_max_m;  // false for NaN
}

legsim_status start_apply(legsim_sim *sim, const legsim_model_desc &m, const StartState &b,
                          const int32_t *given_state, double tol, std::string &error) {
  const int32_t nq = legsim_n_coords(sim), nk = legsim_n_contacts(sim);
  std::vector<legsim_real> q(nq), qd(nq, 0);
  std::vector<legsim_contact> c(nk);
  legsim_status st = legsim_get_q(sim, q.data());
  if (st == LEGSIM_OK) st = legsim_contacts(sim, c.data());  // fresh: the assembly on the ground
  if (st != LEGSIM_OK) {
    error = call_failed("reading the stance", st);
    return st;
  }
  const legsim_ground_desc &g = m.ground;
  const double nx = -std::sin(g.slope_rad), ny = std::cos(g.slope_rad);
  const double ct = std::cos(b.tilt_rad), stt = std::sin(b.tilt_rad);
  const double cx = q[0], cy = q[1];  // the box: body 0 of a robot
  // a point of the stance where the start puts it, and its velocity
  auto moved = [&](double x, double y, double out[2], double vel[2]) {
    const double rx = ct * (x - cx) - stt * (y - cy), ry = stt * (x - cx) + ct * (y - cy);
    out[0] = cx + rx + b.lift_m * nx;
    out[1] = cy + ry + b.lift_m * ny;
    vel[0] = b.velocity_mps[0] - b.spin_radps * ry;
    vel[1] = b.velocity_mps[1] + b.spin_radps * rx;
  };
  for (int32_t i = 0; i + 2 < nq; i += 3) {
    double p[2], v[2];
    moved(q[i], q[i + 1], p, v);
    q[i] = static_cast<legsim_real>(p[0]);
    q[i + 1] = static_cast<legsim_real>(p[1]);
    q[i + 2] = static_cast<legsim_real>(q[i + 2] + b.tilt_rad);
    qd[i] = static_cast<legsim_real>(v[0]);
    qd[i + 1] = static_cast<legsim_real>(v[1]);
    qd[i + 2] = static_cast<legsim_real>(b.spin_radps);
  }
  // each foot's start state, decided before anything changes (all or nothing)
  std::vector<legsim_contact_state> want(nk, LEGSIM_CONTACT_FREE);
  for (int32_t k = 0; k < nk; ++k) {
    double p[2], v[2];
    moved(c[k].position[0], c[k].position[1], p, v);
    const double gap = nx * (p[0] - g.point[0]) + ny * (p[1] - g.point[1]);
    const double speed = std::hypot(v[0], v[1]), vn = nx * v[0] + ny * v[1];
    const std::string name = "contact " + q_name(m, k);
    const int32_t given = given_state ? given_state[k] : -1;
    if (gap < -tol) {
      error = "[start]: " + name + " would start " + num(-gap) + " m below the ground";
      return LEGSIM_ERR_STATE;
    }
    const bool on_ground = gap <= tol;
    if (given < 0) {
      if (on_ground && speed > tol) {
        error = "[start]: " + name + " is on the ground and moving at " + num(speed) +
                " m/s at t = 0: give its [[contact]] state (free or sliding)";
        return LEGSIM_ERR_STATE;
      }
      want[k] = on_ground ? LEGSIM_CONTACT_STUCK : LEGSIM_CONTACT_FREE;
      continue;
    }
    if (given != LEGSIM_CONTACT_FREE && given != LEGSIM_CONTACT_STUCK && given != LEGSIM_CONTACT_SLIDING) {
      error = "[start]: " + name + ": no contact state " + std::to_string(given);
      return LEGSIM_ERR_BAD_INPUT;
    }
    want[k] = static_cast<legsim_contact_state>(given);
    if (given != LEGSIM_CONTACT_FREE && !on_ground) {
      error = "[start]: " + name + " cannot start " + (given == LEGSIM_CONTACT_STUCK ? "stuck" : "sliding") +
              ": it is " + num(gap) + " m above the ground";
      return LEGSIM_ERR_STATE;
    }
    if (given == LEGSIM_CONTACT_STUCK && speed > tol) {
      error = "[start]: " + name + " cannot start stuck: the start moves it at " + num(speed) + " m/s";
      return LEGSIM_ERR_STATE;
    }
    if (given == LEGSIM_CONTACT_SLIDING && std::fabs(vn) > tol) {
      error = "[start]: " + name + " cannot start sliding: the start moves it off the line at " + num(vn) +
              " m/s";
      return LEGSIM_ERR_STATE;
    }
  }
  for (int32_t k = 0; k < nk && st == LEGSIM_OK; ++k) st = legsim_set_contact_state(sim, k, LEGSIM_CONTACT_FREE);
  if (st == LEGSIM_OK) st = legsim_set_state(sim, q.data(), qd.data(), legsim_time(sim));
  if (st != LEGSIM_OK) {
    error = call_failed("[start]: setting the start state", st);
    return st;
  }
  for (int32_t k = 0; k < nk; ++k) {
    if (want[k] == LEGSIM_CONTACT_FREE) continue;
    st = legsim_set_contact_state(sim, k, want[k]);
    if (st != LEGSIM_OK) {
      error = call_failed("[start]: setting " + q_name(m, k) + (want[k] == LEGSIM_CONTACT_STUCK ? " stuck" : " sliding"),
                          st);
      return st;
    }
  }
  return LEGSIM_OK;
}

namespace {

legsim_status run(const Scene &sc, const legsim_model_desc &m, ResultWriter &out, Result &res) {
  Storage storage(legsim_sim_size());
  if (!storage.p) {
    res.error = "out of memory";
    return LEGSIM_ERR_STORAGE;
  }
  legsim_sim *sim = nullptr;
  // box_load: the description with the box's two force elements (it must outlive the sim)
  std::unique_ptr<legsim_model_desc> loaded;
  if (sc.has_box_load) {
    loaded.reset(new legsim_model_desc(m));
    std::string why;
    if (!box_load_add(*loaded, sc.box_load, why)) {
      res.error = "box_load: " + why;
      return LEGSIM_ERR_CAPACITY;
    }
  }
  legsim_status st =
      legsim_init(storage.p, legsim_sim_size(), loaded ? loaded.get() : &m, &sc.options, &sim);
  if (st != LEGSIM_OK) {
    res.error = call_failed("legsim_init", st);
    return st;
  }
  for (const auto &f : sc.forces) {
    legsim_real v[2] = {static_cast<legsim_real>(f.value[0]), static_cast<legsim_real>(f.value[1])};
    st = legsim_set_force(sim, f.index, v);
    if (st != LEGSIM_OK) {
      res.error = call_failed("setting force " + q(f.name), st);
      return st;
    }
  }
  if (sc.pose_index >= 0) {
    st = legsim_assemble_pose(sim, sc.pose_index);
    if (st != LEGSIM_OK) {
      res.error = call_failed("assembling pose " + q(m.pose[sc.pose_index].name), st);
      return st;
    }
  }
  const int32_t na = legsim_n_actuators(sim);
  const int32_t nk = legsim_n_contacts(sim);
  if (nk > 0) {
    // A robot stands on the ground: the feet on the line, their midpoint where the pose put
    // it (its guess has them there), the box pose following; every contact stuck.
    std::vector<legsim_contact> c(nk);
    st = legsim_contacts(sim, c.data());
    double mid = 0;
    const legsim_ground_desc &g = m.ground;
    for (const auto &k : c)
      mid += ((k.position[0] - g.point[0]) * std::cos(g.slope_rad) +
              (k.position[1] - g.point[1]) * std::sin(g.slope_rad)) / nk;
    std::vector<legsim_real> len(sc.lengths.begin(), sc.lengths.end());
    if (st == LEGSIM_OK)
      st = legsim_assemble_on_ground(sim, sc.has_lengths ? len.data() : nullptr, static_cast<legsim_real>(mid));
    if (st != LEGSIM_OK) {
      std::string l;
      for (size_t i = 0; i < sc.lengths.size(); ++i) l += (i ? ", " : "") + num(sc.lengths[i]);
      res.error = call_failed(sc.has_lengths ? "assembling on the ground at the lengths [" + l + "]"
                                             : std::string("assembling on the ground"), st);
      return st;
    }
    if (sc.start.given) {
      std::vector<int32_t> given(nk, -1);
      for (const auto &ci : sc.contacts) given[ci.index] = ci.state;
      st = start_apply(sim, m, sc.start, given.data(), sc.options.newton_tol, res.error);
      if (st != LEGSIM_OK) return st;
    }
    for (const auto &ci : sc.contacts) {
      if (sc.start.given) break;  // start_state set them
      st = legsim_set_contact_state(sim, ci.index, ci.state);
      if (st != LEGSIM_OK) {
        res.error = call_failed("setting contact " + q(ci.name) + " " +
                                    (ci.state == LEGSIM_CONTACT_FREE ? "free" : "stuck"), st);
        return st;
      }
    }
  } else if (sc.has_lengths) {
    std::vector<legsim_real> len(sc.lengths.begin(), sc.lengths.end());
    st = legsim_assemble(sim, len.data());
    if (st != LEGSIM_OK) {
      std::string l;
      for (size_t i = 0; i < sc.lengths.size(); ++i) l += (i ? ", " : "") + num(sc.lengths[i]);
      res.error = call_failed("assembling the lengths [" + l + "]", st);
      return st;
    }
  }
  std::vector<legsim_real> forces(std::max(na, 1)), assembled(std::max(na, 1));
  if (na > 0) legsim_actuator_lengths(sim, assembled.data(), nullptr);
  // value = "initial": the length each actuator was assembled at
  std::vector<Command> commands = sc.commands;
  for (Command &c : commands)
    if (c.signal.kind == Signal::kInitial) c.signal.value = assembled[c.index];
  Sample sample;
  auto emit = [&](double t, const legsim_real *f) {
    record(sim, m, t, f, sample);
    out.sample(sample);
    ++res.n_samples;
  };

  switch (sc.analysis) {
    case Analysis::kAssembly:
      emit(legsim_time(sim), nullptr);
      return LEGSIM_OK;

    case Analysis::kStatics:
      st = legsim_statics(sim, forces.data());
      if (st != LEGSIM_OK) {
        res.error = call_failed("statics", st);
        return st;
      }
      emit(legsim_time(sim), forces.data());
      return LEGSIM_OK;

    case Analysis::kStaticsSweep:
      st = legsim_statics_sweep(sim, sc.grid, &res.worst);
      if (st != LEGSIM_OK) {
        res.error = call_failed("statics sweep", st);
        return st;
      }
      res.has_worst_case = true;
      return LEGSIM_OK;

    case Analysis::kInverseDynamics: {
      // Uncommanded actuators hold their assembled length; a robot's (feet stuck) follow: their
      // motion comes from the commanded lengths and the feet (legsim_inverse_dynamics_on_ground).
      uint32_t follow = 0;
      if (nk > 0) {
        follow = (1u << na) - 1;
        for (const auto &c : commands) follow &= ~(1u << c.index);
      }
      std::vector<legsim_real> len(std::max(na, 1)), rate(std::max(na, 1)), acc(std::max(na, 1));
      for (int64_t k = 0; k <= sc.n_steps; ++k) {
        const double t = static_cast<double>(k * sc.step_ns) / 1e9;
        for (int32_t a = 0; a < na; ++a) {
          len[a] = assembled[a];
          rate[a] = acc[a] = 0;
        }
        for (const auto &c : commands) {
          len[c.index] = static_cast<legsim_real>(c.signal.at(t));
          rate[c.index] = static_cast<legsim_real>(c.signal.rate(t));
          acc[c.index] = static_cast<legsim_real>(c.signal.accel(t));
        }
        st = nk > 0 ? legsim_inverse_dynamics_on_ground(sim, follow, len.data(), rate.data(), acc.data(),
                                                        forces.data())
                    : legsim_inverse_dynamics(sim, len.data(), rate.data(), acc.data(), forces.data());
        if (st != LEGSIM_OK) {
          res.failed_at_s = t;
          res.error = call_failed("inverse dynamics at t = " + num(t) + " s", st);
          return st;
        }
        if (k % sc.record_every == 0 || k == sc.n_steps) emit(t, forces.data());
      }
      return LEGSIM_OK;
    }

    case Analysis::kDynamics: {
      // init: what every actuator does until a command says otherwise
      for (int32_t a = 0; a < na; ++a) {
        st = sc.init == ActuatorInit::kHoldLength ? legsim_command_length(sim, a, assembled[a])
                                                   : legsim_command_force(sim, a, 0);
        if (st != LEGSIM_OK) {
          res.error = call_failed(std::string("init = ") + init_name(sc.init), st);
          return st;
        }
      }
      // a command switched on an event: after from the step after the one that raised it
      std::vector<char> switched(commands.size(), 0);
      auto apply = [&](double t) -> legsim_status {
        for (size_t i = 0; i < commands.size(); ++i) {
          const Command &c = commands[i];
          const legsim_real v = static_cast<legsim_real>(switched[i] ? c.signal.after : c.signal.at(t));
          const legsim_status s2 = c.mode == LEGSIM_ACTUATOR_FORCE ? legsim_command_force(sim, c.index, v)
                                                                  : legsim_command_length(sim, c.index, v);
          if (s2 != LEGSIM_OK) {
            res.failed_at_s = t;
            res.error = call_failed("command " + q(c.actuator) + " at t = " + num(t) + " s", s2);
            return s2;
          }
        }
        return LEGSIM_OK;
      };
      st = apply(0.0);
      // the contact modes at t = 0, as the first step's start finds them: a start that cannot
      // hold changes mode here and the first sample shows it
      if (st == LEGSIM_OK && nk > 0) {
        st = legsim_contacts_check(sim);
        if (st != LEGSIM_OK) res.error = call_failed("checking the contact modes at t = 0", st);
      }
      if (st != LEGSIM_OK) return st;
      // A robot's first sample: the assembly's multipliers are not the dynamics' forces
      // (the first step solves those), so its reactions and ground forces are null, as the
      // leg's reactions are.
      record(sim, m, legsim_time(sim), nullptr, sample);
      if (legsim_n_contacts(sim) > 0) {
        sample.has_reactions = false;
        sample.contact_forces = false;
      }
      out.sample(sample);
      ++res.n_samples;
      for (int64_t k = 1; k <= sc.n_steps; ++k) {
        const double t = legsim_time(sim);
        st = apply(t);
        if (st != LEGSIM_OK) return st;
        st = legsim_step(sim, 1);
        if (st != LEGSIM_OK) {
          res.failed_at_s = t;
          res.error = call_failed("step from t = " + num(t) + " s", st);
          return st;
        }
        // the masks hold the events since the last sample's clear; a switch latches
        for (size_t i = 0; i < commands.size(); ++i) {
          const Signal &g = commands[i].signal;
          if (g.kind == Signal::kSwitch && (legsim_contact_event_mask(sim, g.contact_index) & g.event_bit))
            switched[i] = 1;
        }
        if (k % sc.record_every == 0 || k == sc.n_steps) emit(legsim_time(sim), nullptr);
      }
      return LEGSIM_OK;
    }
  }
  return LEGSIM_OK;
}

}  // namespace

legsim_status run_scene(const Scene &scene, const legsim_model_desc &model, ResultWriter &writer,
                        Result &result) {
  result = Result{};
  try {
    writer.begin();
    result.status = run(scene, model, writer, result);
  } catch (const std::exception &e) {
    result.status = LEGSIM_ERR_STORAGE;
    result.error = e.what();
  } catch (...) {
    result.status = LEGSIM_ERR_STORAGE;
    result.error = "unexpected error";
  }
  try {
    writer.end(result);
  } catch (...) {
    // the stream's own state tells the caller (a failed write)
  }
  return result.status;
}

}  // namespace legsim_host

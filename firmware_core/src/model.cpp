// Model checks and compilation of a legsim_model_desc into the solver's Model.
#include <cmath>
#include <cstring>

#include "sim.hpp"

namespace legsim {
namespace {

// A tiny message builder: snprintf would drag newlib's stdio (and its heap)
// into firmware images, so reasons are assembled from strings and integers.
struct Msg {
  char *buf;
  size_t len, pos;
  void put(const char *s) {
    for (; s && *s && pos + 1 < len; ++s) buf[pos++] = *s;
  }
  void put(int v) {
    char tmp[12];
    int n = 0;
    unsigned u = v < 0 ? 0u - unsigned(v) : unsigned(v);
    do tmp[n++] = char('0' + u % 10); while ((u /= 10) && n < 11);
    if (v < 0) put("-");
    while (n > 0 && pos + 1 < len) buf[pos++] = tmp[--n];
  }
  void put(long v) { put(int(v)); }
  struct Name { const char *s; };  // fixed-size name fields may lack a terminator
  void put(Name n) {
    for (int i = 0; i < LEGSIM_NAME_LEN && n.s[i] && pos + 1 < len; ++i) buf[pos++] = n.s[i];
  }
};
using Name = Msg::Name;

inline void put_all(Msg &) {}
template <typename T, typename... Rest>
void put_all(Msg &m, T first, Rest... rest) {
  m.put(first);
  put_all(m, rest...);
}

// Writes the reason (concatenated parts) into msg, if any, and returns the status.
template <typename... Parts>
legsim_status fail(char *msg, size_t len, legsim_status s, Parts... parts) {
  if (msg && len > 0) {
    Msg m{msg, len, 0};
    put_all(m, parts...);
    msg[m.pos] = '\0';
  }
  return s;
}

bool finite_pos(double x) { return std::isfinite(x) && x > 0.0; }
bool finite2(const double p[2]) { return std::isfinite(p[0]) && std::isfinite(p[1]); }

int joint_rows(legsim_joint_kind k) { return k == LEGSIM_JOINT_SLOT ? 1 : 2; }

}  // namespace

legsim_status model_check(const legsim_model_desc *d, char *msg, size_t len) {
  const legsim_status bad = LEGSIM_ERR_MODEL;
  if (!d) return fail(msg, len, LEGSIM_ERR_NULL, "model is NULL");
  if (d->n_bodies < 1 || d->n_joints < 0 || d->n_actuators < 0 || d->n_forces < 0 || d->n_poses < 0)
    return fail(msg, len, bad, "model '", Name{d->name}, "': counts must be >= 0 (bodies >= 1)");
  if (d->n_bodies > LEGSIM_MAX_BODIES || d->n_joints > LEGSIM_MAX_JOINTS ||
      d->n_actuators > LEGSIM_MAX_ACTUATORS || d->n_forces > LEGSIM_MAX_FORCES ||
      d->n_poses > LEGSIM_MAX_POSES)
    return fail(msg, len, LEGSIM_ERR_CAPACITY, "model has ", int(d->n_bodies), " bodies, ",
                int(d->n_joints), " joints, ", int(d->n_actuators), " actuators, ",
                int(d->n_forces), " forces, ", int(d->n_poses), " poses; this build holds ",
                LEGSIM_MAX_BODIES, ", ", LEGSIM_MAX_JOINTS, ", ", LEGSIM_MAX_ACTUATORS, ", ",
                LEGSIM_MAX_FORCES, ", ", LEGSIM_MAX_POSES);
  if (!finite2(d->gravity_mps2)) return fail(msg, len, bad, "gravity is not finite");
  for (int i = 0; i < d->n_bodies; ++i) {
    const legsim_body_desc &b = d->body[i];
    if (!finite_pos(b.length_m) || !finite_pos(b.mass_kg) || !finite_pos(b.inertia_kgm2))
      return fail(msg, len, bad, "body '", Name{b.name},
                  "': length, mass and inertia must be finite and > 0");
  }
  auto body_ok = [&](int b) { return b >= 0 && b < d->n_bodies; };
  int rows = 0;
  for (int j = 0; j < d->n_joints; ++j) {
    const legsim_joint_desc &jd = d->joint[j];
    if (jd.kind < LEGSIM_JOINT_REVOLUTE_TO_FRAME || jd.kind > LEGSIM_JOINT_SLOT)
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': unknown kind ", int(jd.kind));
    if (!body_ok(jd.body[0]))
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': body index ", int(jd.body[0]),
                  " does not exist");
    const bool to_frame = jd.kind == LEGSIM_JOINT_REVOLUTE_TO_FRAME;
    if (to_frame ? jd.body[1] != LEGSIM_FRAME : !body_ok(jd.body[1]))
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': second body index ", int(jd.body[1]),
                  " is not valid for its kind");
    if (!to_frame && jd.body[0] == jd.body[1])
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': joins a body to itself");
    if (!finite2(jd.point[0]) || !finite2(jd.point[1]))
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': point not finite");
    rows += joint_rows(jd.kind);
  }
  if (rows + d->n_actuators + LEGSIM_MAX_POSE_DRIVERS > LEGSIM_MAX_ROWS)
    return fail(msg, len, LEGSIM_ERR_CAPACITY, "model has ", rows,
                " joint equations; this build holds ",
                LEGSIM_MAX_ROWS - int(d->n_actuators) - LEGSIM_MAX_POSE_DRIVERS);
  for (int a = 0; a < d->n_actuators; ++a) {
    const legsim_actuator_desc &ad = d->actuator[a];
    if (ad.joint < 0 || ad.joint >= d->n_joints || d->joint[ad.joint].kind != LEGSIM_JOINT_PRISMATIC)
      return fail(msg, len, bad, "actuator '", Name{ad.name}, "': joint index ", int(ad.joint),
                  " is not a prismatic joint");
    if (!finite_pos(ad.stroke_min_m) || !std::isfinite(ad.stroke_max_m) ||
        ad.stroke_max_m <= ad.stroke_min_m)
      return fail(msg, len, bad, "actuator '", Name{ad.name}, "': stroke must satisfy 0 < min < max");
    if (!finite_pos(ad.max_force_n) || !std::isfinite(ad.servo_kp_n_per_m) ||
        !std::isfinite(ad.servo_kd_ns_per_m) || ad.servo_kp_n_per_m < 0 || ad.servo_kd_ns_per_m < 0)
      return fail(msg, len, bad, "actuator '", Name{ad.name},
                  "': max force must be > 0 and servo gains >= 0, all finite");
  }
  for (int f = 0; f < d->n_forces; ++f) {
    const legsim_force_desc &fd = d->force[f];
    if (fd.kind < LEGSIM_FORCE_POINT || fd.kind > LEGSIM_FORCE_SPRING_DAMPER)
      return fail(msg, len, bad, "force '", Name{fd.name}, "': unknown kind ", int(fd.kind));
    const bool spring = fd.kind == LEGSIM_FORCE_SPRING_DAMPER;
    const bool a_ok = body_ok(fd.body[0]) || (spring && fd.body[0] == LEGSIM_FRAME);
    const bool b_ok = !spring || body_ok(fd.body[1]) || fd.body[1] == LEGSIM_FRAME;
    if (!a_ok || !b_ok || (spring && fd.body[0] == fd.body[1]))
      return fail(msg, len, bad, "force '", Name{fd.name}, "': body does not exist");
    if (!finite2(fd.point[0]) || !finite2(fd.point[1]) || !finite2(fd.value) ||
        !std::isfinite(fd.stiffness_n_per_m) || !std::isfinite(fd.damping_ns_per_m) ||
        !std::isfinite(fd.rest_length_m) || fd.rest_length_m < 0)
      return fail(msg, len, bad, "force '", Name{fd.name}, "': numbers must be finite (rest length >= 0)");
  }
  for (int p = 0; p < d->n_poses; ++p) {
    const legsim_pose_desc &pd = d->pose[p];
    if (pd.n_drivers < 0 || pd.n_drivers > LEGSIM_MAX_POSE_DRIVERS)
      return fail(msg, len, bad, "pose '", Name{pd.name}, "': ", int(pd.n_drivers),
                  " drivers, at most ", LEGSIM_MAX_POSE_DRIVERS);
    for (int k = 0; k < pd.n_drivers; ++k)
      if (!body_ok(pd.driver[k].body) || pd.driver[k].coord < 0 || pd.driver[k].coord > 2 ||
          !std::isfinite(pd.driver[k].value))
        return fail(msg, len, bad, "pose '", Name{pd.name}, "': driver ", k, " is invalid");
    for (int b = 0; b < d->n_bodies; ++b)
      for (int c = 0; c < 3; ++c)
        if (!std::isfinite(pd.guess[b][c]))
          return fail(msg, len, bad, "pose '", Name{pd.name}, "': guess not finite");
  }
  if (d->foot_body != -1 && (!body_ok(d->foot_body) || !finite2(d->foot_point)))
    return fail(msg, len, bad, "foot: body index ", int(d->foot_body), " does not exist");
  if (msg && len > 0) msg[0] = '\0';
  return LEGSIM_OK;
}

legsim_status model_compile(const legsim_model_desc *d, Model &m) {
  const legsim_status s = model_check(d, nullptr, 0);
  if (s != LEGSIM_OK) return s;
  m.desc = d;
  m.nb = d->n_bodies;
  m.nq = 3 * m.nb;
  m.nj = d->n_joints;
  m.na = d->n_actuators;
  m.nf = d->n_forces;
  for (int i = 0; i < m.nb; ++i) {
    const legsim_body_desc &b = d->body[i];
    m.length[i] = real(b.length_m);
    m.mass[3 * i] = m.mass[3 * i + 1] = real(b.mass_kg);
    m.mass[3 * i + 2] = real(b.inertia_kgm2);
    for (int c = 0; c < 3; ++c) {
      m.minv[3 * i + c] = real(1) / m.mass[3 * i + c];
      m.unit_weight[3 * i + c] = 1;
    }
  }
  m.gravity = Vec2(real(d->gravity_mps2[0]), real(d->gravity_mps2[1]));
  int row = 0;
  for (int j = 0; j < m.nj; ++j) {
    const legsim_joint_desc &jd = d->joint[j];
    Joint &jt = m.joint[j];
    jt.kind = jd.kind;
    jt.a = jd.body[0];
    jt.b = jd.body[1];
    jt.pa = Vec2(real(jd.point[0][0]), real(jd.point[0][1]));
    jt.pb = Vec2(real(jd.point[1][0]), real(jd.point[1][1]));
    jt.row = row;
    jt.nrows = joint_rows(jd.kind);
    row += jt.nrows;
  }
  m.m = row;
  for (int a = 0; a < m.na; ++a) {
    const legsim_actuator_desc &ad = d->actuator[a];
    Actuator &ac = m.act[a];
    ac.joint = ad.joint;
    ac.cyl = d->joint[ad.joint].body[0];
    ac.rod = d->joint[ad.joint].body[1];
    ac.offset_m = real(0.5) * (m.length[ac.cyl] + m.length[ac.rod]);
    ac.lmin = real(ad.stroke_min_m);
    ac.lmax = real(ad.stroke_max_m);
    ac.fmax = real(ad.max_force_n);
    ac.kp = real(ad.servo_kp_n_per_m);
    ac.kd = real(ad.servo_kd_ns_per_m);
  }
  for (int f = 0; f < m.nf; ++f) {
    const legsim_force_desc &fd = d->force[f];
    ForceElement &fe = m.force[f];
    fe.kind = fd.kind;
    fe.a = fd.body[0];
    fe.b = fd.body[1];
    fe.pa = Vec2(real(fd.point[0][0]), real(fd.point[0][1]));
    fe.pb = Vec2(real(fd.point[1][0]), real(fd.point[1][1]));
    fe.k = real(fd.stiffness_n_per_m);
    fe.c = real(fd.damping_ns_per_m);
    fe.l0 = real(fd.rest_length_m);
  }
  m.foot_body = d->foot_body;
  m.foot_point = Vec2(real(d->foot_point[0]), real(d->foot_point[1]));
  return LEGSIM_OK;
}

}  // namespace legsim

// Model checks and compilation of a legsim_model_desc into the solver's Model.
#include <cmath>
#include <cstring>
#include <type_traits>

#include "planar/kernel.hpp"

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

// In [lo, hi] (false for NaN): the sane ranges of legsim.h.
bool in(double x, double lo, double hi) { return x >= lo && x <= hi; }
bool coord(double x) { return in(x, -LEGSIM_MAX_COORD, LEGSIM_MAX_COORD); }
bool coord2(const double p[2]) { return coord(p[0]) && coord(p[1]); }

// The integer a C caller stored in an enum field, read without holding it in
// the enum type (a value outside the enum would be undefined behaviour in C++).
template <typename E>
long long raw_enum(const E &field) {
  std::underlying_type_t<E> v;
  std::memcpy(&v, &field, sizeof v);
  return static_cast<long long>(v);
}

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
  if (!in(d->gravity_mps2[0], -LEGSIM_MAX_GRAVITY_MPS2, LEGSIM_MAX_GRAVITY_MPS2) ||
      !in(d->gravity_mps2[1], -LEGSIM_MAX_GRAVITY_MPS2, LEGSIM_MAX_GRAVITY_MPS2))
    return fail(msg, len, bad, "gravity outside +-LEGSIM_MAX_GRAVITY_MPS2 (or not finite)");
  for (int i = 0; i < d->n_bodies; ++i) {
    const legsim_body_desc &b = d->body[i];
    if (!in(b.length_m, LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD) ||
        !in(b.mass_kg, LEGSIM_MIN_MASS_KG, LEGSIM_MAX_MASS_KG) ||
        !in(b.inertia_kgm2, LEGSIM_MIN_INERTIA_KGM2, LEGSIM_MAX_INERTIA_KGM2))
      return fail(msg, len, bad, "body '", Name{b.name},
                  "': length, mass and inertia must be finite and within their ranges "
                  "(LEGSIM_MIN/MAX_*, legsim.h)");
  }
  auto body_ok = [&](int b) { return b >= 0 && b < d->n_bodies; };
  int rows = 0;
  for (int j = 0; j < d->n_joints; ++j) {
    const legsim_joint_desc &jd = d->joint[j];
    const long long kind = raw_enum(jd.kind);
    if (kind < LEGSIM_JOINT_REVOLUTE_TO_FRAME || kind > LEGSIM_JOINT_SLOT)
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': unknown kind ", int(kind));
    if (!body_ok(jd.body[0]))
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': body index ", int(jd.body[0]),
                  " does not exist");
    const bool to_frame = jd.kind == LEGSIM_JOINT_REVOLUTE_TO_FRAME;
    if (to_frame ? jd.body[1] != LEGSIM_FRAME : !body_ok(jd.body[1]))
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': second body index ", int(jd.body[1]),
                  " is not valid for its kind");
    if (!to_frame && jd.body[0] == jd.body[1])
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': joins a body to itself");
    if (!coord2(jd.point[0]) || !coord2(jd.point[1]))
      return fail(msg, len, bad, "joint '", Name{jd.name}, "': point outside +-LEGSIM_MAX_COORD (or not finite)");
    rows += joint_rows(jd.kind);
  }
  if (d->n_contacts < 0)
    return fail(msg, len, bad, "model '", Name{d->name}, "': counts must be >= 0 (bodies >= 1)");
  if (d->n_contacts > LEGSIM_MAX_CONTACTS)
    return fail(msg, len, LEGSIM_ERR_CAPACITY, "model has ", int(d->n_contacts),
                " contacts; this build holds ", LEGSIM_MAX_CONTACTS);
  if (rows + d->n_actuators + LEGSIM_MAX_POSE_DRIVERS + 2 * d->n_contacts > LEGSIM_MAX_ROWS)
    return fail(msg, len, LEGSIM_ERR_CAPACITY, "model has ", rows,
                " joint equations; this build holds ",
                LEGSIM_MAX_ROWS - int(d->n_actuators) - LEGSIM_MAX_POSE_DRIVERS - 2 * int(d->n_contacts));
  for (int a = 0; a < d->n_actuators; ++a) {
    const legsim_actuator_desc &ad = d->actuator[a];
    if (ad.joint < 0 || ad.joint >= d->n_joints || raw_enum(d->joint[ad.joint].kind) != LEGSIM_JOINT_PRISMATIC)
      return fail(msg, len, bad, "actuator '", Name{ad.name}, "': joint index ", int(ad.joint),
                  " is not a prismatic joint");
    if (!in(ad.stroke_min_m, LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD) ||
        !in(ad.stroke_max_m, LEGSIM_MIN_LENGTH_M, LEGSIM_MAX_COORD) || ad.stroke_max_m <= ad.stroke_min_m)
      return fail(msg, len, bad, "actuator '", Name{ad.name},
                  "': stroke must satisfy LEGSIM_MIN_LENGTH_M <= min < max <= LEGSIM_MAX_COORD");
    if (!in(ad.max_force_n, LEGSIM_MIN_FORCE_N, LEGSIM_MAX_FORCE_N) ||
        !in(ad.servo_kp_n_per_m, 0, LEGSIM_MAX_STIFFNESS_N_PER_M) ||
        !in(ad.servo_kd_ns_per_m, 0, LEGSIM_MAX_DAMPING_NS_PER_M))
      return fail(msg, len, bad, "actuator '", Name{ad.name},
                  "': max force and servo gains must be finite and within their ranges "
                  "(LEGSIM_MAX_FORCE_N, _STIFFNESS_N_PER_M, _DAMPING_NS_PER_M)");
  }
  for (int f = 0; f < d->n_forces; ++f) {
    const legsim_force_desc &fd = d->force[f];
    const long long kind = raw_enum(fd.kind);
    if (kind < LEGSIM_FORCE_POINT || kind > LEGSIM_FORCE_SPRING_DAMPER)
      return fail(msg, len, bad, "force '", Name{fd.name}, "': unknown kind ", int(kind));
    const bool spring = fd.kind == LEGSIM_FORCE_SPRING_DAMPER;
    const bool a_ok = body_ok(fd.body[0]) || (spring && fd.body[0] == LEGSIM_FRAME);
    const bool b_ok = !spring || body_ok(fd.body[1]) || fd.body[1] == LEGSIM_FRAME;
    if (!a_ok || !b_ok || (spring && fd.body[0] == fd.body[1]))
      return fail(msg, len, bad, "force '", Name{fd.name}, "': body does not exist");
    if (!coord2(fd.point[0]) || !coord2(fd.point[1]) ||
        !in(fd.value[0], -LEGSIM_MAX_FORCE_N, LEGSIM_MAX_FORCE_N) ||
        !in(fd.value[1], -LEGSIM_MAX_FORCE_N, LEGSIM_MAX_FORCE_N) ||
        !in(fd.stiffness_n_per_m, 0, LEGSIM_MAX_STIFFNESS_N_PER_M) ||
        !in(fd.damping_ns_per_m, 0, LEGSIM_MAX_DAMPING_NS_PER_M) ||
        !in(fd.rest_length_m, 0, LEGSIM_MAX_COORD))
      return fail(msg, len, bad, "force '", Name{fd.name},
                  "': numbers must be finite and within their ranges (LEGSIM_MAX_*, legsim.h)");
  }
  for (int p = 0; p < d->n_poses; ++p) {
    const legsim_pose_desc &pd = d->pose[p];
    if (pd.n_drivers < 0 || pd.n_drivers > LEGSIM_MAX_POSE_DRIVERS)
      return fail(msg, len, bad, "pose '", Name{pd.name}, "': ", int(pd.n_drivers),
                  " drivers, at most ", LEGSIM_MAX_POSE_DRIVERS);
    for (int k = 0; k < pd.n_drivers; ++k)
      if (!body_ok(pd.driver[k].body) || pd.driver[k].coord < 0 || pd.driver[k].coord > 2 ||
          !coord(pd.driver[k].value))
        return fail(msg, len, bad, "pose '", Name{pd.name}, "': driver ", k, " is invalid");
    for (int b = 0; b < d->n_bodies; ++b)
      for (int c = 0; c < 3; ++c)
        if (!coord(pd.guess[b][c]))
          return fail(msg, len, bad, "pose '", Name{pd.name}, "': guess outside +-LEGSIM_MAX_COORD (or not finite)");
  }
  if (d->foot_body != -1 && (!body_ok(d->foot_body) || !coord2(d->foot_point)))
    return fail(msg, len, bad, "foot: body index ", int(d->foot_body), " does not exist (or point out of range)");
  for (int k = 0; k < d->n_contacts; ++k) {
    const legsim_contact_desc &c = d->contact[k];
    if (!body_ok(c.body) || !coord2(c.point))
      return fail(msg, len, bad, "contact '", Name{c.name}, "': body index ", int(c.body),
                  " does not exist (or point outside +-LEGSIM_MAX_COORD)");
    for (int k2 = 0; k2 < k; ++k2)
      if (d->contact[k2].body == c.body)
        return fail(msg, len, bad, "contact '", Name{c.name}, "': its body has a contact already");
  }
  const legsim_ground_desc &gd = d->ground;
  if (!coord2(gd.point) || !in(gd.slope_rad, -LEGSIM_MAX_SLOPE_RAD, LEGSIM_MAX_SLOPE_RAD))
    return fail(msg, len, bad, "ground: point outside +-LEGSIM_MAX_COORD or |slope| > LEGSIM_MAX_SLOPE_RAD (or not finite)");
  if (!in(gd.mu_kinetic, 0, LEGSIM_MAX_FRICTION) || !in(gd.mu_static, gd.mu_kinetic, LEGSIM_MAX_FRICTION))
    return fail(msg, len, bad, "ground: need 0 <= mu_kinetic <= mu_static <= LEGSIM_MAX_FRICTION");
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
  m.gravity_force.setZero();
  for (int i = 0; i < m.nb; ++i) {
    m.gravity_force[3 * i] = m.mass[3 * i] * m.gravity.x();
    m.gravity_force[3 * i + 1] = m.mass[3 * i + 1] * m.gravity.y();
    m.gravity_force[3 * i + 2] = 0;
  }
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
  m.nc = d->n_contacts;
  for (int k = 0; k < m.nc; ++k) {
    m.contact[k].body = d->contact[k].body;
    m.contact[k].point = Vec2(real(d->contact[k].point[0]), real(d->contact[k].point[1]));
  }
  const legsim_ground_desc &gd = d->ground;
  m.ground_point = Vec2(real(gd.point[0]), real(gd.point[1]));
  const real slope = real(gd.slope_rad);  // in the build's real: no double trigonometry on a float MCU
  real slope_s, slope_c;
  sincos_any(slope, slope_s, slope_c);  // kernel_trig.hpp
  m.ground_t = Vec2(slope_c, slope_s);
  m.ground_n = perp(m.ground_t);
  m.mu_s = real(gd.mu_static);
  m.mu_k = real(gd.mu_kinetic);
  m.kernel = kernel_find(m);  // generated joint-block kernels (kernel.hpp), by structure
  m.stance_kernel = kernel_find(m, true);
  return LEGSIM_OK;
}

}  // namespace legsim

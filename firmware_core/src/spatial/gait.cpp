#include "spatial/gait.hpp"

#include <algorithm>

namespace legsim::spatial {

namespace {
constexpr real kPi = real(3.14159265358979323846);

bool finite(real x) { return std::isfinite(x); }


// A world-fixed point seen from the box sigma seconds after the stance's middle (where it is at
// p_mid): the box moved by the constant twist (v forward, w about z) meanwhile. Its place and
// its velocity in the box's frame (x, y; z kept).
void stance_point(const V3 &p_mid, real v, real w, real sigma, V3 &p, V3 &pd) {
  const real th = w * sigma, c = std::cos(th), s = std::sin(th);
  real dx, dy;
  twist_displacement(v, w, sigma, dx, dy);
  const real x = p_mid.x - dx, y = p_mid.y - dy;
  p = {c * x + s * y, -s * x + c * y, p_mid.z};
  pd = {-v + w * p.y, -w * p.x, 0};  // -(v x) - w z x p
}

// The cubic Hermite curve from (p0, d0) to (p1, d1) over s in [0, 1] (d: d/ds).
real hermite(real p0, real d0, real p1, real d1, real s) {
  const real s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * d0 + (-2 * s3 + 3 * s2) * p1 + (s3 - s2) * d1;
}
}  // namespace

legsim_status gait_check(const TripodGait &g) {
  if (!(finite(g.period_s) && g.period_s > 0)) return LEGSIM_ERR_BAD_INPUT;
  if (!(g.duty >= real(0.5) && g.duty < 1)) return LEGSIM_ERR_BAD_INPUT;
  if (!(finite(g.step_length_m) && g.step_length_m >= 0 && g.step_length_m <= real(LEGSIM_MAX_COORD)))
    return LEGSIM_ERR_BAD_INPUT;
  if (!(finite(g.step_height_m) && g.step_height_m >= 0 && g.step_height_m <= real(LEGSIM_MAX_COORD)))
    return LEGSIM_ERR_BAD_INPUT;
  if (!(std::abs(g.turn_rad) < kPi / 2)) return LEGSIM_ERR_BAD_INPUT;
  for (const V3 &p : g.neutral)
    if (!(std::abs(p.x) <= real(LEGSIM_MAX_COORD) && std::abs(p.y) <= real(LEGSIM_MAX_COORD) &&
          std::abs(p.z) <= real(LEGSIM_MAX_COORD)))
      return LEGSIM_ERR_BAD_INPUT;
  if (!(std::hypot(g.grade[0], g.grade[1]) <= std::tan(real(LEGSIM_MAX_SLOPE_RAD)))) return LEGSIM_ERR_BAD_INPUT;
  return LEGSIM_OK;
}

void gait_feet(const TripodGait &g, double t_s, V3 *feet, bool *stance) {
  const real T = g.period_s, Ts = g.duty * T, Tw = T - Ts;
  const real v = g.step_length_m / Ts, w = g.turn_rad / Ts;
  // the grade in the box's frame now (it turned by w t since t = 0): a point p of the box's
  // frame is over the ground at -neutral.z + gx p.x + gy p.y
  const real th = w * real(t_s), c = std::cos(th), s = std::sin(th);
  const real gx = c * g.grade[0] + s * g.grade[1], gy = -s * g.grade[0] + c * g.grade[1];
  for (int l = 0; l < 6; ++l) {
    const double offset = (l % 2) ? 0.5 * double(T) : 0.0;  // tripod B half a period on
    double tau = std::fmod(t_s - offset, double(T));
    if (tau < 0) tau += double(T);
    V3 pd;
    if (real(tau) < Ts) {
      stance[l] = true;
      stance_point(g.neutral[l], v, w, real(tau) - Ts / 2, feet[l], pd);
      feet[l].z = g.neutral[l].z + (gx * feet[l].x + gy * feet[l].y);
      continue;
    }
    stance[l] = false;
    // from the lift-off (the stance's end) to the next touchdown (its start), leaving and
    // landing with the ground's velocity in the box's frame (at rest in the world), rising
    // and landing without vertical speed
    V3 p0, d0, p1, d1;
    stance_point(g.neutral[l], v, w, Ts / 2, p0, d0);
    stance_point(g.neutral[l], v, w, -Ts / 2, p1, d1);
    const real u = (real(tau) - Ts) / Tw;
    const real x = hermite(p0.x, Tw * d0.x, p1.x, Tw * d1.x, u), y = hermite(p0.y, Tw * d0.y, p1.y, Tw * d1.y, u);
    feet[l] = {x, y, (g.neutral[l].z + (gx * x + gy * y)) + g.step_height_m * (1 - std::cos(2 * kPi * u)) / 2};
  }
}

void gait_box(const TripodGait &g, double t_s, V3 &d, real &yaw) {
  const real Ts = g.duty * g.period_s, v = g.step_length_m / Ts, w = g.turn_rad / Ts;
  twist_displacement(v, w, real(t_s), d.x, d.y);
  d.z = g.grade[0] * d.x + g.grade[1] * d.y;
  yaw = w * real(t_s);
}

real support_margin(const V3 *feet, int n, real com_x, real com_y) {
  if (n < 3) return -real(INFINITY);
  // the convex hull of the feet's (x, y) (gift wrapping: at most six points)
  int hull[6], nh = 0, start = 0;
  for (int i = 1; i < n; ++i)
    if (feet[i].x < feet[start].x || (feet[i].x == feet[start].x && feet[i].y < feet[start].y)) start = i;
  int p = start;
  do {
    hull[nh++] = p;
    int q = (p + 1) % n;
    for (int r = 0; r < n; ++r) {
      const real cr = (feet[q].x - feet[p].x) * (feet[r].y - feet[p].y) - (feet[q].y - feet[p].y) * (feet[r].x - feet[p].x);
      if (cr < 0) q = r;  // r is to the right of p -> q: the hull turns counter-clockwise
    }
    p = q;
  } while (p != start && nh < 6);
  // all on one line: no area (the wrapping may still list three of them)
  real area = 0, span = 0;
  for (int k = 0; k < nh; ++k) {
    const V3 &a = feet[hull[k]], &b = feet[hull[(k + 1) % nh]];
    area += a.x * b.y - b.x * a.y;
    span = std::max(span, std::abs(b.x - a.x) + std::abs(b.y - a.y));
  }
  if (nh < 3 || !(std::abs(area) > real(1e-9) * span * span)) return -real(INFINITY);
  // the signed distance to each edge (counter-clockwise: inside on the left), the least
  real margin = real(INFINITY);
  for (int k = 0; k < nh; ++k) {
    const V3 &a = feet[hull[k]], &b = feet[hull[(k + 1) % nh]];
    const real ex = b.x - a.x, ey = b.y - a.y, len = std::sqrt(ex * ex + ey * ey);
    margin = std::min(margin, (ex * (com_y - a.y) - ey * (com_x - a.x)) / len);
  }
  return margin;
}

void twist_displacement(real v, real w, real sigma, real &dx, real &dy) {
  const real th = w * sigma;
  if (std::abs(th) < real(1e-8)) {
    dx = v * sigma, dy = v * sigma * th / 2;
  } else {
    dx = v / w * std::sin(th), dy = v / w * (1 - std::cos(th));
  }
}

}  // namespace legsim::spatial

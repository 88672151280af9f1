// The tripod gait (docs/design/spatial.md): where each foot is, in the box's frame, at a time of
// the gait, and whether it stands; and the static stability margin of a stance.
//
// Two tripods take turns: A = legs 0, 2, 4 (right front, right rear, left middle in
// models/hexapod.toml's order) stand from phase 0 for a fraction `duty` of the period, B = legs 1,
// 3, 5 half a period later (duty >= 0.5: at least one tripod always stands). The box moves at a
// constant twist in its own frame: forward (x) at step_length / (duty period), turning about its
// z at turn / (duty period) (turn: the box's yaw over one stance, rad). A standing foot holds its
// place in the world: in the box's frame it moves back along the box's motion, from its
// touchdown point to its lift-off point, placed symmetrically about its neutral point (the
// foot's place at the stance's middle). A swinging foot goes from its lift-off point to its
// next touchdown point along a cycloid (velocity zero at both ends) and rises by step_height
// on a sine.
//
// On a sloped ground plane the box stays level (docs/design/spatial.md, "The gait on a slope":
// a level box keeps its instruments level and its centre of mass over the support polygon; the
// box parallel to the slope would lean its centre of mass downhill by its height times the
// slope's sine) and moves along the same path seen from above, its centre at its height
// (-neutral.z) over the ground directly below it. A standing foot is on the plane: in the box's
// frame at -neutral.z plus the plane's rise from below the box's centre to below the foot. A
// swinging foot rises by step_height over the ground directly below it (vertically).
#pragma once

#include "spatial/body.hpp"

namespace legsim::spatial {

struct TripodGait {
  real period_s;        // one cycle (s), > 0
  real duty;            // a foot's stance share of the period, in [0.5, 1)
  real step_length_m;   // the box's forward travel over one stance (m), >= 0
  real step_height_m;   // a swinging foot's rise (m), >= 0
  real turn_rad;        // the box's yaw over one stance (rad), |turn| < pi / 2
  V3 neutral[6];        // each foot's place at its stance's middle on level ground (box frame, m)
  // the ground's rise (dz/dx, dz/dy) along the box's x and y at t = 0 (0, 0: level); it turns
  // with the box, |grade| <= tan(LEGSIM_MAX_SLOPE_RAD)
  real grade[2] = {0, 0};
};

// LEGSIM_ERR_BAD_INPUT for a gait outside the ranges above or not finite.
legsim_status gait_check(const TripodGait &gait);

// Each foot's place (box frame) at time t_s (s, any: the gait repeats on level ground; on a
// slope while it walks straight) and whether it stands.
void gait_feet(const TripodGait &gait, double t_s, V3 *feet, bool *stance);

// The box's planned motion from t = 0 to t_s, in its frame at t = 0: its centre's displacement
// (x, y along the path seen from above; z its rise over the ground's grade) and its yaw.
void gait_box(const TripodGait &gait, double t_s, V3 &displacement, real &yaw);

// The box's displacement (x, y) over sigma seconds at the constant twist (v forward, w about
// z), in its frame at the start.
void twist_displacement(real v, real w, real sigma, real &dx, real &dy);

// The static stability margin (m): the least distance from the centre of mass's projection
// (x, y) to the edges of the support polygon of the n standing feet (their x, y: the convex
// hull), positive inside, negative outside; -INFINITY for fewer than three feet.
real support_margin(const V3 *feet, int n, real com_x, real com_y);

}  // namespace legsim::spatial

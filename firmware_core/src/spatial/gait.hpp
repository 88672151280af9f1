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
#pragma once

#include "spatial/body.hpp"

namespace legsim::spatial {

struct TripodGait {
  real period_s;        // one cycle (s), > 0
  real duty;            // a foot's stance share of the period, in [0.5, 1)
  real step_length_m;   // the box's forward travel over one stance (m), >= 0
  real step_height_m;   // a swinging foot's rise (m), >= 0
  real turn_rad;        // the box's yaw over one stance (rad), |turn| < pi / 2
  V3 neutral[6];        // each foot's place at its stance's middle (box frame, m)
};

// LEGSIM_ERR_BAD_INPUT for a gait outside the ranges above or not finite.
legsim_status gait_check(const TripodGait &gait);

// Each foot's place (box frame) at time t_s (s, any: the gait repeats) and whether it stands.
void gait_feet(const TripodGait &gait, double t_s, V3 *feet, bool *stance);

// The static stability margin (m): the least distance from the centre of mass's projection
// (x, y) to the edges of the support polygon of the n standing feet (their x, y: the convex
// hull), positive inside, negative outside; -INFINITY for fewer than three feet.
real support_margin(const V3 *feet, int n, real com_x, real com_y);

}  // namespace legsim::spatial

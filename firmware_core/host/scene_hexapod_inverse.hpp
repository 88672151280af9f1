// Hexapod scenes of analysis "inverse_gait" (scenes/README.md, "The hexapod", "Inverse dynamics
// along the gait"): the forces that make the robot follow its tripod gait
// (legsim_hexapod_inverse_dynamics), sampled over a duration, as JSON. Host only.
#ifndef LEGSIM_HOST_SCENE_HEXAPOD_INVERSE_HPP
#define LEGSIM_HOST_SCENE_HEXAPOD_INVERSE_HPP

#include <ostream>
#include <string>

#include "scene_hexapod.hpp"

namespace legsim_host {

// True when the hexapod scene text says analysis = "inverse_gait" (false for one that does not
// parse: the hexapod reader then says what is wrong).
bool scene_is_hexapod_inverse(const std::string &text, const std::string &path);

// As run_hexapod_scene, for such a scene.
int run_hexapod_inverse_scene(const std::string &text, const std::string &path, bool check_only, HexapodOutput &out,
                              std::ostream &err);

}  // namespace legsim_host

#endif  // LEGSIM_HOST_SCENE_HEXAPOD_INVERSE_HPP

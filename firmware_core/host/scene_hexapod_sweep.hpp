// Hexapod scenes of analysis "reaction_sweep" (scenes/README.md, "The hexapod", "Section V: the
// reactions over a foot's reach"): the paper's Section V sweep (legsim_hexapod_reaction_sweep),
// whole or one part of it, as JSON. Host only.
#ifndef LEGSIM_HOST_SCENE_HEXAPOD_SWEEP_HPP
#define LEGSIM_HOST_SCENE_HEXAPOD_SWEEP_HPP

#include <ostream>
#include <string>

#include "scene_hexapod.hpp"

namespace legsim_host {

// True when the hexapod scene text says analysis = "reaction_sweep" (false for one that does not
// parse: the hexapod reader then says what is wrong).
bool scene_is_hexapod_sweep(const std::string &text, const std::string &path);

// As run_hexapod_scene, for such a scene.
int run_hexapod_sweep_scene(const std::string &text, const std::string &path, bool check_only, HexapodOutput &out,
                            std::ostream &err);

}  // namespace legsim_host

#endif  // LEGSIM_HOST_SCENE_HEXAPOD_SWEEP_HPP

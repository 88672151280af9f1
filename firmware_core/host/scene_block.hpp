// Block scenes (scenes/README.md, "A block"): a scene whose `model` is a hexapod file of no legs,
// the box alone on its [[box_contact]] points (legsim/hexapod.h): set on the ground (or dropped),
// launched, and left to slide, stick or bounce under the ground's Coulomb cone. Its keys are its
// own; legsim_cli reads and runs it through the hexapod's C API and writes its JSON. Host only.
#ifndef LEGSIM_HOST_SCENE_BLOCK_HPP
#define LEGSIM_HOST_SCENE_BLOCK_HPP

#include <ostream>
#include <string>

#include "scene_hexapod.hpp"

namespace legsim_host {

// As run_hexapod_scene (which calls it when the scene's model is a block).
int run_block_scene(const std::string &text, const std::string &path, bool check_only, HexapodOutput &out,
                    std::ostream &err);

}  // namespace legsim_host

#endif  // LEGSIM_HOST_SCENE_BLOCK_HPP

// Hexapod scenes (scenes/README.md, "The hexapod"): a scene whose `model` is a hexapod file
// (models/hexapod.toml). Its keys are its own (statics on a stance, or the robot moving on its
// servos, its feet stuck, sliding or free); legsim_cli reads and runs it here, through the
// hexapod's C API (legsim/hexapod.h), and writes its JSON (the planar scenes' writers know
// bodies and joints of one plane). Host only.
#ifndef LEGSIM_HOST_SCENE_HEXAPOD_HPP
#define LEGSIM_HOST_SCENE_HEXAPOD_HPP

#include <ostream>
#include <string>

namespace legsim_host {

// True when the scene text (read as the file at path) names in `model` a hexapod file (a block's
// included): legsim_toml_is_hexapod_file, the loader's own rule.
// False for anything else, a scene or model that does not parse included (the planar reader
// then says what is wrong).
bool scene_is_hexapod(const std::string &text, const std::string &path);

// Reads, checks and (unless check_only) runs the hexapod scene, as legsim_cli does a planar
// one: the resolved scene (check_only) or the results as JSON on out, messages on err. Returns
// legsim_cli's exit status: 0 ok, 1 the run failed (the JSON ends with the status), 2 a bad
// scene or model (nothing written). open_out is called once the scene and model are good and
// returns the stream to write (nullptr: it could not be opened, exit 2).
struct HexapodOutput {
  virtual ~HexapodOutput() = default;
  virtual std::ostream *open() = 0;
};
int run_hexapod_scene(const std::string &text, const std::string &path, bool check_only, HexapodOutput &out,
                      std::ostream &err);

}  // namespace legsim_host

#endif  // LEGSIM_HOST_SCENE_HEXAPOD_HPP

// hil_sim: the legsim leg as a CAN FD node (SocketCAN), driven by the bench over can/legsim.dbc.
#include <cerrno>
#include <climits>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include <sched.h>
#include <sys/prctl.h>
#include <sys/mman.h>
#include <sys/signalfd.h>
#include <unistd.h>

#include "can_io.h"
#include "controller.h"
#include "hexapod_node.h"
#include "jitter.h"
#include "protocol.h"
#include "run_loop.h"
#include "session.h"
#include "model_toml.hpp"
#include "scene_toml.hpp"
#ifdef HIL_SIM_HAS_ROBOT
#include "legsim/robot_models.h"
#endif

namespace {

const char kUsage[] =
    "usage: hil_sim [options]\n"
    "\n"
    "Runs the legsim leg (compiled-in models/leg.toml), or the two-leg robot, as a CAN FD node on a SocketCAN\n"
    "interface, driven by the bench over can/legsim.dbc (see can/README.md). Lockstep mode\n"
    "advances exactly N fixed steps per STEP frame and answers with a state sample; real-time\n"
    "mode ticks at 1 / (steps per tick * step size) (1 kHz at h = 1 ms) with clock_nanosleep.\n"
    "\n"
    "options:\n"
    "  --channel NAME        CAN interface (default vcan0); must be up with MTU 72 (CAN FD)\n"
    "  --cmd-timeout-ms N    actuator-command timeout, 0 = none (default 100); simulated time in\n"
    "                        lockstep, wall-clock time in real time; a RESET may override it\n"
    "  --safe-state MODE     on a command timeout: zero-force (default) or hold-length\n"
    "  --model FILE.toml     run this model file (loaded at start by the host loader) instead of\n"
    "                        the compiled-in leg; it needs the DBC's leg: 6 bodies, 8 joints,\n"
    "                        2 actuators, and both variants Ctrl_Variant names (revolute, slot);\n"
    "                        or a robot file (models/robot.toml: a box on two such legs)\n"
    "  --robot               run the compiled-in two-leg robot (models/robot.toml): each leg\n"
    "                        answers with its own frames (leg 1 at the ids + 0x20), plus the\n"
    "                        feet's contacts (ST_CONTACT) and the box (ST_BOX); leg 0's\n"
    "                        LOAD_CMD index 2, 3 set the box load (box.load, box.moment)\n"
    "  --hexapod             run the hexapod in space (models/hexapod.toml, or --model HEXAPOD.toml):\n"
    "                        each leg a node with its command (HEX_CMD_Hj: force or servo set-points\n"
    "                        with feed-forward) and state frames (HEX_LEG_Hj, HEX_FOOT_Hj), the box's\n"
    "                        (HEX_BOX_POSE, HEX_BOX_VEL); can/README.md, The hexapod\n"
    "  --ground S,MS,MK      the robot's ground instead of its file's: slope S (rad), mu_static\n"
    "                        MS, mu_kinetic MK (a scene's [ground]; the bench passes it)\n"
    "  --decimation N        real time: one state sample every N ticks (default 10)\n"
    "  --heartbeat-ms N      HEARTBEAT period, 0 = none (default 100)\n"
    "  --rt-priority N       SCHED_FIFO priority 1-99 and locked memory for real time\n"
    "                        (default: none, normal scheduling)\n"
    "  -v, --verbose         log faults and mode changes on stderr\n"
    "  --version             print the protocol version and exit\n"
    "  -h, --help            this help\n"
    "\n"
    "Exits 0 on SIGINT/SIGTERM/SIGHUP (real-time statistics on stderr), 1 on a socket or\n"
    "setup error, 2 on a usage error. Without SocketCAN in the kernel, run it under\n"
    "tools/with-vcan.\n";

struct Options {
  std::string channel = "vcan0";
  hil::ControllerConfig controller;
  hil::LoopConfig loop;
  int rt_priority = 0;
  std::string model_file;  // "" = the compiled-in leg
  bool robot = false;       // --robot: the compiled-in robot
  bool hexapod = false;     // --hexapod, or --model naming a hexapod file
  bool has_ground = false;  // --ground: slope, mu_static, mu_kinetic
  double ground[3] = {0, 0, 0};
};

// "S,MS,MK": three finite numbers
bool parse_ground(const char *text, double out[3]) {
  const char *p = text;
  for (int i = 0; i < 3; ++i) {
    errno = 0;
    char *end = nullptr;
    out[i] = std::strtod(p, &end);
    if (end == p || errno != 0 || !std::isfinite(out[i])) return false;
    if (i < 2 && *end != ',') return false;
    p = end + (i < 2 ? 1 : 0);
  }
  return *p == '\0';
}

bool parse_uint(const char *text, unsigned long max, unsigned long *out) {
  if (text == nullptr || *text == '\0' || *text == '-') return false;
  errno = 0;
  char *end = nullptr;
  unsigned long v = std::strtoul(text, &end, 10);
  if (errno != 0 || *end != '\0' || v > max) return false;
  *out = v;
  return true;
}

// Returns -1 to go on, else the exit code.
int parse_options(int argc, char **argv, Options *o) {
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    std::string value;
    bool has_value = false;
    size_t eq = arg.find('=');
    if (arg.rfind("--", 0) == 0 && eq != std::string::npos) {
      value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
      has_value = true;
    }
    auto need = [&](const char *name) -> const char * {
      if (has_value) return value.c_str();
      if (i + 1 >= argc) {
        std::fprintf(stderr, "hil_sim: %s needs a value (see --help)\n", name);
        return nullptr;
      }
      return argv[++i];
    };
    auto bad = [&](const char *name, const char *v, const char *what) {
      std::fprintf(stderr, "hil_sim: bad %s '%s': %s\n", name, v, what);
      return 2;
    };
    unsigned long n = 0;
    if (arg == "-h" || arg == "--help") {
      std::fputs(kUsage, stdout);
      return 0;
    } else if (arg == "--version") {
      std::printf("hil_sim (legsim) protocol %d\n", hil::kProtocolVersion);
      return 0;
    } else if (arg == "-v" || arg == "--verbose") {
      o->controller.verbose = o->loop.verbose = true;
    } else if (arg == "--channel") {
      const char *v = need("--channel");
      if (v == nullptr) return 2;
      o->channel = v;
    } else if (arg == "--cmd-timeout-ms") {
      const char *v = need("--cmd-timeout-ms");
      if (v == nullptr) return 2;
      if (!parse_uint(v, 65534, &n)) return bad("--cmd-timeout-ms", v, "expected 0..65534");
      o->controller.cmd_timeout_ms = static_cast<uint32_t>(n);
    } else if (arg == "--model") {
      const char *v = need("--model");
      if (v == nullptr) return 2;
      o->model_file = v;
    } else if (arg == "--robot") {
      o->robot = true;
    } else if (arg == "--hexapod") {
      o->hexapod = true;
    } else if (arg == "--ground") {
      const char *v = need("--ground");
      if (v == nullptr) return 2;
      if (!parse_ground(v, o->ground)) return bad("--ground", v, "expected SLOPE,MU_STATIC,MU_KINETIC");
      o->has_ground = true;
    } else if (arg == "--safe-state") {
      const char *v = need("--safe-state");
      if (v == nullptr) return 2;
      std::string s = v;
      if (s == "zero-force")
        o->controller.safe_mode = hil::SafeMode::kZeroForce;
      else if (s == "hold-length")
        o->controller.safe_mode = hil::SafeMode::kHoldLength;
      else
        return bad("--safe-state", v, "expected zero-force or hold-length");
    } else if (arg == "--decimation") {
      const char *v = need("--decimation");
      if (v == nullptr) return 2;
      if (!parse_uint(v, 10000, &n) || n == 0) return bad("--decimation", v, "expected 1..10000");
      o->controller.decimation = static_cast<uint32_t>(n);
    } else if (arg == "--heartbeat-ms") {
      const char *v = need("--heartbeat-ms");
      if (v == nullptr) return 2;
      if (!parse_uint(v, 60000, &n)) return bad("--heartbeat-ms", v, "expected 0..60000");
      o->loop.heartbeat_ms = static_cast<uint32_t>(n);
    } else if (arg == "--rt-priority") {
      const char *v = need("--rt-priority");
      if (v == nullptr) return 2;
      if (!parse_uint(v, 99, &n) || n == 0) return bad("--rt-priority", v, "expected 1..99");
      o->rt_priority = static_cast<int>(n);
    } else {
      std::fprintf(stderr, "hil_sim: unknown option '%s' (see --help)\n", argv[i]);
      return 2;
    }
  }
  return -1;
}

void setup_realtime(const Options &opt) {
  // clock_nanosleep wakes on time: a normal thread's default timer slack is 50 us
  prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  if (opt.rt_priority > 0) {
    struct sched_param sp = {};
    sp.sched_priority = opt.rt_priority;
    if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0)
      std::fprintf(stderr, "hil_sim: warning: SCHED_FIFO %d refused (%s); normal scheduling\n",
                   opt.rt_priority, std::strerror(errno));
    if (mlockall(MCL_CURRENT | MCL_FUTURE) != 0)
      std::fprintf(stderr, "hil_sim: warning: mlockall failed (%s)\n", std::strerror(errno));
  }
}

// hil_sim --hexapod: the hexapod's node on the bus, the same loop as the leg's.
int run_hexapod(const Options &opt, const legsim_hexapod_desc &desc, int sfd) {
  hil::HexConfig cfg;
  cfg.cmd_timeout_ms = opt.controller.cmd_timeout_ms;
  cfg.decimation = opt.controller.decimation;
  cfg.verbose = opt.controller.verbose;
  std::string error;
  hil::SocketCan can;
  hil::HexapodNode node(desc, can, cfg);
  if (!node.init(&error)) {
    std::fprintf(stderr, "hil_sim: %s\n", error.c_str());
    return 1;
  }
  if (!can.open(opt.channel, &error)) {
    std::fprintf(stderr, "hil_sim: %s\n", error.c_str());
    return 1;
  }
  setup_realtime(opt);
  hil::JitterStats stats;
  std::fprintf(stderr, "hil_sim: hexapod listening on %s (protocol %d, cmd timeout %u ms, decimation %u)\n",
               opt.channel.c_str(), hil::kProtocolVersion, cfg.cmd_timeout_ms, cfg.decimation);
  hil::LoopResult res = hil::run_loop(can, node, sfd, opt.loop, &stats);
  if (res.signal != 0)
    std::fprintf(stderr, "hil_sim: %s, exiting\n", strsignal(res.signal));
  else
    std::fprintf(stderr, "hil_sim: CAN socket failed: %s\n", std::strerror(res.socket_errno));
  std::fprintf(stderr, "hil_sim: %u frames received, %u rejected, %u faults sent, %u frames not sent\n",
               node.rx_frames(), node.rx_rejected(), node.fault_count(), can.tx_errors());
  can.close();
  ::close(sfd);
  return res.signal != 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char **argv) {
  Options opt;
  int rc = parse_options(argc, argv, &opt);
  if (rc >= 0) return rc;

  // signals arrive on a descriptor the loops poll: no handler races, clean exit from any state
  sigset_t mask;
  sigemptyset(&mask);
  sigaddset(&mask, SIGINT);
  sigaddset(&mask, SIGTERM);
  sigaddset(&mask, SIGHUP);
  if (sigprocmask(SIG_BLOCK, &mask, nullptr) != 0) {
    std::perror("hil_sim: sigprocmask");
    return 1;
  }
  int sfd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
  if (sfd < 0) {
    std::fprintf(stderr, "hil_sim: signalfd failed: %s\n", std::strerror(errno));
    return 1;
  }

  if (opt.hexapod && opt.robot) {
    std::fprintf(stderr, "hil_sim: --robot and --hexapod exclude each other (see --help)\n");
    return 2;
  }
  // a hexapod file: --hexapod (this tree's, or --model's), or --model naming one
  static legsim_hexapod_desc hexapod_desc;  // large: not on the stack
  if (opt.hexapod || !opt.model_file.empty()) {
    const std::string path = opt.model_file.empty() ? HIL_SIM_HEXAPOD_FILE : opt.model_file;
    char msg[512] = "";
    if (legsim_hexapod_load_toml(path.c_str(), &hexapod_desc, msg, sizeof msg) == LEGSIM_OK) {
      opt.hexapod = true;
      std::fprintf(stderr, "hil_sim: hexapod %s (6 legs)\n", path.c_str());
    } else if (opt.hexapod) {
      std::fprintf(stderr, "hil_sim: --hexapod: %s\n", msg);
      return 2;
    }
  }
  if (opt.hexapod && opt.has_ground) {
    std::fprintf(stderr, "hil_sim: --ground: the hexapod's ground is its file's\n");
    return 2;
  }
  if (opt.hexapod) return run_hexapod(opt, hexapod_desc, sfd);

  // --model: both variants of the file, checked by the loader (and by session.init below
  // against the DBC's leg); they live to the end of main, past every session.
  legsim_model_desc file_models[2];
  legsim_model_desc robot_desc;  // the robot, with the box's two force elements
  // The robot's box load (a scene's box_load): legsim_host::box_load_add's two force elements
  // (box.load, box.moment; zero until leg 0's LOAD_CMD index 2 and 3 set them).
  auto with_box_load = [](legsim_model_desc &d) {
    const double zero[3] = {0, 0, 0};
    std::string why;
    if (!legsim_host::box_load_add(d, zero, why))
      std::fprintf(stderr, "hil_sim: warning: no box load over CAN (%s)\n", why.c_str());
  };
  if (opt.robot && !opt.model_file.empty()) {
    std::fprintf(stderr, "hil_sim: --robot and --model exclude each other (see --help)\n");
    return 2;
  }
  if (opt.robot) {
#ifdef HIL_SIM_HAS_ROBOT
    robot_desc = legsim_model_robot_revolute;
    with_box_load(robot_desc);
    hil::Session::use_robot(&robot_desc);
    std::fprintf(stderr, "hil_sim: the compiled-in robot '%s' (2 legs)\n",
                 legsim_model_robot_revolute.name);
#else
    std::fprintf(stderr, "hil_sim: --robot: this build's capacities do not hold the robot "
                         "(13 bodies, 16 joints, 4 actuators, 2 contacts); use --model "
                         "models/robot.toml in a build that does\n");
    return 2;
#endif
  } else if (!opt.model_file.empty()) {
    char msg[512] = "";
    if (legsim_model_load_toml(opt.model_file.c_str(), "revolute", &file_models[0], msg,
                               sizeof msg) != LEGSIM_OK) {
      std::fprintf(stderr, "hil_sim: --model: %s\n", msg);
      return 2;
    }
  }
  if (!opt.model_file.empty() && file_models[0].n_contacts > 0) {
    // a robot file: one variant (its legs name theirs)
    with_box_load(file_models[0]);
    hil::Session::use_robot(&file_models[0]);
    std::fprintf(stderr, "hil_sim: robot model %s (2 legs)\n", opt.model_file.c_str());
  } else if (!opt.model_file.empty()) {
    const char *variants[2] = {"revolute", "slot"};
    for (int v = 1; v < 2; ++v) {
      char msg[512] = "";
      if (legsim_model_load_toml(opt.model_file.c_str(), variants[v], &file_models[v], msg,
                                 sizeof msg) != LEGSIM_OK) {
        std::fprintf(stderr, "hil_sim: --model: %s\n", msg);
        return 2;
      }
    }
    hil::Session::use_models(&file_models[0], &file_models[1]);
    std::fprintf(stderr, "hil_sim: model %s (variants revolute, slot)\n", opt.model_file.c_str());
  }
  if (opt.has_ground) {
    // a scene's [ground]: the robot's ground line through its file's point
    legsim_model_desc *robot = opt.robot ? &robot_desc
                               : file_models[0].n_contacts > 0 ? &file_models[0] : nullptr;
    if (robot == nullptr) {
      std::fprintf(stderr, "hil_sim: --ground: the model has no ground (a robot's: --robot or --model ROBOT.toml)\n");
      return 2;
    }
    robot->ground.slope_rad = opt.ground[0];
    robot->ground.mu_static = opt.ground[1];
    robot->ground.mu_kinetic = opt.ground[2];
    char msg[512] = "";
    if (legsim_model_check(robot, msg, sizeof msg) != LEGSIM_OK) {
      std::fprintf(stderr, "hil_sim: --ground: %s\n", msg);
      return 2;
    }
    std::fprintf(stderr, "hil_sim: ground slope %g rad, mu_static %g, mu_kinetic %g\n", opt.ground[0],
                 opt.ground[1], opt.ground[2]);
  }
  hil::Session session;
  std::string error;
  if (!session.init(&error)) {
    std::fprintf(stderr, "hil_sim: %s\n", error.c_str());
    return 1;
  }
  hil::SocketCan can;
  if (!can.open(opt.channel, &error)) {
    std::fprintf(stderr, "hil_sim: %s\n", error.c_str());
    return 1;
  }
  setup_realtime(opt);

  hil::Controller controller(session, can, opt.controller);
  hil::JitterStats stats;
  std::fprintf(stderr,
               "hil_sim: listening on %s (protocol %d, cmd timeout %u ms, safe state %s, "
               "decimation %u)\n",
               opt.channel.c_str(), hil::kProtocolVersion, opt.controller.cmd_timeout_ms,
               opt.controller.safe_mode == hil::SafeMode::kZeroForce ? "zero-force"
                                                                      : "hold-length",
               opt.controller.decimation);
  hil::LoopResult res = hil::run_loop(can, controller, sfd, opt.loop, &stats);

  if (res.signal != 0)
    std::fprintf(stderr, "hil_sim: %s, exiting\n", strsignal(res.signal));
  else
    std::fprintf(stderr, "hil_sim: CAN socket failed: %s\n", std::strerror(res.socket_errno));
  std::fprintf(stderr,
               "hil_sim: %u frames received, %u rejected, %u faults sent, %u frames not sent\n",
               controller.rx_frames(), controller.rx_rejected(), controller.fault_count(),
               can.tx_errors());
  if (stats.count() > 0) hil::print_rt_stats("last real-time run", stats,
                                             controller.rt_period_ns() > 0
                                                 ? 1e9 / controller.rt_period_ns()
                                                 : 0.0);
  can.close();
  ::close(sfd);
  return res.signal != 0 ? 0 : 1;
}

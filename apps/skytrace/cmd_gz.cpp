// `skytrace gz --scenario FILE --world-name NAME --model ROBOT [--link LINK]`: a simulated GNSS
// receiver on a robot of a running Gazebo (docs/gazebo.md). The ignition code lives in
// apps/gz (skytrace_gz_bridge), linked when the build found Gazebo transport.
#include <algorithm>
#include <atomic>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "commands.hpp"
#include "skytrace/core/cancellation.hpp"
#include "skytrace/sim/live_outputs.hpp"

#if SKYTRACE_HAVE_GZ
#include "gz_bridge.hpp"
#endif

namespace skytrace::cli {
namespace {

struct GzArgs {
  std::string scenario;
  std::string world_name;
  std::string model;
  std::string link;
  std::string receiver;
  std::string base_link;
  double rate_hz = 1.0;
  std::string start_time;
  double pose_timeout_s = 1.0;
  bool quiet = false;
  std::vector<std::pair<std::string, std::string>> file_outputs;  // parameter, path
};

int run_gz(const GzArgs& args) {
#if SKYTRACE_HAVE_GZ
  gz::BridgeOptions options;
  options.scenario = args.scenario;
  options.world_name = args.world_name;
  options.model = args.model;
  options.link = args.link;
  options.receiver = args.receiver;
  options.base_link = args.base_link;
  options.rate_hz = args.rate_hz;
  if (!args.start_time.empty()) options.start_time = args.start_time;
  options.pose_timeout_s = args.pose_timeout_s;
  options.quiet = args.quiet;
  options.file_outputs = args.file_outputs;
  install_live_stop_handlers();
  auto st = gz::run_bridge(options);
  const int code = st ? kExitOk : report_error(st.error());
  // The files are complete. ign-transport 11's discovery threads outlive main and may dispatch a
  // message into its shared node while static destructors tear it down (a segfault at exit, seen
  // under load; gz-sim #1317): end here, without the static destructors.
  spdlog::shutdown();
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);
  std::_Exit(code);
#else
  (void)args;
  std::cerr << "skytrace: error: this build has no Gazebo transport (install libignition-transport-dev and "
               "libignition-msgs-dev, see scripts/setup, and rebuild)\n";
  return kExitUsage;
#endif
}

}  // namespace

void register_gz_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<GzArgs>();
  CLI::App* cmd = app.add_subcommand(
      "gz", "Run a receiver on a robot of a running Gazebo (Fortress): poses in, NavSat and observations out");
  cmd->add_option("--scenario", args->scenario, "Scenario file (its world.sdf is the world Gazebo runs)")->required();
  cmd->add_option("--world-name", args->world_name, "Name of the Gazebo world (<world name=...>)")->required();
  cmd->add_option("--model", args->model, "Model carrying the antenna")->required();
  cmd->add_option("--link", args->link, "Link of the model with the antenna (default: the model's origin)");
  cmd->add_option("--receiver", args->receiver, "The receiver of a scenario with several, by name (default: the first)");
  cmd->add_option("--base-link", args->base_link,
                  "A moving-base receiver (rtk.moving_base): the model's link with the base antenna; the heading of "
                  "the baseline then comes as NMEA HDT/THS (default: the base antenna keeps the scenario's baseline)");
  cmd->add_option("--rate-hz", args->rate_hz, "Receiver epochs per second of simulation time")->capture_default_str();
  cmd->add_option("--start-time", args->start_time,
                  "GPST date and time of simulation time zero, YYYY-MM-DDThh:mm:ss (default: the scenario's start)");
  cmd->add_option("--pose-timeout-s", args->pose_timeout_s,
                  "A pose older than this is stale: the receiver is held where it was")
      ->capture_default_str();
  cmd->add_flag("--quiet", args->quiet, "No start-up message");
  // The files a live receiver writes as it runs, one option per kind: --rinex-out, --nmea-out, ...
  const auto& files = sim::live_file_table();
  args->file_outputs.resize(files.size());
  for (size_t i = 0; i < files.size(); ++i) {
    std::string option = std::string("--") + files[i].parameter;
    std::replace(option.begin(), option.end(), '_', '-');
    args->file_outputs[i].first = files[i].parameter;
    cmd->add_option(option, args->file_outputs[i].second,
                    std::string("Write ") + files[i].description + " to this file (moved into place when the bridge stops)");
  }
  cmd->footer(
      "Subscribes to /world/NAME/pose/info (ignition.msgs.Pose_V) and /world/NAME/clock "
      "(ignition.msgs.Clock); publishes ignition.msgs.NavSat on /world/NAME/model/ROBOT/skytrace/navsat and "
      "the raw observations as JSON (ignition.msgs.StringMsg) on /world/NAME/model/ROBOT/skytrace/observations. "
      "Runs until interrupted (Ctrl-C).");
  cmd->callback([args, &exit_code]() { exit_code = run_gz(*args); });
}

}  // namespace skytrace::cli

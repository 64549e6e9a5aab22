// The Gazebo transport bridge behind `skytrace gz` (docs/gazebo.md): a live receiver on a robot of
// a running Gazebo (Fortress, ignition-transport 11). Plain types only, so that the heavy
// ignition headers stay in gz_bridge.cpp.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "skytrace/core/error.hpp"

namespace skytrace::gz {

struct BridgeOptions {
  std::filesystem::path scenario;
  std::string world_name;  // the <world name> Gazebo runs
  std::string model;       // the robot carrying the antenna
  std::string link;        // its link with the antenna; empty: the model's origin
  std::string receiver;    // one receiver of a scenario with several, by name; empty: the first
  // A moving base (the receiver's rtk.moving_base): the model's link with the base antenna; empty:
  // the base antenna follows the antenna at the scenario's baseline.
  std::string base_link;
  double rate_hz = 1.0;    // receiver epochs per second of simulation time
  std::optional<std::string> start_time;  // GPST ISO 8601 of simulation time zero; default the scenario's start
  double pose_timeout_s = 1.0;
  bool quiet = false;
  // Files written as the receiver runs (sim::live_file_table: "rinex_out", "nmea_out", ...) and their paths.
  std::vector<std::pair<std::string, std::string>> file_outputs;
};

// Topics of the bridge (documented in docs/gazebo.md).
[[nodiscard]] std::string pose_topic(const BridgeOptions& options);          // /world/W/pose/info
[[nodiscard]] std::string clock_topic(const BridgeOptions& options);         // /world/W/clock
[[nodiscard]] std::string navsat_topic(const BridgeOptions& options);        // /world/W/model/M/skytrace/navsat
[[nodiscard]] std::string observations_topic(const BridgeOptions& options);  // .../skytrace/observations

// Runs until cancellation is requested (core/cancellation: SIGINT, SIGTERM); the files are then
// finished. Errors: the scenario cannot be loaded, a topic cannot be subscribed or advertised, a
// file cannot be written.
[[nodiscard]] Status run_bridge(const BridgeOptions& options);

}  // namespace skytrace::gz

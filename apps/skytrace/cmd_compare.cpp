// `skytrace compare REAL.obs SIM.obs`: how far a simulation is from a real recording, per system
// and signal (pseudorange, Doppler, epoch-differenced phase, C/N0, tracked-set overlap).
#include <fmt/format.h>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/io/compare.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/sim/trajectory.hpp"

namespace skytrace::cli {
namespace {

struct CompareArgs {
  std::string real_path;
  std::string sim_path;
  std::vector<std::string> nav_files;
  double min_elevation_deg = 10.0;
  std::string systems;
  std::string signals;
  std::string json_path;
  std::string trajectory_path;
  double epoch_tolerance_ms = 1.0;
};

int run_compare(const CompareArgs& args) {
  // Named as the user gave them, before the files are read (compare() checks its options again).
  if (!(args.min_elevation_deg >= -90.0 && args.min_elevation_deg <= 90.0)) {
    return report_error(make_error(ErrorCode::kInvalidArgument,
                                   fmt::format("--min-elevation-deg {}: expected -90 to 90", args.min_elevation_deg)));
  }
  if (!(args.epoch_tolerance_ms >= 0.0 && args.epoch_tolerance_ms <= 500.0)) {
    return report_error(make_error(ErrorCode::kInvalidArgument,
                                   fmt::format("--epoch-tolerance-ms {}: expected 0 to 500", args.epoch_tolerance_ms)));
  }
  io::CompareOptions options;
  options.min_elevation_deg = args.min_elevation_deg;
  options.epoch_tolerance_s = args.epoch_tolerance_ms * 1e-3;
  std::shared_ptr<sim::InterpolatedTrajectory> track;
  if (!args.trajectory_path.empty()) {
    sim::TrajectorySetting setting;
    setting.file = args.trajectory_path;
    // Rows carry ISO times (GPST): the start only matters for rows in seconds, which need one.
    auto samples = sim::read_trajectory_csv(setting, GnssTime{}, std::nullopt);
    if (!samples) return report_error(samples.error().with_context("--trajectory"));
    auto created = sim::InterpolatedTrajectory::create(std::move(*samples), args.trajectory_path);
    if (!created) return report_error(created.error().with_context("--trajectory"));
    track = std::move(*created);
    options.receiver_position = [track](const GnssTime& t) -> std::optional<Eigen::Vector3d> {
      const auto& s = track->samples();
      if (t < s.front().time || s.back().time < t) return std::nullopt;
      auto k = track->at(t);
      if (!k) return std::nullopt;
      return k->position_m;
    };
  }
  if (!args.systems.empty()) {
    auto systems = io::parse_system_letters(args.systems);
    if (!systems) return report_error(systems.error().with_context("--systems"));
    options.systems = std::move(*systems);
  }
  if (!args.signals.empty()) {
    auto signals = io::parse_signal_list(args.signals);
    if (!signals) return report_error(signals.error().with_context("--signals"));
    options.signals = std::move(*signals);
  }
  std::optional<orbits::BroadcastEphemerides> ephemerides;
  if (!args.nav_files.empty()) {
    orbits::NavigationData all;
    for (const auto& path : args.nav_files) {
      auto data = orbits::read_rinex_nav(path);
      if (!data) return report_error(data.error());
      all.merge(std::move(*data));
    }
    for (const auto& warning : all.warnings) std::cerr << "skytrace compare: warning: " << warning << "\n";
    ephemerides.emplace(std::move(all));
    options.satellite_source = &*ephemerides;
  }
  auto report = io::compare_observation_files(args.real_path, args.sim_path, options);
  if (!report) return report_error(report.error());
  for (const auto& warning : report->warnings) std::cerr << "skytrace compare: warning: " << warning << "\n";
  if (!args.json_path.empty()) {
    if (auto s = write_file_atomically(args.json_path, io::comparison_to_json(*report)); !s) {
      return report_error(s.error());
    }
  }
  std::cout << io::format_comparison_table(*report);
  if (!report->elevation_mask_applied) std::cout << "# give --nav for an elevation mask\n";
  return kExitOk;
}

}  // namespace

void register_compare_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Compare real and simulated RINEX observations per system and signal (text table, JSON)");
  cmd->add_option("real", args->real_path,
                  "Real observation file (RINEX 2.11, 3.0x, 4.00; .gz allowed)")
      ->required();
  cmd->add_option("sim", args->sim_path, "Simulated observation file")->required();
  cmd->add_option(
      "--nav", args->nav_files,
      "RINEX navigation file for the elevation mask (repeat for several); without it: no mask");
  cmd->add_option("--min-elevation-deg", args->min_elevation_deg, "Elevation mask (needs --nav)")
      ->capture_default_str();
  cmd->add_option("--systems", args->systems,
                  "Systems to compare as letters, e.g. GE (default: all common)");
  cmd->add_option("--signals", args->signals,
                  "Signals to compare, e.g. G1C,E1C (default: all common)");
  cmd->add_option("--json", args->json_path, "Also write the numbers as JSON to this file");
  cmd->add_option("--trajectory", args->trajectory_path,
                  "A moving receiver's ECEF trajectory (CSV as a scenario's trajectory.file, ISO GPST "
                  "times): the elevation mask looks from its position at each epoch");
  cmd->add_option("--epoch-tolerance-ms", args->epoch_tolerance_ms,
                  "Epochs this close are one epoch; the real side is moved to the simulated time with "
                  "the Doppler (receivers whose clock is not steered tag epochs ms off the second)")
      ->capture_default_str();
  cmd->footer(
      "Residuals are real minus simulated after subtracting, per epoch and system, the median over "
      "the system's satellites (receiver clock, inter-system bias). Epochs are matched to 1 ms unless --epoch-tolerance-ms says otherwise.");
  cmd->callback([args, &exit_code]() { exit_code = run_compare(*args); });
}

}  // namespace skytrace::cli

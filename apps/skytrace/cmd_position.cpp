// `skytrace position OBS.rnx --nav NAV.rnx`: single-point positions of every epoch of a RINEX
// observation file (skytrace's own or a real receiver's) with the project's positioning engine, as
// CSV.
#include <fmt/format.h>

#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/io/compare.hpp"
#include "skytrace/io/fix_csv.hpp"
#include "skytrace/io/rinex_measurements.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/positioning/spp.hpp"

namespace skytrace::cli {
namespace {

struct PositionArgs {
  std::string obs_path;
  std::vector<std::string> nav_files;
  std::string out_path;
  std::string systems;
  double elevation_mask_deg = 10.0;
  double min_cn0_dbhz = 0.0;
  bool reject_outliers = false;
  bool no_ionosphere = false;
  bool no_troposphere = false;
};

int run_position(const PositionArgs& args) {
  positioning::SolverSettings settings;
  settings.elevation_mask_deg = args.elevation_mask_deg;
  settings.min_cn0_dbhz = args.min_cn0_dbhz;
  settings.reject_outliers = args.reject_outliers;
  settings.ionosphere_klobuchar = !args.no_ionosphere;
  settings.troposphere_saastamoinen = !args.no_troposphere;
  if (!args.systems.empty()) {
    auto systems = io::parse_system_letters(args.systems);
    if (!systems) return report_error(systems.error().with_context("--systems"));
    settings.systems = std::move(*systems);
  } else {
    // SBAS GEO broadcast orbits are not meant for ranging at the metre level: opt in with --systems.
    for (GnssSystem system : kAllSystems) {
      if (system != GnssSystem::kSbas) settings.systems.push_back(system);
    }
  }
  if (!(args.elevation_mask_deg >= -90.0 && args.elevation_mask_deg < 90.0)) {
    return report_error(make_error(ErrorCode::kInvalidArgument, "--elevation-mask-deg must be in [-90, 90)"));
  }

  orbits::NavigationData navigation;
  for (const auto& path : args.nav_files) {
    auto data = orbits::read_rinex_nav(path);
    if (!data) return report_error(data.error());
    navigation.merge(std::move(*data));
  }
  if (navigation.record_count() == 0) {
    return report_error(make_error(ErrorCode::kNotFound, "the navigation file(s) hold no ephemeris record"));
  }
  std::optional<orbits::KlobucharCoefficients> klobuchar = navigation.ionosphere.gps;
  if (!klobuchar && settings.ionosphere_klobuchar) {
    std::cerr << "skytrace: warning: no GPS Klobuchar coefficients (ION ALPHA/BETA, GPSA/GPSB) in the "
                 "navigation data: no ionosphere correction\n";
  }
  for (const auto& warning : navigation.warnings) std::cerr << "skytrace position: warning: " << warning << "\n";
  const orbits::BroadcastEphemerides ephemerides(std::move(navigation));

  auto observations = io::read_rinex_obs(args.obs_path);
  if (!observations) return report_error(observations.error());
  for (const auto& warning : observations->warnings) std::cerr << "skytrace position: warning: " << warning << "\n";
  const io::MeasurementExtractor extractor(observations->header);
  positioning::SinglePointSolver solver(ephemerides, settings, klobuchar);

  std::string csv = io::fix_csv_header();
  size_t epochs = 0, fixes = 0;
  std::string first_failure;
  for (const io::ObservationEpoch& epoch : observations->epochs) {
    if (epoch.flag != io::EpochFlag::kOk && epoch.flag != io::EpochFlag::kPowerFailure) continue;
    ++epochs;
    auto fix = solver.solve(extractor.measurements(epoch));
    if (!fix) return report_error(fix.error().with_context(args.obs_path));
    if (fix->type != positioning::FixType::kNone) {
      ++fixes;
    } else if (first_failure.empty()) {
      first_failure = fix->receiver_time.to_iso8601(TimeScale::kGpst) + ": " + fix->message;
    }
    csv += io::fix_csv_row(*fix);
  }
  if (epochs == 0) return report_error(make_error(ErrorCode::kNotFound, args.obs_path + ": no observation epoch"));
  if (fixes == 0) {
    return report_error(make_error(ErrorCode::kOutOfRange, "no epoch of " + args.obs_path +
                                                               " could be positioned; first: " + first_failure));
  }
  if (args.out_path.empty()) {
    std::cout << csv;
  } else {
    if (auto s = write_file_atomically(args.out_path, csv); !s) {
      std::cerr << "skytrace: error: " << s.error().message << "\n";
      return kExitOutput;
    }
    std::cerr << fmt::format("skytrace: {} of {} epochs positioned -> {}\n", fixes, epochs, args.out_path);
  }
  return kExitOk;
}

}  // namespace

void register_position_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<PositionArgs>();
  CLI::App* cmd = app.add_subcommand(
      "position", "Single-point positions, velocities and DOPs of every epoch of a RINEX observation file (CSV)");
  cmd->add_option("obs", args->obs_path, "Observation file (RINEX 2.11, 3.0x, 4.0x; .gz allowed)")->required();
  cmd->add_option("--nav", args->nav_files, "RINEX navigation file (repeat for several)")->required();
  cmd->add_option("--out", args->out_path, "CSV file to write (default: standard output)");
  cmd->add_option("--systems", args->systems, "Systems to use as letters, e.g. G,E (default: all but SBAS)");
  cmd->add_option("--elevation-mask-deg", args->elevation_mask_deg, "Elevation mask")->capture_default_str();
  cmd->add_option("--min-cn0-dbhz", args->min_cn0_dbhz, "Ignore signals below this C/N0 (0: no limit)")
      ->capture_default_str();
  cmd->add_flag("--reject-outliers", args->reject_outliers,
                "Exclude the worst satellite while the chi-square residual test fails (p = 0.001)");
  cmd->add_flag("--no-ionosphere", args->no_ionosphere, "Do not apply the Klobuchar model");
  cmd->add_flag("--no-troposphere", args->no_troposphere, "Do not apply the Saastamoinen model");
  cmd->footer(
      "One code per satellite (L1 C/A, E1, B1I, G1 first) with its broadcast group delay, one receiver "
      "clock per system, elevation-dependent weights; velocity and clock drift from Doppler. Rows of "
      "epochs without a fix give the reason in `message`.");
  cmd->callback([args, &exit_code]() { exit_code = run_position(*args); });
}

}  // namespace skytrace::cli

// `skytrace orbits`: satellite positions and clocks from broadcast ephemerides (or the nominal
// constellation) on a time grid, as CSV. Used to check the orbit layer against precise products.
#include <fmt/format.h>

#include <cmath>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "skytrace/core/input_limits.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/nominal.hpp"
#include "skytrace/orbits/rinex_nav.hpp"

namespace skytrace::cli {
namespace {

struct OrbitsArgs {
  std::vector<std::string> nav_files;
  std::string start = "2020-06-25T00:00:00";
  std::string scale = "GPST";
  double duration_s = 86400.0;
  double interval_s = 900.0;
  std::string csv_path;
  std::string write_nav_path;
};

Result<orbits::NavigationData> load_navigation(const OrbitsArgs& args, const GnssTime& start) {
  if (args.nav_files.empty()) {
    return orbits::make_nominal_constellation(start, args.duration_s);
  }
  orbits::NavigationData all;
  for (const auto& path : args.nav_files) {
    auto data = orbits::read_rinex_nav(path);
    if (!data) return data.error();
    all.merge(std::move(*data));
  }
  return all;
}

int run_orbits(const OrbitsArgs& args) {
  auto scale = parse_time_scale(args.scale);
  if (!scale) return report_error(scale.error().with_context("--scale"));
  auto start = GnssTime::parse_iso8601(args.start, *scale);
  if (!start) return report_error(start.error().with_context("--start"));
  if (!(args.interval_s > 0.0) || !(args.duration_s >= 0.0) || !std::isfinite(args.duration_s)) {
    return report_error(make_error(ErrorCode::kInvalidArgument,
                                   "--interval-s must be positive and --duration-s not negative"));
  }
  auto navigation = load_navigation(args, *start);
  if (!navigation) return report_error(navigation.error());
  if (!args.write_nav_path.empty()) {
    if (auto s = write_file_atomically(args.write_nav_path, orbits::format_rinex3_nav(*navigation)); !s) {
      return report_error(s.error());
    }
  }
  const orbits::BroadcastEphemerides ephemerides(std::move(*navigation));
  const auto satellites = ephemerides.satellites();
  if (satellites.empty()) {
    return report_error(make_error(ErrorCode::kNotFound, "the navigation data holds no ephemeris"));
  }

  // The table is built in memory: bound it before the first row.
  const double table_rows = (std::floor(args.duration_s / args.interval_s + 1e-9) + 1.0) * static_cast<double>(satellites.size());
  if (!(table_rows <= static_cast<double>(input_limits().max_table_rows))) {
    return report_error(make_error(
        ErrorCode::kInvalidArgument,
        fmt::format("--duration-s {} and --interval-s {} give {:.3g} rows for {} satellites, more than a table may have {}",
                    args.duration_s, args.interval_s, table_rows, satellites.size(),
                    limit_hint(input_limits().max_table_rows, "SKYTRACE_MAX_TABLE_ROWS"))));
  }
  std::string csv = "time_gpst,sat,x_m,y_m,z_m,clock_s\n";
  size_t rows = 0;
  size_t missing = 0;
  std::string first_missing;
  const auto epochs = static_cast<long>(args.duration_s / args.interval_s + 1e-9) + 1;
  for (long k = 0; k < epochs; ++k) {
    const GnssTime t = *start + static_cast<double>(k) * args.interval_s;
    const std::string time_text = t.to_iso8601(TimeScale::kGpst, 3);
    for (const auto& sat : satellites) {
      auto state = ephemerides.state(sat, t);
      if (state && !(state->position_m.allFinite() && std::isfinite(state->clock_bias_s))) {
        state = make_error(ErrorCode::kParse, sat.to_string() + ": its ephemeris gives no finite position at " +
                                                  time_text + " (a malformed record)");
      }
      if (!state) {
        if (missing++ == 0) first_missing = state.error().message;
        continue;
      }
      fmt::format_to(std::back_inserter(csv), "{},{},{:.3f},{:.3f},{:.3f},{:.12e}\n", time_text,
                     sat.to_string(), state->position_m.x(), state->position_m.y(), state->position_m.z(),
                     state->clock_bias_s);
      ++rows;
    }
  }
  if (rows == 0) {
    return report_error(make_error(ErrorCode::kOutOfRange,
                                   "no satellite has a valid ephemeris between " +
                                       start->to_iso8601(*scale, 0) + " " + args.scale + " and " +
                                       (*start + args.duration_s).to_iso8601(*scale, 0) + " " +
                                       args.scale + ": " + first_missing));
  }
  if (args.csv_path.empty() || args.csv_path == "-") {
    std::cout << csv;
  } else if (auto s = write_file_atomically(args.csv_path, csv); !s) {
    return report_error(s.error());
  } else {
    std::cerr << fmt::format("skytrace orbits: {} rows ({} satellites, {} epochs) written to {}\n", rows,
                             satellites.size(), epochs, args.csv_path);
  }
  if (missing > 0) {
    std::cerr << fmt::format("skytrace orbits: {} satellite-epochs without a valid ephemeris skipped "
                             "(first: {})\n",
                             missing, first_missing);
  }
  return kExitOk;
}

}  // namespace

void register_orbits_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<OrbitsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "orbits", "Satellite ECEF positions and clocks from broadcast ephemerides on a time grid (CSV)");
  cmd->add_option("--nav", args->nav_files,
                  "RINEX navigation file (2.x, 3.x, 4.00; .gz allowed); repeat for several. "
                  "Without it: the nominal constellation")
      ->check(CLI::ExistingFile);
  cmd->add_option("--start", args->start, "First epoch, ISO 8601 (YYYY-MM-DDThh:mm:ss)")->capture_default_str();
  cmd->add_option("--scale", args->scale, "Time scale of --start (GPST, GST, BDT, GLONASST, UTC, ...)")
      ->capture_default_str();
  cmd->add_option("--duration-s", args->duration_s, "Span in seconds")->capture_default_str();
  cmd->add_option("--interval-s", args->interval_s, "Step in seconds")->capture_default_str();
  cmd->add_option("--csv", args->csv_path, "Output CSV (header time_gpst,sat,x_m,y_m,z_m,clock_s); '-' = stdout");
  cmd->add_option("--write-nav", args->write_nav_path,
                  "Also write the navigation data used as a RINEX 3.04 navigation file");
  cmd->footer(
      "clock_s is the navigation-message clock polynomial without the relativistic term or group "
      "delays (the quantity SP3 clocks give).");
  cmd->callback([args, &exit_code]() { exit_code = run_orbits(*args); });
}

}  // namespace skytrace::cli

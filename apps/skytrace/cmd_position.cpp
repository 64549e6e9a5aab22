// `skytrace position OBS.rnx --nav NAV.rnx`: single-point positions of every epoch of a RINEX
// observation file (skytrace's own or a real receiver's) with the project's positioning engine, as
// CSV.
#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/io/compare.hpp"
#include "skytrace/io/fix_csv.hpp"
#include "skytrace/io/rinex_measurements.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/positioning/rtk.hpp"
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
  // RTK: a base station's observations and position.
  std::string base_path;
  std::string base_position;  // X,Y,Z (m, ECEF) of the base antenna reference point
  std::string ambiguity_mode = "fix-and-hold";
  std::string dynamics = "kinematic";
  double ratio_threshold = 3.0;
  double rtk_elevation_mask_deg = 15.0;
};

// The base's antenna reference point: --base-position, else the header's APPROX POSITION XYZ plus
// its ANTENNA: DELTA H/E/N (up, east, north from the marker).
Result<Eigen::Vector3d> base_position(const PositionArgs& args, const io::ObservationHeader& header) {
  if (!args.base_position.empty()) {
    std::vector<double> values;
    std::string text = args.base_position;
    for (char& c : text) {
      if (c == ',') c = ' ';
    }
    std::istringstream in(text);
    for (double v = 0.0; in >> v;) values.push_back(v);
    if (!in.eof() || values.size() != 3 || Eigen::Vector3d(values[0], values[1], values[2]).norm() < 6.0e6 ||
        Eigen::Vector3d(values[0], values[1], values[2]).norm() > 7.0e6) {
      return make_error(ErrorCode::kInvalidArgument,
                        "--base-position: expected X,Y,Z in metres (ECEF, near the Earth's surface), got '" +
                            args.base_position + "'");
    }
    return Eigen::Vector3d(values[0], values[1], values[2]);
  }
  if (!header.approx_position_ecef_m) {
    return make_error(ErrorCode::kInvalidArgument, args.base_path +
                                                       ": no APPROX POSITION XYZ in the header: give the base "
                                                       "position with --base-position X,Y,Z");
  }
  const auto& p = *header.approx_position_ecef_m;
  const Eigen::Vector3d marker(p[0], p[1], p[2]);
  if (marker.norm() < 6.0e6 || marker.norm() > 7.0e6) {
    return make_error(ErrorCode::kInvalidArgument,
                      args.base_path + ": APPROX POSITION XYZ is not a place on the Earth: give the base position "
                                       "with --base-position X,Y,Z");
  }
  const auto& d = header.antenna_delta_hen_m;
  return enu_to_ecef(Eigen::Vector3d(d[1], d[2], d[0]), ecef_to_geodetic(marker));
}

// Whether a file holds RTCM 3 (a frame preamble within its first bytes) rather than RINEX text.
bool looks_like_rtcm3(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  char head[64] = {};
  in.read(head, sizeof head);
  for (std::streamsize i = 0; i + 2 < in.gcount(); ++i) {
    if (static_cast<unsigned char>(head[i]) == 0xD3 && (static_cast<unsigned char>(head[i + 1]) & 0xFC) == 0) return true;
  }
  return false;
}

// The base's epochs, each with the base's antenna reference point: from a RINEX file (position from
// --base-position or the header), or from an RTCM 3 file (position from --base-position or its
// 1005/1006; `rover_start` places the RTCM times of week).
Result<std::vector<positioning::BaseEpoch>> read_base(const PositionArgs& args, const GnssTime& rover_start) {
  std::vector<positioning::BaseEpoch> out;
  if (looks_like_rtcm3(args.base_path)) {
    std::ifstream in(args.base_path, std::ios::binary);
    if (!in) return make_error(ErrorCode::kIo, args.base_path + ": cannot open");
    io::Rtcm3Decoder decoder(rover_start);
    std::vector<std::uint8_t> chunk(1 << 16);
    while (in) {
      in.read(reinterpret_cast<char*>(chunk.data()), static_cast<std::streamsize>(chunk.size()));
      decoder.feed(std::span<const std::uint8_t>(chunk.data(), static_cast<size_t>(in.gcount())));
    }
    decoder.finish();
    const auto& counts = decoder.counts();
    if (counts.skipped_bytes > 0 || counts.malformed_messages > 0 || counts.unknown_signal_cells > 0) {
      std::cerr << fmt::format("skytrace position: warning: {}: {} bytes outside valid frames, {} malformed messages, "
                               "{} MSM cells of unknown signals skipped\n",
                               args.base_path, counts.skipped_bytes, counts.malformed_messages, counts.unknown_signal_cells);
    }
    Eigen::Vector3d position = Eigen::Vector3d::Zero();
    if (!args.base_position.empty()) {
      io::ObservationHeader none;
      auto given = base_position(args, none);
      if (!given) return given.error();
      position = *given;
    } else if (decoder.station()) {
      position = decoder.station()->arp_ecef_m;
    } else {
      return make_error(ErrorCode::kInvalidArgument,
                        args.base_path + ": the RTCM stream carries no station position (message 1005 or 1006): give "
                                         "the base position with --base-position X,Y,Z");
    }
    io::RtcmMeasurementConverter converter;
    for (const auto& epoch : decoder.take_epochs()) out.push_back(positioning::BaseEpoch{converter.convert(epoch), position});
    if (out.empty()) {
      return make_error(ErrorCode::kNotFound, args.base_path + ": no MSM observation message in the RTCM stream");
    }
    std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
      return a.measurements.receiver_time < b.measurements.receiver_time;
    });
    return out;
  }
  auto base = io::read_rinex_obs(args.base_path);
  if (!base) return base.error();
  for (const auto& warning : base->warnings) std::cerr << "skytrace position: warning: " << warning << "\n";
  auto position = base_position(args, base->header);
  if (!position) return position.error();
  const io::MeasurementExtractor extractor(base->header);
  for (const auto& b : base->epochs) {
    if (b.flag != io::EpochFlag::kOk && b.flag != io::EpochFlag::kPowerFailure) continue;
    out.push_back(positioning::BaseEpoch{extractor.measurements(b), *position});
  }
  return out;
}

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
  // CLI11's range check lets NaN through (no comparison with it fails).
  if (!(args.ratio_threshold >= 1.0 && args.ratio_threshold <= 100.0)) {
    return report_error(make_error(ErrorCode::kInvalidArgument,
                                   fmt::format("--ratio-threshold {}: expected 1 to 100", args.ratio_threshold)));
  }
  if (!(args.rtk_elevation_mask_deg >= -90.0 && args.rtk_elevation_mask_deg < 90.0)) {
    return report_error(make_error(ErrorCode::kInvalidArgument, "--rtk-elevation-mask-deg must be in [-90, 90)"));
  }
  if (!(args.min_cn0_dbhz >= 0.0 && args.min_cn0_dbhz <= 100.0)) {
    return report_error(make_error(ErrorCode::kInvalidArgument,
                                   fmt::format("--min-cn0-dbhz {}: expected 0 (no limit) to 100", args.min_cn0_dbhz)));
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

  // RTK with a base: its epochs (a RINEX observation file, or an RTCM 3 file as a reference
  // station streams it), its position and the engine.
  std::vector<positioning::BaseEpoch> base_epochs;
  std::optional<positioning::RtkEngine> rtk;
  if (!args.base_path.empty()) {
    auto base = read_base(args, observations->epochs.empty() ? GnssTime{} : observations->epochs.front().time);
    if (!base) return report_error(base.error());
    base_epochs = std::move(*base);
    positioning::RtkSettings rtk_settings;
    rtk_settings.single_point = settings;
    rtk_settings.systems = settings.systems;
    rtk_settings.elevation_mask_deg = args.rtk_elevation_mask_deg;
    rtk_settings.ratio_threshold = args.ratio_threshold;
    rtk_settings.ambiguity_mode = args.ambiguity_mode == "float"        ? positioning::AmbiguityMode::kFloat
                                  : args.ambiguity_mode == "continuous" ? positioning::AmbiguityMode::kContinuous
                                                                        : positioning::AmbiguityMode::kFixAndHold;
    rtk_settings.dynamics =
        args.dynamics == "static" ? positioning::RtkDynamics::kStatic : positioning::RtkDynamics::kKinematic;
    rtk.emplace(ephemerides, rtk_settings, klobuchar);
  } else if (!args.base_position.empty()) {
    return report_error(make_error(ErrorCode::kInvalidArgument, "--base-position needs --base"));
  }
  size_t base_next = 0;  // the first base epoch not yet passed
  const positioning::BaseEpoch* base_epoch = nullptr;

  std::string csv = io::fix_csv_header();
  size_t epochs = 0, fixes = 0;
  std::string first_failure;
  for (const io::ObservationEpoch& epoch : observations->epochs) {
    if (epoch.flag != io::EpochFlag::kOk && epoch.flag != io::EpochFlag::kPowerFailure) continue;
    ++epochs;
    if (rtk) {
      // The latest base epoch at or before the rover's (within a millisecond): the engine says
      // when it is too old.
      while (base_next < base_epochs.size() && base_epochs[base_next].measurements.receiver_time - epoch.time <= 1e-3) {
        base_epoch = &base_epochs[base_next++];
      }
    }
    auto fix = rtk ? rtk->solve(extractor.measurements(epoch), base_epoch)
                   : solver.solve(extractor.measurements(epoch));
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
    // Observations wholly outside what the records serve (their reference times and validity
    // windows, as `skytrace run` tells it) are another day's, which is what to say.
    const GnssTime& obs_first = observations->epochs.front().time;
    const GnssTime& obs_last = observations->epochs.back().time;
    if (const auto span = orbits::served_span(ephemerides.data());
        span && (span->last < obs_first || obs_last < span->first)) {
      const auto iso = [](const GnssTime& t) { return t.to_iso8601(TimeScale::kGpst, 1); };
      return report_error(make_error(
          ErrorCode::kOutOfRange,
          fmt::format("the navigation data does not cover {}: its records serve {} to {} GPST, the "
                      "observations run from {} to {} GPST (give the navigation file of the observations' day)",
                      args.obs_path, iso(span->first), iso(span->last), iso(obs_first), iso(obs_last))));
    }
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
  cmd->add_option("--base", args->base_path,
                  "RTK: base station observations, a RINEX file or an RTCM 3 file (MSM4-7, 1005/1006); the "
                  "rover's fixes become rtk_fixed / rtk_float / dgnss");
  cmd->add_option("--base-position", args->base_position,
                  "RTK: base antenna reference point X,Y,Z (m, ECEF); default: the base header's APPROX POSITION "
                  "XYZ plus its antenna delta");
  cmd->add_option("--ambiguity-mode", args->ambiguity_mode, "RTK: fix-and-hold, continuous or float")
      ->check(CLI::IsMember({"fix-and-hold", "continuous", "float"}))
      ->capture_default_str();
  cmd->add_option("--dynamics", args->dynamics, "RTK: kinematic or static rover")
      ->check(CLI::IsMember({"kinematic", "static"}))
      ->capture_default_str();
  cmd->add_option("--ratio-threshold", args->ratio_threshold, "RTK: ambiguity ratio test threshold")
      ->check(CLI::Range(1.0, 100.0))
      ->capture_default_str();
  cmd->add_option("--rtk-elevation-mask-deg", args->rtk_elevation_mask_deg, "RTK: elevation mask of the double differences")
      ->capture_default_str();
  cmd->footer(
      "One code per satellite (L1 C/A, E1, B1I, G1 first) with its broadcast group delay, one receiver "
      "clock per system, elevation-dependent weights; velocity and clock drift from Doppler. Rows of "
      "epochs without a fix give the reason in `message`.");
  cmd->callback([args, &exit_code]() { exit_code = run_position(*args); });
}

}  // namespace skytrace::cli

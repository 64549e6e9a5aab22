#include "skytrace/sim/setup.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <future>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <set>

#include "skytrace/atmosphere/ionex.hpp"
#include "skytrace/core/version.hpp"
#include "skytrace/orbits/nominal.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/receiver/antenna.hpp"
#include "skytrace/sim/trajectory.hpp"

namespace skytrace::sim {
namespace {

// "2021-04-28 19:30:00" (GPST, whole seconds).
std::string gpst_text(const GnssTime& t) {
  std::string text = t.to_iso8601(TimeScale::kGpst, 0);
  if (text.size() > 10 && text[10] == 'T') text[10] = ' ';
  return text;
}

// "2021-04-28 19:30:00 to 20:30:00": the second date only when it differs from the first, the first
// only when it differs from `reference` (when given).
std::string span_text(const GnssTime& a, const GnssTime& b, const std::optional<GnssTime>& reference = std::nullopt) {
  const std::string first = gpst_text(a), second = gpst_text(b);
  auto date = [](const std::string& text) { return text.substr(0, 10); };
  auto clock = [](const std::string& text) { return text.size() > 11 ? text.substr(11) : text; };
  const bool same_day_as_reference = reference && date(gpst_text(*reference)) == date(first);
  return (same_day_as_reference ? clock(first) : first) + " to " +
         (date(first) == date(second) ? clock(second) : second);
}

std::string file_names(const std::vector<std::filesystem::path>& files) {
  std::string names;
  for (const auto& f : files) names += (names.empty() ? "" : ", ") + f.filename().string();
  return names;
}

// "COD0MGX...CLK covers " / "A.SP3, B.SP3 cover ".
std::string files_cover(const std::vector<std::filesystem::path>& files) {
  return file_names(files) + (files.size() == 1 ? " covers " : " cover ");
}

std::string spans_text(const std::vector<orbits::PreciseEphemerides::Span>& spans) {
  std::string text;
  for (const auto& span : spans) text += (text.empty() ? "" : ", ") + span_text(span.first, span.last);
  return text;
}

}  // namespace

std::set<SatelliteId> PreciseTruthCoverage::broadcast_truth() const {
  std::set<SatelliteId> out;
  for (const auto& [sat, c] : lacking) out.insert(sat);
  for (const auto& [sat, c] : gaps) out.insert(sat);
  return out;
}

std::vector<std::string> PreciseTruthCoverage::warnings() const {
  std::vector<std::string> out;
  if (!lacking.empty()) {
    std::string list;
    for (const auto& [sat, c] : lacking) {
      list += (list.empty() ? "" : " ") + sat.to_string();
      if (c.in_orbits != c.in_clocks) list += c.in_orbits ? " (no clock)" : " (no orbit)";
    }
    out.push_back(fmt::format("the precise products lack {} satellite{} of the navigation data, which keep{} the "
                              "broadcast truth: {}",
                              lacking.size(), lacking.size() == 1 ? "" : "s", lacking.size() == 1 ? "s" : "", list));
  }
  if (!gaps.empty()) {
    std::string list;
    for (const auto& [sat, c] : gaps) {
      std::string what;
      if (!c.orbit_gaps.empty()) what += "orbit " + spans_text(c.orbit_gaps);
      if (!c.clock_gaps.empty()) what += (what.empty() ? "" : "; ") + std::string("clock ") + spans_text(c.clock_gaps);
      list += (list.empty() ? "" : ", ") + sat.to_string() + " (" + what + " GPST)";
    }
    out.push_back(fmt::format("the precise products cannot serve {} satellite{} over the whole run, which keep{} "
                              "the broadcast truth for all of it: {}",
                              gaps.size(), gaps.size() == 1 ? "" : "s", gaps.size() == 1 ? "s" : "", list));
  }
  return out;
}

std::string PreciseTruthCoverage::to_json() const {
  auto spans = [](const std::vector<orbits::PreciseEphemerides::Span>& list) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& span : list) out.push_back({gpst_text(span.first), gpst_text(span.last)});
    return out;
  };
  nlohmann::json j;
  j["checked_from"] = from.to_iso8601(TimeScale::kGpst, 1);
  j["checked_to"] = to.to_iso8601(TimeScale::kGpst, 1);
  nlohmann::json broadcast = nlohmann::json::array();
  for (const SatelliteId& sat : broadcast_truth()) broadcast.push_back(sat.to_string());
  j["broadcast_truth_satellites"] = broadcast;
  nlohmann::json lacking_json = nlohmann::json::object();
  for (const auto& [sat, c] : lacking) {
    lacking_json[sat.to_string()] = {{"in_orbits", c.in_orbits}, {"in_clocks", c.in_clocks}};
  }
  j["lacking"] = lacking_json;
  nlohmann::json gaps_json = nlohmann::json::object();
  for (const auto& [sat, c] : gaps) {
    gaps_json[sat.to_string()] = {{"orbit", spans(c.orbit_gaps)}, {"clock", spans(c.clock_gaps)}};
  }
  j["gaps"] = gaps_json;
  return j.dump();
}

Result<PreciseTruthCoverage> check_precise_coverage(const Scenario& s, const orbits::BroadcastEphemerides& eph,
                                                    const orbits::PreciseEphemerides& precise, const GnssTime& start,
                                                    const GnssTime& end) {
  constexpr double kTolerance_s = 1e-6;
  auto check_span = [&](const char* key, const std::vector<std::filesystem::path>& files,
                        const orbits::PreciseEphemerides::Span& span) -> Status {
    if (span.first - start <= kTolerance_s && end - span.last <= kTolerance_s) return Ok{};
    return make_error(ErrorCode::kOutOfRange,
                      fmt::format("ephemeris.{}: {}{} GPST; the run needs {} GPST (give the neighbouring days' "
                                  "files as well, or shorten the run)",
                                  key, files_cover(files), span_text(span.first, span.last),
                                  span_text(start, end, span.first)));
  };
  if (auto st = check_span("precise_orbits", s.ephemeris.precise_orbits, precise.orbit_span()); !st) return st.error();
  if (const auto clocks = precise.clock_file_span()) {
    if (auto st = check_span("precise_clocks", s.ephemeris.precise_clocks, *clocks); !st) return st.error();
  } else {
    const auto& data = precise.orbits();
    const bool any_clock = std::any_of(data.records.begin(), data.records.end(), [](const auto& series) {
      return std::any_of(series.begin(), series.end(), [](const orbits::Sp3Record& r) { return r.has_clock; });
    });
    if (!any_clock) {
      return make_error(ErrorCode::kNotFound,
                        fmt::format("ephemeris.precise_orbits: {} {} no satellite clock and no "
                                    "ephemeris.precise_clocks file is given",
                                    file_names(s.ephemeris.precise_orbits),
                                    s.ephemeris.precise_orbits.size() == 1 ? "holds" : "hold"));
    }
  }
  std::set<GnssSystem> systems;
  for (const auto& r : s.receivers) {
    for (const auto& signal : r.signals) systems.insert(signal.system);
  }
  PreciseTruthCoverage out;
  out.from = start - kTransmissionLead_s;
  out.to = end;
  for (const SatelliteId& sat : eph.satellites()) {
    if (systems.count(sat.system) == 0) continue;
    auto c = precise.coverage(sat, out.from, out.to);
    if (!c.in_orbits || !c.in_clocks) {
      out.lacking.emplace(sat, std::move(c));
    } else if (!c.complete()) {
      out.gaps.emplace(sat, std::move(c));
    }
  }
  return out;
}

Result<orbits::NavigationData> load_navigation(const Scenario& s) {
  if (s.ephemeris.nominal) return orbits::make_nominal_constellation(s.time.start, s.time.duration_s);
  orbits::NavigationData all;
  for (const auto& path : s.ephemeris.navigation) {
    auto data = orbits::read_rinex_nav(path);
    if (!data) return data.error();
    all.merge(std::move(*data));
  }
  return all;
}

Result<SystemCoverage> check_coverage(const Scenario& s, const orbits::BroadcastEphemerides& eph,
                                      const GnssTime& start, const GnssTime& end) {
  std::map<GnssSystem, std::vector<Signal>> wanted;  // the receivers' signals per system
  for (const auto& r : s.receivers) {
    for (const auto& signal : r.signals) wanted[signal.system].push_back(signal);
  }
  // Not a structured binding: clang 14 cannot capture those in the lambda below.
  const orbits::ServedSpan span = orbits::served_span(eph.data()).value_or(orbits::ServedSpan{});
  const GnssTime& first = span.first;
  const GnssTime& last = span.last;
  const auto why = [&](GnssSystem system, const char* which, const GnssTime& t) {
    return fmt::format("the navigation data has no valid {} ephemeris at the scenario's {} ({} GPST); the "
                       "navigation files cover {} to {} GPST",
                       system_name(system), which, t.to_iso8601(TimeScale::kGpst, 0),
                       first.to_iso8601(TimeScale::kGpst, 0), last.to_iso8601(TimeScale::kGpst, 0));
  };
  SystemCoverage out;
  std::vector<std::string> reasons;
  for (const auto& [system, signals] : wanted) {
    bool at_start = false, at_end = false;
    for (const SatelliteId& sat : eph.satellites()) {
      if (sat.system != system) continue;
      at_start = at_start || eph.has_usable_record(sat, start, signals);
      at_end = at_end || eph.has_usable_record(sat, end, signals);
      if (at_start && at_end) break;
    }
    if (!at_start) {
      // A receiver tracks what it holds ephemerides for: the system is left out, as it would be.
      reasons.push_back(why(system, "start", start));
      out.left_out.emplace(system, reasons.back() + "; its signals are left out");
    } else if (!at_end) {
      out.warnings.push_back(why(system, "end", end) + "; its satellites have no ephemeris from some time on");
    }
  }
  if (!wanted.empty() && out.left_out.size() == wanted.size()) {
    std::string message;
    for (const auto& reason : reasons) message += (message.empty() ? "" : "; ") + reason;
    return make_error(ErrorCode::kOutOfRange, message);
  }
  for (const auto& r : s.receivers) {
    const bool served = std::any_of(r.signals.begin(), r.signals.end(),
                                    [&](const Signal& signal) { return out.left_out.count(signal.system) == 0; });
    if (!served) {
      return make_error(ErrorCode::kOutOfRange,
                        fmt::format("receiver '{}': none of its systems can be served: {}", r.name,
                                    out.left_out.at(r.signals.front().system)));
    }
  }
  return out;
}

std::vector<Signal> served_signals(const ReceiverSettings& receiver, const std::map<GnssSystem, std::string>& left_out) {
  std::vector<Signal> out;
  for (const Signal& signal : receiver.signals) {
    if (left_out.count(signal.system) == 0) out.push_back(signal);
  }
  return out;
}

Result<ScenarioResources> prepare_resources(const Scenario& s) {
  ScenarioResources r;
  // The precise clock file, the largest input of most runs (a day at 30 s: 17 MB), is read on a
  // thread of its own while the world and the navigation files load; its error, if any, comes
  // where it would come reading in order.
  std::future<Result<orbits::RinexClockData>> clock_file;
  if (!s.ephemeris.precise_orbits.empty() && !s.ephemeris.precise_clocks.empty()) {
    clock_file = std::async(std::launch::async, [&s] { return orbits::read_rinex_clock(s.ephemeris.precise_clocks); });
  }
  auto world = load_world(s);
  if (!world) return world.error();
  r.world = std::move(*world);
  auto navigation = load_navigation(s);
  if (!navigation) return navigation.error();
  r.warnings = navigation->warnings;
  if (s.models.ionosphere == "ionex") {
    auto maps = atmosphere::read_ionex(*s.models.ionex_file);
    if (!maps) return maps.error();
    r.ionosphere = std::make_shared<atmosphere::IonexIonosphere>(std::move(*maps));
  } else if (s.models.ionosphere == "klobuchar") {
    if (!navigation->ionosphere.gps) {
      return make_error(ErrorCode::kNotFound,
                        "models.ionosphere is klobuchar but no navigation file has GPS Klobuchar coefficients "
                        "(IONOSPHERIC CORR GPSA/GPSB or ION ALPHA/BETA)");
    }
    r.ionosphere = std::make_shared<atmosphere::KlobucharIonosphere>(*navigation->ionosphere.gps);
  }
  // What the model leaves, one field for every receiver: correlated over about a few hundred km
  // and ten minutes (docs/models/atmosphere-residuals.md).
  constexpr double kIonosphereResidualTime_s = 600.0;
  constexpr double kTroposphereResidualTime_s = 1800.0;
  if (s.models.ionosphere_residual_ppm > 0.0) {
    const auto field = atmosphere::ResidualField::for_gradient_ppm(
        s.models.ionosphere_residual_ppm, s.models.ionosphere_residual_length_km * 1e3, kIonosphereResidualTime_s,
        s.seed * 0x9E3779B97F4A7C15ULL + 1);
    r.ionosphere = std::make_shared<atmosphere::IonosphereWithResidual>(r.ionosphere, atmosphere::ResidualField(field));
  }
  if (s.models.troposphere_residual_ppm > 0.0) {
    r.troposphere_residual = std::make_shared<atmosphere::ResidualField>(atmosphere::ResidualField::for_gradient_ppm(
        s.models.troposphere_residual_ppm, s.models.troposphere_residual_length_km * 1e3, kTroposphereResidualTime_s,
        s.seed * 0x9E3779B97F4A7C15ULL + 2));
  }
  r.ephemerides = std::make_unique<orbits::BroadcastEphemerides>(std::move(*navigation));
  if (!s.ephemeris.precise_orbits.empty()) {
    auto orbits_data = orbits::read_sp3(s.ephemeris.precise_orbits);
    if (!orbits_data) return orbits_data.error();
    std::optional<orbits::RinexClockData> clocks;
    if (!s.ephemeris.precise_clocks.empty()) {
      auto clock_data = clock_file.get();
      if (!clock_data) return clock_data.error();
      clocks = std::move(*clock_data);
    }
    auto created = orbits::PreciseEphemerides::create(std::move(*orbits_data), std::move(clocks));
    if (!created) return created.error();
    r.precise = std::make_unique<orbits::PreciseEphemerides>(std::move(*created));
  }
  const GnssTime end = s.time.start + s.time.duration_s;
  auto coverage = check_coverage(s, *r.ephemerides, s.time.start, end);
  if (!coverage) return coverage.error();
  for (const auto& [system, warning] : coverage->left_out) r.warnings.push_back(warning);
  for (auto& warning : coverage->warnings) r.warnings.push_back(std::move(warning));
  r.left_out_systems = std::move(coverage->left_out);
  if (r.precise) {
    auto precise_coverage = check_precise_coverage(s, *r.ephemerides, *r.precise, s.time.start, end);
    if (!precise_coverage) return precise_coverage.error();
    r.precise_coverage = std::move(*precise_coverage);
    // Satellites of left-out systems are not observed: nothing to say about their products.
    const auto left_out = [&](const auto& entry) { return r.left_out_systems.count(entry.first.system) != 0; };
    std::erase_if(r.precise_coverage->lacking, left_out);
    std::erase_if(r.precise_coverage->gaps, left_out);
    for (auto& warning : r.precise_coverage->warnings()) r.warnings.push_back(std::move(warning));
  }
  return r;
}

Eigen::Vector3d antenna_point(const Eigen::Vector3d& marker_m, const ReceiverSettings& r) {
  const Geodetic g = ecef_to_geodetic(marker_m);
  const Eigen::Matrix3d to_enu = ecef_to_enu_rotation(g);
  const Eigen::Vector3d offset_enu(r.antenna_offset_en_m.x(), r.antenna_offset_en_m.y(), r.antenna_height_m);
  return marker_m + to_enu.transpose() * offset_enu;
}

std::optional<LocalFrame> world_origin(const Scenario& s, const std::optional<LoadedWorld>& world) {
  if (world) return world->frame;
  if (s.world.latitude_deg && s.world.longitude_deg) {
    return LocalFrame{Geodetic{*s.world.latitude_deg, *s.world.longitude_deg, s.world.elevation_m.value_or(0.0)},
                      s.world.heading_deg.value_or(0.0)};
  }
  return std::nullopt;
}

Result<std::shared_ptr<const receiver::KinematicsSource>> make_kinematics(const Scenario& s, const ReceiverSettings& r,
                                                                          const std::optional<LocalFrame>& world,
                                                                          Eigen::Vector3d& marker_m) {
  if (r.position) {
    auto ecef = position_to_ecef(*r.position, world);
    if (!ecef) return ecef.error().with_context(s.source.string() + ": receiver '" + r.name + "'");
    marker_m = *ecef;
    return std::shared_ptr<const receiver::KinematicsSource>(std::make_shared<StaticPosition>(antenna_point(*ecef, r)));
  }
  auto samples = read_trajectory_csv(*r.trajectory, s.time.start, world);
  if (!samples) return samples.error();
  if (samples->empty()) return make_error(ErrorCode::kParse, r.trajectory->file.string() + ": no trajectory samples");
  marker_m = samples->front().position_m;
  for (auto& sample : *samples) sample.position_m = antenna_point(sample.position_m, r);
  auto trajectory = InterpolatedTrajectory::create(std::move(*samples), r.trajectory->file.string());
  if (!trajectory) return trajectory.error();
  return std::shared_ptr<const receiver::KinematicsSource>(*trajectory);
}

std::string antex_antenna_name(const ReceiverSettings& receiver, const std::string& antenna_rinex_type) {
  return receiver.antenna_type.empty() ? antenna_rinex_type : receiver.antenna_type;
}

Result<std::shared_ptr<const receiver::AntennaPhaseCentre>> load_antenna_phase_centre(const Scenario& s,
                                                                                     const ReceiverSettings& rx,
                                                                                     std::span<const Signal> signals,
                                                                                     const std::string& antenna_rinex_type) {
  if (!rx.antex) return std::shared_ptr<const receiver::AntennaPhaseCentre>{};
  const std::string name = antex_antenna_name(rx, antenna_rinex_type);
  const std::string where = s.source.string() + ": receiver '" + rx.name + "'";
  if (name.empty()) {
    return make_error(ErrorCode::kParse,  // a scenario mistake, exit 3 like the others
                      where + ": receiver.antex needs the antenna's IGS name to look up in " + rx.antex->string() +
                              ": give receiver.antenna_type (e.g. 'TRM59800.00     NONE') or an antenna profile that has one");
  }
  auto file = receiver::read_antex(*rx.antex);
  if (!file) return file.error();
  auto antenna = file->find(name, s.time.start);
  if (!antenna) return antenna.error().with_context(where);
  auto model = receiver::AntennaPhaseCentre::create(**antenna, signals, rx.antex->string());
  if (!model) return model.error().with_context(where);
  return std::make_shared<const receiver::AntennaPhaseCentre>(std::move(*model));
}

Result<std::unique_ptr<receiver::ObservationGenerator>> make_generator(
    const Scenario& s, const ScenarioResources& resources, size_t index,
    std::shared_ptr<const receiver::KinematicsSource> kinematics) {
  const ReceiverSettings& rx = s.receivers.at(index);
  if (resources.world) {
    if (auto start_position = kinematics->at(s.time.start)) {
      if (auto inside = check_outside_objects(*resources.world, start_position->position_m, rx.name); !inside) {
        return inside.error().with_context(s.source.string());
      }
    }
  }
  auto profile = receiver::load_profile(rx.profile, s.source.parent_path());
  if (!profile) return profile.error().with_context(s.source.string() + ": receiver.profile");
  // A signal the receiver cannot track is an error rather than a silently shorter file.
  for (const Signal& signal : rx.signals) {
    if (profile->tracked(signal) != nullptr) continue;
    std::string list;
    for (const auto& t : profile->signals) list += (list.empty() ? "" : ", ") + t.signal.to_string();
    return make_error(ErrorCode::kInvalidArgument, s.source.string() + ": receiver.signals: profile '" + profile->name +
                                                       "' cannot track " + signal.to_string() + " (it tracks " + list + ")");
  }
  if (auto st = receiver::attach_antenna(*profile, rx.antenna, rx.signals, s.source.parent_path()); !st) {
    return st.error().with_context(s.source.string());
  }
  if (auto preset = receiver::oscillator_preset(s.models.receiver_clock)) {
    profile->oscillator.h0 = preset->h0;
    profile->oscillator.h_minus1 = preset->h_minus1;
    profile->oscillator.h_minus2 = preset->h_minus2;
  }
  receiver::GeneratorSettings g;
  g.signals = served_signals(rx, resources.left_out_systems);
  g.elevation_mask_deg = rx.elevation_mask_deg;
  g.profile = *profile;
  g.ionosphere = resources.ionosphere;
  g.troposphere_residual = resources.troposphere_residual;
  g.troposphere = s.models.troposphere == "saastamoinen" ? atmosphere::TroposphereModel::kSaastamoinen
                 : s.models.troposphere == "unb3m"      ? atmosphere::TroposphereModel::kUnb3m
                                                        : atmosphere::TroposphereModel::kNone;
  g.noise = s.models.noise;
  g.ideal_clock = s.models.receiver_clock == "ideal";
  g.seed = s.seed;
  g.receiver_index = static_cast<int>(index);
  g.multipath = s.models.multipath;
  g.path_search.radius_m = s.models.multipath_radius_m;
  g.path_search.max_reflection_order = s.models.multipath_order;
  g.path_search.second_order_radius_m = s.models.multipath_order2_radius_m;
  g.path_search.diffraction = s.models.diffraction;
  g.path_search.scattering_coefficient = s.models.scattering_coefficient;
  g.path_search.scattering_lobe_exponent = s.models.scattering_lobe_exponent;
  g.path_search.scattering_radius_m = s.models.scattering_radius_m;
  // Only an antenna that cannot move has paths worth keeping per sky cell (a live pose may move it).
  if (kinematics->fixed()) {
    g.path_search.static_sky_cell_deg = s.models.static_sky_cell_deg;
  } else {
    g.path_search.moving_cell_m = s.models.moving_cell_m;
  }
  g.foliage.enabled = s.models.foliage_fading;
  g.foliage.diffuse_db = s.models.foliage_diffuse_db;
  g.foliage.wind_spread_hz = s.models.foliage_wind_spread_hz;
  g.incoming_signals = s.output.iq.has_value() && index == 0;  // the IQ samples are the first receiver's
  if (resources.precise_coverage) g.broadcast_truth = resources.precise_coverage->broadcast_truth();
  auto phase_centre = load_antenna_phase_centre(s, rx, g.signals, g.profile.antenna_rinex_type);
  if (!phase_centre) return phase_centre.error();
  g.antenna_phase_centre = std::move(*phase_centre);
  auto generator = std::make_unique<receiver::ObservationGenerator>(std::move(g), *resources.ephemerides,
                                                                    std::move(kinematics), resources.precise.get());
  if (resources.world) generator->set_world(resources.world->scene.get(), resources.world->frame);
  return generator;
}

io::ObservationHeader make_observation_header(const Scenario& s, const ReceiverSettings& rx,
                                              const Eigen::Vector3d& marker_m, const orbits::BroadcastEphemerides& eph,
                                              const std::map<GnssSystem, std::string>& left_out_systems,
                                              const std::string& antenna_in_use) {
  io::ObservationHeader h;
  h.version = s.output.rinex_version == "4.00" ? 4.00 : 3.04;
  h.program = std::string("skytrace ") + version();
  h.run_by = "skytrace";
  h.date = rinex_creation_date(s);
  h.comments.push_back("Simulated by skytrace from scenario " + s.name);
  h.comments.push_back("Profile " + rx.profile + ", seed " + std::to_string(s.seed));
  h.marker_name = rx.name;
  h.marker_type = rx.trajectory ? "NON_GEODETIC" : "GEODETIC";
  h.observer = "skytrace";
  h.agency = "skytrace";
  h.receiver_number = "1";
  h.receiver_type = rx.receiver_type;
  h.receiver_version = version();
  h.antenna_number = "1";
  // The scenario's antenna_type says what the header says; else the IGS name of the antenna in use.
  h.antenna_type = rx.antenna_type.empty() ? antenna_in_use : rx.antenna_type;
  h.approx_position_ecef_m = {marker_m.x(), marker_m.y(), marker_m.z()};
  h.antenna_delta_hen_m = {rx.antenna_height_m, rx.antenna_offset_en_m.x(), rx.antenna_offset_en_m.y()};
  for (const Signal& signal : served_signals(rx, left_out_systems)) {
    auto& types = h.observation_types[signal.system];
    for (char kind : {'C', 'L', 'D', 'S'}) types.push_back(io::ObservationType{std::string{kind} + signal.code(), ""});
  }
  h.signal_strength_unit = "DBHZ";
  h.interval_s = s.time.interval_s;
  h.time_system = TimeScale::kGpst;
  h.leap_seconds = gps_minus_utc_s(s.time.start);
  if (h.observation_types.count(GnssSystem::kGlonass) != 0) {
    for (const SatelliteId& sat : eph.satellites()) {
      if (sat.system != GnssSystem::kGlonass) continue;
      if (auto k = eph.glonass_channel(sat)) h.glonass_slots.push_back({sat.number, *k});
    }
    for (const char* code : {"C1C", "C1P", "C2C", "C2P"}) h.glonass_code_phase_biases.push_back({code, 0.0});
  }
  return h;
}

std::string rinex_creation_date(const Scenario& s) {
  if (const char* epoch = std::getenv("SOURCE_DATE_EPOCH"); epoch != nullptr && *epoch != '\0') {
    char* end = nullptr;
    const long long seconds = std::strtoll(epoch, &end, 10);
    if (*end == '\0' && seconds >= 0) {
      const std::time_t t = static_cast<std::time_t>(seconds);
      std::tm utc{};
      gmtime_r(&t, &utc);
      return fmt::format("{:04d}{:02d}{:02d} {:02d}{:02d}{:02d} UTC", utc.tm_year + 1900, utc.tm_mon + 1, utc.tm_mday,
                         utc.tm_hour, utc.tm_min, utc.tm_sec);
    }
  }
  // The second the start falls in (a date stamp: truncated, not rounded), split with integer
  // fields: a start a hair before midnight stays 235959, never 235960 (60 only in a leap second).
  const RoundedCalendarTime c =
      GnssTime::from_gpst_seconds(s.time.start.whole_seconds()).to_rounded_calendar(TimeScale::kUtc, 0);
  return fmt::format("{:04d}{:02d}{:02d} {:02d}{:02d}{:02d} UTC", c.year, c.month, c.day, c.hour, c.minute, c.second);
}

int signal_strength_indicator(double cn0_dbhz) {
  return std::clamp(static_cast<int>(std::floor(cn0_dbhz / 6.0)), 1, 9);
}

RinexRecordMaker::RinexRecordMaker(const io::ObservationHeader& header) : header_(header) {
  for (const auto& [system, types] : header.observation_types) {
    for (size_t i = 0; i < types.size(); ++i) {
      const std::string& code = types[i].code;
      if (code.size() == 3 && code[0] == 'C') code_column_[Signal{system, code[1], code[2]}] = i;
    }
  }
}

io::ObservationEpoch RinexRecordMaker::record(const receiver::EpochObservations& epoch) const {
  io::ObservationEpoch out;
  record_into(epoch, out);
  return out;
}

void RinexRecordMaker::record_into(const receiver::EpochObservations& epoch, io::ObservationEpoch& out) const {
  out.time = epoch.receiver_time;
  out.flag = io::EpochFlag::kOk;
  out.receiver_clock_offset_s.reset();
  out.event_records.clear();
  size_t records = 0;
  for (const auto& sat : epoch.satellites) {
    if (sat.status != receiver::SatelliteStatus::kTracked) continue;
    const auto types = header_.observation_types.find(sat.satellite.system);
    if (types == header_.observation_types.end()) continue;
    if (records == out.satellites.size()) out.satellites.emplace_back();
    io::SatelliteObservations& record = out.satellites[records++];
    record.satellite = sat.satellite;
    record.values.assign(types->second.size(), io::ObservationValue{});
    for (const auto& m : sat.signals) {
      const auto column = code_column_.find(m.signal);
      if (column == code_column_.end()) continue;
      const size_t index = column->second;
      const auto ssi = static_cast<std::uint8_t>(signal_strength_indicator(m.cn0_dbhz));
      record.values[index] = {m.pseudorange_m, 0, ssi};
      record.values[index + 1] = {m.carrier_phase_cycles, static_cast<std::uint8_t>((m.loss_of_lock ? 1 : 0) | (m.half_cycle_unresolved ? 2 : 0)), ssi};
      record.values[index + 2] = {m.doppler_hz, 0, 0};
      record.values[index + 3] = {m.cn0_dbhz, 0, 0};
    }
  }
  out.satellites.resize(records);
}

positioning::EpochMeasurements to_measurements(const receiver::EpochObservations& epoch) {
  positioning::EpochMeasurements out;
  to_measurements(epoch, out);
  return out;
}

void to_measurements(const receiver::EpochObservations& epoch, positioning::EpochMeasurements& out) {
  out.receiver_time = epoch.receiver_time;
  out.signals.clear();
  size_t signals = 0;
  for (const auto& sat : epoch.satellites) {
    if (sat.status == receiver::SatelliteStatus::kTracked) signals += sat.signals.size();
  }
  out.signals.reserve(signals);
  for (const auto& sat : epoch.satellites) {
    if (sat.status != receiver::SatelliteStatus::kTracked) continue;
    for (const auto& m : sat.signals) {
      positioning::SignalMeasurement pm;
      pm.satellite = sat.satellite;
      pm.signal = m.signal;
      pm.pseudorange_m = m.pseudorange_m;
      pm.doppler_hz = m.doppler_hz;
      pm.carrier_hz = m.carrier_hz;
      pm.cn0_dbhz = m.cn0_dbhz;
      if (m.carrier_phase_cycles != 0.0) pm.carrier_phase_cycles = m.carrier_phase_cycles;
      pm.loss_of_lock = m.loss_of_lock;
      pm.half_cycle_unresolved = m.half_cycle_unresolved;
      out.signals.push_back(pm);
    }
  }
}

}  // namespace skytrace::sim

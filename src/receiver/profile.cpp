#include "skytrace/receiver/profile.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>

#include "skytrace/core/constants.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/core/yaml_field.hpp"
#include "pattern_table.hpp"

#ifndef SKYTRACE_PROFILE_DIR
#define SKYTRACE_PROFILE_DIR "profiles"
#endif

namespace skytrace::receiver {

using detail::check_increasing;
using detail::looks_like_path;
using detail::parse_gain_rows;

namespace {

// Profile keys with their path and line in every message (core/yaml_field.hpp).
using Field = YamlField;

AntennaPattern parse_antenna(const Field& node) {
  node.expect_keys({"model", "elevation_deg", "azimuth_deg", "rhcp_gain_dbic", "lhcp_gain_dbic"});
  AntennaPattern a;
  const Field elevation = node.required("elevation_deg");
  a.elevation_deg = elevation.as_doubles_in(-90.0, 90.0);
  check_increasing(elevation, a.elevation_deg);
  if (auto c = node.child("azimuth_deg")) {
    a.azimuth_deg = c->as_doubles_in(0.0, 359.999999);
    check_increasing(*c, a.azimuth_deg);
  }
  a.rhcp_gain_dbic = parse_gain_rows(node.required("rhcp_gain_dbic"), a.elevation_deg.size(), a.azimuth_deg.size(),
                                     -60.0, 25.0);
  a.lhcp_gain_dbic = parse_gain_rows(node.required("lhcp_gain_dbic"), a.elevation_deg.size(), a.azimuth_deg.size(),
                                     -60.0, 25.0);
  return a;
}

OscillatorSettings parse_oscillator(const Field& node) {
  node.expect_keys({"preset", "h0", "h_minus1", "h_minus2", "initial_bias_s", "initial_drift_s_per_s", "steering"});
  OscillatorSettings o;
  bool preset = false;
  if (auto c = node.child("preset")) {
    o = *oscillator_preset(c->as_choice({"tcxo", "ocxo"}));
    preset = true;
  }
  // Without a preset the three coefficients are required.
  auto coefficient = [&](const char* key, double& value) {
    if (auto c = preset ? node.child(key) : std::optional<Field>(node.required(key))) value = c->as_double_in(0.0, 1e-15);
  };
  coefficient("h0", o.h0);
  coefficient("h_minus1", o.h_minus1);
  coefficient("h_minus2", o.h_minus2);
  o.initial_bias_s = node.required("initial_bias_s").as_double_in(0.0, 1e-3);
  o.initial_drift_s_per_s = node.required("initial_drift_s_per_s").as_double_in(0.0, 1e-5);
  o.steered = node.required("steering").as_choice({"steered", "free-running"}) == "steered";
  return o;
}

ReceiverProfile parse_root(const Field& root, const std::string& source) {
  root.expect_keys({"name", "description", "signals", "signal_extra_loss_db", "channels", "elevation_mask_deg",
                    "default_antenna", "antenna", "front_end", "tracking", "oscillator", "rtk"});
  ReceiverProfile p;
  p.source = source;
  p.name = root.required("name").as_string();
  const Field signals = root.required("signals");
  if (!signals.is_sequence()) {
    if (signals.as_string() != "all") signals.fail("expected a list of signals (e.g. [G1C, E1C]) or 'all'");
    p.all_signals = true;
  } else {
    for (const Field& item : signals.elements()) {
      auto signal = Signal::parse(item.as_string());
      if (!signal) item.fail(signal.error().message);
      if (find_signal_info(*signal) == nullptr) item.fail("signal " + signal->to_string() + " is not in the catalogue");
      if (p.tracked(*signal) != nullptr) item.fail("signal " + signal->to_string() + " listed twice");
      p.signals.push_back({*signal, 0.0});
    }
    if (p.signals.empty()) signals.fail("list at least one signal");
  }
  if (auto losses = root.child("signal_extra_loss_db")) {
    for (const auto& [key, value] : losses->entries()) {
      auto signal = Signal::parse(key);
      if (!signal) value.fail(signal.error().message);
      const auto tracked = std::find_if(p.signals.begin(), p.signals.end(),
                                        [&](const TrackedSignal& t) { return t.signal == *signal; });
      if (tracked == p.signals.end()) value.fail("signal " + key + " is not among the profile's signals");
      tracked->extra_loss_db = value.as_double_in(-10.0, 40.0);
    }
  }
  p.channel_count = root.required("channels").as_int_in(0, 100000);
  p.elevation_mask_deg = root.required("elevation_mask_deg").as_double_in(-10.0, 90.0);
  if (auto c = root.child("default_antenna")) {
    p.default_antenna = c->as_string();
    if (p.default_antenna.empty()) c->fail("expected the name of an antenna profile (profiles/antennas)");
  }
  if (auto c = root.child("antenna")) {
    if (!p.default_antenna.empty()) c->fail("give default_antenna or an inline antenna table, not both");
    p.antenna = parse_antenna(*c);
    p.inline_antenna = true;
  }

  const Field front_end = root.required("front_end");
  front_end.expect_keys({"system_noise_temperature_k", "implementation_loss_db"});
  p.system_noise_temperature_k = front_end.required("system_noise_temperature_k").as_double_in(10.0, 10000.0);
  p.implementation_loss_db = front_end.required("implementation_loss_db").as_double_in(0.0, 20.0);

  const Field tracking = root.required("tracking");
  tracking.expect_keys({"dll_bandwidth_hz", "pll_bandwidth_hz", "fll_bandwidth_hz", "correlator_spacing_chips",
                        "integration_time_s", "acquisition_threshold_dbhz", "tracking_threshold_dbhz",
                        "acquisition_time_s", "half_cycle_resolution_s", "cn0_resolution_dbhz",
                        "output_requires_ephemeris", "semicodeless_aiding_bandwidth_hz",
                        "semicodeless_threshold_dbhz", "reacquisition_threshold_dbhz"});
  p.dll_bandwidth_hz = tracking.required("dll_bandwidth_hz").as_double_in(0.0, 50.0);
  p.pll_bandwidth_hz = tracking.required("pll_bandwidth_hz").as_double_in(0.0, 100.0);
  p.fll_bandwidth_hz = tracking.required("fll_bandwidth_hz").as_double_in(0.0, 50.0);
  p.correlator_spacing_chips = tracking.required("correlator_spacing_chips").as_double_in(0.01, 1.5);
  p.integration_time_s = tracking.required("integration_time_s").as_double_in(0.001, 0.2);
  p.acquisition_threshold_dbhz = tracking.required("acquisition_threshold_dbhz").as_double_in(0.0, 60.0);
  const Field tracking_threshold = tracking.required("tracking_threshold_dbhz");
  p.tracking_threshold_dbhz = tracking_threshold.as_double_in(0.0, 60.0);
  if (p.tracking_threshold_dbhz > p.acquisition_threshold_dbhz) {
    tracking_threshold.fail("must not exceed tracking.acquisition_threshold_dbhz (a receiver keeps tracking weaker "
                            "signals than it can acquire)");
  }
  p.acquisition_time_s = tracking.required("acquisition_time_s").as_double_in(0.0, 600.0);
  if (auto c = tracking.child("reacquisition_threshold_dbhz")) {
    p.reacquisition_threshold_dbhz = c->as_double_in(0.0, 60.0);
    if (*p.reacquisition_threshold_dbhz < p.tracking_threshold_dbhz ||
        *p.reacquisition_threshold_dbhz > p.acquisition_threshold_dbhz) {
      c->fail("must lie between tracking.tracking_threshold_dbhz and tracking.acquisition_threshold_dbhz (an aided "
              "search finds weaker signals than a cold one, and a signal below the tracking threshold is not kept)");
    }
  }
  p.half_cycle_resolution_s = tracking.required("half_cycle_resolution_s").as_double_in(0.0, 600.0);
  p.cn0_resolution_dbhz = tracking.required("cn0_resolution_dbhz").as_double_in(0.0, 10.0);
  if (auto c = tracking.child("output_requires_ephemeris")) p.output_requires_ephemeris = c->as_bool();
  if (auto c = tracking.child("semicodeless_aiding_bandwidth_hz")) {
    p.semicodeless_aiding_bandwidth_hz = c->as_double_in(0.0, 100.0);
  }
  if (auto c = tracking.child("semicodeless_threshold_dbhz")) {
    p.semicodeless_threshold_dbhz = c->as_double_in(0.0, 60.0);
    if (*p.semicodeless_threshold_dbhz > p.tracking_threshold_dbhz) {
      c->fail("must not exceed tracking.tracking_threshold_dbhz (aided semi-codeless channels hold weaker signals "
              "than unaided ones)");
    }
  }

  p.oscillator = parse_oscillator(root.required("oscillator"));
  if (auto rtk = root.child("rtk")) {
    rtk->expect_keys({"elevation_mask_deg", "min_cn0_dbhz", "ratio_threshold", "ambiguity_mode", "dynamics",
                      "estimate_velocity", "sigma_phase_m", "code_phase_ratio", "acceleration_noise_mps2",
                      "ambiguity_noise_cycles", "cn0_weighting_dbhz"});
    RtkProfile& r = p.rtk;
    if (auto c = rtk->child("elevation_mask_deg")) r.elevation_mask_deg = c->as_double_in(0.0, 60.0);
    if (auto c = rtk->child("min_cn0_dbhz")) r.min_cn0_dbhz = c->as_double_in(0.0, 60.0);
    if (auto c = rtk->child("ratio_threshold")) r.ratio_threshold = c->as_double_in(1.0, 100.0);
    if (auto c = rtk->child("ambiguity_mode")) r.ambiguity_mode = c->as_choice({"fix-and-hold", "continuous", "float"});
    if (auto c = rtk->child("dynamics")) r.dynamics = c->as_choice({"kinematic", "static"});
    if (auto c = rtk->child("estimate_velocity")) r.estimate_velocity = c->as_bool();
    if (auto c = rtk->child("sigma_phase_m")) r.sigma_phase_m = c->as_double_in(0.0001, 0.1);
    if (auto c = rtk->child("code_phase_ratio")) r.code_phase_ratio = c->as_double_in(1.0, 10000.0);
    if (auto c = rtk->child("acceleration_noise_mps2")) r.acceleration_noise_mps2 = c->as_double_in(0.0, 100.0);
    if (auto c = rtk->child("ambiguity_noise_cycles")) r.ambiguity_noise_cycles = c->as_double_in(0.0, 10.0);
    if (auto c = rtk->child("cn0_weighting_dbhz")) r.cn0_weighting_dbhz = c->as_double_in(0.0, 60.0);
  }
  return p;
}

double interpolate_row(const std::vector<double>& x, const std::vector<double>& y, double at) {
  if (at <= x.front()) return y.front();
  if (at >= x.back()) return y.back();
  const auto upper = std::upper_bound(x.begin(), x.end(), at);
  const size_t i = static_cast<size_t>(upper - x.begin());
  const double w = (at - x[i - 1]) / (x[i] - x[i - 1]);
  return y[i - 1] + w * (y[i] - y[i - 1]);
}

double interpolate_pattern(const AntennaPattern& a, const std::vector<std::vector<double>>& rows, double elevation_deg,
                           double azimuth_deg) {
  if (rows.empty()) return 0.0;
  if (a.azimuth_deg.empty() || rows.size() == 1) return interpolate_row(a.elevation_deg, rows.front(), elevation_deg);
  // Azimuth wraps: between the last azimuth and the first plus 360.
  double az = std::fmod(azimuth_deg, 360.0);
  if (az < 0.0) az += 360.0;
  const auto& azimuths = a.azimuth_deg;
  size_t upper = static_cast<size_t>(std::upper_bound(azimuths.begin(), azimuths.end(), az) - azimuths.begin());
  const size_t lower = upper == 0 ? azimuths.size() - 1 : upper - 1;
  if (upper == azimuths.size()) upper = 0;
  double span = azimuths[upper] - azimuths[lower];
  double offset = az - azimuths[lower];
  if (span <= 0.0) span += 360.0;
  if (offset < 0.0) offset += 360.0;
  const double w = offset / span;
  return (1.0 - w) * interpolate_row(a.elevation_deg, rows[lower], elevation_deg) +
         w * interpolate_row(a.elevation_deg, rows[upper], elevation_deg);
}

}  // namespace

std::optional<OscillatorSettings> oscillator_preset(const std::string& name) {
  // Typical crystal oscillators (Brown & Hwang, Introduction to Random Signals and Applied Kalman
  // Filtering, 3rd ed., table 9.2; also Van Dierendonck, GPS: Theory and Applications I, ch. 8).
  OscillatorSettings o;
  if (name == "tcxo") {
    o.h0 = 2e-19;
    o.h_minus1 = 7e-21;
    o.h_minus2 = 2e-20;
    return o;
  }
  if (name == "ocxo") {
    o.h0 = 2e-25;
    o.h_minus1 = 7e-25;
    o.h_minus2 = 6e-25;
    return o;
  }
  return std::nullopt;
}

double AntennaPattern::rhcp_dbic(double elevation_deg_, double azimuth_deg_) const {
  return interpolate_pattern(*this, rhcp_gain_dbic, elevation_deg_, azimuth_deg_);
}
double AntennaPattern::lhcp_dbic(double elevation_deg_, double azimuth_deg_) const {
  return interpolate_pattern(*this, lhcp_gain_dbic, elevation_deg_, azimuth_deg_);
}

const TrackedSignal* ReceiverProfile::tracked(const Signal& signal) const {
  for (const TrackedSignal& s : signals) {
    if (s.signal == signal) return &s;
  }
  if (all_signals) {
    static thread_local TrackedSignal any;
    any = TrackedSignal{signal, 0.0};
    return &any;
  }
  return nullptr;
}

Result<ReceiverProfile> parse_profile(const std::string& yaml_text, const std::string& source) {
  try {
    const YAML::Node root = YAML::Load(yaml_text);
    if (!root || root.IsNull()) return make_error(ErrorCode::kParse, source + ": empty profile");
    if (auto duplicate = find_duplicate_key(root, source)) return make_error(ErrorCode::kParse, *duplicate);
    return parse_root(Field(root, "", &source, "profile"), source);
  } catch (const YamlFieldError& e) {
    return make_error(ErrorCode::kParse, e.message);
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kParse, source + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

std::vector<std::filesystem::path> profile_search_path(const std::filesystem::path& scenario_dir) {
  std::vector<std::filesystem::path> dirs;
  if (!scenario_dir.empty()) dirs.push_back(scenario_dir / "profiles");
  if (const char* env = std::getenv("SKYTRACE_PROFILE_PATH")) {
    std::string text(env);
    size_t start = 0;
    while (start <= text.size()) {
      const size_t end = std::min(text.find(':', start), text.size());
      if (end > start) dirs.emplace_back(text.substr(start, end - start));
      start = end + 1;
    }
  }
  dirs.emplace_back(SKYTRACE_PROFILE_DIR);
  return dirs;
}

Result<ReceiverProfile> load_profile(const std::string& name_or_path, const std::filesystem::path& scenario_dir) {
  std::filesystem::path file;
  std::error_code ec;
  if (looks_like_path(name_or_path)) {
    file = name_or_path;
    if (file.is_relative() && !scenario_dir.empty()) file = scenario_dir / file;
    if (!std::filesystem::is_regular_file(file, ec)) {
      return make_error(ErrorCode::kNotFound, "receiver profile file not found: " + file.string());
    }
  } else {
    std::string searched;
    for (const auto& dir : profile_search_path(scenario_dir)) {
      const auto candidate = dir / (name_or_path + ".yaml");
      if (std::filesystem::is_regular_file(candidate, ec)) {
        file = candidate;
        break;
      }
      searched += (searched.empty() ? "" : ", ") + dir.string();
    }
    if (file.empty()) {
      std::string names;
      for (const auto& n : available_profile_names(scenario_dir)) names += (names.empty() ? "" : ", ") + n;
      return make_error(ErrorCode::kNotFound, "unknown receiver profile '" + name_or_path + "' (known: " + names +
                                                  "; searched " + searched + ")");
    }
  }
  auto text = read_text_file(file);
  if (!text) return text.error();
  auto profile = parse_profile(*text, file.string());
  if (!profile) return profile.error();
  return profile;
}

std::vector<std::string> available_profile_names(const std::filesystem::path& scenario_dir) {
  std::set<std::string> names;
  std::error_code ec;
  for (const auto& dir : profile_search_path(scenario_dir)) {
    if (!std::filesystem::is_directory(dir, ec)) continue;
    for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
      if (entry.path().extension() == ".yaml") names.insert(entry.path().stem().string());
    }
  }
  return {names.begin(), names.end()};
}


namespace {
// PLL thermal jitter (rad) from C/N0 as a ratio (Hz).
double pll_jitter_from_ratio_rad(const ReceiverProfile& profile, double cn0_hz, double bandwidth_hz) {
  if (bandwidth_hz <= 0.0) return 0.0;
  const double var_rad2 = bandwidth_hz / cn0_hz * (1.0 + 1.0 / (2.0 * profile.integration_time_s * cn0_hz));
  return std::sqrt(var_rad2);
}
}  // namespace

TrackingNoise tracking_noise(const ReceiverProfile& profile, const SignalInfo& signal, double carrier_hz,
                             double cn0_dbhz) {
  TrackingNoise noise;
  const double cn0_hz = std::pow(10.0, cn0_dbhz / 10.0);
  const double t_s = profile.integration_time_s;
  if (profile.dll_bandwidth_hz > 0.0) {
    // Coherent early-minus-late DLL with BPSK-like correlation peak of chip width 1/chip_rate.
    const double d = profile.correlator_spacing_chips;
    const double var_chips2 = profile.dll_bandwidth_hz * d / (2.0 * cn0_hz) * (1.0 + 2.0 / (t_s * cn0_hz * (2.0 - d)));
    const double chip_m = constants::kSpeedOfLight_mps / signal.chip_rate_hz;
    // A BOC signal's sharper peak divides the error by about sqrt(subcarrier factor) relative to BPSK.
    double shape = 1.0;
    if (signal.modulation.subcarrier_factor > 0.0) shape = 1.0 / std::sqrt(2.0 * signal.modulation.subcarrier_factor / signal.modulation.chip_factor);
    noise.code_m = std::sqrt(var_chips2) * chip_m * shape;
  }
  const double wavelength_m = constants::kSpeedOfLight_mps / carrier_hz;
  if (profile.pll_bandwidth_hz > 0.0) {
    noise.phase_m = pll_jitter_from_ratio_rad(profile, cn0_hz, profile.pll_bandwidth_hz) * wavelength_m /
                    (2.0 * std::numbers::pi);
  }
  if (profile.fll_bandwidth_hz > 0.0) {
    // FLL thermal noise (Hz) scaled to range rate.
    const double var_hz2 = 4.0 * profile.fll_bandwidth_hz / (std::pow(2.0 * std::numbers::pi * t_s, 2) * cn0_hz) *
                           (1.0 + 1.0 / (t_s * cn0_hz));
    noise.doppler_mps = std::sqrt(var_hz2) * wavelength_m;
  }
  return noise;
}

double loop_time_constant_s(double bandwidth_hz) {
  return bandwidth_hz > 0.0 ? 1.0 / (4.0 * bandwidth_hz) : std::numeric_limits<double>::infinity();
}

double gauss_markov_step(double previous, double dt_s, double tau_s, double white) {
  if (!std::isfinite(dt_s) || dt_s <= 0.0 || !(tau_s > 0.0) || !std::isfinite(tau_s)) return white;
  // A receiver's loops keep their time constants and step by its interval: the coefficients of the
  // last few (step, time constant) pairs are kept instead of taking the exponential every time.
  struct Coefficients {
    double dt_s = std::numeric_limits<double>::quiet_NaN();
    double tau_s = 0.0;
    double kept = 0.0;  // exp(-dt / tau)
    double fresh = 0.0; // sqrt(1 - kept^2)
  };
  thread_local std::array<Coefficients, 4> recent;
  thread_local size_t next = 0;
  for (const Coefficients& c : recent) {
    if (c.dt_s == dt_s && c.tau_s == tau_s) return c.kept * previous + c.fresh * white;
  }
  const double a = std::exp(-dt_s / tau_s);
  const double b = std::sqrt(1.0 - a * a);
  recent[next] = Coefficients{dt_s, tau_s, a, b};
  next = (next + 1) % recent.size();
  return a * previous + b * white;
}

double pll_jitter_rad(const ReceiverProfile& profile, double cn0_dbhz) {
  return pll_jitter_rad(profile, cn0_dbhz, profile.pll_bandwidth_hz);
}

double pll_jitter_rad(const ReceiverProfile& profile, double cn0_dbhz, double bandwidth_hz) {
  if (bandwidth_hz <= 0.0) return 0.0;
  return pll_jitter_from_ratio_rad(profile, std::pow(10.0, cn0_dbhz / 10.0), bandwidth_hz);
}

double mean_time_to_slip_s(double jitter_rad, double bandwidth_hz, bool costas) {
  if (jitter_rad <= 0.0 || bandwidth_hz <= 0.0) return std::numeric_limits<double>::infinity();
  const double rho = costas ? 1.0 / (4.0 * jitter_rad * jitter_rad) : 1.0 / (jitter_rad * jitter_rad);
  // I0(rho)^2 overflows beyond rho ~ 350: by then the time is astronomically long anyway.
  if (rho > 300.0) return std::numeric_limits<double>::infinity();
  const double i0 = std::cyl_bessel_i(0.0, rho);
  return std::numbers::pi * std::numbers::pi * rho * i0 * i0 / (2.0 * bandwidth_hz);
}

double slip_probability(double jitter_rad, double bandwidth_hz, bool costas, double interval_s) {
  if (jitter_rad > 0.0 && bandwidth_hz > 0.0) {
    const double rho = costas ? 1.0 / (4.0 * jitter_rad * jitter_rad) : 1.0 / (jitter_rad * jitter_rad);
    // Beyond rho 300, T is infinite (mean_time_to_slip_s) and the probability zero.
    if (rho >= 1.0 && rho <= 300.0) {
      // I0(x) > e^x / sqrt(2 pi x) for x >= 1 (sqrt(2 pi x) e^-x I0(x) falls from 1.17 at x = 1
      // towards its limit 1; test), so T > pi^2 rho e^(2 rho) / (2 pi rho 2 B) = pi e^(2 rho) / (4 B).
      const double lower_bound_s = std::numbers::pi * std::exp(2.0 * rho) / (4.0 * bandwidth_hz);
      const double upper_bound = -std::expm1(-interval_s / lower_bound_s);
      if (upper_bound > 0.0 && upper_bound < 0x1p-60) return upper_bound;
    }
  }
  return -std::expm1(-interval_s / mean_time_to_slip_s(jitter_rad, bandwidth_hz, costas));
}

bool has_data_modulation(const SignalInfo& signal) {
  // Pilot components, and data+pilot tracking (which follows the pilot), carry no navigation data
  // bits, hence no half-cycle ambiguity. RINEX 3 attributes of the pilot-tracked signals:
  const char band = signal.signal.band;
  const char a = signal.signal.attribute;
  const auto in = [](char c, std::string_view set) { return set.find(c) != std::string_view::npos; };
  switch (signal.signal.system) {
    case GnssSystem::kGps: return !(in(a, "LX") && in(band, "12")) && !(in(a, "QX") && band == '5');
    case GnssSystem::kGlonass: return !(in(a, "BX") && in(band, "46")) && !(in(a, "QX") && band == '3');
    case GnssSystem::kGalileo: return !in(a, "CQXZ");
    case GnssSystem::kBeiDou:
      return !(a == 'P' || (a == 'X' && in(band, "158")) || (a == 'Z' && band == '7'));
    case GnssSystem::kQzss: return !(in(a, "LX") && in(band, "126")) && !(in(a, "QXPZ") && band == '5');
    case GnssSystem::kNavic: return !in(a, "CXP");
    case GnssSystem::kSbas: return !(in(a, "QX") && band == '5');
  }
  return true;
}

namespace detail {

std::vector<std::vector<double>> parse_gain_rows(const YamlField& node, size_t elevations, size_t azimuths,
                                                 double low_db, double high_db) {
  // One list (no azimuth) or one list per azimuth, each as long as the elevations.
  std::vector<std::vector<double>> rows;
  if (azimuths == 0) {
    rows.push_back(node.as_doubles_in(low_db, high_db));
  } else {
    const auto items = node.elements();
    if (items.size() != azimuths) {
      node.fail("expected one row per azimuth (" + std::to_string(azimuths) + "), got " + std::to_string(items.size()));
    }
    for (const YamlField& row : items) rows.push_back(row.as_doubles_in(low_db, high_db));
  }
  for (size_t i = 0; i < rows.size(); ++i) {
    if (rows[i].size() != elevations) {
      node.fail("expected " + std::to_string(elevations) + " gains (one per elevation), got " +
                std::to_string(rows[i].size()));
    }
  }
  return rows;
}

void check_increasing(const YamlField& node, const std::vector<double>& values) {
  if (values.size() < 2) node.fail("expected at least 2 values");
  for (size_t i = 1; i < values.size(); ++i) {
    if (values[i] <= values[i - 1]) node.fail("values must increase");
  }
}

bool looks_like_path(const std::string& text) {
  return text.find('/') != std::string::npos || (text.size() > 5 && text.ends_with(".yaml"));
}

}  // namespace detail

}  // namespace skytrace::receiver

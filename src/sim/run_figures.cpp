#include "skytrace/sim/run_figures.hpp"

#include <cmath>

#include "skytrace/core/frames.hpp"

namespace skytrace::sim {

RunFigures::RunFigures(const std::vector<SinkReceiver>& receivers) {
  for (const SinkReceiver& rx : receivers) receivers_.emplace_back().name = rx.settings->name;
}

Status RunFigures::add(const SinkEpoch& e) {
  Receiver& r = receivers_.at(e.receiver_index);
  const receiver::EpochObservations& epoch = *e.observations;
  if (r.epochs++ == 0) r.first_epoch = epoch.receiver_time;
  const double t_s = epoch.receiver_time - *r.first_epoch;  // since the first epoch
  for (const auto& sat : epoch.satellites) {
    switch (sat.status) {
      case receiver::SatelliteStatus::kTracked:
        ++r.tracked;
        r.signals += static_cast<std::int64_t>(sat.signals.size());
        if (sat.path_kind == receiver::PathKind::kNlos) {
          ++r.nlos;
        } else if (sat.path_kind == receiver::PathKind::kMultipath) {
          ++r.multipath;
        } else {
          ++r.line_of_sight;
        }
        break;
      case receiver::SatelliteStatus::kBlocked: ++r.blocked; break;
      case receiver::SatelliteStatus::kAttenuated: ++r.attenuated; break;
      default: break;
    }
  }
  if (e.fix == nullptr) return Ok{};
  const auto type = e.fix->type;
  ++r.epochs_per_fix_type.at(static_cast<size_t>(type));
  if (type == positioning::FixType::kNone || !e.fix->position_ecef_m.allFinite()) return Ok{};
  if (std::isnan(r.first_fix_s)) r.first_fix_s = t_s;
  if (type == positioning::FixType::kRtkFixed && std::isnan(r.first_rtk_fixed_s)) r.first_rtk_fixed_s = t_s;
  const Eigen::Vector3d& truth_m = epoch.receiver.position_m;
  const Eigen::Vector3d enu_m = ecef_to_enu_rotation(ecef_to_geodetic(truth_m)) * (e.fix->position_ecef_m - truth_m);
  r.horizontal_error.add(std::hypot(enu_m.x(), enu_m.y()));
  r.vertical_error.add(enu_m.z());
  ++r.fixes_with_error;
  r.satellites_used_sum += e.fix->satellites_used;
  return Ok{};
}

namespace {

// NaN and inf are not JSON: null.
nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

// Share with 6 decimals, null without a denominator.
nlohmann::json share(std::int64_t part, std::int64_t whole) {
  if (whole <= 0) return nullptr;
  return std::round(1e6 * static_cast<double>(part) / static_cast<double>(whole)) / 1e6;
}

// Percentiles to 3 significant digits, as precise as the histogram's 2.3 % bins; the maximum to 0.1 mm.
nlohmann::json error_figures(const ErrorHistogram& histogram) {
  const auto significant3 = [](double value) {
    if (!std::isfinite(value) || value <= 0.0) return number_or_null(value);
    const double scale = std::pow(10.0, 2.0 - std::floor(std::log10(value)));
    return nlohmann::json(std::round(value * scale) / scale);
  };
  return {{"p50", significant3(histogram.quantile_m(0.5))},
          {"p95", significant3(histogram.quantile_m(0.95))},
          {"max", histogram.count() > 0 ? nlohmann::json(std::round(histogram.max_m() * 1e4) / 1e4) : nlohmann::json(nullptr)}};
}

}  // namespace

nlohmann::json RunFigures::to_json() const {
  using nlohmann::json;
  json out = json::array();
  for (const Receiver& r : receivers_) {
    json rx;
    rx["name"] = r.name;
    rx["epochs"] = r.epochs;
    json types = json::object();
    std::int64_t fixed_epochs = 0, solved = 0;
    for (size_t i = 0; i < r.epochs_per_fix_type.size(); ++i) {
      const auto type = static_cast<positioning::FixType>(i);
      types[std::string(positioning::to_string(type))] = r.epochs_per_fix_type[i];
      solved += r.epochs_per_fix_type[i];
      if (type != positioning::FixType::kNone) fixed_epochs += r.epochs_per_fix_type[i];
    }
    if (solved > 0) {
      json fix;
      fix["epochs_per_type"] = types;
      fix["availability"] = share(fixed_epochs, solved);
      fix["rtk_fixed_share"] = share(r.epochs_per_fix_type[static_cast<size_t>(positioning::FixType::kRtkFixed)], solved);
      fix["time_to_first_fix_s"] = number_or_null(r.first_fix_s);
      fix["time_to_first_rtk_fixed_s"] = number_or_null(r.first_rtk_fixed_s);
      fix["horizontal_error_m"] = error_figures(r.horizontal_error);
      fix["vertical_error_m"] = error_figures(r.vertical_error);
      fix["mean_satellites_used"] =
          r.fixes_with_error > 0 ? json(r.satellites_used_sum / static_cast<double>(r.fixes_with_error)) : json(nullptr);
      rx["fix"] = fix;
    }
    rx["satellite_epochs"] = {{"tracked", r.tracked},           {"line_of_sight", r.line_of_sight},
                              {"multipath", r.multipath},       {"nlos", r.nlos},
                              {"blocked", r.blocked},           {"attenuated", r.attenuated}};
    rx["signal_observations"] = r.signals;
    rx["mean_tracked_satellites"] = r.epochs > 0 ? json(static_cast<double>(r.tracked) / static_cast<double>(r.epochs)) : json(nullptr);
    rx["nlos_share"] = share(r.nlos, r.tracked);
    rx["multipath_share"] = share(r.multipath, r.tracked);
    out.push_back(std::move(rx));
  }
  return out;
}

}  // namespace skytrace::sim

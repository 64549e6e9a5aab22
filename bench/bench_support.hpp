// Helpers shared by the benchmarks: where the real data lives, and the citysim world.
#pragma once

#include <Eigen/Core>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skytrace/io/rinex_measurements.hpp"
#include "skytrace/io/rinex_obs.hpp"
#include "skytrace/orbits/broadcast.hpp"
#include "skytrace/orbits/rinex_nav.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::bench {

// A file of ../shared/data (or $SKYTRACE_SHARED_DATA).
inline std::filesystem::path shared_file(const std::string& relative) {
  const char* env = std::getenv("SKYTRACE_SHARED_DATA");
  const std::filesystem::path base = env != nullptr && *env != '\0' ? env : SKYTRACE_DEFAULT_SHARED_DATA;
  return base / relative;
}

// Gazebo's citysim (simple_city.world with worlds/models on the model path); nullopt when the data
// is absent or does not load.
inline std::optional<world::WorldModel> load_citysim() {
  const auto path = shared_file("worlds/citysim/simple_city.world");
  if (!std::filesystem::exists(path)) return std::nullopt;
  world::SdfLoadOptions options;
  options.model_paths = {shared_file("worlds/models")};
  options.use_environment_paths = false;
  auto loaded = world::load_sdf_world(path, options);
  if (!loaded.ok()) return std::nullopt;
  return std::move(*loaded);
}

// The first hour of the real ESBC recording (GPS, GLONASS, Galileo, BeiDou: about 35 satellites
// per epoch) as positioning input, with its broadcast navigation file; `error` set when absent.
struct EsbcFirstHour {
  std::unique_ptr<orbits::BroadcastEphemerides> ephemerides;
  std::optional<orbits::KlobucharCoefficients> klobuchar;
  std::vector<positioning::EpochMeasurements> epochs;
  std::optional<Eigen::Vector3d> approx_position_m;  // the header's APPROX POSITION XYZ
  std::string error;
};

inline const EsbcFirstHour& esbc_first_hour() {
  static const EsbcFirstHour data = [] {
    EsbcFirstHour out;
    auto nav = orbits::read_rinex_nav(shared_file("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_MN.rnx"));
    auto obs = io::read_rinex_obs(shared_file("real/esbc_2020177/ESBC00DNK_R_20201770000_01D_30S_MO_first1h.rnx"));
    if (!nav || !obs) {
      out.error = !nav ? nav.error().message : obs.error().message;
      return out;
    }
    out.klobuchar = nav->ionosphere.gps;
    out.ephemerides = std::make_unique<orbits::BroadcastEphemerides>(std::move(*nav));
    const io::MeasurementExtractor extractor(obs->header);
    for (const auto& epoch : obs->epochs) out.epochs.push_back(extractor.measurements(epoch));
    if (const auto& p = obs->header.approx_position_ecef_m) out.approx_position_m = Eigen::Vector3d((*p)[0], (*p)[1], (*p)[2]);
    return out;
  }();
  return data;
}

}  // namespace skytrace::bench

// Sky mask: per azimuth, the elevation below which opaque objects hide the sky.
#include <algorithm>
#include <cmath>
#include <string>

#include "skytrace/world/scene.hpp"

namespace skytrace::world {

Result<std::vector<double>> sky_mask_elevation_deg(const PathQuery& query, const Eigen::Vector3d& origin_m,
                                                   double azimuth_step_deg, const SkyMaskOptions& options) {
  if (!origin_m.allFinite()) {
    return make_error(ErrorCode::kInvalidArgument, "sky mask: origin is not finite");
  }
  if (!(azimuth_step_deg > 0.0 && azimuth_step_deg <= 360.0)) {
    return make_error(ErrorCode::kInvalidArgument,
                      "sky mask: azimuth step must be in (0, 360] deg, got " + std::to_string(azimuth_step_deg));
  }
  if (!(options.min_elevation_deg >= -90.0 && options.min_elevation_deg < 90.0)) {
    return make_error(ErrorCode::kInvalidArgument, "sky mask: min_elevation_deg must be in [-90, 90), got " +
                                                       std::to_string(options.min_elevation_deg));
  }
  if (!(options.coarse_step_deg > 0.0 && options.tolerance_deg > 0.0 && std::isfinite(options.coarse_step_deg))) {
    return make_error(ErrorCode::kInvalidArgument, "sky mask: coarse_step_deg and tolerance_deg must be > 0");
  }

  // Azimuths 0, step, ... below 360 (a step that divides 360 gives exactly 360/step of them).
  const auto azimuth_count = static_cast<std::size_t>(std::ceil(360.0 / azimuth_step_deg - 1e-9));
  const double low_deg = options.min_elevation_deg;
  const auto sample_count = static_cast<std::size_t>(std::ceil((90.0 - low_deg) / options.coarse_step_deg - 1e-9)) + 1;
  auto sample_elevation_deg = [&](std::size_t k) {
    return k + 1 == sample_count ? 90.0 : low_deg + static_cast<double>(k) * options.coarse_step_deg;
  };

  // Coarse pass, one batch: the highest blocked sample of each azimuth.
  std::vector<Eigen::Vector3d> directions;
  directions.reserve(azimuth_count * sample_count);
  for (std::size_t a = 0; a < azimuth_count; ++a) {
    for (std::size_t k = 0; k < sample_count; ++k) {
      directions.push_back(enu_direction(static_cast<double>(a) * azimuth_step_deg, sample_elevation_deg(k)));
    }
  }
  const std::vector<RayOutcome> coarse = query.trace_line_of_sight(origin_m, directions);
  std::vector<double> mask_deg(azimuth_count, low_deg);
  std::vector<double> blocked_deg(azimuth_count, 0.0);
  std::vector<double> free_deg(azimuth_count, 0.0);
  std::vector<std::size_t> open;  // azimuths whose transition lies between two samples
  for (std::size_t a = 0; a < azimuth_count; ++a) {
    std::size_t highest = sample_count;  // none blocked
    for (std::size_t k = sample_count; k-- > 0;) {
      if (coarse[a * sample_count + k].blocked) {
        highest = k;
        break;
      }
    }
    if (highest == sample_count) continue;  // free down to the lowest elevation
    if (highest + 1 == sample_count) {
      mask_deg[a] = 90.0;  // even the zenith is blocked
      continue;
    }
    blocked_deg[a] = sample_elevation_deg(highest);
    free_deg[a] = sample_elevation_deg(highest + 1);
    open.push_back(a);
  }

  // Bisection, all open azimuths in one batch per step; every interval starts at most one coarse
  // step wide.
  const int bisections =
      std::max(0, static_cast<int>(std::ceil(std::log2(options.coarse_step_deg / options.tolerance_deg))));
  for (int iteration = 0; iteration < bisections && !open.empty(); ++iteration) {
    directions.clear();
    for (const std::size_t a : open) {
      directions.push_back(
          enu_direction(static_cast<double>(a) * azimuth_step_deg, 0.5 * (blocked_deg[a] + free_deg[a])));
    }
    const std::vector<RayOutcome> step = query.trace_line_of_sight(origin_m, directions);
    for (std::size_t j = 0; j < open.size(); ++j) {
      const std::size_t a = open[j];
      const double middle_deg = 0.5 * (blocked_deg[a] + free_deg[a]);
      (step[j].blocked ? blocked_deg[a] : free_deg[a]) = middle_deg;
    }
  }
  for (const std::size_t a : open) mask_deg[a] = 0.5 * (blocked_deg[a] + free_deg[a]);
  return mask_deg;
}

}  // namespace skytrace::world

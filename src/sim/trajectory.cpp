#include "skytrace/sim/trajectory.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "skytrace/core/text_file.hpp"

namespace skytrace::sim {

Eigen::Vector3d world_enu_to_ecef(const Eigen::Vector3d& world_m, const WorldOrigin& origin) {
  return origin.to_ecef(world_m);
}

Result<Eigen::Vector3d> position_to_ecef(const PositionSetting& position, const std::optional<WorldOrigin>& world) {
  switch (position.kind) {
    case PositionSetting::Kind::kEcef: return position.value;
    case PositionSetting::Kind::kLla:
      return geodetic_to_ecef(Geodetic{position.value.x(), position.value.y(), position.value.z()});
    case PositionSetting::Kind::kWorldEnu:
      if (!world) return make_error(ErrorCode::kInvalidArgument, "world_enu_m coordinates need a world origin");
      return world_enu_to_ecef(position.value, *world);
  }
  return make_error(ErrorCode::kInvalidArgument, "unknown position kind");
}

Result<std::shared_ptr<InterpolatedTrajectory>> InterpolatedTrajectory::create(std::vector<TrajectorySample> samples,
                                                                               std::string name) {
  if (samples.size() < 2) {
    return make_error(ErrorCode::kParse, name + ": a trajectory needs at least two samples");
  }
  for (size_t i = 1; i < samples.size(); ++i) {
    if (!(samples[i - 1].time < samples[i].time)) {
      return make_error(ErrorCode::kParse, name + ": sample " + std::to_string(i + 1) +
                                                         " is not later than the one before it");
    }
  }
  return std::shared_ptr<InterpolatedTrajectory>(new InterpolatedTrajectory(std::move(samples), std::move(name)));
}

Result<receiver::Kinematics> InterpolatedTrajectory::at(const GnssTime& t) const {
  const GnssTime& first = samples_.front().time;
  const GnssTime& last = samples_.back().time;
  // The epochs are the receiver's: its clock offset (up to a millisecond for receivers that let it
  // run free) puts the true instant of the first or last epoch just outside a trajectory that
  // spans the run exactly. The end segments' curves carry on over that much.
  constexpr double kEndTolerance_s = 0.01;
  if (t < first - kEndTolerance_s || last + kEndTolerance_s < t) {
    return make_error(ErrorCode::kOutOfRange, name_ + ": time " + t.to_iso8601(TimeScale::kGpst) +
                                                  " GPST is outside the trajectory (" + first.to_iso8601(TimeScale::kGpst) +
                                                  " to " + last.to_iso8601(TimeScale::kGpst) + ")");
  }
  // Segment i: samples i and i+1.
  size_t i = static_cast<size_t>(std::upper_bound(samples_.begin(), samples_.end(), t,
                                                  [](const GnssTime& a, const TrajectorySample& s) { return a < s.time; }) -
                                 samples_.begin());
  i = std::min(std::max<size_t>(i, 1), samples_.size() - 1) - 1;
  const auto& p0 = samples_[i];
  const auto& p1 = samples_[i + 1];
  const double h = p1.time - p0.time;
  // Catmull-Rom tangents (one-sided at the ends) make velocity continuous across samples.
  auto tangent = [&](size_t k) -> Eigen::Vector3d {
    if (k == 0) return (samples_[1].position_m - samples_[0].position_m) / (samples_[1].time - samples_[0].time);
    if (k + 1 == samples_.size()) {
      return (samples_[k].position_m - samples_[k - 1].position_m) / (samples_[k].time - samples_[k - 1].time);
    }
    return (samples_[k + 1].position_m - samples_[k - 1].position_m) / (samples_[k + 1].time - samples_[k - 1].time);
  };
  const Eigen::Vector3d m0 = tangent(i) * h;
  const Eigen::Vector3d m1 = tangent(i + 1) * h;
  const double s = (t - p0.time) / h;
  const double s2 = s * s, s3 = s2 * s;
  receiver::Kinematics k;
  k.position_m = (2 * s3 - 3 * s2 + 1) * p0.position_m + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1.position_m +
                 (s3 - s2) * m1;
  k.velocity_mps = ((6 * s2 - 6 * s) * p0.position_m + (3 * s2 - 4 * s + 1) * m0 + (-6 * s2 + 6 * s) * p1.position_m +
                    (3 * s2 - 2 * s) * m1) /
                   h;
  return k;
}

Result<std::vector<TrajectorySample>> read_trajectory_csv(const TrajectorySetting& setting, const GnssTime& start,
                                                          const std::optional<WorldOrigin>& world) {
  auto lines = TextLines::read(setting.file);
  if (!lines) return lines.error();
  std::vector<TrajectorySample> samples;
  bool header_seen = false;
  size_t previous_line = 0;
  for (size_t i = 0; i < lines->size(); ++i) {
    std::string_view line = (*lines)[i];
    if (line.empty() || line.front() == '#') continue;
    std::vector<std::string> cells;
    std::stringstream stream{std::string(line)};
    std::string cell;
    while (std::getline(stream, cell, ',')) {
      while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
      while (!cell.empty() && cell.back() == ' ') cell.pop_back();
      cells.push_back(cell);
    }
    if (!header_seen) {
      header_seen = true;
      // A header line names the columns; its first cell is not a number or a date.
      if (!cells.empty() && !cells[0].empty() && !std::isdigit(static_cast<unsigned char>(cells[0][0])) &&
          cells[0][0] != '-' && cells[0][0] != '.') {
        if (cells.size() != 4) return lines->error_at(i, "expected 4 columns: time and three coordinates");
        continue;
      }
    }
    if (cells.size() != 4) return lines->error_at(i, "expected 4 columns: time and three coordinates");
    TrajectorySample sample;
    if (cells[0].find('-', 1) != std::string::npos && cells[0].find(':') != std::string::npos) {
      auto t = GnssTime::parse_iso8601(cells[0], setting.time_scale);
      if (!t) return lines->error_at(i, t.error().message);
      sample.time = *t;
    } else {
      auto seconds = parse_fortran_double(cells[0]);
      if (!seconds) return lines->error_at(i, "time: " + seconds.error().message);
      if (std::fabs(*seconds) > kMaxSecondsFromStart_s) return lines->error_at(i, "time: expected seconds within 400 days of the start");
      sample.time = start + *seconds;
    }
    Eigen::Vector3d value;
    for (int k = 0; k < 3; ++k) {
      auto v = parse_fortran_double(cells[static_cast<size_t>(k + 1)]);
      if (!v) return lines->error_at(i, "coordinate " + std::to_string(k + 1) + ": " + v.error().message);
      value[k] = *v;
    }
    auto ecef = position_to_ecef(PositionSetting{setting.frame, value}, world);
    if (!ecef) return lines->error_at(i, ecef.error().message);
    if (ecef->norm() < 6.3e6) return lines->error_at(i, "position is below the Earth's surface");
    if (ecef->norm() > 5e7) return lines->error_at(i, "position is farther than 50000 km from the Earth's centre");
    if (!samples.empty() && !(samples.back().time < sample.time)) {
      return lines->error_at(i, "time is not later than the previous sample's (line " + std::to_string(previous_line + 1) +
                                    "): a trajectory's times must increase");
    }
    if (!samples.empty()) {
      const double speed_mps = (*ecef - samples.back().position_m).norm() / (sample.time - samples.back().time);
      if (speed_mps > kMaxAntennaSpeed_mps) {
        return lines->error_at(i, fmt::format("{:.3g} km/s from the previous sample (line {}), more than {:g} km/s: "
                                              "a coordinate or a time is wrong",
                                              speed_mps / 1e3, previous_line + 1, kMaxAntennaSpeed_mps / 1e3));
      }
    }
    previous_line = i;
    sample.position_m = *ecef;
    samples.push_back(sample);
  }
  return samples;
}

}  // namespace skytrace::sim

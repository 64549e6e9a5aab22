#include "skytrace/sim/moving_models.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <sstream>

#include "skytrace/core/text_file.hpp"

namespace skytrace::sim {
namespace {

std::vector<std::string> split_csv(std::string_view line) {
  std::vector<std::string> cells;
  std::stringstream stream{std::string(line)};
  std::string cell;
  while (std::getline(stream, cell, ',')) {
    while (!cell.empty() && std::isspace(static_cast<unsigned char>(cell.front())) != 0)
      cell.erase(cell.begin());
    while (!cell.empty() && std::isspace(static_cast<unsigned char>(cell.back())) != 0)
      cell.pop_back();
    cells.push_back(cell);
  }
  return cells;
}

// The yaw difference b - a taken the shorter way round, in (-180, 180].
double yaw_step_deg(double a_deg, double b_deg) {
  double d = std::fmod(b_deg - a_deg, 360.0);
  if (d > 180.0) d -= 360.0;
  if (d <= -180.0) d += 360.0;
  return d;
}

constexpr std::size_t kColumns = 5;

}  // namespace

Result<ModelTrajectory> ModelTrajectory::read_csv(const MovingModelSetting& setting,
                                                  const GnssTime& start) {
  auto lines = TextLines::read(setting.trajectory);
  if (!lines) return lines.error();
  std::vector<ModelPoseSample> samples;
  bool first_line = true;
  for (size_t i = 0; i < lines->size(); ++i) {
    const std::string_view line = (*lines)[i];
    if (line.empty() || line.front() == '#' ||
        line.find_first_not_of(" \t\r") == std::string_view::npos)
      continue;
    const auto cells = split_csv(line);
    const bool header = first_line && !cells.empty() && !cells[0].empty() &&
                        std::isdigit(static_cast<unsigned char>(cells[0][0])) == 0 &&
                        cells[0][0] != '-' && cells[0][0] != '.' && cells[0][0] != '+';
    first_line = false;
    if (cells.size() != kColumns) {
      return lines->error_at(i, "expected 5 columns: time, x_m, y_m, z_m, yaw_deg (got " +
                                    std::to_string(cells.size()) + ")");
    }
    if (header) continue;
    ModelPoseSample sample;
    if (cells[0].find('-', 1) != std::string::npos && cells[0].find(':') != std::string::npos) {
      auto t = GnssTime::parse_iso8601(cells[0], setting.time_scale);
      if (!t) return lines->error_at(i, "time: " + t.error().message);
      sample.time = *t;
    } else {
      auto seconds = parse_fortran_double(cells[0]);
      if (!seconds || !(std::fabs(*seconds) <= kMaxSecondsFromStart_s))
        return lines->error_at(
            i,
            "time: expected seconds since time.start (within 400 days) or an ISO 8601 time, got '" + cells[0] + "'");
      sample.time = start + *seconds;
    }
    double values[4];
    constexpr const char* kNames[4] = {"x_m", "y_m", "z_m", "yaw_deg"};
    for (size_t k = 0; k < 4; ++k) {
      auto v = parse_fortran_double(cells[k + 1]);
      if (!v || !std::isfinite(*v))
        return lines->error_at(
            i, std::string(kNames[k]) + ": expected a number, got '" + cells[k + 1] + "'");
      values[k] = *v;
    }
    sample.position_m = {values[0], values[1], values[2]};
    if (sample.position_m.norm() > kMaxWorldDistance_m) {
      return lines->error_at(i, fmt::format("position ({:g}, {:g}, {:g}) m: expected within 1000 km of the world's origin",
                                            values[0], values[1], values[2]));
    }
    sample.yaw_deg = values[3];
    if (!samples.empty() && !(samples.back().time < sample.time)) {
      return lines->error_at(i, "time is not later than the row before it");
    }
    samples.push_back(sample);
  }
  if (samples.empty()) {
    return make_error(ErrorCode::kParse, setting.trajectory.string() +
                                             ": no poses (moving model '" + setting.model + "')");
  }
  return ModelTrajectory(std::move(samples));
}

Result<ModelTrajectory> ModelTrajectory::create(std::vector<ModelPoseSample> samples,
                                                const std::string& name) {
  if (samples.empty()) return make_error(ErrorCode::kInvalidArgument, name + ": no poses");
  for (size_t i = 0; i < samples.size(); ++i) {
    if (!samples[i].position_m.allFinite() || !std::isfinite(samples[i].yaw_deg)) {
      return make_error(ErrorCode::kInvalidArgument,
                        name + ": pose " + std::to_string(i + 1) + " is not finite");
    }
    if (i > 0 && !(samples[i - 1].time < samples[i].time)) {
      return make_error(ErrorCode::kInvalidArgument, name + ": pose " + std::to_string(i + 1) +
                                                         " is not later than the one before it");
    }
  }
  return ModelTrajectory(std::move(samples));
}

Eigen::Isometry3d ModelTrajectory::at(const GnssTime& t) const {
  Eigen::Vector3d position = samples_.front().position_m;
  double yaw_deg = samples_.front().yaw_deg;
  if (!(t < samples_.back().time)) {
    position = samples_.back().position_m;
    yaw_deg = samples_.back().yaw_deg;
  } else if (samples_.front().time < t) {
    const auto next =
        std::upper_bound(samples_.begin(), samples_.end(), t,
                         [](const GnssTime& a, const ModelPoseSample& s) { return a < s.time; });
    const ModelPoseSample& b = *next;
    const ModelPoseSample& a = *std::prev(next);
    const double f = (t - a.time) / (b.time - a.time);
    position = a.position_m + f * (b.position_m - a.position_m);
    yaw_deg = a.yaw_deg + f * yaw_step_deg(a.yaw_deg, b.yaw_deg);
  }
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() = position;
  pose.linear() = Eigen::AngleAxisd(yaw_deg * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ())
                      .toRotationMatrix();
  return pose;
}

}  // namespace skytrace::sim

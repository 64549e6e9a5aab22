// Reading RTKLIB solution files (out-solformat=xyz) in tests.
#pragma once

#include <Eigen/Core>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace skytrace::test {

struct RtklibSolution {
  Eigen::Vector3d ecef_m = Eigen::Vector3d::Zero();
  int quality = 0;  // 1 fix, 2 float, 5 single
};

inline std::vector<RtklibSolution> read_rtklib_xyz(const std::filesystem::path& path) {
  std::vector<RtklibSolution> solutions;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '%') continue;
    std::istringstream fields(line);
    std::string date, time;
    RtklibSolution s;
    fields >> date >> time >> s.ecef_m.x() >> s.ecef_m.y() >> s.ecef_m.z() >> s.quality;
    if (fields) solutions.push_back(s);
  }
  return solutions;
}

// Sorted 3D distances of the solutions from a point.
inline std::vector<double> sorted_errors_m(const std::vector<RtklibSolution>& solutions, const Eigen::Vector3d& truth) {
  std::vector<double> errors;
  for (const auto& s : solutions) errors.push_back((s.ecef_m - truth).norm());
  std::sort(errors.begin(), errors.end());
  return errors;
}

}  // namespace skytrace::test

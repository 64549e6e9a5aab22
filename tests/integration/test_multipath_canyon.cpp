// The contract scenario canyon.yaml: a noise-free receiver between two long walls with multipath
// on. Satellites hidden by one wall and received only off the other carry a pseudorange excess of
// exactly the single-bounce geometry, 2 d cos(el) |cos(az)| (d: the reflecting wall's distance from
// the antenna, worlds/canyon.sdf); satellites in view carry a non-zero multipath error. The
// expectations come from the walls' positions, the excess from the pseudorange minus every other
// modelled term of truth.csv.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "process.hpp"
#include "test_support.hpp"
#include "zst_text.hpp"

namespace skytrace {
namespace {

// One CSV line into cells (quoted cells may hold commas).
std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> cells(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '"') {
      if (quoted && i + 1 < line.size() && line[i + 1] == '"') {
        cells.back() += '"';
        ++i;
      } else {
        quoted = !quoted;
      }
    } else if (c == ',' && !quoted) {
      cells.emplace_back();
    } else {
      cells.back() += c;
    }
  }
  return cells;
}

struct Table {
  std::map<std::string, std::size_t> column;
  std::vector<std::vector<std::string>> rows;
  [[nodiscard]] const std::string& at(const std::vector<std::string>& row, const std::string& name) const {
    return row.at(column.at(name));
  }
  [[nodiscard]] double number(const std::vector<std::string>& row, const std::string& name) const {
    return std::stod(at(row, name));
  }
};

Table read_csv(const std::filesystem::path& path) {
  Table t;
  std::istringstream in(test::read_zst_text(path));
  std::string line;
  if (!std::getline(in, line)) return t;
  const auto header = split_csv(line);
  for (std::size_t i = 0; i < header.size(); ++i) t.column[header[i]] = i;
  while (std::getline(in, line)) t.rows.push_back(split_csv(line));
  return t;
}

// Code chip length of the scenario's signals (m).
double chip_length_m(const std::string& signal) {
  const double c = 299792458.0;
  if (signal == "R1C") return c / 0.511e6;
  if (signal == "C2I") return c / 2.046e6;
  return c / 1.023e6;  // G1C, E1C
}

TEST(MultipathCanyon, NlosExcessIsTheSingleBounceGeometry) {
  const auto scenario = test::shared_data_dir().parent_path() / "contract" / "canyon.yaml";
  if (!std::filesystem::exists(scenario)) GTEST_SKIP() << "contract scenario absent: " << scenario;
  const auto out = test::make_temp_dir("multipath_canyon");
  const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                   test::shell_quote(scenario.string()) + " --out " + test::shell_quote(out.string()) +
                                   " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;

  const Table truth = read_csv(out / "truth.csv.zst");
  const Table paths = read_csv(out / "paths.csv.zst");
  ASSERT_FALSE(truth.rows.empty());
  ASSERT_FALSE(paths.rows.empty());
  for (const char* name : {"path_type", "code_multipath_m", "phase_multipath_m", "multipath_power_db"}) {
    ASSERT_TRUE(truth.column.count(name)) << name;
  }

  // Paths per satellite-epoch.
  std::map<std::string, std::vector<const std::vector<std::string>*>> paths_of;
  for (const auto& row : paths.rows) paths_of[paths.at(row, "time_gpst") + paths.at(row, "sat")].push_back(&row);

  // canyon.sdf: the north wall's south face 9.5 m north of the antenna, the south wall's north
  // face 19.5 m south; the antenna 1.5 m above the ground at the origin.
  constexpr double kNorthFace_m = 9.5, kSouthFace_m = 19.5;
  constexpr double kDeg = std::numbers::pi / 180.0;
  std::size_t single_bounce = 0, nlos_mixed = 0, in_view = 0, in_view_with_error = 0;
  double worst_single_m = 0.0;
  for (const auto& row : truth.rows) {
    if (truth.at(row, "status") != "tracked" || truth.at(row, "signal").empty()) continue;
    const double az = truth.number(row, "az_deg"), el = truth.number(row, "el_deg");
    // Pseudorange minus the direct range and every other modelled term.
    const double excess_m = truth.number(row, "pseudorange_m") - truth.number(row, "range_m") -
                            truth.number(row, "rx_clock_m") + truth.number(row, "sat_clock_m") +
                            truth.number(row, "relativistic_m") - truth.number(row, "group_delay_m") -
                            truth.number(row, "iono_m") - truth.number(row, "tropo_m");
    // The truth's own multipath column is that same excess.
    EXPECT_NEAR(excess_m, truth.number(row, "code_multipath_m"), 2e-3) << truth.at(row, "sat") << " " << az << " " << el;
    const std::string type = truth.at(row, "path_type");
    if (type == "nlos") {
      const bool north = std::cos(az * kDeg) > 0.0;  // hidden by the north wall, reflected by the south one
      const double d_m = north ? kSouthFace_m : kNorthFace_m;
      const double expected_m = 2.0 * d_m * std::cos(el * kDeg) * std::abs(std::cos(az * kDeg));
      const auto& sat_paths = paths_of[truth.at(row, "time_gpst") + truth.at(row, "sat")];
      ASSERT_FALSE(sat_paths.empty());
      if (sat_paths.size() == 1 && paths.at(*sat_paths[0], "type") == "reflected") {
        // The only path: off the opposite wall, at the wall's face.
        EXPECT_NEAR(paths.number(*sat_paths[0], "point_y_m"), north ? -kSouthFace_m : kNorthFace_m, 1e-3);
        EXPECT_NEAR(paths.number(*sat_paths[0], "excess_delay_m"), expected_m, 1e-3);
        EXPECT_NEAR(excess_m, expected_m, 0.10) << truth.at(row, "time_gpst") << " " << truth.at(row, "sat") << " "
                                                << truth.at(row, "signal") << " az " << az << " el " << el;
        worst_single_m = std::max(worst_single_m, std::abs(excess_m - expected_m));
        ++single_bounce;
      } else {
        // Several paths (a diffracted one over an edge, or only that): the code locks between
        // the paths' delays, within the early-late envelope (half the spacing, 0.05 chips).
        double lo_m = 1e9, hi_m = -1e9;
        for (const auto* p : sat_paths) {
          lo_m = std::min(lo_m, paths.number(*p, "excess_delay_m"));
          hi_m = std::max(hi_m, paths.number(*p, "excess_delay_m"));
        }
        const double margin_m = 0.05 * chip_length_m(truth.at(row, "signal"));
        EXPECT_GE(excess_m, lo_m - margin_m) << truth.at(row, "sat") << " az " << az << " el " << el;
        EXPECT_LE(excess_m, hi_m + margin_m) << truth.at(row, "sat") << " az " << az << " el " << el;
        ++nlos_mixed;
      }
    } else {
      ASSERT_TRUE(type == "los" || type == "multipath") << type;
      ++in_view;
      if (std::abs(excess_m) > 1e-4) ++in_view_with_error;
      if (type == "multipath") {
        EXPECT_GT(std::abs(truth.number(row, "code_multipath_m")), 1e-4);
      }
    }
  }
  std::printf("[ figures ] canyon.yaml: %zu single-bounce NLOS signal-epochs (worst %.4f m off the geometry), "
              "%zu NLOS with a diffracted path too, %zu in view of which %zu with a multipath error\n",
              single_bounce, worst_single_m, nlos_mixed, in_view, in_view_with_error);
  EXPECT_GT(single_bounce, 20u);
  EXPECT_GT(in_view, 100u);
  // Every satellite in view has at least its ground reflection (the wall's edge can cut it).
  EXPECT_GT(static_cast<double>(in_view_with_error), 0.95 * static_cast<double>(in_view));
}

}  // namespace
// With the second order the canyon's hidden satellites also come over the far wall's top edge and
// back off the near wall (or the reverse): paths.csv gives such a path both its points, the
// reflection and the edge, and a plain path only its own.
TEST(MultipathCanyon, DiffractionWithAReflectionListsBothItsPoints) {
  const auto scenario = test::shared_data_dir().parent_path() / "contract" / "canyon.yaml";
  if (!std::filesystem::exists(scenario)) GTEST_SKIP() << "contract scenario absent: " << scenario;
  const auto out = test::make_temp_dir("multipath_canyon_order2");
  const auto r = test::run_command(test::shell_quote(test::skytrace_executable().string()) + " run " +
                                   test::shell_quote(scenario.string()) + " --out " + test::shell_quote(out.string()) +
                                   " --quiet --set models.multipath_order=2 --set time.duration_s=1800");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Table paths = read_csv(out / "paths.csv.zst");
  std::size_t combined = 0;
  for (const auto& row : paths.rows) {
    const bool two_points = paths.at(row, "reflections") == "2" ||
                            (paths.at(row, "type") == "diffracted" && paths.at(row, "reflections") == "1");
    EXPECT_EQ(paths.at(row, "second_y_m").empty(), !two_points) << paths.at(row, "time_gpst") << " " << paths.at(row, "sat");
    if (paths.at(row, "type") != "diffracted" || paths.at(row, "reflections") != "1") continue;
    ++combined;
    // Two distinct points, one of them the reflection on a wall's inner face (y = 9.5 or -19.5) or
    // on the ground (z = 0).
    const Eigen::Vector3d first(paths.number(row, "point_x_m"), paths.number(row, "point_y_m"), paths.number(row, "point_z_m"));
    const Eigen::Vector3d second(paths.number(row, "second_x_m"), paths.number(row, "second_y_m"),
                                 paths.number(row, "second_z_m"));
    const auto on_reflector = [](const Eigen::Vector3d& p) {
      return std::abs(p.y() - 9.5) < 1e-3 || std::abs(p.y() + 19.5) < 1e-3 || std::abs(p.z()) < 1e-3;
    };
    EXPECT_GT((first - second).norm(), 1.0);
    EXPECT_TRUE(on_reflector(first) || on_reflector(second)) << first.transpose() << " / " << second.transpose();
  }
  EXPECT_GT(combined, 0u);
}

}  // namespace skytrace

// Helpers shared by the tests: where the real data lives, temporary folders.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace skytrace::test {

// ../shared/data beside the checkout, or $SKYTRACE_SHARED_DATA.
std::filesystem::path shared_data_dir();
std::filesystem::path source_dir();
std::filesystem::path binary_dir();
// A fresh empty folder under the build tree for one test (test-tmp/NAME/SUITE.TEST while a test runs).
std::filesystem::path make_temp_dir(const std::string& name);
// The YAML text of a plain receiver profile for generator tests (G1C and E1C, isotropic antenna,
// thresholds 40/20 dB-Hz, acquisition 3 s, steered OCXO); channels 0 = unlimited.
std::string test_profile_yaml(int channels = 0, bool output_requires_ephemeris = false);
// A scenario of two F9P antennas on one body for heading tests: ANT1 the moving base at world ENU
// (0, 0, 1.5), ANT2 the rover at `rover_enu_m` (e.g. "0.7, 1.2124356, 1.5": 1.4 m at 30 deg),
// 2020-06-25 06:00 GPST for `duration_s` at 1 Hz, ESBC's navigation file `nav`, noise on, seed 3.
std::string moving_base_scenario_yaml(const std::filesystem::path& nav, const std::string& rover_enu_m, int duration_s);

}  // namespace skytrace::test

// Skips the current test when a shared-data file is missing: use as
//   const auto path = SKYTRACE_SHARED_FILE("real/esbc_2020177/...");
#define SKYTRACE_SHARED_FILE(relative)                                                  \
  ([&]() {                                                                              \
    const auto p = ::skytrace::test::shared_data_dir() / (relative);                    \
    return p;                                                                           \
  }());                                                                                 \
  if (!std::filesystem::exists(::skytrace::test::shared_data_dir() / (relative)))      \
  GTEST_SKIP() << "shared data file absent: " << (::skytrace::test::shared_data_dir() / (relative)) \
               << " (set SKYTRACE_SHARED_DATA)"

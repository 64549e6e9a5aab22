// Scenario YAML (sim::parse_scenario). Relative paths resolve against an empty folder of this
// process, so that a scenario only reaches the project's own profiles.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "fuzz_support.hpp"
#include "skytrace/sim/scenario.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path base_dir = [] {
    auto dir = std::filesystem::temp_directory_path() / ("skytrace-fuzz-scenario-" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir);
    return dir;
  }();
  auto scenario = skytrace::sim::parse_scenario(skytrace::fuzz::as_string(data, size), "fuzz.yaml", base_dir);
  if (scenario.ok()) (void)skytrace::sim::scenario_to_json(*scenario);
  return 0;
}

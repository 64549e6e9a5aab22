#include "test_support.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace skytrace::test {

std::filesystem::path shared_data_dir() {
  if (const char* env = std::getenv("SKYTRACE_SHARED_DATA"); env != nullptr && *env != '\0') {
    return env;
  }
  return SKYTRACE_DEFAULT_SHARED_DATA;
}

std::filesystem::path source_dir() { return SKYTRACE_SOURCE_DIR; }
std::filesystem::path binary_dir() { return SKYTRACE_BINARY_DIR; }

std::filesystem::path make_temp_dir(const std::string& name) {
  // One folder per test: ctest runs the tests of one fixture in parallel processes, and a folder
  // shared by them would be removed under another test's feet.
  std::filesystem::path dir = binary_dir() / "test-tmp" / name;
  if (const auto* test = ::testing::UnitTest::GetInstance()->current_test_info(); test != nullptr) {
    dir /= std::string(test->test_suite_name()) + "." + test->name();
  }
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace skytrace::test

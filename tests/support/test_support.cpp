#include "test_support.hpp"

#include <cstdlib>

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
  const auto dir = binary_dir() / "test-tmp" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace skytrace::test

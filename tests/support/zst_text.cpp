#include "zst_text.hpp"

#include <gtest/gtest.h>

#include "skytrace/io/zstd_file.hpp"

namespace skytrace::test {

std::string read_zst_text(const std::filesystem::path& path) {
  auto text = io::read_zstd_file(path);
  if (!text) {
    ADD_FAILURE() << text.error().message;
    return {};
  }
  return *text;
}

}  // namespace skytrace::test

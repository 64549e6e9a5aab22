// Reading the zstd-compressed outputs of a run (truth.csv.zst, paths.csv.zst) in tests.
#pragma once

#include <filesystem>
#include <string>

namespace skytrace::test {

// The decompressed text of `path`; adds a test failure and returns "" when it cannot be read.
std::string read_zst_text(const std::filesystem::path& path);

}  // namespace skytrace::test

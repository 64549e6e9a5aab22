// Helpers shared by the libFuzzer targets of this folder (docs/reliability.md).
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <string_view>

namespace skytrace::fuzz {

// The fuzzer's bytes as text.
inline std::string as_string(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

// A file of this process in the temporary folder, rewritten with every input, for loaders that
// only take a path (the extension selects the format). Removed when the process exits normally.
class TempInputFile {
 public:
  explicit TempInputFile(const std::string& extension)
      : path_(std::filesystem::temp_directory_path() /
              ("skytrace-fuzz-" + std::to_string(::getpid()) + extension)) {}
  ~TempInputFile() {
    std::error_code ignored;
    std::filesystem::remove(path_, ignored);
  }
  TempInputFile(const TempInputFile&) = delete;
  TempInputFile& operator=(const TempInputFile&) = delete;

  // Replaces the content; false when the file cannot be written (the input is then skipped).
  [[nodiscard]] bool write(std::string_view content) const {
    std::FILE* file = std::fopen(path_.c_str(), "wb");
    if (file == nullptr) return false;
    const bool ok = std::fwrite(content.data(), 1, content.size(), file) == content.size();
    return std::fclose(file) == 0 && ok;
  }
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace skytrace::fuzz

// Reading text files line by line, plain or gzip-compressed, with file:line context for errors.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/output_file.hpp"  // write_file_atomically, for the writers that read too

namespace skytrace {

// Why `path` cannot serve as an input file ("no such file", "is a folder, expected a file", "not a
// regular file ..."), or an empty string when it is a regular file. Only regular files are read:
// a device or a pipe could block or never end (/dev/zero).
[[nodiscard]] std::string why_not_an_input_file(const std::filesystem::path& path);

// Reads a whole file; gzip-compressed content (.gz or by magic number) is decompressed.
[[nodiscard]] Result<std::string> read_text_file(const std::filesystem::path& path);

// A file split into lines (without line terminators; a trailing '\r' is removed).
class TextLines {
 public:
  [[nodiscard]] static Result<TextLines> read(const std::filesystem::path& path);
  TextLines(std::string name, std::string content);

  [[nodiscard]] size_t size() const { return lines_.size(); }
  [[nodiscard]] std::string_view operator[](size_t index) const { return lines_[index]; }
  [[nodiscard]] const std::string& name() const { return name_; }
  // "path:LINE" for 0-based index `index`.
  [[nodiscard]] std::string where(size_t index) const;
  // A parse error naming the file and the 1-based line of `index`.
  [[nodiscard]] Error error_at(size_t index, const std::string& message) const;

 private:
  std::string name_;
  std::string content_;
  std::vector<std::string_view> lines_;
};

// Fixed-column field helpers for RINEX-like formats: the substring [start, start+width), clipped
// to the line, with surrounding blanks removed.
[[nodiscard]] std::string_view field(std::string_view line, size_t start, size_t width);
// The blank- or tab-separated words of a line (free-format records: IONEX, ANTEX grids).
[[nodiscard]] std::vector<std::string_view> split_words(std::string_view text);
// Parses a Fortran-style number ("1.234D-05", "-.5E+01"); a blank field is an error.
[[nodiscard]] Result<double> parse_fortran_double(std::string_view text);
[[nodiscard]] Result<long> parse_integer(std::string_view text);

}  // namespace skytrace

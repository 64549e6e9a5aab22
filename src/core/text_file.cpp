#include "skytrace/core/text_file.hpp"

#include "skytrace/core/input_limits.hpp"

#include <zlib.h>

#include <cerrno>
#include <cmath>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <system_error>

namespace skytrace {

std::string why_not_an_input_file(const std::filesystem::path& path) {
  if (path.empty()) return "an empty path was given for a file";
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (std::filesystem::is_regular_file(status)) return {};
  if (std::filesystem::is_directory(status)) return path.string() + ": is a folder, expected a file";
  if (std::filesystem::exists(status)) {
    return path.string() + ": not a regular file (a device, pipe or socket); give a file";
  }
  return path.string() + ": no such file";
}

Result<std::string> read_text_file(const std::filesystem::path& path) {
  if (std::string why = why_not_an_input_file(path); !why.empty()) return make_error(ErrorCode::kIo, why);
  // gzopen reads plain files transparently and decompresses gzip ones.
  gzFile file = gzopen(path.c_str(), "rb");
  if (file == nullptr) {
    return make_error(ErrorCode::kIo, path.string() + ": cannot open (" + std::strerror(errno) + ")");
  }
  gzbuffer(file, 1 << 17);
  const bool compressed = gzdirect(file) == 0;
  const std::uint64_t limit = input_limits().max_decompressed_bytes;
  std::string content;
  char buffer[1 << 16];
  while (true) {
    const int n = gzread(file, buffer, sizeof buffer);
    if (n > 0 && compressed && content.size() + static_cast<size_t>(n) > limit) {
      gzclose(file);
      return make_error(ErrorCode::kIo, path.string() + ": decompresses to more than " + std::to_string(limit >> 20) +
                                            " MiB " + limit_hint(limit >> 20, "SKYTRACE_MAX_DECOMPRESSED_MB") +
                                            "; a compression bomb or a file too large to read at once");
    }
    if (n < 0) {
      int errnum = 0;
      const std::string message = gzerror(file, &errnum);
      gzclose(file);
      return make_error(ErrorCode::kIo, path.string() + ": read error (" + message + ")");
    }
    if (n == 0) break;
    content.append(buffer, static_cast<size_t>(n));
  }
  const int close_status = gzclose(file);
  if (close_status != Z_OK && close_status != Z_BUF_ERROR) {
    return make_error(ErrorCode::kIo, path.string() + ": truncated or corrupt compressed data");
  }
  if (close_status == Z_BUF_ERROR) {
    return make_error(ErrorCode::kIo, path.string() + ": truncated compressed data");
  }
  return content;
}

Result<TextLines> TextLines::read(const std::filesystem::path& path) {
  auto content = read_text_file(path);
  if (!content) return content.error();
  return TextLines(path.string(), std::move(*content));
}

TextLines::TextLines(std::string name, std::string content)
    : name_(std::move(name)), content_(std::move(content)) {
  std::string_view all(content_);
  size_t start = 0;
  while (start < all.size()) {
    size_t end = all.find('\n', start);
    if (end == std::string_view::npos) end = all.size();
    std::string_view line = all.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines_.push_back(line);
    start = end + 1;
  }
}

std::string TextLines::where(size_t index) const { return name_ + ":" + std::to_string(index + 1); }

Error TextLines::error_at(size_t index, const std::string& message) const {
  return Error{ErrorCode::kParse, where(index) + ": " + message};
}

std::string_view field(std::string_view line, size_t start, size_t width) {
  if (start >= line.size()) return {};
  std::string_view f = line.substr(start, width);
  while (!f.empty() && (f.front() == ' ' || f.front() == '\t')) f.remove_prefix(1);
  while (!f.empty() && (f.back() == ' ' || f.back() == '\t')) f.remove_suffix(1);
  return f;
}

std::vector<std::string_view> split_words(std::string_view text) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
    const size_t start = i;
    while (i < text.size() && text[i] != ' ' && text[i] != '\t') ++i;
    if (i > start) out.push_back(text.substr(start, i - start));
  }
  return out;
}

Result<double> parse_fortran_double(std::string_view text) {
  while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
  while (!text.empty() && text.back() == ' ') text.remove_suffix(1);
  if (text.empty()) return make_error(ErrorCode::kParse, "empty numeric field");
  char buffer[64];
  if (text.size() >= sizeof buffer) return make_error(ErrorCode::kParse, "numeric field too long");
  size_t n = 0;
  for (char c : text) buffer[n++] = (c == 'D' || c == 'd') ? 'E' : c;
  buffer[n] = '\0';
  const char* begin = buffer;
  if (*begin == '+') ++begin;
  double value = 0.0;
  auto [ptr, ec] = std::from_chars(begin, buffer + n, value);
  if (ec != std::errc() || ptr != buffer + n) {
    return make_error(ErrorCode::kParse, "not a number: '" + std::string(text) + "'");
  }
  // from_chars takes "nan" and "inf"; no format read here has a use for them.
  if (!std::isfinite(value)) return make_error(ErrorCode::kParse, "not a finite number: '" + std::string(text) + "'");
  return value;
}

Result<long> parse_integer(std::string_view text) {
  while (!text.empty() && text.front() == ' ') text.remove_prefix(1);
  while (!text.empty() && text.back() == ' ') text.remove_suffix(1);
  if (text.empty()) return make_error(ErrorCode::kParse, "empty integer field");
  if (text.front() == '+') text.remove_prefix(1);
  long value = 0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size()) {
    return make_error(ErrorCode::kParse, "not an integer: '" + std::string(text) + "'");
  }
  return value;
}

}  // namespace skytrace

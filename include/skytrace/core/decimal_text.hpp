// Numbers appended to text, fast, for the large per-signal tables (truth.csv, paths.csv). The
// characters are exactly those of printf("%.Nf") and fmt's "{:.Nf}" (std::to_chars: the correctly
// rounded decimal of the binary value, the sign of negative zero kept, nan and inf as they write
// them), about twice as fast as fmt with its format string parsed per row.
#pragma once

#include <charconv>
#include <cstdint>
#include <string>
#include <string_view>

namespace skytrace {

// `value` with `decimals` digits after the point (0-17).
inline void append_fixed(std::string& out, double value, int decimals) {
  char buffer[352];  // the longest fixed text of a double: 309 digits, sign, point, 17 decimals
  const auto written = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::fixed, decimals);
  out.append(buffer, written.ptr);
}

inline void append_integer(std::string& out, std::int64_t value) {
  char buffer[24];
  const auto written = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, written.ptr);
}

// Cells of a comma-separated row: each call appends one cell after a separator (none before the
// first cell of the row). end() ends the row.
class CsvRow {
 public:
  explicit CsvRow(std::string& out) : out_(out) {}
  CsvRow& fixed(double value, int decimals) {
    separate();
    append_fixed(out_, value, decimals);
    return *this;
  }
  CsvRow& integer(std::int64_t value) {
    separate();
    append_integer(out_, value);
    return *this;
  }
  // Text as it is (the caller quotes it when it may hold a comma).
  CsvRow& text(std::string_view value) {
    separate();
    out_.append(value);
    return *this;
  }
  // Several cells already joined by commas (or empty cells: ",,,").
  CsvRow& raw(std::string_view cells) {
    separate();
    out_.append(cells);
    return *this;
  }
  CsvRow& empty(int count = 1) {
    for (int i = 0; i < count; ++i) separate();
    return *this;
  }
  void end() {
    out_.push_back('\n');
    first_ = true;
  }

 private:
  void separate() {
    if (!first_) out_.push_back(',');
    first_ = false;
  }
  std::string& out_;
  bool first_ = true;
};

}  // namespace skytrace

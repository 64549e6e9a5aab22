// Numbers appended to text, fast, for the large per-signal tables (truth.csv, paths.csv). The
// characters are exactly those of printf("%.Nf") and fmt's "{:.Nf}" (std::to_chars: the correctly
// rounded decimal of the binary value, the sign of negative zero kept, nan and inf as they write
// them), about twice as fast as fmt with its format string parsed per row.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <string>
#include <string_view>

namespace skytrace {

// `value` with `decimals` digits after the point (0-17), exactly as std::to_chars writes it.
inline void append_fixed_slow(std::string& out, double value, int decimals) {
  char buffer[352];  // the longest fixed text of a double: 309 digits, sign, point, 17 decimals
  const auto written = std::to_chars(buffer, buffer + sizeof buffer, value, std::chars_format::fixed, decimals);
  out.append(buffer, written.ptr);
}

// The same characters, about three times faster for the table's usual values: value * 10^decimals
// is one correctly rounded product, so where it is not within its own rounding error of a
// half-integer, rounding it to the nearest integer rounds the exact decimal value the same way;
// other values (near a tie, too large, nan, inf) go to std::to_chars.
inline void append_fixed(std::string& out, double value, int decimals) {
  static constexpr double kPowerOfTen[] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
  static constexpr std::uint64_t kIntegerPowerOfTen[] = {1,         10,         100,         1000,     10000,
                                                         100000,    1000000,    10000000,    100000000, 1000000000};
  constexpr double kLargest = 4.0e15;  // below 2^53: every integer up to it is a double
  if (decimals < 0 || decimals > 9) {
    append_fixed_slow(out, value, decimals);
    return;
  }
  const double scaled = std::abs(value) * kPowerOfTen[decimals];  // NaN fails the test below
  if (!(scaled < kLargest)) {
    append_fixed_slow(out, value, decimals);
    return;
  }
  const double whole = std::floor(scaled);
  const double distance_from_tie = std::abs(scaled - whole - 0.5);
  if (distance_from_tie <= scaled * 0x1p-51 + 0x1p-60) {
    append_fixed_slow(out, value, decimals);
    return;
  }
  auto digits = static_cast<std::uint64_t>(scaled - whole > 0.5 ? whole + 1.0 : whole);
  char buffer[40];
  char* end = buffer + sizeof buffer;
  char* p = end;
  if (decimals > 0) {
    std::uint64_t fraction = digits % kIntegerPowerOfTen[decimals];
    digits /= kIntegerPowerOfTen[decimals];
    for (int i = 0; i < decimals; ++i) {
      *--p = static_cast<char>('0' + fraction % 10);
      fraction /= 10;
    }
    *--p = '.';
  }
  do {
    *--p = static_cast<char>('0' + digits % 10);
    digits /= 10;
  } while (digits != 0);
  if (std::signbit(value)) *--p = '-';
  out.append(p, end);
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

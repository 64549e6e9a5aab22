// Numbers appended to text, fast, for the large per-signal tables (truth.csv, paths.csv). The
// characters are exactly those of printf("%.Nf") and fmt's "{:.Nf}" (std::to_chars: the correctly
// rounded decimal of the binary value, the sign of negative zero kept, nan and inf as they write
// them), about twice as fast as fmt with its format string parsed per row.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

namespace skytrace {

// `value` with `decimals` digits after the point (0-17) written at `p` (room for 352 bytes: 309
// digits, sign, point, 17 decimals) by std::to_chars, the reference; returns the end.
inline char* write_fixed_to_chars(char* p, double value, int decimals) {
  return std::to_chars(p, p + 352, value, std::chars_format::fixed, decimals).ptr;
}

// The same, appended to `out` (the tests' reference).
inline void append_fixed_slow(std::string& out, double value, int decimals) {
  char buffer[352];
  out.append(buffer, write_fixed_to_chars(buffer, value, decimals));
}

namespace decimal_text_detail {

inline constexpr double kPowerOfTen[] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};
// 10^0 .. 10^16: the integer part of a value below kLargest has at most 16 digits.
inline constexpr std::uint64_t kIntegerPowerOfTen[] = {1ULL,
                                                      10ULL,
                                                      100ULL,
                                                      1000ULL,
                                                      10000ULL,
                                                      100000ULL,
                                                      1000000ULL,
                                                      10000000ULL,
                                                      100000000ULL,
                                                      1000000000ULL,
                                                      10000000000ULL,
                                                      100000000000ULL,
                                                      1000000000000ULL,
                                                      10000000000000ULL,
                                                      100000000000000ULL,
                                                      1000000000000000ULL,
                                                      10000000000000000ULL};
inline constexpr char kPairs[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

// write_fixed with the number of decimals known when compiling: the divisions by 10^decimals
// become multiplications (a division by a variable power of ten was most of the time).
template <int Decimals>
char* write_fixed_exact(char* p, double value) {
  static_assert(Decimals >= 0 && Decimals <= 9);
  constexpr double kLargest = 4.0e15;  // below 2^53: every integer up to it is a double
  constexpr std::uint64_t kScale = kIntegerPowerOfTen[Decimals];
  const double scaled = std::abs(value) * kPowerOfTen[Decimals];  // NaN fails the test below
  if (!(scaled < kLargest)) return write_fixed_to_chars(p, value, Decimals);
  const auto whole = static_cast<std::uint64_t>(scaled);  // the floor: scaled is not negative
  const double remainder = scaled - static_cast<double>(whole);
  if (std::abs(remainder - 0.5) <= scaled * 0x1p-51 + 0x1p-60) return write_fixed_to_chars(p, value, Decimals);
  const std::uint64_t digits = remainder > 0.5 ? whole + 1 : whole;
  // Written from the last digit, two at a time, straight into place: first the length.
  std::uint64_t fraction = digits % kScale;
  std::uint64_t integer = digits / kScale;
  int integer_digits = 1;
  while (integer >= kIntegerPowerOfTen[integer_digits]) ++integer_digits;
  if (std::signbit(value)) *p++ = '-';
  char* const end = p + integer_digits + (Decimals > 0 ? Decimals + 1 : 0);
  char* q = end;
  int left = Decimals;
  for (; left >= 2; left -= 2) {
    q -= 2;
    std::memcpy(q, kPairs + 2 * (fraction % 100), 2);
    fraction /= 100;
  }
  if (left == 1) *--q = static_cast<char>('0' + fraction);
  if (Decimals > 0) *--q = '.';
  while (integer >= 100) {
    q -= 2;
    std::memcpy(q, kPairs + 2 * (integer % 100), 2);
    integer /= 100;
  }
  if (integer >= 10) {
    q -= 2;
    std::memcpy(q, kPairs + 2 * integer, 2);
  } else {
    *--q = static_cast<char>('0' + integer);
  }
  return end;
}

}  // namespace decimal_text_detail

// The same characters written at `p` (room for 352 bytes), returning the end, several times
// faster for the table's usual values: value * 10^decimals is one correctly rounded product, so
// where it is not within its own rounding error of a half-integer, rounding it to the nearest
// integer rounds the exact decimal value the same way; other values (near a tie, too large, nan,
// inf) go to std::to_chars.
inline char* write_fixed(char* p, double value, int decimals) {
  using decimal_text_detail::write_fixed_exact;
  switch (decimals) {
    case 0: return write_fixed_exact<0>(p, value);
    case 1: return write_fixed_exact<1>(p, value);
    case 2: return write_fixed_exact<2>(p, value);
    case 3: return write_fixed_exact<3>(p, value);
    case 4: return write_fixed_exact<4>(p, value);
    case 5: return write_fixed_exact<5>(p, value);
    case 6: return write_fixed_exact<6>(p, value);
    case 7: return write_fixed_exact<7>(p, value);
    case 8: return write_fixed_exact<8>(p, value);
    case 9: return write_fixed_exact<9>(p, value);
    default: return write_fixed_to_chars(p, value, decimals);
  }
}

// `value` with `decimals` digits after the point, appended to `out` (write_fixed's characters).
inline void append_fixed(std::string& out, double value, int decimals) {
  char buffer[360];
  out.append(buffer, write_fixed(buffer, value, decimals));
}

// Cells of a comma-separated row: each call appends one cell after a separator (none before the
// first cell of the row). end() ends the row. The row is built in a buffer of its own and appended
// to `out` once (at end() or when the row object goes), not cell by cell.
class CsvRow {
 public:
  explicit CsvRow(std::string& out) : out_(out), cursor_(buffer_) {}
  ~CsvRow() { flush(); }
  CsvRow(const CsvRow&) = delete;
  CsvRow& operator=(const CsvRow&) = delete;

  CsvRow& fixed(double value, int decimals) {
    make_room(kNumberRoom);
    separate();
    cursor_ = write_fixed(cursor_, value, decimals);
    return *this;
  }
  CsvRow& integer(std::int64_t value) {
    make_room(32);
    separate();
    cursor_ = std::to_chars(cursor_, cursor_ + 24, value).ptr;
    return *this;
  }
  // Text as it is (the caller quotes it when it may hold a comma).
  CsvRow& text(std::string_view value) {
    if (value.size() + 1 > kBufferBytes / 2) {
      separate_into_out();
      out_.append(value);
      return *this;
    }
    make_room(value.size() + 1);
    separate();
    std::memcpy(cursor_, value.data(), value.size());
    cursor_ += value.size();
    return *this;
  }
  // Several cells already joined by commas (or empty cells: ",,,").
  CsvRow& raw(std::string_view cells) { return text(cells); }
  CsvRow& empty(int count = 1) {
    for (int i = 0; i < count; ++i) {
      make_room(1);
      separate();
    }
    return *this;
  }
  void end() {
    make_room(1);
    *cursor_++ = '\n';
    first_ = true;
    flush();
  }

 private:
  static constexpr size_t kBufferBytes = 2048;
  static constexpr size_t kNumberRoom = 360;  // a separator and write_fixed's longest text
  void separate() {
    if (!first_) *cursor_++ = ',';
    first_ = false;
  }
  void separate_into_out() {
    flush();
    if (!first_) out_.push_back(',');
    first_ = false;
  }
  void make_room(size_t bytes) {
    if (static_cast<size_t>(buffer_ + kBufferBytes - cursor_) < bytes) flush();
  }
  void flush() {
    if (cursor_ != buffer_) out_.append(buffer_, cursor_);
    cursor_ = buffer_;
  }
  std::string& out_;
  char buffer_[kBufferBytes];
  char* cursor_;
  bool first_ = true;
};

}  // namespace skytrace

// parse_fortran_double against glibc's strtod (correctly rounded) on the numeric fields of RINEX,
// SP3 and clock files: D and E exponents, fixed decimals, every magnitude the files hold, and
// what must stay an error.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "skytrace/core/text_file.hpp"

namespace skytrace {
namespace {

double reference(std::string text) {
  for (char& c : text) {
    if (c == 'D' || c == 'd') c = 'E';
  }
  return std::strtod(text.c_str(), nullptr);
}

TEST(TextFields, FortranDoublesEqualStrtodBitForBit) {
  std::mt19937_64 random(42);
  std::uniform_real_distribution<double> exponent(-30.0, 30.0);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::uniform_int_distribution<int> precision(0, 17);
  const char* formats[] = {"%.*E", "%.*e", "%.*f", "%.*G"};
  char buffer[128];
  for (int i = 0; i < 1'000'000; ++i) {
    const double value = unit(random) * std::pow(10.0, exponent(random));
    const int format = i % 4;
    const int digits = precision(random);
    if (format == 2 && std::abs(value) > 1e20) continue;
    std::snprintf(buffer, sizeof buffer, formats[format], digits, value);
    std::string text = buffer;
    if (i % 3 == 0) {
      for (char& c : text) {
        if (c == 'E') c = 'D';  // Fortran's exponent letter
      }
    }
    auto parsed = parse_fortran_double(text);
    ASSERT_TRUE(parsed) << text << ": " << parsed.error().message;
    const double expected = reference(text);
    ASSERT_EQ(std::signbit(*parsed), std::signbit(expected)) << text;
    ASSERT_EQ(*parsed, expected) << text;
  }
}

TEST(TextFields, RecordFieldsAndErrors) {
  EXPECT_EQ(parse_fortran_double(" -0.404037740176D-04").value(), -0.404037740176e-04);
  EXPECT_EQ(parse_fortran_double("  0.123456789012E+05 ").value(), 12345.6789012);
  EXPECT_EQ(parse_fortran_double("+5.").value(), 5.0);
  EXPECT_EQ(parse_fortran_double(".25").value(), 0.25);
  EXPECT_TRUE(std::signbit(parse_fortran_double("-0.000").value()));
  EXPECT_EQ(parse_fortran_double("17230.175165").value(), 17230.175165);
  EXPECT_EQ(parse_fortran_double("123456789012345678").value(), 123456789012345678.0);
  EXPECT_EQ(parse_fortran_double("1.5E-300").value(), 1.5e-300);
  for (const char* bad : {"", "   ", "-", "+", ".", "1.2.3", "1E", "1E+", "D5", "1x", "--1", "nan", "inf", "1E99999",
                          "0x10", "1,5"}) {
    EXPECT_FALSE(parse_fortran_double(bad)) << "'" << bad << "'";
  }
}

}  // namespace
}  // namespace skytrace

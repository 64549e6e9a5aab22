// append_fixed's fast path against std::to_chars (the characters of printf("%.Nf")) on values of
// every magnitude the tables write, on exact ties and near-ties, and on the special values.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>

#include "skytrace/core/decimal_text.hpp"

namespace skytrace {
namespace {

std::string fast(double value, int decimals) {
  std::string out = "x";  // appends after what is there
  append_fixed(out, value, decimals);
  return out.substr(1);
}

std::string reference(double value, int decimals) {
  std::string out;
  append_fixed_slow(out, value, decimals);
  return out;
}

TEST(DecimalText, AgreesWithToCharsOnRandomValuesOfEveryMagnitude) {
  std::mt19937_64 random(20261127);
  std::uniform_real_distribution<double> exponent(-12.0, 17.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> decimals(0, 12);
  for (int i = 0; i < 2'000'000; ++i) {
    const double magnitude = std::pow(10.0, exponent(random));
    const double value = (unit(random) < 0.5 ? -1.0 : 1.0) * magnitude * unit(random);
    const int d = decimals(random);
    ASSERT_EQ(fast(value, d), reference(value, d)) << value << " with " << d << " decimals";
  }
}

TEST(DecimalText, AgreesOnTiesAndTheirNeighbours) {
  // Exact binary ties (k + 1/2) / 10^d exist only where 10^d's factor 5^d divides out; test
  // halves, quarters, eighths... and the doubles next to them, and decimal "ties" that are not
  // exact in binary (2.675 is 2.67499999...).
  for (int d = 0; d <= 9; ++d) {
    for (int k = -2000; k <= 2000; ++k) {
      for (const double denominator : {2.0, 4.0, 8.0, 16.0, 1024.0}) {
        const double tie = (k + 0.5) / denominator;
        for (const double value : {tie, std::nextafter(tie, 1e300), std::nextafter(tie, -1e300)}) {
          ASSERT_EQ(fast(value, d), reference(value, d)) << value << " with " << d << " decimals";
        }
      }
      const double decimal_tie = (k + 0.5) / std::pow(10.0, d);
      ASSERT_EQ(fast(decimal_tie, d), reference(decimal_tie, d)) << decimal_tie << " with " << d << " decimals";
    }
  }
  EXPECT_EQ(fast(2.675, 2), "2.67");  // 2.67499999999999982236431605997495353221893310546875
  EXPECT_EQ(fast(0.5, 0), reference(0.5, 0));
  EXPECT_EQ(fast(2.5, 0), reference(2.5, 0));
}

TEST(DecimalText, SpecialValuesAndLimits) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const double value : {0.0, -0.0, -1e-7, 1e-7, -0.00004, 4.0e15, -4.0e15, 3.99999999e15, 1e20, -1e300, inf, -inf,
                             nan, -nan, std::numeric_limits<double>::denorm_min(), 9007199254740993.0}) {
    for (int d = 0; d <= 17; ++d) {
      EXPECT_EQ(fast(value, d), reference(value, d)) << value << " with " << d << " decimals";
    }
  }
  EXPECT_EQ(fast(-0.00004, 4), "-0.0000");  // the sign of a value rounding to zero is kept
  EXPECT_EQ(fast(22709884.44575, 4), reference(22709884.44575, 4));
}

TEST(DecimalText, CsvRowsBuiltInTheirBufferComeOutWhole) {
  std::string out = "head\n";
  {
    CsvRow row(out);
    row.empty(2).text("a").fixed(-1.25, 1).integer(-42).raw(",,").empty().fixed(0.5, 0).end();
  }
  EXPECT_EQ(out, "head\n,,a,-1.2,-42,,,,,0\n");  // -1.25 and 0.5 are exact ties: to_chars's rounding
  // A row longer than the buffer, and a text cell longer than half of it.
  out.clear();
  const std::string long_text(1500, 'x');
  {
    CsvRow row(out);
    for (int i = 0; i < 400; ++i) row.fixed(22709884.4458 + i, 4);
    row.text(long_text).text("end");
  }  // no end(): the cells come out when the row goes
  std::string expected;
  for (int i = 0; i < 400; ++i) {
    if (i > 0) expected += ',';
    append_fixed_slow(expected, 22709884.4458 + i, 4);
  }
  expected += "," + long_text + ",end";
  EXPECT_EQ(out, expected);
}

}  // namespace
}  // namespace skytrace

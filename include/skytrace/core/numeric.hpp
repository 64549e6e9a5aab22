// Conversions of numbers read from files, where any double may arrive (1e40, NaN): a cast to an
// integer outside the integer's range is undefined behaviour, so readers convert through these.
#pragma once

#include <limits>
#include <optional>

namespace skytrace {

// `value` truncated toward zero like static_cast<int>, or nullopt when it is not finite or the
// result would fall outside [min_value, max_value].
[[nodiscard]] constexpr std::optional<int> to_int_within(double value, int min_value = std::numeric_limits<int>::min(),
                                                         int max_value = std::numeric_limits<int>::max()) {
  // Truncation maps exactly (min - 1, max + 1) onto [min, max]; NaN fails both comparisons.
  if (!(value > static_cast<double>(min_value) - 1.0 && value < static_cast<double>(max_value) + 1.0)) {
    return std::nullopt;
  }
  return static_cast<int>(value);
}

}  // namespace skytrace

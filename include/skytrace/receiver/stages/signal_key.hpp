// Keys of the per (satellite, signal) state the stages keep from epoch to epoch: a hash for the
// maps (looked up several times per signal and epoch) and the words of the random stream keys.
#pragma once

#include <cstdint>
#include <functional>
#include <utility>

#include "skytrace/core/signal.hpp"

namespace skytrace::receiver::stages {

using SignalKey = std::pair<SatelliteId, Signal>;

struct SignalKeyHash {
  std::size_t operator()(const SignalKey& k) const noexcept {
    return std::hash<std::uint32_t>{}(static_cast<std::uint32_t>(k.first.system) << 24 |
                                      static_cast<std::uint32_t>(k.first.number) << 16 |
                                      static_cast<std::uint32_t>(static_cast<unsigned char>(k.second.band)) << 8 |
                                      static_cast<std::uint32_t>(static_cast<unsigned char>(k.second.attribute)));
  }
};

// Words of stream_key (core/random.hpp) for a satellite and a signal.
[[nodiscard]] inline std::uint64_t satellite_key(const SatelliteId& sat) {
  return (static_cast<std::uint64_t>(sat.system) << 8) | sat.number;
}
[[nodiscard]] inline std::uint64_t signal_key(const Signal& signal) {
  return (static_cast<std::uint64_t>(signal.system) << 16) | (static_cast<std::uint64_t>(signal.band) << 8) |
         static_cast<std::uint64_t>(signal.attribute);
}

}  // namespace skytrace::receiver::stages

// Deterministic random streams. No global generator: every stream is derived from the scenario
// seed and the names of what it perturbs (model, satellite, signal), so adding a satellite or a
// model changes no one else's numbers, and results are identical on every platform (the standard
// library's distributions are implementation-defined, so the distributions here are our own).
#pragma once

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <string_view>

namespace skytrace {

// 64-bit mix (SplitMix64 finaliser).
constexpr std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// FNV-1a of a name, to key streams by model name.
constexpr std::uint64_t hash_name(std::string_view name) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (char c : name) {
    h ^= static_cast<unsigned char>(c);
    h *= 0x100000001b3ULL;
  }
  return h;
}

// Key of a stream from a seed and any number of identifying integers.
constexpr std::uint64_t stream_key(std::uint64_t seed, std::initializer_list<std::uint64_t> parts) {
  std::uint64_t key = mix64(seed);
  for (std::uint64_t part : parts) key = mix64(key ^ part);
  return key;
}

// xoshiro256** generator with uniform and Gaussian draws.
class RandomStream {
 public:
  explicit RandomStream(std::uint64_t key) {
    std::uint64_t s = key;
    for (auto& word : state_) {
      s += 0x9e3779b97f4a7c15ULL;
      word = mix64(s);
    }
  }

  std::uint64_t next_u64() {
    const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }
  // Uniform in [0, 1).
  double uniform() { return static_cast<double>(next_u64() >> 11) * 0x1.0p-53; }
  // Standard normal (Marsaglia polar method; the spare value is kept).
  double gaussian() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u = 0.0, v = 0.0, s = 0.0;
    do {
      u = 2.0 * uniform() - 1.0;
      v = 2.0 * uniform() - 1.0;
      s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double factor = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * factor;
    has_spare_ = true;
    return u * factor;
  }
  // Uniform integer in [low, high].
  std::int64_t uniform_int(std::int64_t low, std::int64_t high) {
    const auto span = static_cast<std::uint64_t>(high - low) + 1;
    return low + static_cast<std::int64_t>(next_u64() % span);
  }

 private:
  static constexpr std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t state_[4]{};
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace skytrace

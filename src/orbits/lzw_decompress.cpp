// Decoder for Unix `compress` (.Z) files, the format of the older IGS archive products.
//
// Format (as written by compress 4.x and read by gzip's unlzw): bytes 1f 9d, a flag byte (low five
// bits: the largest code width, 9..16; bit 7: block mode, in which code 256 clears the table),
// then LZW codes packed least-significant bit first, starting 9 bits wide. compress emits codes in
// groups of eight (one group = `width` bytes); whenever the width grows or the table is cleared it
// pads the current group to its full size, so the reader must skip to the next group boundary,
// measured from where the previous width began.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/orbits/fetch.hpp"

namespace skytrace::orbits {

namespace {

constexpr unsigned kMagic0 = 0x1f;
constexpr unsigned kMagic1 = 0x9d;
constexpr unsigned kBitsMask = 0x1f;
constexpr unsigned kBlockModeFlag = 0x80;
constexpr int kInitialBits = 9;
constexpr int kMinMaxBits = 9;
constexpr int kMaxMaxBits = 16;
constexpr std::uint32_t kClearCode = 256;

}  // namespace

Result<std::string> uncompress_lzw(std::string_view data) {
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  if (data.size() < 3 || bytes[0] != kMagic0 || bytes[1] != kMagic1) {
    return make_error(ErrorCode::kParse, "not Unix compress (.Z) data (no 1f 9d magic number)");
  }
  const int max_bits = static_cast<int>(bytes[2] & kBitsMask);
  const bool block_mode = (bytes[2] & kBlockModeFlag) != 0;
  if (max_bits < kMinMaxBits || max_bits > kMaxMaxBits) {
    return make_error(ErrorCode::kParse, ".Z data with unsupported maximum code width of " + std::to_string(max_bits) +
                                             " bits (expected 9..16)");
  }
  const std::uint32_t table_size = std::uint32_t{1} << max_bits;  // codes are < table_size
  std::vector<std::uint16_t> prefix(table_size, 0);
  std::vector<unsigned char> suffix(table_size, 0);
  for (std::uint32_t i = 0; i < 256; ++i) suffix[i] = static_cast<unsigned char>(i);

  const unsigned char* codes = bytes + 3;
  const std::uint64_t total_bits = static_cast<std::uint64_t>(data.size() - 3) * 8;
  std::uint64_t position_bits = 0;     // next code's first bit
  std::uint64_t group_origin_bits = 0; // where the current code width began
  int width_bits = kInitialBits;
  std::uint32_t max_code = (std::uint32_t{1} << width_bits) - 1;
  std::uint32_t next_free = block_mode ? kClearCode + 1 : kClearCode;
  std::int64_t previous = -1;  // previous code, -1 before the first one
  unsigned char first_char = 0;

  // Skip the padding that completes the current group of eight codes.
  const auto skip_to_group_end = [&]() {
    const std::uint64_t group_bits = static_cast<std::uint64_t>(width_bits) * 8;
    const std::uint64_t used = position_bits - group_origin_bits;
    position_bits = group_origin_bits + (used + group_bits - 1) / group_bits * group_bits;
    group_origin_bits = position_bits;
  };

  std::string out;
  out.reserve(data.size() * 3);
  std::vector<unsigned char> stack;
  stack.reserve(table_size);

  while (position_bits + static_cast<std::uint64_t>(width_bits) <= total_bits) {
    if (next_free > max_code) {
      skip_to_group_end();
      ++width_bits;
      max_code = width_bits == max_bits ? table_size : (std::uint32_t{1} << width_bits) - 1;
      continue;
    }
    // A code spans at most three bytes (16 bits starting at any bit offset).
    const std::uint64_t byte_index = position_bits >> 3;
    std::uint32_t window = 0;
    for (std::uint64_t k = 0; k < 3 && byte_index + k < data.size() - 3; ++k) {
      window |= static_cast<std::uint32_t>(codes[byte_index + k]) << (8 * k);
    }
    std::uint32_t code = (window >> (position_bits & 7)) & ((std::uint32_t{1} << width_bits) - 1);
    position_bits += static_cast<std::uint64_t>(width_bits);

    if (previous < 0) {
      if (code >= 256) {
        return make_error(ErrorCode::kParse, "corrupt .Z data: first code " + std::to_string(code) + " is not a literal");
      }
      first_char = static_cast<unsigned char>(code);
      out.push_back(static_cast<char>(first_char));
      previous = code;
      continue;
    }
    if (block_mode && code == kClearCode) {
      // Entry 256 is rewritten (harmlessly) by the next code, exactly as compress expects.
      next_free = kClearCode;
      skip_to_group_end();
      width_bits = kInitialBits;
      max_code = (std::uint32_t{1} << width_bits) - 1;
      continue;
    }
    const std::uint32_t this_code = code;
    stack.clear();
    if (code >= next_free) {
      // With the table full (next_free == table_size, reachable at 9 bits, where the width still
      // grows to 10 as in compress) no entry code == next_free is ever made: refuse it, else it
      // would become `previous` and index one past the tables.
      if (code > next_free || next_free == table_size) {
        return make_error(ErrorCode::kParse, "corrupt .Z data: code " + std::to_string(code) +
                                                 " is beyond the table (next free entry " + std::to_string(next_free) +
                                                 ") at byte " + std::to_string(3 + (position_bits >> 3)));
      }
      // The "cScSc" case: the string is the previous one plus its own first character.
      stack.push_back(first_char);
      code = static_cast<std::uint32_t>(previous);
    }
    while (code >= 256) {
      stack.push_back(suffix[code]);
      code = prefix[code];
      if (stack.size() > table_size) return make_error(ErrorCode::kParse, "corrupt .Z data: looping code table");
    }
    first_char = suffix[code];
    stack.push_back(first_char);
    out.append(stack.rbegin(), stack.rend());
    if (next_free < table_size) {
      prefix[next_free] = static_cast<std::uint16_t>(previous);
      suffix[next_free] = first_char;
      ++next_free;
    }
    previous = this_code;
  }
  return out;
}

}  // namespace skytrace::orbits

#include "skytrace/ros2/cdr.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

namespace skytrace::ros2 {
namespace {
constexpr size_t kEncapsulationBytes = 4;
}

CdrWriter::CdrWriter(std::vector<std::uint8_t>&& storage) : buffer_(std::move(storage)) {
  buffer_.assign(std::begin(kCdrLittleEndian), std::end(kCdrLittleEndian));
}

CdrWriter::CdrWriter() {
  buffer_.reserve(256);
  buffer_.assign(std::begin(kCdrLittleEndian), std::end(kCdrLittleEndian));
}

void CdrWriter::align(size_t alignment) {
  const size_t offset = buffer_.size() - kEncapsulationBytes;
  const size_t padding = (alignment - offset % alignment) % alignment;
  buffer_.insert(buffer_.end(), padding, 0);
}


void CdrWriter::write_string(std::string_view text) {
  write_u32(static_cast<std::uint32_t>(text.size() + 1));
  buffer_.insert(buffer_.end(), text.begin(), text.end());
  buffer_.push_back(0);
}

void CdrWriter::write_byte_sequence(std::span<const std::uint8_t> bytes) {
  write_count(bytes.size());
  write_raw(bytes);
}

CdrReader::CdrReader(std::span<const std::uint8_t> message) {
  if (message.size() < kEncapsulationBytes) {
    fail("shorter than the 4-byte CDR encapsulation header");
    return;
  }
  // Representation identifier: 0x0000 CDR_BE, 0x0001 CDR_LE (PL_CDR and XCDR2 are not used by ROS 2's rmw).
  if (message[0] != 0 || message[1] > 1) {
    fail("unsupported CDR representation " + std::to_string(message[0]) + "," + std::to_string(message[1]) +
         " (expected CDR_LE 0x0001 or CDR_BE 0x0000)");
    return;
  }
  big_endian_ = message[1] == 0;
  data_ = message.subspan(kEncapsulationBytes);
}

void CdrReader::fail(std::string why) {
  if (error_.empty()) error_ = std::move(why);
  position_ = data_.size();
}

bool CdrReader::align(size_t alignment) {
  const size_t padding = (alignment - position_ % alignment) % alignment;
  if (padding > remaining()) {
    fail("truncated at byte " + std::to_string(position_ + kEncapsulationBytes));
    return false;
  }
  position_ += padding;
  return true;
}

template <typename T>
T CdrReader::read_primitive() {
  if (!ok() || !align(sizeof(T))) return T{};
  if (remaining() < sizeof(T)) {
    fail("truncated at byte " + std::to_string(position_ + kEncapsulationBytes));
    return T{};
  }
  std::uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, data_.data() + position_, sizeof(T));
  if (big_endian_) std::reverse(bytes, bytes + sizeof(T));
  position_ += sizeof(T);
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

template std::uint16_t CdrReader::read_primitive<std::uint16_t>();
template std::int16_t CdrReader::read_primitive<std::int16_t>();
template std::uint32_t CdrReader::read_primitive<std::uint32_t>();
template std::int32_t CdrReader::read_primitive<std::int32_t>();
template std::uint64_t CdrReader::read_primitive<std::uint64_t>();
template std::int64_t CdrReader::read_primitive<std::int64_t>();
template float CdrReader::read_primitive<float>();
template double CdrReader::read_primitive<double>();

std::uint8_t CdrReader::read_u8() {
  if (!ok()) return 0;
  if (remaining() < 1) {
    fail("truncated at byte " + std::to_string(position_ + kEncapsulationBytes));
    return 0;
  }
  return data_[position_++];
}

bool CdrReader::read_bool() {
  const std::uint8_t value = read_u8();
  if (value > 1) fail("boolean of value " + std::to_string(value) + " (expected 0 or 1)");
  return value == 1;
}

std::string CdrReader::read_string() {
  const std::uint32_t length = read_u32();
  if (!ok()) return {};
  if (length == 0) return {};  // some writers send an empty string without its NUL
  if (length > remaining()) {
    fail("string of " + std::to_string(length) + " bytes with " + std::to_string(remaining()) + " left");
    return {};
  }
  const char* begin = reinterpret_cast<const char*>(data_.data() + position_);
  position_ += length;
  if (begin[length - 1] != '\0') {
    fail("string not terminated by NUL");
    return {};
  }
  return std::string(begin, length - 1);
}

size_t CdrReader::read_count(size_t min_element_bytes) {
  const std::uint32_t count = read_u32();
  if (!ok()) return 0;
  if (min_element_bytes > 0 && count > remaining() / min_element_bytes) {
    fail("sequence of " + std::to_string(count) + " elements with " + std::to_string(remaining()) + " bytes left");
    return 0;
  }
  return count;
}

std::vector<std::uint8_t> CdrReader::read_byte_sequence() {
  const size_t count = read_count(1);
  if (!ok()) return {};
  std::vector<std::uint8_t> bytes(data_.begin() + static_cast<std::ptrdiff_t>(position_),
                                  data_.begin() + static_cast<std::ptrdiff_t>(position_ + count));
  position_ += count;
  return bytes;
}

void CdrReader::read_raw(std::span<std::uint8_t> out) {
  if (!ok()) return;
  if (out.size() > remaining()) {
    fail("truncated at byte " + std::to_string(position_ + kEncapsulationBytes));
    return;
  }
  std::memcpy(out.data(), data_.data() + position_, out.size());
  position_ += out.size();
}

}  // namespace skytrace::ros2

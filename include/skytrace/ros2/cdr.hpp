// OMG CDR (XCDR version 1, little endian) as ROS 2's middlewares put a message on the wire and
// rosbag2 stores it: a 4-byte encapsulation header (0x00 0x01 0x00 0x00, CDR_LE), then the fields in
// order, each primitive aligned to its own size counted from the end of the header; strings as a
// uint32 length that counts the terminating NUL, the bytes and the NUL; sequences as a uint32 count
// and the elements; fixed arrays as the elements only.
#pragma once

#include <cstddef>
#include <bit>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"

namespace skytrace::ros2 {

inline constexpr std::uint8_t kCdrLittleEndian[4] = {0x00, 0x01, 0x00, 0x00};

class CdrWriter {
 public:
  CdrWriter();  // starts with the encapsulation header
  // The same, writing into `storage` (cleared; its capacity is reused).
  explicit CdrWriter(std::vector<std::uint8_t>&& storage);
  void write_bool(bool value) { write_u8(value ? 1 : 0); }
  void write_u8(std::uint8_t value) { buffer_.push_back(value); }
  void write_i8(std::int8_t value) { write_u8(static_cast<std::uint8_t>(value)); }
  void write_u16(std::uint16_t value) { write_primitive(value); }
  void write_i16(std::int16_t value) { write_primitive(value); }
  void write_u32(std::uint32_t value) { write_primitive(value); }
  void write_i32(std::int32_t value) { write_primitive(value); }
  void write_u64(std::uint64_t value) { write_primitive(value); }
  void write_i64(std::int64_t value) { write_primitive(value); }
  void write_f32(float value) { write_primitive(value); }
  void write_f64(double value) { write_primitive(value); }
  void write_string(std::string_view text);
  // A sequence's element count (the elements follow).
  void write_count(size_t count) { write_u32(static_cast<std::uint32_t>(count)); }
  // uint8[] / char[]: count and bytes.
  void write_byte_sequence(std::span<const std::uint8_t> bytes);
  // uint8[N] / char[N]: the bytes only.
  void write_raw(std::span<const std::uint8_t> bytes) { buffer_.insert(buffer_.end(), bytes.begin(), bytes.end()); }

  [[nodiscard]] size_t size() const { return buffer_.size(); }
  [[nodiscard]] std::vector<std::uint8_t> take() { return std::move(buffer_); }

 private:
  // Inline: a message is mostly primitives, and a call per double costs more than the copy.
  template <typename T>
  void write_primitive(T value) {
    static_assert(std::endian::native == std::endian::little, "CdrWriter writes little-endian CDR on little-endian hosts");
    // Aligned to the value's size counted after the 4-byte encapsulation header; the padding is
    // zero-filled by resize.
    const size_t offset = buffer_.size() - 4;
    const size_t start = buffer_.size() + (sizeof(T) - offset % sizeof(T)) % sizeof(T);
    buffer_.resize(start + sizeof(T));
    std::memcpy(buffer_.data() + start, &value, sizeof(T));
  }
  void align(size_t alignment);
  std::vector<std::uint8_t> buffer_;
};

// Reads what CdrWriter writes (and big-endian payloads, encapsulation 0x00 0x00). Errors do not
// throw: the first one is kept, later reads return zeros, and ok()/error() tell the caller.
class CdrReader {
 public:
  explicit CdrReader(std::span<const std::uint8_t> message);
  [[nodiscard]] bool read_bool();
  [[nodiscard]] std::uint8_t read_u8();
  [[nodiscard]] std::int8_t read_i8() { return static_cast<std::int8_t>(read_u8()); }
  [[nodiscard]] std::uint16_t read_u16() { return read_primitive<std::uint16_t>(); }
  [[nodiscard]] std::int16_t read_i16() { return read_primitive<std::int16_t>(); }
  [[nodiscard]] std::uint32_t read_u32() { return read_primitive<std::uint32_t>(); }
  [[nodiscard]] std::int32_t read_i32() { return read_primitive<std::int32_t>(); }
  [[nodiscard]] std::uint64_t read_u64() { return read_primitive<std::uint64_t>(); }
  [[nodiscard]] std::int64_t read_i64() { return read_primitive<std::int64_t>(); }
  [[nodiscard]] float read_f32() { return read_primitive<float>(); }
  [[nodiscard]] double read_f64() { return read_primitive<double>(); }
  [[nodiscard]] std::string read_string();
  // A sequence's element count, refused (0 and an error) when the elements, each at least
  // `min_element_bytes` long, cannot fit in what is left of the message.
  [[nodiscard]] size_t read_count(size_t min_element_bytes = 1);
  [[nodiscard]] std::vector<std::uint8_t> read_byte_sequence();
  void read_raw(std::span<std::uint8_t> out);

  [[nodiscard]] bool ok() const { return error_.empty(); }
  [[nodiscard]] const std::string& error() const { return error_; }
  [[nodiscard]] size_t remaining() const { return data_.size() - position_; }
  void fail(std::string why);

 private:
  template <typename T>
  T read_primitive();
  bool align(size_t alignment);
  std::span<const std::uint8_t> data_;  // after the encapsulation header
  size_t position_ = 0;
  bool big_endian_ = false;
  std::string error_;
};

}  // namespace skytrace::ros2

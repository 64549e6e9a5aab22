// An MCAP writer (https://mcap.dev/spec, major version 0), written from the specification: the
// indexed, chunked layout that rosbag2's MCAP storage and Foxglove read.
//
//   Magic Header [Schema|Channel|Metadata|Chunk MessageIndex...]* DataEnd
//   Schema* Channel* Statistics ChunkIndex* MetadataIndex* SummaryOffset* Footer Magic
//
// Messages are collected in a chunk of about `chunk_size_bytes` (uncompressed records) that is
// compressed and written as soon as it is full, followed by one Message Index record per channel;
// only the chunk being filled, the schemas and channels and one Chunk Index per written chunk stay
// in memory, so memory does not grow with the number of messages. Schema, Channel and Metadata
// records go straight into the data section (before any chunk that uses them) and are repeated in
// the summary. Every write, and the final close, is checked: a failure (a full disk, a file size
// limit) is returned as ErrorCode::kOutput and the writer refuses everything afterwards.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <span>
#include <string>

#include "skytrace/core/error.hpp"

namespace skytrace::io {

struct McapOptions {
  std::string compression = "zstd";       // "zstd", "lz4" (LZ4 frame format) or "" (none)
  size_t chunk_size_bytes = size_t{1} << 20;  // a chunk is written once its records reach this size
  std::string profile = "ros2";
  std::string library;  // Header's library field; empty: "skytrace <version>"
  // Chunks compressed and written on a thread of the writer's own while the caller fills the next
  // one; false: on the caller's thread (a run limited to one thread). The file is the same.
  bool worker_thread = true;
};

// What has been written so far (Statistics record contents).
struct McapStatistics {
  std::uint64_t message_count = 0;
  std::uint32_t chunk_count = 0;
  std::uint64_t message_start_time_ns = 0;  // 0 while there is no message
  std::uint64_t message_end_time_ns = 0;
  std::map<std::uint16_t, std::uint64_t> channel_message_counts;  // channels with messages only
};

class McapWriter {
 public:
  // Creates (or truncates) the file and starts it. A path that cannot be opened for writing (a
  // folder, a missing parent, no permission) is an ErrorCode::kOutput error.
  [[nodiscard]] static Result<std::unique_ptr<McapWriter>> open(const std::filesystem::path& path,
                                                                McapOptions options = {});
  // Closes the file without finishing it when close() was not called (an error path: the file is
  // then incomplete and the caller discards it).
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  // A schema (e.g. name "sensor_msgs/msg/NavSatFix", encoding "ros2msg", the definition text).
  // Adding the same name, encoding and data again returns the first one's id.
  [[nodiscard]] Result<std::uint16_t> add_schema(std::string name, std::string encoding, std::string data);
  // A channel on `topic` whose messages follow `schema_id` (0: no schema).
  [[nodiscard]] Result<std::uint16_t> add_channel(std::uint16_t schema_id, std::string topic,
                                                  std::string message_encoding,
                                                  std::map<std::string, std::string> metadata);
  // A Metadata record (name and key-value pairs), indexed in the summary.
  [[nodiscard]] Status add_metadata(std::string name, std::map<std::string, std::string> metadata);
  // One message; the bytes are copied into the current chunk.
  [[nodiscard]] Status write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                             std::span<const std::uint8_t> data);
  // Writes the last chunk, Data End, the summary, the summary offsets and the footer, and closes
  // the file. Calling it again returns the first call's outcome.
  [[nodiscard]] Status close();

  [[nodiscard]] const McapStatistics& statistics() const;
  [[nodiscard]] const std::filesystem::path& path() const;

 private:
  struct State;
  explicit McapWriter(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

// The library string written by default ("skytrace 0.1.0").
[[nodiscard]] std::string mcap_library_name();

}  // namespace skytrace::io

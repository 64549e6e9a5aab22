#include "skytrace/io/mcap.hpp"

#include "skytrace/core/version.hpp"

#include <fcntl.h>
#include <lz4frame.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>
#include <cstring>
#include <iterator>
#include <limits>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>


namespace skytrace::io {
namespace {

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
constexpr size_t kRecordPrefixBytes = 1 + 8;          // opcode and uint64 content length
constexpr size_t kFileFlushBytes = size_t{64} << 10;  // small records are gathered up to this size
// Level 1, as rosbag2's "zstd_fast" preset: measured on an hour of ESBC at 1 Hz (scripts/bench-mcap)
// it compresses the bag about as well as level 3 at half the CPU time.
constexpr int kZstdLevel = 1;

// Little-endian serialization into a byte vector, as every MCAP field is written.
class ByteSink {
 public:
  explicit ByteSink(std::vector<std::uint8_t>& out) : out_(out) {}
  void u8(std::uint8_t value) { out_.push_back(value); }
  void u16(std::uint16_t value) { little_endian(value, 2); }
  void u32(std::uint32_t value) { little_endian(value, 4); }
  void u64(std::uint64_t value) { little_endian(value, 8); }
  void bytes(std::span<const std::uint8_t> data) { out_.insert(out_.end(), data.begin(), data.end()); }
  void bytes(std::string_view text) { out_.insert(out_.end(), text.begin(), text.end()); }
  void string(std::string_view text) {  // String and uint32 length-prefixed Bytes
    u32(static_cast<std::uint32_t>(text.size()));
    bytes(text);
  }
  // A record: opcode, then a content length patched by end_record().
  size_t begin_record(Opcode opcode) {
    u8(opcode);
    const size_t length_at = out_.size();
    u64(0);
    return length_at;
  }
  void end_record(size_t length_at) { patch(length_at, out_.size() - length_at - 8, 8); }
  // A Map or Array: uint32 byte length, patched by end_length32().
  size_t begin_length32() {
    const size_t length_at = out_.size();
    u32(0);
    return length_at;
  }
  void end_length32(size_t length_at) { patch(length_at, out_.size() - length_at - 4, 4); }
  void string_map(const std::map<std::string, std::string>& map) {
    const size_t at = begin_length32();
    for (const auto& [key, value] : map) {
      string(key);
      string(value);
    }
    end_length32(at);
  }
  [[nodiscard]] size_t size() const { return out_.size(); }

 private:
  void little_endian(std::uint64_t value, int byte_count) {
    for (int i = 0; i < byte_count; ++i) out_.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
  }
  void patch(size_t at, std::uint64_t value, int byte_count) {
    for (int i = 0; i < byte_count; ++i) out_[at + static_cast<size_t>(i)] = static_cast<std::uint8_t>(value >> (8 * i));
  }
  std::vector<std::uint8_t>& out_;
};

std::uint32_t crc32_update(std::uint32_t crc, std::span<const std::uint8_t> data) {
  // zlib takes uInt lengths: feed large buffers in pieces.
  constexpr size_t kPiece = size_t{1} << 30;
  uLong value = crc;
  for (size_t at = 0; at < data.size(); at += kPiece) {
    const size_t n = std::min(kPiece, data.size() - at);
    value = ::crc32(value, data.data() + at, static_cast<uInt>(n));
  }
  return static_cast<std::uint32_t>(value);
}

std::string errno_text(int error_number) {
  if (error_number == ENOSPC) return "no space left on the device";
  if (error_number == EFBIG) return "file size limit exceeded";
  return std::strerror(error_number);
}

struct SchemaRecord {
  std::uint16_t id = 0;
  std::string name, encoding, data;
};
struct ChannelRecord {
  std::uint16_t id = 0, schema_id = 0;
  std::string topic, message_encoding;
  std::map<std::string, std::string> metadata;
};
struct ChunkIndexEntry {
  std::uint64_t message_start_time = 0, message_end_time = 0;
  std::uint64_t chunk_start_offset = 0, chunk_length = 0;
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  std::uint64_t message_index_length = 0;
  std::uint64_t compressed_size = 0, uncompressed_size = 0;
};
struct MetadataIndexEntry {
  std::uint64_t offset = 0, length = 0;
  std::string name;
};

void append_schema(ByteSink& sink, const SchemaRecord& schema) {
  const size_t at = sink.begin_record(kSchema);
  sink.u16(schema.id);
  sink.string(schema.name);
  sink.string(schema.encoding);
  sink.string(schema.data);
  sink.end_record(at);
}

void append_channel(ByteSink& sink, const ChannelRecord& channel) {
  const size_t at = sink.begin_record(kChannel);
  sink.u16(channel.id);
  sink.u16(channel.schema_id);
  sink.string(channel.topic);
  sink.string(channel.message_encoding);
  sink.string_map(channel.metadata);
  sink.end_record(at);
}

// A filled chunk on its way to the file: its uncompressed records and, per channel, (log time,
// offset in it) of its messages.
struct ChunkJob {
  std::vector<std::uint8_t> records;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> message_index;
  std::uint64_t start_time = 0, end_time = 0;
  bool has_messages = false;
};

}  // namespace

// Chunks are compressed and written by a worker thread while the caller fills the next one (at
// most kQueuedChunks wait, so memory stays bounded); everything else that goes into the file waits
// until the worker is idle (drain), so records keep their order.
struct McapWriter::State {
  static constexpr size_t kQueuedChunks = 2;
  std::filesystem::path path;
  McapOptions options;
  int fd = -1;

  std::vector<std::uint8_t> pending;  // bytes for the file not written yet
  std::uint64_t written_bytes = 0;    // bytes already in the file
  std::uint32_t data_section_crc = 0;
  bool in_data_section = true;
  std::optional<Error> failure;  // the first write error; every later call returns it (under `mutex`)
  bool closed = false;

  std::mutex mutex;
  std::condition_variable changed;
  std::deque<ChunkJob> jobs;
  bool worker_busy = false, stopping = false;
  std::vector<std::vector<std::uint8_t>> spare_chunks;  // written chunks' buffers, for reuse
  std::thread worker;

  std::vector<SchemaRecord> schemas;    // id = index + 1
  std::vector<ChannelRecord> channels;  // id = index + 1 (as the reference writers count)
  std::vector<std::uint32_t> sequences;  // next Message sequence number of each channel
  std::vector<MetadataIndexEntry> metadata_indexes;
  std::vector<ChunkIndexEntry> chunk_indexes;
  McapStatistics statistics;

  // The chunk being filled: its uncompressed records and, per channel, (log time, offset in it).
  std::vector<std::uint8_t> chunk;
  std::uint64_t chunk_start_time = 0, chunk_end_time = 0;
  bool chunk_has_messages = false;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_message_index;
  std::vector<std::uint8_t> compressed;  // reused between chunks
  ZSTD_CCtx* zstd = nullptr;

  ~State() {
    stop_worker();
    if (zstd != nullptr) ZSTD_freeCCtx(zstd);
    if (fd >= 0) ::close(fd);
  }

  void stop_worker() {
    if (!worker.joinable()) return;
    {
      std::lock_guard lock(mutex);
      stopping = true;
    }
    changed.notify_all();
    worker.join();
  }

  void work() {
    std::unique_lock lock(mutex);
    for (;;) {
      changed.wait(lock, [&] { return stopping || !jobs.empty(); });
      if (jobs.empty()) return;  // stopping, nothing left
      ChunkJob job = std::move(jobs.front());
      jobs.pop_front();
      worker_busy = true;
      const bool failed = failure.has_value();
      lock.unlock();
      Status written = failed ? Status(Ok{}) : write_chunk(job);
      lock.lock();
      if (!written.ok() && !failure) failure = written.error();
      job.records.clear();
      spare_chunks.push_back(std::move(job.records));
      worker_busy = false;
      changed.notify_all();
    }
  }

  // Waits until every handed-over chunk is in the file; the first failure if any.
  Status drain() {
    std::unique_lock lock(mutex);
    changed.wait(lock, [&] { return jobs.empty() && !worker_busy; });
    if (failure) return *failure;
    return Ok{};
  }

  [[nodiscard]] std::uint64_t offset() const { return written_bytes + pending.size(); }

  Error output_error(const std::string& what) const {
    return make_error(ErrorCode::kOutput, path.string() + ": " + what);
  }

  // Refuses calls after a failure or after close().
  [[nodiscard]] std::optional<Error> usable() {
    std::lock_guard lock(mutex);
    if (failure) return failure;
    if (closed) return output_error("MCAP writer already closed");
    return std::nullopt;
  }

  Status fail(Error error) {
    std::lock_guard lock(mutex);
    if (!failure) failure = std::move(error);
    return *failure;
  }

  Status flush() {
    size_t done = 0;
    while (done < pending.size()) {
      const ssize_t n = ::write(fd, pending.data() + done, pending.size() - done);
      if (n < 0) {
        if (errno == EINTR) continue;
        return fail(output_error("write failed (" + errno_text(errno) + ")"));
      }
      done += static_cast<size_t>(n);
    }
    written_bytes += pending.size();
    pending.clear();
    return Ok{};
  }

  // Hands bytes to the file (through `pending`), keeping the data section's CRC.
  Status emit(std::span<const std::uint8_t> bytes) {
    if (in_data_section) data_section_crc = crc32_update(data_section_crc, bytes);
    pending.insert(pending.end(), bytes.begin(), bytes.end());
    if (pending.size() >= kFileFlushBytes) return flush();
    return Ok{};
  }

  Result<std::span<const std::uint8_t>> compress_chunk(const std::vector<std::uint8_t>& records) {
    const std::string& method = options.compression;
    if (method.empty()) return std::span<const std::uint8_t>(records);
    if (method == "zstd") {
      if (zstd == nullptr) zstd = ZSTD_createCCtx();
      if (zstd == nullptr) return output_error("zstd: cannot create a compression context");
      compressed.resize(ZSTD_compressBound(records.size()));
      const size_t n = ZSTD_compressCCtx(zstd, compressed.data(), compressed.size(), records.data(), records.size(), kZstdLevel);
      if (ZSTD_isError(n) != 0U) return output_error(std::string("zstd: ") + ZSTD_getErrorName(n));
      return std::span<const std::uint8_t>(compressed.data(), n);
    }
    // lz4: the LZ4 frame format (magic 0x184D2204), which MCAP readers expect.
    LZ4F_preferences_t preferences;
    std::memset(&preferences, 0, sizeof preferences);
    preferences.frameInfo.contentSize = records.size();
    compressed.resize(LZ4F_compressFrameBound(records.size(), &preferences));
    const size_t n = LZ4F_compressFrame(compressed.data(), compressed.size(), records.data(), records.size(), &preferences);
    if (LZ4F_isError(n) != 0U) return output_error(std::string("lz4: ") + LZ4F_getErrorName(n));
    return std::span<const std::uint8_t>(compressed.data(), n);
  }

  // Hands the chunk being filled (if any) to the worker, which writes it; the worker's failure, if
  // one has happened.
  Status finish_chunk() {
    if (chunk.empty()) return Ok{};
    ChunkJob job;
    job.records = std::move(chunk);
    job.message_index = std::move(chunk_message_index);
    job.start_time = chunk_start_time;
    job.end_time = chunk_end_time;
    job.has_messages = chunk_has_messages;
    chunk_message_index.clear();
    chunk_has_messages = false;
    ++statistics.chunk_count;
    if (!options.worker_thread) {
      Status written = write_chunk(job);
      chunk = std::move(job.records);  // keeps its capacity for the next chunk
      chunk.clear();
      if (!written.ok()) {
        std::lock_guard lock(mutex);
        if (!failure) failure = written.error();
      }
      return written;
    }
    std::unique_lock lock(mutex);
    chunk.clear();
    if (!spare_chunks.empty()) {
      chunk = std::move(spare_chunks.back());  // keeps its capacity: the next chunk reuses the memory
      spare_chunks.pop_back();
    }
    if (!worker.joinable()) worker = std::thread([this] { work(); });
    changed.wait(lock, [&] { return jobs.size() < kQueuedChunks; });
    if (failure) return *failure;
    jobs.push_back(std::move(job));
    changed.notify_all();
    return Ok{};
  }

  // Writes a chunk, its Message Index records, and remembers its index (the worker's part, or the
  // caller's once the worker has stopped).
  Status write_chunk(ChunkJob& job) {
    const std::vector<std::uint8_t>& records = job.records;
    const std::uint32_t uncompressed_crc = crc32_update(0, records);
    auto body = compress_chunk(records);
    if (!body.ok()) return fail(body.error());

    ChunkIndexEntry entry;
    entry.message_start_time = job.has_messages ? job.start_time : 0;
    entry.message_end_time = job.has_messages ? job.end_time : 0;
    entry.chunk_start_offset = offset();
    entry.compressed_size = body->size();
    entry.uncompressed_size = records.size();

    std::vector<std::uint8_t> head;
    ByteSink sink(head);
    const size_t at = sink.begin_record(kChunk);
    sink.u64(entry.message_start_time);
    sink.u64(entry.message_end_time);
    sink.u64(entry.uncompressed_size);
    sink.u32(uncompressed_crc);
    sink.string(options.compression);
    sink.u64(body->size());
    // The content length counts the records that follow this prefix.
    const std::uint64_t content_length = head.size() - at - 8 + body->size();
    for (int i = 0; i < 8; ++i) head[at + static_cast<size_t>(i)] = static_cast<std::uint8_t>(content_length >> (8 * i));
    if (auto status = emit(head); !status.ok()) return status;
    if (auto status = emit(*body); !status.ok()) return status;
    entry.chunk_length = offset() - entry.chunk_start_offset;

    // One Message Index per channel of the chunk, entries in log time order.
    const std::uint64_t index_start = offset();
    std::vector<std::uint8_t> index;
    for (auto& [channel_id, entries] : job.message_index) {
      std::stable_sort(entries.begin(), entries.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      index.clear();
      ByteSink index_sink(index);
      const size_t record_at = index_sink.begin_record(kMessageIndex);
      index_sink.u16(channel_id);
      const size_t array_at = index_sink.begin_length32();
      for (const auto& [log_time, message_offset] : entries) {
        index_sink.u64(log_time);
        index_sink.u64(message_offset);
      }
      index_sink.end_length32(array_at);
      index_sink.end_record(record_at);
      entry.message_index_offsets[channel_id] = offset();
      if (auto status = emit(index); !status.ok()) return status;
    }
    entry.message_index_length = offset() - index_start;
    chunk_indexes.push_back(std::move(entry));
    // The compressed chunk is in the file now; anything waiting goes out with it.
    return flush();
  }

  Status finish_file() {
    // The worker's chunks first, then the last chunk and the rest on this thread.
    if (auto status = drain(); !status.ok()) return status;
    stop_worker();
    if (!chunk.empty()) {
      ChunkJob last;
      last.records = std::move(chunk);
      last.message_index = std::move(chunk_message_index);
      last.start_time = chunk_start_time;
      last.end_time = chunk_end_time;
      last.has_messages = chunk_has_messages;
      ++statistics.chunk_count;
      if (auto status = write_chunk(last); !status.ok()) return status;
    }

    // Data End carries the CRC of everything before it, from the leading magic on.
    std::vector<std::uint8_t> data_end;
    {
      ByteSink sink(data_end);
      const size_t at = sink.begin_record(kDataEnd);
      sink.u32(data_section_crc);
      sink.end_record(at);
    }
    in_data_section = false;
    if (auto status = emit(data_end); !status.ok()) return status;

    // Summary: records grouped by opcode, each group listed by a Summary Offset record.
    const std::uint64_t summary_start = offset();
    std::vector<std::uint8_t> tail;
    ByteSink sink(tail);
    struct Group {
      Opcode opcode;
      std::uint64_t start, length;
    };
    std::vector<Group> groups;
    auto group = [&](Opcode opcode, auto&& append_records) {
      const size_t before = tail.size();
      append_records();
      if (tail.size() > before) groups.push_back({opcode, summary_start + before, tail.size() - before});
    };
    group(kSchema, [&] {
      for (const auto& schema : schemas) append_schema(sink, schema);
    });
    group(kChannel, [&] {
      for (const auto& channel : channels) append_channel(sink, channel);
    });
    group(kStatistics, [&] {
      const size_t at = sink.begin_record(kStatistics);
      sink.u64(statistics.message_count);
      sink.u16(static_cast<std::uint16_t>(schemas.size()));
      sink.u32(static_cast<std::uint32_t>(channels.size()));
      sink.u32(0);  // attachments
      sink.u32(static_cast<std::uint32_t>(metadata_indexes.size()));
      sink.u32(statistics.chunk_count);
      sink.u64(statistics.message_start_time_ns);
      sink.u64(statistics.message_end_time_ns);
      const size_t map_at = sink.begin_length32();
      for (const auto& [channel_id, count] : statistics.channel_message_counts) {
        sink.u16(channel_id);
        sink.u64(count);
      }
      sink.end_length32(map_at);
      sink.end_record(at);
    });
    group(kChunkIndex, [&] {
      for (const auto& entry : chunk_indexes) {
        const size_t at = sink.begin_record(kChunkIndex);
        sink.u64(entry.message_start_time);
        sink.u64(entry.message_end_time);
        sink.u64(entry.chunk_start_offset);
        sink.u64(entry.chunk_length);
        const size_t map_at = sink.begin_length32();
        for (const auto& [channel_id, index_offset] : entry.message_index_offsets) {
          sink.u16(channel_id);
          sink.u64(index_offset);
        }
        sink.end_length32(map_at);
        sink.u64(entry.message_index_length);
        sink.string(options.compression);
        sink.u64(entry.compressed_size);
        sink.u64(entry.uncompressed_size);
        sink.end_record(at);
      }
    });
    group(kMetadataIndex, [&] {
      for (const auto& entry : metadata_indexes) {
        const size_t at = sink.begin_record(kMetadataIndex);
        sink.u64(entry.offset);
        sink.u64(entry.length);
        sink.string(entry.name);
        sink.end_record(at);
      }
    });
    const std::uint64_t summary_offset_start = summary_start + tail.size();
    for (const auto& g : groups) {
      const size_t at = sink.begin_record(kSummaryOffset);
      sink.u8(g.opcode);
      sink.u64(g.start);
      sink.u64(g.length);
      sink.end_record(at);
    }
    // Footer: its CRC covers the summary, the summary offsets and the footer up to the CRC.
    sink.u8(kFooter);
    sink.u64(8 + 8 + 4);  // a fixed length, known before the CRC is taken
    sink.u64(summary_start);
    sink.u64(summary_offset_start);
    sink.u32(crc32_update(0, tail));
    sink.bytes(std::span<const std::uint8_t>(kMagic));
    if (auto status = emit(tail); !status.ok()) return status;
    if (auto status = flush(); !status.ok()) return status;

    const int fd_to_close = fd;
    fd = -1;
    if (::close(fd_to_close) != 0) return fail(output_error("close failed (" + errno_text(errno) + ")"));
    return Ok{};
  }
};

std::string mcap_library_name() { return std::string("skytrace ") + version(); }

McapWriter::McapWriter(std::unique_ptr<State> state) : state_(std::move(state)) {}
McapWriter::~McapWriter() = default;

Result<std::unique_ptr<McapWriter>> McapWriter::open(const std::filesystem::path& path, McapOptions options) {
  if (options.compression != "zstd" && options.compression != "lz4" && !options.compression.empty()) {
    return make_error(ErrorCode::kInvalidArgument,
                      "MCAP compression '" + options.compression + "': expected zstd, lz4 or none");
  }
  if (options.library.empty()) options.library = mcap_library_name();
  auto state = std::make_unique<State>();
  state->path = path;
  state->options = std::move(options);
  state->fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOCTTY, 0666);
  if (state->fd < 0) return state->output_error("cannot open for writing (" + errno_text(errno) + ")");

  std::vector<std::uint8_t> start(std::begin(kMagic), std::end(kMagic));
  ByteSink sink(start);
  const size_t at = sink.begin_record(kHeader);
  sink.string(state->options.profile);
  sink.string(state->options.library);
  sink.end_record(at);
  if (auto status = state->emit(start); !status.ok()) return status.error();
  // Written at once, so an unwritable target is reported before any work is done.
  if (auto status = state->flush(); !status.ok()) return status.error();
  return std::unique_ptr<McapWriter>(new McapWriter(std::move(state)));
}

Result<std::uint16_t> McapWriter::add_schema(std::string name, std::string encoding, std::string data) {
  State& s = *state_;
  if (auto error = s.usable()) return *error;
  for (const auto& schema : s.schemas) {
    if (schema.name == name && schema.encoding == encoding && schema.data == data) return schema.id;
  }
  if (s.schemas.size() >= std::numeric_limits<std::uint16_t>::max()) {
    return make_error(ErrorCode::kInvalidArgument, s.path.string() + ": too many MCAP schemas");
  }
  if (data.size() > std::numeric_limits<std::uint32_t>::max()) {
    return make_error(ErrorCode::kInvalidArgument, s.path.string() + ": schema " + name + " is too long");
  }
  if (auto status = s.drain(); !status.ok()) return status.error();
  SchemaRecord schema{static_cast<std::uint16_t>(s.schemas.size() + 1), std::move(name), std::move(encoding),
                      std::move(data)};
  std::vector<std::uint8_t> record;
  ByteSink sink(record);
  append_schema(sink, schema);
  if (auto status = s.emit(record); !status.ok()) return status.error();
  s.schemas.push_back(std::move(schema));
  return s.schemas.back().id;
}

Result<std::uint16_t> McapWriter::add_channel(std::uint16_t schema_id, std::string topic, std::string message_encoding,
                                              std::map<std::string, std::string> metadata) {
  State& s = *state_;
  if (auto error = s.usable()) return *error;
  if (schema_id > s.schemas.size()) {
    return make_error(ErrorCode::kInvalidArgument,
                      s.path.string() + ": channel " + topic + " names unknown schema " + std::to_string(schema_id));
  }
  if (s.channels.size() >= std::numeric_limits<std::uint16_t>::max()) {
    return make_error(ErrorCode::kInvalidArgument, s.path.string() + ": too many MCAP channels");
  }
  if (auto status = s.drain(); !status.ok()) return status.error();
  ChannelRecord channel{static_cast<std::uint16_t>(s.channels.size() + 1), schema_id, std::move(topic),
                        std::move(message_encoding), std::move(metadata)};
  std::vector<std::uint8_t> record;
  ByteSink sink(record);
  append_channel(sink, channel);
  if (auto status = s.emit(record); !status.ok()) return status.error();
  s.channels.push_back(std::move(channel));
  s.sequences.push_back(0);
  return s.channels.back().id;
}

Status McapWriter::add_metadata(std::string name, std::map<std::string, std::string> metadata) {
  State& s = *state_;
  if (auto error = s.usable()) return *error;
  std::vector<std::uint8_t> record;
  ByteSink sink(record);
  const size_t at = sink.begin_record(kMetadata);
  sink.string(name);
  sink.string_map(metadata);
  sink.end_record(at);
  if (auto status = s.drain(); !status.ok()) return status;
  const std::uint64_t offset = s.offset();
  if (auto status = s.emit(record); !status.ok()) return status;
  s.metadata_indexes.push_back({offset, record.size(), std::move(name)});
  return Ok{};
}

Status McapWriter::write(std::uint16_t channel_id, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
                         std::span<const std::uint8_t> data) {
  State& s = *state_;
  if (auto error = s.usable()) return *error;
  if (channel_id == 0 || channel_id > s.channels.size()) {
    return make_error(ErrorCode::kInvalidArgument,
                      s.path.string() + ": message on unknown MCAP channel " + std::to_string(channel_id));
  }
  const std::uint64_t offset_in_chunk = s.chunk.size();
  ByteSink sink(s.chunk);
  sink.u8(kMessage);
  sink.u64(2 + 4 + 8 + 8 + data.size());
  sink.u16(channel_id);
  sink.u32(s.sequences[channel_id - 1]++);
  sink.u64(log_time_ns);
  sink.u64(publish_time_ns);
  sink.bytes(data);
  s.chunk_message_index[channel_id].emplace_back(log_time_ns, offset_in_chunk);

  if (!s.chunk_has_messages || log_time_ns < s.chunk_start_time) s.chunk_start_time = log_time_ns;
  if (!s.chunk_has_messages || log_time_ns > s.chunk_end_time) s.chunk_end_time = log_time_ns;
  s.chunk_has_messages = true;
  McapStatistics& stats = s.statistics;
  if (stats.message_count == 0 || log_time_ns < stats.message_start_time_ns) stats.message_start_time_ns = log_time_ns;
  if (stats.message_count == 0 || log_time_ns > stats.message_end_time_ns) stats.message_end_time_ns = log_time_ns;
  ++stats.message_count;
  ++stats.channel_message_counts[channel_id];

  if (s.chunk.size() >= s.options.chunk_size_bytes) return s.finish_chunk();
  return Ok{};
}

Status McapWriter::close() {
  State& s = *state_;
  if (s.closed) {
    std::lock_guard lock(s.mutex);
    if (s.failure) return *s.failure;
    return Ok{};
  }
  if (auto error = s.usable()) {
    s.closed = true;
    return *error;
  }
  s.closed = true;
  return s.finish_file();
}

const McapStatistics& McapWriter::statistics() const { return state_->statistics; }
const std::filesystem::path& McapWriter::path() const { return state_->path; }

}  // namespace skytrace::io

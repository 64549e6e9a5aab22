// MCAP writer and rosbag2 folder writer: record layout read back by a small independent parser
// of the specification (opcodes, lengths, offsets, CRCs, the index records), chunk splitting,
// every compression, write failures (a full device, a file size limit) and metadata.yaml as
// rosbag2 writes it. Foxglove's own readers check the bags in tests/integration/test_mcap_bag.cpp.
// Every test runs for each chunk compression; their names start with "mcap/" (ctest -R mcap).
#include <gtest/gtest.h>
#include <lz4frame.h>
#include <malloc.h>
#include <sys/resource.h>
#include <yaml-cpp/yaml.h>
#include <zlib.h>
#include <zstd.h>

#include <csignal>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "skytrace/io/mcap.hpp"
#include "skytrace/io/rosbag2.hpp"
#include "test_support.hpp"

namespace skytrace::io {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

std::string read_text(const std::filesystem::path& path) {
  const Bytes bytes = read_file(path);
  return std::string(bytes.begin(), bytes.end());
}

std::uint32_t crc_of(const std::uint8_t* data, size_t size) {
  return static_cast<std::uint32_t>(::crc32(0, data, static_cast<uInt>(size)));
}

// A reader of the fields the specification defines, independent of the writer's code.
class Fields {
 public:
  Fields(const std::uint8_t* data, size_t size) : data_(data), size_(size) {}
  std::uint64_t uint(int bytes) {
    if (at_ + static_cast<size_t>(bytes) > size_) throw std::runtime_error("field past the end");
    std::uint64_t value = 0;
    for (int i = 0; i < bytes; ++i) value |= std::uint64_t{data_[at_ + static_cast<size_t>(i)]} << (8 * i);
    at_ += static_cast<size_t>(bytes);
    return value;
  }
  std::uint8_t u8() { return static_cast<std::uint8_t>(uint(1)); }
  std::uint16_t u16() { return static_cast<std::uint16_t>(uint(2)); }
  std::uint32_t u32() { return static_cast<std::uint32_t>(uint(4)); }
  std::uint64_t u64() { return uint(8); }
  std::string string() {
    const size_t n = u32();
    if (at_ + n > size_) throw std::runtime_error("string past the end");
    std::string text(reinterpret_cast<const char*>(data_ + at_), n);
    at_ += n;
    return text;
  }
  std::map<std::string, std::string> string_map() {
    const size_t end = u32() + at_;
    std::map<std::string, std::string> map;
    while (at_ < end) {
      std::string key = string();
      map[key] = string();
    }
    return map;
  }
  Bytes rest() {
    Bytes bytes(data_ + at_, data_ + size_);
    at_ = size_;
    return bytes;
  }
  Bytes take(size_t n) {
    if (at_ + n > size_) throw std::runtime_error("bytes past the end");
    Bytes bytes(data_ + at_, data_ + at_ + n);
    at_ += n;
    return bytes;
  }
  [[nodiscard]] size_t position() const { return at_; }
  [[nodiscard]] bool done() const { return at_ == size_; }

 private:
  const std::uint8_t* data_;
  size_t size_;
  size_t at_ = 0;
};

struct Record {
  std::uint8_t opcode = 0;
  std::uint64_t offset = 0;  // of the opcode, from the start of the file (or of the chunk data)
  std::uint64_t length = 0;  // opcode, length field and content
  Bytes content;
};

std::vector<Record> split_records(const Bytes& bytes, size_t begin, size_t end) {
  std::vector<Record> records;
  size_t at = begin;
  while (at < end) {
    Fields prefix(bytes.data() + at, end - at);
    Record record;
    record.opcode = prefix.u8();
    const std::uint64_t content_length = prefix.u64();
    if (at + 9 + content_length > end) throw std::runtime_error("record past the end");
    record.offset = at;
    record.length = 9 + content_length;
    record.content.assign(bytes.begin() + static_cast<long>(at + 9), bytes.begin() + static_cast<long>(at + 9 + content_length));
    records.push_back(std::move(record));
    at += 9 + content_length;
  }
  return records;
}

const Bytes kMagic = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

Bytes decompress(const std::string& compression, const Bytes& data, size_t uncompressed_size) {
  if (compression.empty()) return data;
  Bytes out(uncompressed_size);
  if (compression == "zstd") {
    const size_t n = ZSTD_decompress(out.data(), out.size(), data.data(), data.size());
    if (ZSTD_isError(n) != 0U || n != uncompressed_size) throw std::runtime_error("zstd");
    return out;
  }
  LZ4F_dctx* context = nullptr;
  LZ4F_createDecompressionContext(&context, LZ4F_VERSION);
  size_t out_size = out.size();
  size_t in_size = data.size();
  const size_t left = LZ4F_decompress(context, out.data(), &out_size, data.data(), &in_size, nullptr);
  LZ4F_freeDecompressionContext(context);
  if (LZ4F_isError(left) != 0U || left != 0 || out_size != uncompressed_size) throw std::runtime_error("lz4");
  return out;
}

struct Message {
  std::uint16_t channel_id = 0;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0, publish_time = 0;
  Bytes data;
};

// Everything a reader needs, each structural rule of the specification checked on the way.
struct ParsedFile {
  std::string profile, library;
  std::map<std::uint16_t, std::string> schema_names;
  std::map<std::uint16_t, std::map<std::string, std::string>> channel_metadata;
  std::map<std::uint16_t, std::string> channel_topics;
  std::vector<Message> messages;                 // in file order
  std::vector<std::uint64_t> chunk_uncompressed;  // record bytes of each chunk
  std::vector<std::string> chunk_compressions;
  std::map<std::string, std::map<std::string, std::string>> metadata;
  std::uint64_t statistics_messages = 0;
  std::uint32_t statistics_chunks = 0;
  std::uint64_t statistics_start = 0, statistics_end = 0;
  std::map<std::uint16_t, std::uint64_t> statistics_channel_counts;
};

ParsedFile parse_mcap(const Bytes& file) {
  ParsedFile parsed;
  EXPECT_GE(file.size(), 2 * kMagic.size());
  EXPECT_TRUE(std::equal(kMagic.begin(), kMagic.end(), file.begin())) << "leading magic";
  EXPECT_TRUE(std::equal(kMagic.begin(), kMagic.end(), file.end() - 8)) << "trailing magic";

  // Footer: the last record before the trailing magic, 20 bytes of content.
  const size_t footer_at = file.size() - 8 - 29;
  Fields footer(file.data() + footer_at, 29);
  EXPECT_EQ(footer.u8(), 0x02);
  EXPECT_EQ(footer.u64(), 20u);
  const std::uint64_t summary_start = footer.u64();
  const std::uint64_t summary_offset_start = footer.u64();
  const std::uint32_t summary_crc = footer.u32();
  EXPECT_NE(summary_start, 0u);
  EXPECT_EQ(summary_crc, crc_of(file.data() + summary_start, footer_at + 1 + 8 + 16 - summary_start)) << "summary CRC";

  // Data section: Header first, Data End last (its CRC covers everything before it).
  const auto data_records = split_records(file, 8, summary_start);
  EXPECT_FALSE(data_records.empty());
  EXPECT_EQ(data_records.front().opcode, 0x01);
  EXPECT_EQ(data_records.back().opcode, 0x0F);
  {
    Fields header(data_records.front().content.data(), data_records.front().content.size());
    parsed.profile = header.string();
    parsed.library = header.string();
    Fields data_end(data_records.back().content.data(), data_records.back().content.size());
    EXPECT_EQ(data_end.u32(), crc_of(file.data(), data_records.back().offset)) << "data section CRC";
  }

  std::map<std::uint64_t, std::uint64_t> chunk_lengths;  // offset -> record length
  std::map<std::uint64_t, Record> message_indexes;       // offset -> record
  std::map<std::uint64_t, std::string> metadata_names;   // offset -> name
  std::map<std::uint16_t, bool> channel_seen;
  for (size_t r = 0; r < data_records.size(); ++r) {
    const Record& record = data_records[r];
    Fields fields(record.content.data(), record.content.size());
    switch (record.opcode) {
      case 0x03: {
        const std::uint16_t id = fields.u16();
        parsed.schema_names[id] = fields.string();
        EXPECT_NE(id, 0u);
        break;
      }
      case 0x04: {
        const std::uint16_t id = fields.u16();
        const std::uint16_t schema_id = fields.u16();
        EXPECT_TRUE(schema_id == 0 || parsed.schema_names.count(schema_id) == 1) << "channel before its schema";
        parsed.channel_topics[id] = fields.string();
        EXPECT_EQ(fields.string(), "cdr");
        parsed.channel_metadata[id] = fields.string_map();
        EXPECT_TRUE(fields.done());
        channel_seen[id] = true;
        break;
      }
      case 0x06: {
        chunk_lengths[record.offset] = record.length;
        const std::uint64_t start = fields.u64();
        const std::uint64_t end = fields.u64();
        const std::uint64_t uncompressed_size = fields.u64();
        const std::uint32_t uncompressed_crc = fields.u32();
        const std::string compression = fields.string();
        const std::uint64_t records_size = fields.u64();
        const Bytes chunk = decompress(compression, fields.take(records_size), uncompressed_size);
        EXPECT_TRUE(fields.done());
        EXPECT_EQ(crc_of(chunk.data(), chunk.size()), uncompressed_crc) << "chunk CRC";
        parsed.chunk_uncompressed.push_back(uncompressed_size);
        parsed.chunk_compressions.push_back(compression);
        // Message Index records follow the chunk: every message of the chunk listed at its offset.
        std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> listed;
        for (size_t i = r + 1; i < data_records.size() && data_records[i].opcode == 0x07; ++i) {
          message_indexes[data_records[i].offset] = data_records[i];
          Fields index(data_records[i].content.data(), data_records[i].content.size());
          const std::uint16_t channel = index.u16();
          const size_t array_end = index.u32() + index.position();
          while (index.position() < array_end) {
            const std::uint64_t time = index.u64();
            listed[channel].emplace_back(time, index.u64());
          }
        }
        std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> found;
        std::uint64_t min_time = UINT64_MAX, max_time = 0;
        for (const Record& inner : split_records(chunk, 0, chunk.size())) {
          EXPECT_EQ(inner.opcode, 0x05) << "only messages in chunks";
          Fields m(inner.content.data(), inner.content.size());
          Message message;
          message.channel_id = m.u16();
          message.sequence = m.u32();
          message.log_time = m.u64();
          message.publish_time = m.u64();
          message.data = m.rest();
          EXPECT_TRUE(channel_seen[message.channel_id]) << "message before its channel";
          found[message.channel_id].emplace_back(message.log_time, inner.offset);
          min_time = std::min(min_time, message.log_time);
          max_time = std::max(max_time, message.log_time);
          parsed.messages.push_back(std::move(message));
        }
        for (auto& [channel, entries] : found) {
          std::stable_sort(entries.begin(), entries.end(), [](auto& a, auto& b) { return a.first < b.first; });
        }
        EXPECT_EQ(listed, found) << "message index of the chunk at " << record.offset;
        EXPECT_EQ(start, min_time);
        EXPECT_EQ(end, max_time);
        break;
      }
      case 0x0C: {
        const std::string name = fields.string();
        parsed.metadata[name] = fields.string_map();
        metadata_names[record.offset] = name;
        break;
      }
      case 0x01:
      case 0x07:
      case 0x0F:
        break;
      default:
        ADD_FAILURE() << "unexpected record " << int{record.opcode} << " in the data section";
    }
  }

  // Summary: groups by opcode, each listed by a Summary Offset record.
  const auto summary = split_records(file, summary_start, summary_offset_start);
  const auto offsets = split_records(file, summary_offset_start, footer_at);
  std::map<std::uint8_t, std::pair<std::uint64_t, std::uint64_t>> groups;
  for (const Record& record : summary) {
    auto& group = groups[record.opcode];
    if (group.second == 0) group.first = record.offset;
    EXPECT_EQ(group.first + group.second, record.offset) << "summary records grouped by opcode";
    group.second += record.length;
  }
  EXPECT_EQ(offsets.size(), groups.size());
  for (const Record& record : offsets) {
    EXPECT_EQ(record.opcode, 0x0E);
    Fields fields(record.content.data(), record.content.size());
    const std::uint8_t opcode = fields.u8();
    EXPECT_EQ(fields.u64(), groups[opcode].first);
    EXPECT_EQ(fields.u64(), groups[opcode].second);
  }
  size_t chunk_indexes = 0;
  for (const Record& record : summary) {
    Fields fields(record.content.data(), record.content.size());
    if (record.opcode == 0x0B) {
      parsed.statistics_messages = fields.u64();
      EXPECT_EQ(fields.u16(), parsed.schema_names.size());
      EXPECT_EQ(fields.u32(), parsed.channel_topics.size());
      EXPECT_EQ(fields.u32(), 0u);
      EXPECT_EQ(fields.u32(), parsed.metadata.size());
      parsed.statistics_chunks = fields.u32();
      parsed.statistics_start = fields.u64();
      parsed.statistics_end = fields.u64();
      const size_t end = fields.u32() + fields.position();
      while (fields.position() < end) {
        const std::uint16_t channel = fields.u16();
        parsed.statistics_channel_counts[channel] = fields.u64();
      }
      EXPECT_TRUE(fields.done());
    } else if (record.opcode == 0x08) {
      ++chunk_indexes;
      fields.u64();
      fields.u64();
      const std::uint64_t chunk_offset = fields.u64();
      EXPECT_EQ(fields.u64(), chunk_lengths[chunk_offset]) << "chunk index length";
      const size_t end = fields.u32() + fields.position();
      std::uint64_t index_bytes = 0;
      while (fields.position() < end) {
        fields.u16();
        const std::uint64_t index_offset = fields.u64();
        EXPECT_EQ(message_indexes.count(index_offset), 1u) << "chunk index points at a message index";
        index_bytes += message_indexes[index_offset].length;
      }
      EXPECT_EQ(fields.u64(), index_bytes);
      fields.string();
      fields.u64();
      fields.u64();
      EXPECT_TRUE(fields.done());
    } else if (record.opcode == 0x0D) {
      const std::uint64_t offset = fields.u64();
      fields.u64();
      EXPECT_EQ(metadata_names[offset], fields.string());
    } else if (record.opcode == 0x04) {
      const std::uint16_t id = fields.u16();
      EXPECT_EQ(parsed.channel_topics.count(id), 1u);
    }
  }
  EXPECT_EQ(chunk_indexes, chunk_lengths.size());
  EXPECT_EQ(groups.count(0x03), parsed.schema_names.empty() ? 0u : 1u);
  EXPECT_EQ(groups.count(0x0B), 1u);
  return parsed;
}

std::string compression_name(const testing::TestParamInfo<std::string>& info) {
  return info.param.empty() ? "none" : info.param;
}

class McapWriterTest : public testing::TestWithParam<std::string> {
 protected:
  McapOptions options(size_t chunk_size_bytes = size_t{1} << 20) const {
    McapOptions o;
    o.compression = GetParam();
    o.chunk_size_bytes = chunk_size_bytes;
    return o;
  }
};

TEST_P(McapWriterTest, EmptyFileHasHeaderSummaryAndFooter) {
  const auto path = test::make_temp_dir("mcap") / "empty.mcap";
  auto writer = McapWriter::open(path, options());
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  ASSERT_TRUE((*writer)->close().ok());
  const ParsedFile parsed = parse_mcap(read_file(path));
  EXPECT_EQ(parsed.profile, "ros2");
  EXPECT_EQ(parsed.library, mcap_library_name());
  EXPECT_EQ(parsed.library.rfind("skytrace ", 0), 0u);
  EXPECT_EQ(parsed.statistics_messages, 0u);
  EXPECT_EQ(parsed.statistics_chunks, 0u);
  EXPECT_TRUE(parsed.chunk_uncompressed.empty());
}

TEST_P(McapWriterTest, MessagesComeBackInChunksWithTheirIndexes) {
  const auto path = test::make_temp_dir("mcap") / "two_channels.mcap";
  auto writer = McapWriter::open(path, options(4096));
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  McapWriter& w = **writer;
  const auto schema = w.add_schema("pkg/msg/A", "ros2msg", "float64 x\n");
  ASSERT_TRUE(schema.ok());
  const auto again = w.add_schema("pkg/msg/A", "ros2msg", "float64 x\n");
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(*again, *schema) << "the same schema is stored once";
  const auto fix = w.add_channel(*schema, "/fix", "cdr", {{"offered_qos_profiles", "- depth: 5"}});
  const auto obs = w.add_channel(*schema, "/obs", "cdr", {});
  ASSERT_TRUE(fix.ok() && obs.ok());
  EXPECT_NE(*fix, *obs);
  std::vector<Message> written;
  for (int i = 0; i < 200; ++i) {
    Message m;
    m.channel_id = (i % 3 == 0) ? *obs : *fix;
    m.log_time = 1'700'000'000'000'000'000ULL + static_cast<std::uint64_t>(i) * 100'000'000;
    m.publish_time = m.log_time - 5;
    m.data.assign(static_cast<size_t>(20 + (i * 37) % 300), static_cast<std::uint8_t>(i));
    ASSERT_TRUE(w.write(m.channel_id, m.log_time, m.publish_time, m.data).ok());
    written.push_back(m);
  }
  ASSERT_TRUE(w.close().ok());
  EXPECT_TRUE(w.close().ok()) << "closing twice repeats the outcome";

  const ParsedFile parsed = parse_mcap(read_file(path));
  ASSERT_EQ(parsed.messages.size(), written.size());
  std::map<std::uint16_t, std::uint32_t> next_sequence;
  for (size_t i = 0; i < written.size(); ++i) {
    EXPECT_EQ(parsed.messages[i].channel_id, written[i].channel_id);
    EXPECT_EQ(parsed.messages[i].log_time, written[i].log_time);
    EXPECT_EQ(parsed.messages[i].publish_time, written[i].publish_time);
    EXPECT_EQ(parsed.messages[i].data, written[i].data);
    EXPECT_EQ(parsed.messages[i].sequence, next_sequence[written[i].channel_id]++);
  }
  EXPECT_GT(parsed.chunk_uncompressed.size(), 5u) << "4 KiB chunks for ~40 KiB of messages";
  for (const auto& compression : parsed.chunk_compressions) EXPECT_EQ(compression, GetParam());
  EXPECT_EQ(parsed.statistics_messages, 200u);
  EXPECT_EQ(parsed.statistics_chunks, parsed.chunk_uncompressed.size());
  EXPECT_EQ(parsed.statistics_start, written.front().log_time);
  EXPECT_EQ(parsed.statistics_end, written.back().log_time);
  EXPECT_EQ(parsed.statistics_channel_counts.at(*obs), 67u);
  EXPECT_EQ(parsed.statistics_channel_counts.at(*fix), 133u);
  EXPECT_EQ(parsed.channel_topics.at(*fix), "/fix");
  EXPECT_EQ(parsed.channel_metadata.at(*fix).at("offered_qos_profiles"), "- depth: 5");
  EXPECT_EQ(parsed.schema_names.at(*schema), "pkg/msg/A");
  EXPECT_EQ(w.statistics().chunk_count, parsed.chunk_uncompressed.size());
}

TEST_P(McapWriterTest, ChunksCloseOnceTheyReachTheTargetSize) {
  const auto path = test::make_temp_dir("mcap") / "split.mcap";
  constexpr size_t kChunkBytes = 1000;
  auto writer = McapWriter::open(path, options(kChunkBytes));
  ASSERT_TRUE(writer.ok());
  McapWriter& w = **writer;
  const auto channel = w.add_channel(0, "/raw", "cdr", {});
  ASSERT_TRUE(channel.ok());
  const Bytes payload(300, 7);  // a record of 9 + 22 + 300 bytes
  for (int i = 0; i < 20; ++i) ASSERT_TRUE(w.write(*channel, static_cast<std::uint64_t>(i), 0, payload).ok());
  // A message larger than the target size makes a chunk of its own.
  const Bytes big(5000, 9);
  ASSERT_TRUE(w.write(*channel, 100, 100, big).ok());
  ASSERT_TRUE(w.close().ok());
  const ParsedFile parsed = parse_mcap(read_file(path));
  constexpr size_t kRecord = 9 + 22 + 300;
  // Full chunks hold 4 records (the fourth crosses 1000 bytes): 5 of them, then the big message.
  ASSERT_EQ(parsed.chunk_uncompressed.size(), 6u);
  for (size_t i = 0; i < 5; ++i) EXPECT_EQ(parsed.chunk_uncompressed[i], 4 * kRecord);
  EXPECT_EQ(parsed.chunk_uncompressed[5], 9 + 22 + big.size());
  EXPECT_EQ(parsed.messages.size(), 21u);
}

TEST_P(McapWriterTest, MemoryDoesNotGrowWithTheNumberOfMessages) {
  const auto path = test::make_temp_dir("mcap") / "long.mcap";
  auto writer = McapWriter::open(path, options(size_t{256} << 10));
  ASSERT_TRUE(writer.ok());
  McapWriter& w = **writer;
  const auto channel = w.add_channel(0, "/obs", "cdr", {});
  ASSERT_TRUE(channel.ok());
  Bytes payload(400);
  std::uint64_t t = 0;
  auto write_mib = [&](int mib) {
    for (size_t written = 0; written < (size_t(mib) << 20); written += payload.size()) {
      for (size_t i = 0; i < payload.size(); i += 8) payload[i] = static_cast<std::uint8_t>(t >> (i % 16));
      ASSERT_TRUE(w.write(*channel, t, t, payload).ok());
      t += 1'000'000;
    }
  };
  write_mib(4);  // the chunk buffers and compression context have reached their size
  ASSERT_FALSE(HasFatalFailure());
  const size_t in_use_after_4_mib = mallinfo2().uordblks;
  write_mib(32);
  ASSERT_FALSE(HasFatalFailure());
  const size_t in_use_after_36_mib = mallinfo2().uordblks;
  // 128 more chunks keep a Chunk Index entry each (~100 bytes): nothing near the 32 MiB written.
  // The worker thread holds up to kQueuedChunks (2) chunks waiting, one being compressed with its
  // output, and the one being filled: how many of those buffers exist when memory is sampled depends
  // on how far the worker is behind (0.03-0.5 MiB more on an idle machine, up to 0.9 MiB while a CI
  // run loaded it), so the bound allows six chunks' worth (1.5 MiB), a 21st of what was written.
  EXPECT_LT(in_use_after_36_mib, in_use_after_4_mib + 6 * (size_t{256} << 10));
  EXPECT_GT(w.statistics().chunk_count, 140u);
  ASSERT_TRUE(w.close().ok());
  EXPECT_GT(std::filesystem::file_size(path), 0u);
}

TEST_P(McapWriterTest, MessagesOutOfTimeOrderAreIndexedInTimeOrder) {
  const auto path = test::make_temp_dir("mcap") / "unordered.mcap";
  auto writer = McapWriter::open(path, options());
  ASSERT_TRUE(writer.ok());
  McapWriter& w = **writer;
  const auto channel = w.add_channel(0, "/a", "cdr", {});
  ASSERT_TRUE(channel.ok());
  for (const std::uint64_t t : {30u, 10u, 20u}) ASSERT_TRUE(w.write(*channel, t, t, Bytes{1, 2}).ok());
  ASSERT_TRUE(w.close().ok());
  const ParsedFile parsed = parse_mcap(read_file(path));  // checks the index is sorted by time
  EXPECT_EQ(parsed.statistics_start, 10u);
  EXPECT_EQ(parsed.statistics_end, 30u);
}

TEST_P(McapWriterTest, MetadataRecordsAreIndexed) {
  const auto path = test::make_temp_dir("mcap") / "metadata.mcap";
  auto writer = McapWriter::open(path, options());
  ASSERT_TRUE(writer.ok());
  ASSERT_TRUE((*writer)->add_metadata("rosbag2", {{"serialized_metadata", "version: 9"}}).ok());
  ASSERT_TRUE((*writer)->close().ok());
  const ParsedFile parsed = parse_mcap(read_file(path));
  EXPECT_EQ(parsed.metadata.at("rosbag2").at("serialized_metadata"), "version: 9");
}

TEST_P(McapWriterTest, RefusesUnknownChannelsSchemasAndWritesAfterClose) {
  const auto path = test::make_temp_dir("mcap") / "misuse.mcap";
  auto writer = McapWriter::open(path, options());
  ASSERT_TRUE(writer.ok());
  McapWriter& w = **writer;
  EXPECT_EQ(w.add_channel(3, "/x", "cdr", {}).error().code, ErrorCode::kInvalidArgument);
  EXPECT_EQ(w.write(1, 0, 0, Bytes{1}).error().code, ErrorCode::kInvalidArgument);
  ASSERT_TRUE(w.close().ok());
  EXPECT_FALSE(w.write(1, 0, 0, Bytes{1}).ok());
  EXPECT_FALSE(w.add_schema("a", "b", "c").ok());
}

TEST_P(McapWriterTest, UnknownCompressionIsRefused) {
  McapOptions o = options();
  o.compression = "bz2";
  const auto writer = McapWriter::open(test::make_temp_dir("mcap") / "x.mcap", o);
  ASSERT_FALSE(writer.ok());
  EXPECT_EQ(writer.error().code, ErrorCode::kInvalidArgument);
}

TEST_P(McapWriterTest, AFolderOrMissingParentIsAnOutputError) {
  const auto dir = test::make_temp_dir("mcap");
  const auto on_folder = McapWriter::open(dir, options());
  ASSERT_FALSE(on_folder.ok());
  EXPECT_EQ(on_folder.error().code, ErrorCode::kOutput);
  EXPECT_NE(on_folder.error().message.find(dir.string()), std::string::npos);
  const auto missing = McapWriter::open(dir / "no" / "such.mcap", options());
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kOutput);
}

TEST_P(McapWriterTest, AFullDeviceIsAnOutputError) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  const auto writer = McapWriter::open("/dev/full", options());
  ASSERT_FALSE(writer.ok());
  EXPECT_EQ(writer.error().code, ErrorCode::kOutput);
  EXPECT_NE(writer.error().message.find("no space left"), std::string::npos) << writer.error().message;
}

// Runs in a child process: a file size limit makes a write fail part way through the file.
int write_past_a_file_size_limit(const std::filesystem::path& path, const McapOptions& options) {
  std::signal(SIGXFSZ, SIG_IGN);  // write() then fails with EFBIG instead of killing the process
  rlimit limit{};
  limit.rlim_cur = limit.rlim_max = 64 * 1024;
  if (setrlimit(RLIMIT_FSIZE, &limit) != 0) return 10;
  auto writer = McapWriter::open(path, options);
  if (!writer.ok()) return 11;
  McapWriter& w = **writer;
  const auto channel = w.add_channel(0, "/raw", "cdr", {});
  if (!channel.ok()) return 12;
  // Random bytes do not compress: the chunks reach the file at their full size.
  Bytes payload(4000);
  std::uint32_t state = 12345;
  for (auto& b : payload) b = static_cast<std::uint8_t>((state = state * 1103515245u + 12345u) >> 24);
  Status failed = Ok{};
  for (int i = 0; i < 100 && failed.ok(); ++i) failed = w.write(*channel, static_cast<std::uint64_t>(i), 0, payload);
  if (failed.ok()) return 13;  // 400 kB cannot fit under 64 KiB
  if (failed.error().code != ErrorCode::kOutput) return 14;
  if (failed.error().message.find("file size limit") == std::string::npos) return 15;
  if (failed.error().message.find(path.string()) == std::string::npos) return 16;
  // Every later call reports the failure, close() included.
  if (w.write(*channel, 0, 0, payload).ok()) return 17;
  const Status closed = w.close();
  if (closed.ok() || closed.error().code != ErrorCode::kOutput) return 18;
  return 0;
}

TEST_P(McapWriterTest, AWriteFailurePartWayIsReportedByWriteAndClose) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const auto path = test::make_temp_dir("mcap") / "limited.mcap";
  McapOptions o = options(16 * 1024);
  EXPECT_EXIT(std::_Exit(write_past_a_file_size_limit(path, o)), testing::ExitedWithCode(0), "");
}

INSTANTIATE_TEST_SUITE_P(mcap, McapWriterTest, testing::Values(std::string("zstd"), std::string("lz4"), std::string()),
                         compression_name);

// --- rosbag2 folders --------------------------------------------------------------------------------

class Rosbag2WriterTest : public testing::TestWithParam<std::string> {
 protected:
  Rosbag2Options options() const {
    Rosbag2Options o;
    o.mcap.compression = GetParam();
    return o;
  }
};

constexpr const char* kExpectedMetadata = R"(rosbag2_bagfile_information:
  version: 9
  storage_identifier: mcap
  duration:
    nanoseconds: 1500000000
  starting_time:
    nanoseconds_since_epoch: 1700000000000000000
  message_count: 3
  topics_with_message_count:
    - topic_metadata:
        name: /fix
        type: sensor_msgs/msg/NavSatFix
        serialization_format: cdr
        offered_qos_profiles:
          - history: keep_last
            depth: 5
            reliability: best_effort
            durability: volatile
            deadline:
              sec: 9223372036
              nsec: 854775807
            lifespan:
              sec: 9223372036
              nsec: 854775807
            liveliness: automatic
            liveliness_lease_duration:
              sec: 9223372036
              nsec: 854775807
            avoid_ros_namespace_conventions: false
        type_description_hash: ""
      message_count: 2
    - topic_metadata:
        name: /world
        type: visualization_msgs/msg/MarkerArray
        serialization_format: cdr
        offered_qos_profiles:
          - history: keep_last
            depth: 1
            reliability: reliable
            durability: transient_local
            deadline:
              sec: 9223372036
              nsec: 854775807
            lifespan:
              sec: 9223372036
              nsec: 854775807
            liveliness: automatic
            liveliness_lease_duration:
              sec: 9223372036
              nsec: 854775807
            avoid_ros_namespace_conventions: false
        type_description_hash: RIHS01_abc
      message_count: 1
    - topic_metadata:
        name: /nmea
        type: nmea_msgs/msg/Sentence
        serialization_format: cdr
        offered_qos_profiles:
          - history: keep_last
            depth: 10
            reliability: reliable
            durability: volatile
            deadline:
              sec: 9223372036
              nsec: 854775807
            lifespan:
              sec: 9223372036
              nsec: 854775807
            liveliness: automatic
            liveliness_lease_duration:
              sec: 9223372036
              nsec: 854775807
            avoid_ros_namespace_conventions: false
        type_description_hash: ""
      message_count: 0
  compression_format: ""
  compression_mode: ""
  relative_file_paths:
    - drive_0.mcap
  files:
    - path: drive_0.mcap
      starting_time:
        nanoseconds_since_epoch: 1700000000000000000
      duration:
        nanoseconds: 1500000000
      message_count: 3
  custom_data: ~
  ros_distro: jazzy)";

TEST_P(Rosbag2WriterTest, WritesTheFolderAsRosbag2Does) {
  const auto folder = test::make_temp_dir("mcap") / "drive";
  auto writer = Rosbag2Writer::open(folder, options());
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  Rosbag2Writer& w = **writer;
  const auto fix = w.add_topic("/fix", "sensor_msgs/msg/NavSatFix", "std_msgs/Header header\n", QosProfileKind::kSensorData);
  const auto world = w.add_topic("/world", "visualization_msgs/msg/MarkerArray", "Marker[] markers\n",
                                 QosProfileKind::kTransientLocal, "RIHS01_abc");
  const auto nmea = w.add_topic("/nmea", "nmea_msgs/msg/Sentence", "string sentence\n", QosProfileKind::kDefault);
  ASSERT_TRUE(fix.ok() && world.ok() && nmea.ok());
  EXPECT_EQ(w.add_topic("/fix", "sensor_msgs/msg/NavSatFix", "x", QosProfileKind::kDefault).error().code,
            ErrorCode::kInvalidArgument);
  const std::uint64_t t0 = 1'700'000'000'000'000'000ULL;
  ASSERT_TRUE(w.write(*world, t0, Bytes{0, 1, 0, 0, 0, 0, 0, 0}).ok());
  ASSERT_TRUE(w.write(*fix, t0 + 500'000'000, Bytes{0, 1, 0, 0, 1}).ok());
  ASSERT_TRUE(w.write(*fix, t0 + 1'500'000'000, Bytes{0, 1, 0, 0, 2}).ok());
  EXPECT_FALSE(std::filesystem::exists(folder / "metadata.yaml")) << "metadata.yaml only once finished";
  ASSERT_TRUE(w.close().ok());

  EXPECT_EQ(w.mcap_path(), folder / "drive_0.mcap");
  EXPECT_EQ(read_text(folder / "metadata.yaml"), kExpectedMetadata);
  std::vector<std::string> entries;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) entries.push_back(entry.path().filename());
  std::sort(entries.begin(), entries.end());
  EXPECT_EQ(entries, (std::vector<std::string>{"drive_0.mcap", "metadata.yaml"}));

  const ParsedFile parsed = parse_mcap(read_file(folder / "drive_0.mcap"));
  EXPECT_EQ(parsed.profile, "ros2");
  EXPECT_EQ(parsed.schema_names.size(), 3u);
  const auto& fix_metadata = parsed.channel_metadata.at(*fix);
  EXPECT_EQ(fix_metadata.at("offered_qos_profiles"), rosbag2_offered_qos_yaml(QosProfileKind::kSensorData));
  EXPECT_EQ(fix_metadata.at("topic_type_hash"), "");
  EXPECT_EQ(parsed.channel_metadata.at(*world).at("topic_type_hash"), "RIHS01_abc");
  ASSERT_EQ(parsed.messages.size(), 3u);
  EXPECT_EQ(parsed.messages[1].log_time, t0 + 500'000'000);
  EXPECT_EQ(parsed.messages[1].publish_time, t0 + 500'000'000);
  // The bag metadata inside the MCAP file is metadata.yaml's, without the top-level key.
  const YAML::Node embedded = YAML::Load(parsed.metadata.at("rosbag2").at("serialized_metadata"));
  const YAML::Node on_disk = YAML::LoadFile((folder / "metadata.yaml").string())["rosbag2_bagfile_information"];
  EXPECT_EQ(YAML::Dump(embedded), YAML::Dump(on_disk));
  const auto topics = w.topics();
  ASSERT_EQ(topics.size(), 3u);
  EXPECT_EQ(topics[0].message_count, 2u);
  EXPECT_EQ(topics[2].message_count, 0u);
}

TEST_P(Rosbag2WriterTest, OfferedQosIsTheYamlListRosbag2Stores) {
  EXPECT_EQ(rosbag2_offered_qos_yaml(QosProfileKind::kDefault),
            "- history: keep_last\n"
            "  depth: 10\n"
            "  reliability: reliable\n"
            "  durability: volatile\n"
            "  deadline:\n"
            "    sec: 9223372036\n"
            "    nsec: 854775807\n"
            "  lifespan:\n"
            "    sec: 9223372036\n"
            "    nsec: 854775807\n"
            "  liveliness: automatic\n"
            "  liveliness_lease_duration:\n"
            "    sec: 9223372036\n"
            "    nsec: 854775807\n"
            "  avoid_ros_namespace_conventions: false");
}

TEST_P(Rosbag2WriterTest, AnEmptyBagHasRosbag2sStartAndNoMessages) {
  const auto folder = test::make_temp_dir("mcap") / "empty";
  Rosbag2Options o = options();
  o.file_stem = "run";
  auto writer = Rosbag2Writer::open(folder / "", o);  // a trailing separator names the same folder
  ASSERT_TRUE(writer.ok()) << writer.error().message;
  ASSERT_TRUE((*writer)->add_topic("/fix", "sensor_msgs/msg/NavSatFix", "x", QosProfileKind::kSensorData).ok());
  ASSERT_TRUE((*writer)->close().ok());
  const YAML::Node info = YAML::LoadFile((folder / "metadata.yaml").string())["rosbag2_bagfile_information"];
  EXPECT_EQ(info["message_count"].as<std::uint64_t>(), 0u);
  EXPECT_EQ(info["starting_time"]["nanoseconds_since_epoch"].as<std::int64_t>(), INT64_MAX);
  EXPECT_EQ(info["relative_file_paths"][0].as<std::string>(), "run_0.mcap");
  EXPECT_TRUE(std::filesystem::exists(folder / "run_0.mcap"));
}

TEST_P(Rosbag2WriterTest, RefusesAFolderThatHoldsFilesOrIsAFile) {
  const auto dir = test::make_temp_dir("mcap");
  std::ofstream(dir / "old.txt") << "x";
  const auto not_empty = Rosbag2Writer::open(dir, options());
  ASSERT_FALSE(not_empty.ok());
  EXPECT_EQ(not_empty.error().code, ErrorCode::kOutput);
  const auto file = Rosbag2Writer::open(dir / "old.txt", options());
  ASSERT_FALSE(file.ok());
  EXPECT_EQ(file.error().code, ErrorCode::kOutput);
  const auto no_parent = Rosbag2Writer::open(dir / "a" / "b", options());
  ASSERT_FALSE(no_parent.ok());
  EXPECT_EQ(no_parent.error().code, ErrorCode::kOutput);
}

INSTANTIATE_TEST_SUITE_P(mcap, Rosbag2WriterTest, testing::Values(std::string("zstd"), std::string("lz4"), std::string()),
                         compression_name);

}  // namespace
}  // namespace skytrace::io

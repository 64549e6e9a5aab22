// io::ZstdFileWriter (truth.csv.zst, paths.csv.zst): one standard zstd frame with its content
// checksum, the same content whether libzstd's worker or the caller's thread compresses, errors
// that name the file.
#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <sstream>

#include "skytrace/io/zstd_file.hpp"
#include "test_support.hpp"

namespace skytrace::io {
namespace {

std::string sample_table(size_t rows) {
  std::string text = "time_gpst,sat,range_m\n";
  for (size_t i = 0; i < rows; ++i) {
    text += "2020-06-25T00:00:" + std::to_string(i % 60) + ".000000,G" + std::to_string(i % 32 + 1) + "," +
            std::to_string(20000000.0 + 1234.5678 * static_cast<double>(i)) + "\n";
  }
  return text;
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(ZstdFile, RoundTripInPieces) {
  const auto dir = test::make_temp_dir("zstd_file_round_trip");
  const std::string text = sample_table(200000);  // several MB: several zstd blocks
  {
    const auto path = dir / "t.csv.zst";
    auto writer = ZstdFileWriter::create(path, ZstdWriteOptions{1});
    ASSERT_TRUE(writer) << writer.error().message;
    for (size_t at = 0; at < text.size(); at += 4093) {
      ASSERT_TRUE((*writer)->write(std::string_view(text).substr(at, 4093)));
    }
    ASSERT_TRUE((*writer)->close());
    EXPECT_FALSE((*writer)->write("late"));
    const std::string bytes = read_bytes(path);
    EXPECT_LT(bytes.size(), text.size() / 4);
    // A zstd frame (magic 28 B5 2F FD) whose descriptor sets Content_Checksum_flag (bit 2).
    ASSERT_GT(bytes.size(), 5u);
    EXPECT_EQ(bytes.substr(0, 4), std::string("\x28\xB5\x2F\xFD", 4));
    EXPECT_NE(static_cast<unsigned char>(bytes[4]) & 0x04u, 0u);
    auto back = read_zstd_file(path);
    ASSERT_TRUE(back) << back.error().message;
    EXPECT_TRUE(*back == text);
  }
}

// The background thread compresses the same stream: the same bytes as the caller's thread, however
// the writes are cut.
TEST(ZstdFile, BackgroundThreadWritesTheSameBytes) {
  const auto dir = test::make_temp_dir("zstd_file_background");
  const std::string text = sample_table(300000);  // about 12 MB: some fifty chunks handed over
  std::string reference;
  for (const bool background : {false, true}) {
    for (const size_t piece : {size_t{97}, size_t{4093}, size_t{3} << 20}) {
      const auto path = dir / ("b" + std::to_string(background) + "_" + std::to_string(piece) + ".zst");
      ZstdWriteOptions options;
      options.background_thread = background;
      auto writer = ZstdFileWriter::create(path, options);
      ASSERT_TRUE(writer) << writer.error().message;
      for (size_t at = 0; at < text.size(); at += piece) {
        ASSERT_TRUE((*writer)->write(std::string_view(text).substr(at, piece)));
      }
      ASSERT_TRUE((*writer)->close());
      EXPECT_FALSE((*writer)->write("late"));
      const std::string bytes = read_bytes(path);
      if (reference.empty()) reference = bytes;
      EXPECT_TRUE(bytes == reference) << "background " << background << ", pieces of " << piece;
    }
  }
  // Appending in place to the background writer's buffer: the same bytes again; none without it.
  for (const bool background : {false, true}) {
    const auto path = dir / ("appended_" + std::to_string(background) + ".zst");
    ZstdWriteOptions options;
    options.background_thread = background;
    auto writer = ZstdFileWriter::create(path, options);
    ASSERT_TRUE(writer) << writer.error().message;
    for (size_t at = 0; at < text.size(); at += 4093) {
      const std::string_view piece = std::string_view(text).substr(at, 4093);
      if (std::string* buffer = (*writer)->append_buffer()) {
        buffer->append(piece);
        ASSERT_TRUE((*writer)->commit_appended());
      } else {
        EXPECT_FALSE(background);
        ASSERT_TRUE((*writer)->write(piece));
      }
    }
    ASSERT_TRUE((*writer)->close());
    EXPECT_EQ((*writer)->append_buffer(), nullptr);  // closed
    EXPECT_TRUE(read_bytes(path) == reference) << "appended, background " << background;
  }
  auto back = zstd_decompress(reference);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_TRUE(*back == text);
  // A writer dropped unclosed stops its thread (no hang, no crash).
  ZstdWriteOptions options;
  options.background_thread = true;
  auto dropped = ZstdFileWriter::create(dir / "dropped.zst", options);
  ASSERT_TRUE(dropped);
  ASSERT_TRUE((*dropped)->write(text));
  dropped->reset();
}

TEST(ZstdFile, EmptyFileIsAFrameOfNothing) {
  const auto path = test::make_temp_dir("zstd_file_empty") / "e.zst";
  auto writer = ZstdFileWriter::create(path);
  ASSERT_TRUE(writer);
  ASSERT_TRUE((*writer)->close());
  auto back = read_zstd_file(path);
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(*back, "");
}

TEST(ZstdFile, TruncatedOrCorruptFramesAreRefused) {
  const auto dir = test::make_temp_dir("zstd_file_truncated");
  const auto path = dir / "t.zst";
  auto writer = ZstdFileWriter::create(path, ZstdWriteOptions{1, 0});
  ASSERT_TRUE(writer);
  ASSERT_TRUE((*writer)->write(sample_table(1000)));
  ASSERT_TRUE((*writer)->close());
  std::string bytes = read_bytes(path);
  EXPECT_FALSE(zstd_decompress(std::string_view(bytes).substr(0, bytes.size() - 3)));
  bytes[bytes.size() - 1] ^= 0x5a;  // the checksum
  EXPECT_FALSE(zstd_decompress(bytes));
  EXPECT_FALSE(read_zstd_file(dir / "absent.zst"));
}

TEST(ZstdFile, FullDiskNamesTheFile) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full";
  for (const bool background : {false, true}) {
    ZstdWriteOptions options;
    options.background_thread = background;
    auto writer = ZstdFileWriter::create("/dev/full", options);
    ASSERT_TRUE(writer) << writer.error().message;
    // Written in pieces, as a run does: with the background thread the failure comes back from a
    // later write or from close().
    Status st = Ok{};
    const std::string text = sample_table(100000);
    for (size_t at = 0; at < text.size() && st; at += 4096) st = (*writer)->write(std::string_view(text).substr(at, 4096));
    if (st) st = (*writer)->close();
    ASSERT_FALSE(st) << background;
    EXPECT_NE(st.error().message.find("/dev/full: write failed (no space left on the device)"), std::string::npos)
        << st.error().message;
  }
}

TEST(ZstdFile, UncreatableFileIsRefused) {
  auto writer = ZstdFileWriter::create("/proc/skytrace-cannot-be-here/t.zst");
  ASSERT_FALSE(writer);
  EXPECT_NE(writer.error().message.find("cannot create"), std::string::npos);
}

}  // namespace
}  // namespace skytrace::io

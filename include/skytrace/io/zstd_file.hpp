// zstd-compressed files (one standard frame, RFC 8878, with its content checksum) written as they
// grow: truth.csv.zst and paths.csv.zst of `skytrace run` (docs/adr/0004-truth-format.md). The zstd
// tool, pandas, polars and DuckDB read them as they are.
#pragma once

#include <cstdio>
#include <condition_variable>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>

#include "skytrace/core/error.hpp"

namespace skytrace::io {

struct ZstdWriteOptions {
  // Level 1: the fastest of the standard levels, and on truth.csv also the smallest of 1..3
  // (docs/performance.md, "truth.csv.zst").
  int level = 1;
  // Compress on a thread of this writer's own, fed in chunks of about 256 KiB: the same bytes as on
  // the caller's thread (libzstd's single-threaded stream does not depend on how its input is
  // cut), while write() only copies (a run's writer thread formats the next rows meanwhile).
  bool background_thread = false;
};

// Errors (ErrorCode::kOutput) name the file; a failed file is left for its caller to remove (the
// run's staging folder).
class ZstdFileWriter {
 public:
  [[nodiscard]] static Result<std::unique_ptr<ZstdFileWriter>> create(const std::filesystem::path& path,
                                                                     const ZstdWriteOptions& options = {});
  ~ZstdFileWriter();
  ZstdFileWriter(const ZstdFileWriter&) = delete;
  ZstdFileWriter& operator=(const ZstdFileWriter&) = delete;

  [[nodiscard]] Status write(std::string_view bytes);
  // With the background thread: the text not yet handed over, to append to in place (nullptr
  // without it, or once closed); commit_appended() then hands it over when a chunk is full. The same
  // bytes as write() of what was appended, one copy fewer.
  [[nodiscard]] std::string* append_buffer();
  [[nodiscard]] Status commit_appended();
  // Ends the frame and closes the file; later writes fail.
  [[nodiscard]] Status close();
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  struct Context;
  struct Background;
  ZstdFileWriter(std::filesystem::path path, std::FILE* file, std::unique_ptr<Context> context);
  [[nodiscard]] Status drain(int end_op, std::string_view bytes);
  // Background thread: hands the pending chunk over (waiting while four are queued).
  [[nodiscard]] Status hand_over();
  // Background thread: waits until every chunk is compressed, stops the thread; its status.
  [[nodiscard]] Status stop_background();
  [[nodiscard]] Status error(const std::string& what) const;
  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  std::unique_ptr<Context> context_;
  std::string out_;  // one output block of ZSTD_CStreamOutSize()
  std::unique_ptr<Background> background_;
  std::string pending_;  // bytes not yet handed to the background thread
};

// The decompressed content of a file of one or more zstd frames (checksums checked).
[[nodiscard]] Result<std::string> read_zstd_file(const std::filesystem::path& path);
[[nodiscard]] Result<std::string> zstd_decompress(std::string_view frames);

}  // namespace skytrace::io

#include "skytrace/io/zstd_file.hpp"

#include <zstd.h>

#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <fstream>
#include <mutex>
#include <sstream>
#include <thread>
#include <vector>

#include "skytrace/core/output_file.hpp"

namespace skytrace::io {

struct ZstdFileWriter::Context {
  ZSTD_CCtx* cctx = nullptr;
  ~Context() {
    if (cctx != nullptr) ZSTD_freeCCtx(cctx);
  }
};

ZstdFileWriter::ZstdFileWriter(std::filesystem::path path, std::FILE* file, std::unique_ptr<Context> context)
    : path_(std::move(path)), file_(file), context_(std::move(context)), out_(ZSTD_CStreamOutSize(), '\0') {}

namespace {
// Chunks of 256 KiB, four queued at most: read by the compression thread while they are still in
// the shared cache (with the run's 8-epoch batches, 1 MiB chunks took the 6 h realistic run 2.38 s
// against 2.35 s on two threads, about the host's noise: docs/performance.md, "Threads").
constexpr size_t kChunkBytes = size_t{1} << 18;
constexpr size_t kMaxQueuedChunks = 4;
}  // namespace

// The chunks waiting for the background thread, and what it found.
struct ZstdFileWriter::Background {
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<std::string> queue;
  std::vector<std::string> spent;  // emptied chunks, their capacity reused
  bool closing = false;
  Status status = Ok{};  // the first failure
  std::thread thread;
};

ZstdFileWriter::~ZstdFileWriter() {
  if (background_ != nullptr) (void)stop_background();
  // The context first: its worker threads stop before the file they feed is closed.
  context_.reset();
  if (file_ != nullptr) std::fclose(file_);
}

Result<std::unique_ptr<ZstdFileWriter>> ZstdFileWriter::create(const std::filesystem::path& path,
                                                               const ZstdWriteOptions& options) {
  auto context = std::make_unique<Context>();
  context->cctx = ZSTD_createCCtx();
  if (context->cctx == nullptr) return make_error(ErrorCode::kOutput, path.string() + ": zstd: out of memory");
  auto set = [&](ZSTD_cParameter parameter, int value) {
    return ZSTD_isError(ZSTD_CCtx_setParameter(context->cctx, parameter, value)) == 0U;
  };
  if (!set(ZSTD_c_compressionLevel, options.level) || !set(ZSTD_c_checksumFlag, 1)) {
    return make_error(ErrorCode::kOutput, path.string() + ": zstd: level " + std::to_string(options.level) + " refused");
  }
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) {
    return make_error(ErrorCode::kOutput, path.string() + ": cannot create (" + output_errno_text(errno) + ")");
  }
  std::unique_ptr<ZstdFileWriter> writer(new ZstdFileWriter(path, file, std::move(context)));
  if (options.background_thread) {
    writer->background_ = std::make_unique<Background>();
    Background& b = *writer->background_;
    ZstdFileWriter* self = writer.get();
    b.thread = std::thread([self, &b] {
      std::unique_lock lock(b.mutex);
      for (;;) {
        b.changed.wait(lock, [&] { return !b.queue.empty() || b.closing; });
        if (b.queue.empty()) return;
        std::string chunk = std::move(b.queue.front());
        b.queue.pop_front();
        const bool failed = !b.status;
        lock.unlock();
        Status st = failed ? Status(Ok{}) : self->drain(ZSTD_e_continue, chunk);
        chunk.clear();
        lock.lock();
        if (!st && b.status) b.status = std::move(st);
        b.spent.push_back(std::move(chunk));
        b.changed.notify_all();
      }
    });
    writer->pending_.reserve(kChunkBytes + 65536);
  }
  return writer;
}

Status ZstdFileWriter::hand_over() {
  Background& b = *background_;
  std::unique_lock lock(b.mutex);
  b.changed.wait(lock, [&] { return b.queue.size() < kMaxQueuedChunks; });
  if (!b.status) return b.status;
  b.queue.push_back(std::move(pending_));
  pending_.clear();
  if (!b.spent.empty()) {
    pending_ = std::move(b.spent.back());
    b.spent.pop_back();
  }
  b.changed.notify_all();
  return Ok{};
}

Status ZstdFileWriter::stop_background() {
  Background& b = *background_;
  {
    std::lock_guard lock(b.mutex);
    b.closing = true;
    b.changed.notify_all();
  }
  if (b.thread.joinable()) b.thread.join();
  Status st = std::move(b.status);
  background_.reset();
  return st;
}

Status ZstdFileWriter::error(const std::string& what) const {
  return make_error(ErrorCode::kOutput, path_.string() + ": " + what);
}

// Feeds `bytes` (ZSTD_e_continue) or ends the frame (ZSTD_e_end), writing what comes out.
Status ZstdFileWriter::drain(int end_op, std::string_view bytes) {
  if (file_ == nullptr) return error("written after it was closed");
  ZSTD_inBuffer in{bytes.data(), bytes.size(), 0};
  const auto mode = static_cast<ZSTD_EndDirective>(end_op);
  for (;;) {
    ZSTD_outBuffer out{out_.data(), out_.size(), 0};
    const size_t remaining = ZSTD_compressStream2(context_->cctx, &out, &in, mode);
    if (ZSTD_isError(remaining) != 0U) return error(std::string("zstd: ") + ZSTD_getErrorName(remaining));
    if (out.pos > 0 && std::fwrite(out_.data(), 1, out.pos, file_) != out.pos) {
      return error("write failed (" + output_errno_text(errno) + ")");
    }
    const bool done = mode == ZSTD_e_end ? remaining == 0 : in.pos == in.size;
    if (done) return Ok{};
  }
}

Status ZstdFileWriter::write(std::string_view bytes) {
  if (bytes.empty()) return Ok{};
  if (background_ == nullptr) return drain(ZSTD_e_continue, bytes);
  if (file_ == nullptr) return error("written after it was closed");
  pending_.append(bytes);
  return pending_.size() >= kChunkBytes ? hand_over() : Status(Ok{});
}

std::string* ZstdFileWriter::append_buffer() {
  return background_ != nullptr && file_ != nullptr ? &pending_ : nullptr;
}

Status ZstdFileWriter::commit_appended() {
  if (background_ == nullptr) return Ok{};
  return pending_.size() >= kChunkBytes ? hand_over() : Status(Ok{});
}

Status ZstdFileWriter::close() {
  if (file_ == nullptr) return Ok{};
  if (background_ != nullptr) {
    Status queued = pending_.empty() ? Status(Ok{}) : hand_over();
    Status compressed = stop_background();
    if (!queued || !compressed) {
      std::fclose(file_);
      file_ = nullptr;
      context_.reset();
      return !compressed ? compressed : queued;
    }
  }
  auto st = drain(ZSTD_e_end, {});
  const bool flushed = std::fflush(file_) == 0;
  const int saved_errno = errno;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  context_.reset();
  if (!st) return st;
  if (!flushed || !closed) return error("write failed (" + output_errno_text(saved_errno) + ")");
  return Ok{};
}

Result<std::string> zstd_decompress(std::string_view frames) {
  ZSTD_DCtx* dctx = ZSTD_createDCtx();
  if (dctx == nullptr) return make_error(ErrorCode::kIo, "zstd: out of memory");
  std::string text;
  std::string block(ZSTD_DStreamOutSize(), '\0');
  ZSTD_inBuffer in{frames.data(), frames.size(), 0};
  size_t last = 0;
  while (in.pos < in.size) {
    ZSTD_outBuffer out{block.data(), block.size(), 0};
    last = ZSTD_decompressStream(dctx, &out, &in);
    if (ZSTD_isError(last) != 0U) {
      ZSTD_freeDCtx(dctx);
      return make_error(ErrorCode::kParse, std::string("zstd: ") + ZSTD_getErrorName(last));
    }
    text.append(block.data(), out.pos);
    if (out.pos == 0 && in.pos == in.size) break;
  }
  // Output still held in the context after the input is consumed.
  while (last != 0) {
    ZSTD_outBuffer out{block.data(), block.size(), 0};
    last = ZSTD_decompressStream(dctx, &out, &in);
    if (ZSTD_isError(last) != 0U || out.pos == 0) break;
    text.append(block.data(), out.pos);
  }
  ZSTD_freeDCtx(dctx);
  if (last != 0) return make_error(ErrorCode::kParse, "zstd: truncated frame");
  return text;
}

Result<std::string> read_zstd_file(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) return make_error(ErrorCode::kIo, path.string() + ": cannot open");
  std::ostringstream bytes;
  bytes << file.rdbuf();
  auto text = zstd_decompress(bytes.str());
  if (!text) return make_error(text.error().code, path.string() + ": " + text.error().message);
  return text;
}

}  // namespace skytrace::io

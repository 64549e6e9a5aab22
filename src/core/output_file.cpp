#include "skytrace/core/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>
#include <system_error>

namespace skytrace {
std::string output_errno_text(int error_number) {
  if (error_number == ENOSPC) return "no space left on the device";
  if (error_number == EFBIG) return "file size limit exceeded";
  return std::strerror(error_number);
}

namespace {

constexpr int kMaxSymlinkHops = 40;  // Linux's MAXSYMLINKS

Error output_error(const std::filesystem::path& path, const std::string& what) {
  return make_error(ErrorCode::kOutput, path.string() + ": " + what);
}

std::string errno_text(int error_number) { return output_errno_text(error_number); }

// Writes all of `data` to `fd`, retrying after interruptions and short writes.
bool write_all(int fd, const char* data, size_t size, int& error_number) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      error_number = errno;
      return false;
    }
    data += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

// Opens `target` for writing in place (a device or FIFO); never creates or truncates anything else.
Result<int> open_stream(const std::filesystem::path& target) {
  const int fd = ::open(target.c_str(), O_WRONLY | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) return output_error(target, std::string("cannot open for writing (") + errno_text(errno) + ")");
  return fd;
}

Status copy_file_into(const std::filesystem::path& source, int fd, const std::filesystem::path& target) {
  const int in = ::open(source.c_str(), O_RDONLY | O_CLOEXEC);
  if (in < 0) return output_error(source, std::string("cannot read back (") + errno_text(errno) + ")");
  char buffer[1 << 16];
  while (true) {
    const ssize_t n = ::read(in, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int e = errno;
      ::close(in);
      return output_error(source, std::string("cannot read back (") + errno_text(e) + ")");
    }
    if (n == 0) break;
    int error_number = 0;
    if (!write_all(fd, buffer, static_cast<size_t>(n), error_number)) {
      ::close(in);
      return output_error(target, "write failed (" + errno_text(error_number) + ")");
    }
  }
  ::close(in);
  return Ok{};
}

void remove_quietly(const std::filesystem::path& path) {
  std::error_code ignored;
  std::filesystem::remove(path, ignored);
}

// Writes `content` to a new temporary sibling of `target`; returns its path.
Result<std::filesystem::path> write_temporary(const std::filesystem::path& target, std::string_view content) {
  const auto tmp = temporary_sibling(target, "tmp");
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) {
    return output_error(target, std::string("cannot create a temporary file beside it (") + errno_text(errno) + ")");
  }
  int error_number = 0;
  const bool written = write_all(fd, content.data(), content.size(), error_number);
  if (::close(fd) != 0 && written) error_number = errno;
  if (!written || error_number != 0) {
    remove_quietly(tmp);
    return output_error(target, "write failed (" + errno_text(error_number) + ")");
  }
  return tmp;
}

}  // namespace

std::filesystem::path temporary_sibling(const std::filesystem::path& target, std::string_view role) {
  std::random_device rd;
  char suffix[48];
  std::snprintf(suffix, sizeof suffix, "%d-%08x", static_cast<int>(::getpid()), rd());
  std::string name = ".";
  name += target.filename().string();
  name += '.';
  name += role;
  name += '-';
  name += suffix;
  return target.parent_path() / name;
}

Result<OutputTarget> resolve_output_target(const std::filesystem::path& requested) {
  if (requested.empty() || requested.filename().empty()) return output_error(requested, "not a file name");
  std::filesystem::path path = requested;
  for (int hop = 0; hop <= kMaxSymlinkHops; ++hop) {
    struct stat info {};
    if (::lstat(path.c_str(), &info) != 0) {
      if (errno == ENOENT) return OutputTarget{path, OutputKind::kFile};
      return output_error(path, std::string("cannot inspect (") + errno_text(errno) + ")");
    }
    if (S_ISLNK(info.st_mode)) {
      std::error_code ec;
      const auto link_target = std::filesystem::read_symlink(path, ec);
      if (ec) return output_error(path, "cannot read the symbolic link (" + ec.message() + ")");
      path = link_target.is_absolute() ? link_target : path.parent_path() / link_target;
      continue;
    }
    if (S_ISREG(info.st_mode)) return OutputTarget{path, OutputKind::kFile};
    if (S_ISDIR(info.st_mode)) return output_error(requested, "is a folder, expected a file name");
    return OutputTarget{path, OutputKind::kStream};  // device, FIFO, socket
  }
  return output_error(requested, "too many levels of symbolic links");
}

Status install_output_file(const std::filesystem::path& finished, const std::filesystem::path& target) {
  auto resolved = resolve_output_target(target);
  if (!resolved) {
    remove_quietly(finished);
    return resolved.error();
  }
  if (resolved->kind == OutputKind::kStream) {
    auto fd = open_stream(resolved->path);
    if (!fd) {
      remove_quietly(finished);
      return fd.error();
    }
    auto copied = copy_file_into(finished, *fd, resolved->path);
    const int close_status = ::close(*fd);
    const int close_errno = errno;
    remove_quietly(finished);
    if (!copied) return copied.error();
    if (close_status != 0) return output_error(resolved->path, "write failed (" + errno_text(close_errno) + ")");
    return Ok{};
  }
  std::error_code ec;
  std::filesystem::rename(finished, resolved->path, ec);
  if (!ec) return Ok{};
  if (ec != std::errc::cross_device_link) {
    remove_quietly(finished);
    return output_error(resolved->path, "cannot move the finished file into place (" + ec.message() + ")");
  }
  // Another file system (a link out of the output folder): copy beside the target, then rename.
  const auto sibling = temporary_sibling(resolved->path, "tmp");
  std::filesystem::copy_file(finished, sibling, ec);
  remove_quietly(finished);
  if (ec) {
    remove_quietly(sibling);
    return output_error(resolved->path, "cannot create a temporary file beside it (" + ec.message() + ")");
  }
  std::filesystem::rename(sibling, resolved->path, ec);
  if (ec) {
    remove_quietly(sibling);
    return output_error(resolved->path, "cannot move the finished file into place (" + ec.message() + ")");
  }
  return Ok{};
}

Status write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  auto resolved = resolve_output_target(path);
  if (!resolved) return resolved.error();
  if (resolved->kind == OutputKind::kStream) {
    auto fd = open_stream(resolved->path);
    if (!fd) return fd.error();
    int error_number = 0;
    const bool written = write_all(*fd, content.data(), content.size(), error_number);
    if (::close(*fd) != 0 && written) error_number = errno;
    if (!written || error_number != 0) return output_error(resolved->path, "write failed (" + errno_text(error_number) + ")");
    return Ok{};
  }
  auto tmp = write_temporary(resolved->path, content);
  if (!tmp) return tmp.error();
  return install_output_file(*tmp, resolved->path);
}

}  // namespace skytrace

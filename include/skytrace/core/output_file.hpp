// Writing outputs without harming what the output path is. A regular file (or a path that does not
// exist yet) is written to a temporary sibling and renamed over the target, so a partial file never
// appears. A symbolic link is followed: its final target is written, the link stays. A device, FIFO
// or socket (/dev/null, /dev/stdout, a named pipe) is written in place, never replaced. A folder is
// refused. Errors carry ErrorCode::kOutput.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include "skytrace/core/error.hpp"

namespace skytrace {

enum class OutputKind {
  kFile,    // absent or a regular file: temporary sibling, then rename
  kStream,  // character or block device, FIFO, socket: written in place
};

struct OutputTarget {
  std::filesystem::path path;  // after following symbolic links
  OutputKind kind = OutputKind::kFile;
};

// Follows symbolic links (at most 40, as the kernel does) and classifies what the path is.
[[nodiscard]] Result<OutputTarget> resolve_output_target(const std::filesystem::path& requested);

// Writes `content` to `path` as described above.
[[nodiscard]] Status write_file_atomically(const std::filesystem::path& path, std::string_view content);

// Puts the finished file `finished` (a temporary file of the caller) at `target` as described
// above: renamed over a regular file (copied to a sibling first when they lie on different file
// systems), or copied into a stream target. `finished` is gone afterwards, also on error.
[[nodiscard]] Status install_output_file(const std::filesystem::path& finished, const std::filesystem::path& target);

// What a failed write's errno means, as the outputs' errors say it: "no space left on the device",
// "file size limit exceeded", else strerror.
[[nodiscard]] std::string output_errno_text(int error_number);

// A name for a temporary sibling of `target` ("obs.rnx" -> "obs.rnx.<role>-<pid>-<random>"),
// unique for this process.
[[nodiscard]] std::filesystem::path temporary_sibling(const std::filesystem::path& target, std::string_view role);

}  // namespace skytrace

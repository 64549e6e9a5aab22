// Optional parts of skytrace built as modules, shared objects loaded on first use: the world
// loaders that need sdformat and GDAL, and the Gazebo bridge. Linked into the executable, their
// libraries (some 110 shared objects) would cost every command about 55 ms of loading before it
// starts (docs/adr/0005-optional-modules.md).
#pragma once

#include <cstdint>
#include <string>

#include "skytrace/core/error.hpp"

namespace skytrace {

// The folder the modules are loaded from: $SKYTRACE_MODULE_DIR when set, else lib/skytrace beside
// the folder of the running executable (build/bin/skytrace -> build/lib/skytrace).
[[nodiscard]] std::string module_dir();

// The address of `symbol` in the module `file_name` (e.g. "skytrace-world.so") of module_dir(),
// loaded once per process and kept. The error (kNotFound) names the file and the loader's reason.
[[nodiscard]] Result<void*> module_symbol(const std::string& file_name, const char* symbol);

// A module's table of functions: `entry` (extern "C", no arguments) returns it. A table whose
// `revision` or `layout` differ from the executable's is from another build of skytrace and is
// refused (kNotFound, naming the file), never called.
template <typename Table>
[[nodiscard]] Result<const Table*> module_table(const std::string& file_name, const char* entry,
                                               std::uint32_t revision, std::uint64_t layout) {
  auto address = module_symbol(file_name, entry);
  if (!address) return address.error();
  const Table* table = reinterpret_cast<const Table* (*)()>(*address)();
  if (table == nullptr || table->revision != revision || table->layout != layout) {
    return make_error(ErrorCode::kNotFound,
                      module_dir() + "/" + file_name + " is from another build of skytrace: rebuild the project");
  }
  return table;
}

}  // namespace skytrace

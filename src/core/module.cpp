#include "skytrace/core/module.hpp"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>

namespace skytrace {

std::string module_dir() {
  if (const char* dir = std::getenv("SKYTRACE_MODULE_DIR"); dir != nullptr && *dir != '\0') return dir;
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return "lib/skytrace";
  return (exe.parent_path().parent_path() / "lib" / "skytrace").string();
}

Result<void*> module_symbol(const std::string& file_name, const char* symbol) {
  static std::mutex mutex;
  static std::map<std::string, void*> handles;  // kept loaded until the process ends
  const std::lock_guard lock(mutex);
  const std::string path = module_dir() + "/" + file_name;
  void*& handle = handles[path];
  if (handle == nullptr) {
    // Every symbol resolved now: a module that does not fit the executable fails here, not mid-run.
    handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* reason = dlerror();
      return make_error(ErrorCode::kNotFound, "cannot load the module " + path + ": " +
                                                   (reason != nullptr ? reason : "unknown reason") +
                                                   " (build it with the project, or set SKYTRACE_MODULE_DIR)");
    }
  }
  dlerror();
  void* address = dlsym(handle, symbol);
  if (address == nullptr) {
    return make_error(ErrorCode::kNotFound, "the module " + path + " has no " + symbol + ": it is not skytrace's");
  }
  return address;
}

}  // namespace skytrace

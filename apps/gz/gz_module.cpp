// `skytrace gz`'s bridge, from the module skytrace-gz.so (gz_module.hpp).
#include "gz_module.hpp"

#include "skytrace/core/module.hpp"

namespace skytrace::gz {

Status run_bridge(const BridgeOptions& options) {
  auto entry = module_symbol(kGzBackendModule, kGzBackendEntry);
  if (!entry) return entry.error().with_context("skytrace gz");
  const GzBackend* table = reinterpret_cast<const GzBackend* (*)()>(*entry)();
  if (table == nullptr || table->revision != kGzBackendRevision || table->layout != gz_backend_layout()) {
    return make_error(ErrorCode::kNotFound, module_dir() + "/" + kGzBackendModule +
                                                " is from another build of skytrace: rebuild the project");
  }
  return table->run_bridge(options);
}

}  // namespace skytrace::gz

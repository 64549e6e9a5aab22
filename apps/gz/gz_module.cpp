// `skytrace gz`'s bridge, from the module skytrace-gz.so (gz_module.hpp).
#include "gz_module.hpp"

#include "skytrace/core/module.hpp"

namespace skytrace::gz {

Status run_bridge(const BridgeOptions& options) {
  auto table = module_table<GzBackend>(kGzBackendModule, kGzBackendEntry, kGzBackendRevision, gz_backend_layout());
  if (!table) return table.error().with_context("skytrace gz");
  return (*table)->run_bridge(options);
}

}  // namespace skytrace::gz

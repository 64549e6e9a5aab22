// The Gazebo bridge as a module (docs/adr/0005-optional-modules.md): gz_bridge.cpp and the
// ignition-transport, ignition-msgs and protobuf libraries it needs are built into skytrace-gz.so,
// which `skytrace gz` loads (gz_module.cpp); other commands never load them.
#pragma once

#include <cstdint>

#include "gz_bridge.hpp"

namespace skytrace::gz {

// The module's table; one of another build of skytrace is refused instead of called.
struct GzBackend {
  std::uint32_t revision = 0;
  std::uint64_t layout = 0;
  Status (*run_bridge)(const BridgeOptions& options) = nullptr;
};
inline constexpr std::uint32_t kGzBackendRevision = 1;
inline constexpr std::uint64_t gz_backend_layout() { return sizeof(GzBackend) + (sizeof(BridgeOptions) << 16); }
inline constexpr const char* kGzBackendModule = "skytrace-gz.so";
inline constexpr const char* kGzBackendEntry = "skytrace_gz_backend";

}  // namespace skytrace::gz

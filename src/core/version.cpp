#include "skytrace/core/version.hpp"

#ifndef SKYTRACE_VERSION_STRING
#define SKYTRACE_VERSION_STRING "unknown"
#endif

namespace skytrace {

const char* version() { return SKYTRACE_VERSION_STRING; }

}  // namespace skytrace

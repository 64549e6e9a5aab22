// How the process's heap allocator treats the large, short-lived buffers of the path search.
#pragma once

namespace skytrace {

// With glibc: blocks up to 32 MiB come from the heap instead of fresh mmap()ed pages, and freed
// memory stays with the process up to 256 MiB instead of going back to the kernel at once. The
// path search of a city allocates buffers of hundreds of kB per epoch (rays, lit patches); glibc's
// defaults mapped and zero-filled them anew every epoch, a fifth of a city run's time in the
// kernel (docs/performance.md). Called by the programs (skytrace, the live nodes' receiver);
// without glibc it does nothing.
void tune_allocator_for_epochs();

}  // namespace skytrace

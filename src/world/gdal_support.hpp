// GDAL for the world layer's loaders (internal): a dataset opened quietly, GDAL's own messages
// kept for the caller's error text instead of going to stderr.
#pragma once

#include <gdal_priv.h>

#include <filesystem>
#include <memory>
#include <string>

namespace skytrace::world::gdal {

struct DatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(d); }
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

// While it lives, GDAL's (and GEOS's) messages are not printed; CPLGetLastErrorMsg() keeps the last.
class QuietErrors {
 public:
  QuietErrors();
  ~QuietErrors();
  QuietErrors(const QuietErrors&) = delete;
  QuietErrors& operator=(const QuietErrors&) = delete;
};

// Opens `path` with `flags` (GDAL_OF_VECTOR or GDAL_OF_RASTER, read-only added), the drivers
// registered once; nullptr with `reason` (GDAL's last message, may be empty) when GDAL cannot.
// Call inside a QuietErrors scope.
[[nodiscard]] Dataset open(const std::filesystem::path& path, unsigned flags, std::string& reason);

}  // namespace skytrace::world::gdal

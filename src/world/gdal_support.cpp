#include "gdal_support.hpp"

#include <mutex>

namespace skytrace::world::gdal {

QuietErrors::QuietErrors() {
  CPLPushErrorHandler(CPLQuietErrorHandler);
  CPLErrorReset();
}

QuietErrors::~QuietErrors() { CPLPopErrorHandler(); }

Dataset open(const std::filesystem::path& path, unsigned flags, std::string& reason) {
  static std::once_flag registered;
  std::call_once(registered, [] { GDALAllRegister(); });
  Dataset dataset(GDALDataset::Open(path.c_str(), flags | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!dataset) reason = CPLGetLastErrorMsg();
  return dataset;
}

}  // namespace skytrace::world::gdal

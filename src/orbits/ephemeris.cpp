#include "skytrace/orbits/ephemeris.hpp"

#include <algorithm>

namespace skytrace::orbits {

std::string_view to_string(NavMessage message) {
  switch (message) {
    case NavMessage::kGpsLnav: return "LNAV";
    case NavMessage::kGpsCnav: return "CNAV";
    case NavMessage::kGpsCnav2: return "CNV2";
    case NavMessage::kGalileoInav: return "INAV";
    case NavMessage::kGalileoFnav: return "FNAV";
    case NavMessage::kBeiDouD1: return "D1";
    case NavMessage::kBeiDouD2: return "D2";
    case NavMessage::kBeiDouCnav1: return "CNV1";
    case NavMessage::kBeiDouCnav2: return "CNV2";
    case NavMessage::kBeiDouCnav3: return "CNV3";
    case NavMessage::kQzssLnav: return "LNAV";
    case NavMessage::kQzssCnav: return "CNAV";
    case NavMessage::kQzssCnav2: return "CNV2";
    case NavMessage::kNavicLnav: return "LNAV";
    case NavMessage::kGlonassFdma: return "FDMA";
    case NavMessage::kSbas: return "SBAS";
  }
  return "?";
}

namespace {

bool same_record(const KeplerEphemeris& a, const KeplerEphemeris& b) {
  return a.satellite == b.satellite && a.message == b.message && a.toe == b.toe && a.toc == b.toc &&
         a.iode == b.iode && a.af0_s == b.af0_s && a.m0_rad == b.m0_rad && a.data_source == b.data_source;
}
bool same_record(const GlonassEphemeris& a, const GlonassEphemeris& b) {
  return a.satellite == b.satellite && a.toe == b.toe && a.position_m == b.position_m &&
         a.minus_tau_n_s == b.minus_tau_n_s;
}
bool same_record(const SbasEphemeris& a, const SbasEphemeris& b) {
  return a.satellite == b.satellite && a.toe == b.toe && a.position_m == b.position_m;
}

template <typename Record>
void append_unique(std::vector<Record>& into, std::vector<Record>&& from) {
  const size_t existing = into.size();
  for (auto& record : from) {
    const auto begin = into.begin();
    const auto end = into.begin() + static_cast<std::ptrdiff_t>(existing);
    if (std::none_of(begin, end, [&](const Record& r) { return same_record(r, record); })) {
      into.push_back(std::move(record));
    }
  }
}

template <typename T>
void keep_first(std::optional<T>& mine, const std::optional<T>& theirs) {
  if (!mine && theirs) mine = theirs;
}

}  // namespace

void NavigationData::merge(NavigationData other) {
  append_unique(kepler, std::move(other.kepler));
  append_unique(glonass, std::move(other.glonass));
  append_unique(sbas, std::move(other.sbas));
  keep_first(ionosphere.gps, other.ionosphere.gps);
  keep_first(ionosphere.qzss, other.ionosphere.qzss);
  keep_first(ionosphere.beidou, other.ionosphere.beidou);
  keep_first(ionosphere.navic, other.ionosphere.navic);
  keep_first(ionosphere.galileo, other.ionosphere.galileo);
  for (auto& correction : other.time_corrections) {
    const bool known = std::any_of(time_corrections.begin(), time_corrections.end(),
                                   [&](const TimeSystemCorrection& c) { return c.type == correction.type; });
    if (!known) time_corrections.push_back(std::move(correction));
  }
  keep_first(leap_seconds, other.leap_seconds);
  for (auto& file : other.source_files) source_files.push_back(std::move(file));
}

}  // namespace skytrace::orbits

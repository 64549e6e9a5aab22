// Receiver antenna phase centres from ANTEX 1.4 (IGS antenna exchange format): the mean phase
// centre offset (north, east, up from the antenna reference point) and the phase centre
// variations over zenith angle and azimuth, per frequency. Satellite antennas are skipped (the
// satellite side is not modelled). docs/models/antenna.md gives the convention.
#pragma once

#include <Eigen/Core>

#include <filesystem>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/signal.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::receiver {

// One "START OF FREQUENCY" block of a receiver antenna.
struct AntexFrequency {
  std::string code;  // ANTEX frequency code, e.g. "G01", "E05", "C02"
  Eigen::Vector3d offset_neu_m = Eigen::Vector3d::Zero();  // PCO: north, east, up
  // PCV (m) at the zenith nodes ZEN1, ZEN1 + DZEN, ..., ZEN2: the NOAZI row, and with DAZI > 0 the
  // rows at azimuths 0, DAZI, ..., 360 (row-major: azimuth row, then zenith node).
  std::vector<double> noazi_m;
  std::vector<double> grid_m;
};

struct AntexAntenna {
  std::string type;    // antenna code (columns 1-16, e.g. "TRM59800.00")
  std::string radome;  // radome code (columns 17-20, e.g. "NONE")
  std::string serial;  // empty: the type mean
  double dazi_deg = 0.0;  // 0: no azimuth-dependent rows
  double zen1_deg = 0.0, zen2_deg = 90.0, dzen_deg = 5.0;
  std::optional<GnssTime> valid_from, valid_until;
  std::vector<AntexFrequency> frequencies;

  // "TYPE            RADO": the IGS name as RINEX ANT # / TYPE carries it (20 characters).
  [[nodiscard]] std::string name() const;
  [[nodiscard]] const AntexFrequency* frequency(std::string_view code) const;
  [[nodiscard]] size_t zenith_nodes() const;
  [[nodiscard]] size_t azimuth_rows() const;  // 0 without azimuth-dependent rows
  // PCV (m) of `f` at a zenith angle and azimuth (deg): bilinear between the grid nodes (the NOAZI
  // row without azimuth rows); zenith angles beyond the grid take its last node (as RTKLIB does).
  [[nodiscard]] double variation_m(const AntexFrequency& f, double zenith_deg, double azimuth_deg) const;
};

struct AntexFile {
  std::string source;  // file name, for messages
  char pcv_type = 'A';  // 'A' absolute, 'R' relative
  std::vector<AntexAntenna> receiver_antennas;
  size_t satellite_antennas_skipped = 0;

  // The type-mean calibration (blank serial) of `igs_name` ("TRM59800.00     NONE", or the type and
  // radome separated by blanks, or the type alone for NONE) valid at `at` (any when nullopt). An
  // absent radome falls back to the same type with radome NONE, as IGS users do. Not found: an
  // error (kNotFound) naming the file, the antenna and the closest names the file holds.
  [[nodiscard]] Result<const AntexAntenna*> find(std::string_view igs_name,
                                                 const std::optional<GnssTime>& at = std::nullopt) const;
};

// Parses ANTEX text; `name` names the source in messages ("file:line: expected ...").
[[nodiscard]] Result<AntexFile> parse_antex(const std::string& name, std::string content);
[[nodiscard]] Result<AntexFile> read_antex(const std::filesystem::path& path);

// An IGS antenna name split into type and radome (radome NONE when absent); nullopt when it
// cannot be one (empty, a type over 16 characters, a radome over 4).
struct IgsAntennaName {
  std::string type;
  std::string radome;
};
[[nodiscard]] std::optional<IgsAntennaName> split_igs_antenna_name(std::string_view text);

// The ANTEX frequency code of a signal: system letter and RINEX 3 band digit ("G01" for GPS L1,
// "C02" for BeiDou B1I, "R01" for GLONASS G1).
[[nodiscard]] std::string antex_frequency_code(const Signal& signal);

// The phase centre of one receiver antenna for the signals of a run, resolved once: every signal
// gets its frequency block (QZSS falling back to the GPS frequency of the same band, as IGS does;
// any other system lacking its own block takes the GPS block closest in carrier frequency).
class AntennaPhaseCentre {
 public:
  // Error (kNotFound) naming the file and antenna when a signal has no usable frequency.
  [[nodiscard]] static Result<AntennaPhaseCentre> create(const AntexAntenna& antenna, std::span<const Signal> signals,
                                                         const std::string& source);

  // The change (m) of the range of `signal` towards `direction` (at the reference point) that the
  // phase centre makes: -(e . PCO) + PCV(zenith, azimuth), e the unit line of sight in the local
  // east-north-up frame. Added to code and carrier phase alike. 0 for a signal not resolved.
  [[nodiscard]] double range_correction_m(const Signal& signal, const AzimuthElevation& direction) const;

  [[nodiscard]] const AntexAntenna& antenna() const { return antenna_; }
  // The frequency block a signal uses (nullptr: none).
  [[nodiscard]] const AntexFrequency* frequency_of(const Signal& signal) const;

 private:
  AntexAntenna antenna_;
  std::map<Signal, size_t> frequency_index_;  // into antenna_.frequencies
};

}  // namespace skytrace::receiver

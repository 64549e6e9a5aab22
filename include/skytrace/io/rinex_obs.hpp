// RINEX observation files: one data model for what a receiver records, a streaming writer
// (RINEX 3.04 and 4.00) and a reader (RINEX 2.11, 3.0x and 4.0x).
//
// Times inside the program are GnssTime on the GPST timeline; in the file they are written in the
// header's time system (TIME OF FIRST OBS), which is GPS time unless the header says otherwise.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/satellite.hpp"
#include "skytrace/core/time.hpp"

namespace skytrace::io {

// One observation type of one system.
struct ObservationType {
  // RINEX 3 code: type letter (C code, L phase, D Doppler, S signal strength, I ionosphere delay,
  // X receiver channel), band digit and attribute, e.g. "C1C", "L2W"; "X1" and "I5" (RINEX 3.01+:
  // the attribute of these two is blank). Empty when a RINEX 2 code has no RINEX 3 equivalent for the
  // system (rinex2_code then tells what the column holds).
  std::string code;
  // The two-letter code of a RINEX 2 file ("C1", "P2", "L1"), empty for RINEX 3 and 4 files.
  std::string rinex2_code;

  // 'C', 'L', 'D', 'S', 'I', 'X' (a RINEX 2 'P' code counts as 'C'), or '\0' if unknown (RINEX 2 'T').
  [[nodiscard]] char kind() const;
  friend bool operator==(const ObservationType&, const ObservationType&) = default;
};

// One value of a satellite's record: units are those of the type (m for C, cycles for L, Hz for D,
// the SIGNAL STRENGTH UNIT for S).
struct ObservationValue {
  std::optional<double> value;  // nullopt: blank field
  std::uint8_t lli = 0;         // loss-of-lock indicator, bits 0-2 (0 and blank are the same)
  std::uint8_t ssi = 0;         // signal-strength indicator 1-9 (0 and blank: unknown)
};

struct SatelliteObservations {
  SatelliteId satellite;
  // In the order of the header's observation types of the satellite's system; a shorter vector
  // means the remaining values are blank.
  std::vector<ObservationValue> values;
};

enum class EpochFlag : std::uint8_t {
  kOk = 0,
  kPowerFailure = 1,    // power failure between the previous epoch and this one
  kStartMoving = 2,     // event: start of moving antenna
  kNewSite = 3,         // event: new site occupation, header records follow
  kHeaderInfo = 4,      // event: header records follow
  kExternalEvent = 5,   // event: external event (time significant)
  kCycleSlip = 6,       // cycle-slip records, in the layout of observations
};

// Flags 2-5 carry `event_records` instead of observations.
[[nodiscard]] inline bool is_event_flag(EpochFlag flag) {
  return flag >= EpochFlag::kStartMoving && flag <= EpochFlag::kExternalEvent;
}

struct ObservationEpoch {
  GnssTime time;  // GPST timeline (written in the header's time system)
  EpochFlag flag = EpochFlag::kOk;
  std::optional<double> receiver_clock_offset_s;
  std::vector<SatelliteObservations> satellites;  // flags 0, 1 and 6
  // Flags 2-5: the header-format lines that follow the epoch line (without line terminator).
  std::vector<std::string> event_records;

  // The record of a satellite, or nullptr.
  [[nodiscard]] const SatelliteObservations* find(const SatelliteId& satellite) const;
};

// SYS / PHASE SHIFT (RINEX 3.01 to 3.05; deprecated from 4.00, which ignores it).
struct PhaseShift {
  GnssSystem system = GnssSystem::kGps;
  std::string code;                     // phase observation code, e.g. "L2L" (may be empty in files)
  std::optional<double> shift_cycles;   // correction applied; nullopt: blank field
  std::vector<SatelliteId> satellites;  // empty: all satellites of the system
  friend bool operator==(const PhaseShift&, const PhaseShift&) = default;
};

// GLONASS COD/PHS/BIS (RINEX 3.02 to 3.05): code-phase alignment bias per code.
struct GlonassCodePhaseBias {
  std::string code;               // "C1C", "C1P", "C2C", "C2P"
  std::optional<double> bias_m;   // nullopt: blank (unknown)
  friend bool operator==(const GlonassCodePhaseBias&, const GlonassCodePhaseBias&) = default;
};

// GLONASS SLOT / FRQ #.
struct GlonassSlotFrequency {
  int slot = 1;     // satellite number R01..R24 (and spares)
  int channel = 0;  // frequency channel number k, -7..+6
  friend bool operator==(const GlonassSlotFrequency&, const GlonassSlotFrequency&) = default;
};

struct ObservationHeader {
  // Reader: the file's version (2.11, 3.05, 4.00 ...). Writer: 3.04 or 4.00.
  double version = 3.04;
  // Reader: the single system of the file, nullopt for mixed files ('M'). The writer derives it
  // from observation_types and ignores this field.
  std::optional<GnssSystem> file_system;

  std::string program;   // PGM / RUN BY / DATE
  std::string run_by;
  std::string date;      // "yyyymmdd hhmmss UTC"; the writer uses the current UTC time when empty
  std::vector<std::string> comments;

  std::string marker_name;
  std::string marker_number;
  std::string marker_type;  // e.g. GEODETIC, NON_GEODETIC, GROUND_CRAFT, AIRBORNE, HUMAN
  std::string observer;
  std::string agency;
  std::string receiver_number;
  std::string receiver_type;
  std::string receiver_version;
  std::string antenna_number;
  std::string antenna_type;
  std::optional<std::array<double, 3>> approx_position_ecef_m;  // APPROX POSITION XYZ
  std::array<double, 3> antenna_delta_hen_m{};                   // height, east, north

  // SYS / # / OBS TYPES (RINEX 3/4). For RINEX 2 files the reader lists the file's common types
  // under every system that appears in the file (the codes mapped per system).
  std::map<GnssSystem, std::vector<ObservationType>> observation_types;
  std::string signal_strength_unit;       // "DBHZ" or empty
  std::optional<double> interval_s;       // the writer fills it from the epochs when unset
  TimeScale time_system = TimeScale::kGpst;
  std::optional<GnssTime> time_of_first_obs;  // the writer sets both from the epochs
  std::optional<GnssTime> time_of_last_obs;
  std::optional<int> receiver_clock_offset_applied;  // RCV CLOCK OFFS APPL: 1 applied, 0 not
  std::optional<int> leap_seconds;                   // current GPS-UTC leap seconds
  std::vector<GlonassSlotFrequency> glonass_slots;
  std::vector<GlonassCodePhaseBias> glonass_code_phase_biases;
  // Writer, version 3.04: when empty, a zero shift is written for every phase type of every system.
  std::vector<PhaseShift> phase_shifts;
  // SYS / SCALE FACTOR: the reader has already divided the values by these factors.
  std::map<GnssSystem, std::map<std::string, int>> scale_factors;
  // Reader: header lines kept verbatim because this model has no field for them (the writer
  // does not write them).
  std::vector<std::string> other_records;

  // Index of a code ("C1C", or for RINEX 2 files also the original "P1") in a system's list.
  [[nodiscard]] std::optional<size_t> type_index(GnssSystem system, std::string_view code) const;
};

struct ObservationFile {
  ObservationHeader header;
  std::vector<ObservationEpoch> epochs;
  // Reader: what the format defines but skytrace does not use (channel numbers X1, ionosphere
  // pseudo-observables I, codes of signals outside the catalogue, RINEX 2 types without a RINEX 3
  // equivalent): one note per file naming them, each prefixed with the file name. Their columns are
  // read and left alone.
  std::vector<std::string> warnings;
};

// Reads a RINEX 2.10/2.11, 3.0x or 4.0x observation file (plain or gzip). Errors name file and line.
[[nodiscard]] Result<ObservationFile> read_rinex_obs(const std::filesystem::path& path);
// Same from text already in memory; `name` is used in error messages.
[[nodiscard]] Result<ObservationFile> parse_rinex_obs(std::string name, std::string content);

// The RINEX 3 code a RINEX 2 observation code stands for in a system ("P2", GPS -> "C2W"), or an
// empty string when there is none.
[[nodiscard]] std::string rinex2_to_rinex3_code(GnssSystem system, std::string_view rinex2_code);

struct RinexObsWriterOptions {
  // What write_epoch does with a value that F14.3 cannot hold (|value| > 999999999.999, NaN, inf):
  // false: fail naming satellite, type and time; true: write a blank field and count it.
  bool omit_unrepresentable_values = false;
  // Body bytes gathered in memory before each write to the temporary file.
  size_t buffer_bytes = size_t{1} << 20;
  // The first and last epochs (and the interval, unless the header has one) when the caller knows
  // them before writing, as a simulation on a time grid does: the header is written first and the
  // body after it, and finish() only renames the file when the epochs written give the same header;
  // otherwise it writes the final header before the body as without them. The bytes are the same.
  std::optional<GnssTime> expected_first_obs;
  std::optional<GnssTime> expected_last_obs;
  std::optional<double> expected_interval_s;
};

// Streaming writer. The body goes to a temporary file next to the target; finish() writes the
// final file (header with TIME OF FIRST/LAST OBS, then the body) under another temporary name and
// renames it (or renames the temporary itself when it already begins with that header:
// RinexObsWriterOptions::expected_first_obs), so a partial file never appears under the target
// name. Destroying a writer that has not finished removes its temporaries.
class RinexObsWriter {
 public:
  RinexObsWriter();
  ~RinexObsWriter();
  RinexObsWriter(RinexObsWriter&&) noexcept;
  RinexObsWriter& operator=(RinexObsWriter&&) noexcept;
  RinexObsWriter(const RinexObsWriter&) = delete;
  RinexObsWriter& operator=(const RinexObsWriter&) = delete;

  // Checks the header (version 3.04 or 4.00, observation codes, time system) and creates the body
  // temporary. A writer can be opened once.
  [[nodiscard]] Status open(const std::filesystem::path& path, ObservationHeader header,
                            RinexObsWriterOptions options = {});
  // Satellites are written sorted (G R E C J I S, then by number); epochs must not go back in time.
  [[nodiscard]] Status write_epoch(const ObservationEpoch& epoch);
  [[nodiscard]] Status finish();

  [[nodiscard]] bool is_open() const;
  [[nodiscard]] size_t epoch_count() const;
  // Values written blank under omit_unrepresentable_values.
  [[nodiscard]] size_t omitted_value_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Whole file at once through RinexObsWriter.
[[nodiscard]] Status write_rinex_obs(const std::filesystem::path& path, const ObservationHeader& header,
                                     const std::vector<ObservationEpoch>& epochs,
                                     RinexObsWriterOptions options = {});

namespace detail {
// Writes `value` as Fortran F14.3 (right-aligned, rounded to 1e-3) into out[0..14). Returns false,
// leaving `out` untouched, when |value| > 999999999.999 or it is not finite, so a field never
// overflows into its neighbours.
[[nodiscard]] bool format_f14_3(double value, char* out);
}  // namespace detail

}  // namespace skytrace::io

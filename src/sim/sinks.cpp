#include "skytrace/sim/sinks.hpp"

#include <fmt/format.h>

#include <cerrno>
#include <cmath>
#include <complex>
#include <cstring>
#include <optional>
#include <set>

#include "skytrace/core/constants.hpp"
#include "skytrace/core/decimal_text.hpp"
#include "skytrace/core/frames.hpp"
#include "skytrace/core/output_file.hpp"
#include "skytrace/io/fix_csv.hpp"
#include "skytrace/io/nmea.hpp"
#include "skytrace/io/report.hpp"
#include "skytrace/io/rtcm3.hpp"
#include "skytrace/io/zstd_file.hpp"
#include "skytrace/sim/run.hpp"
#include "skytrace/sim/streams.hpp"
#include "skytrace/sim/world_setup.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::sim {

// --- StagedFile ----------------------------------------------------------------------------------
namespace {
constexpr size_t kFlushBytes = 1u << 20;
}

Result<std::unique_ptr<StagedFile>> StagedFile::create(const std::filesystem::path& path) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) {
    return make_error(ErrorCode::kOutput, path.string() + ": cannot create (" + output_errno_text(errno) + ")");
  }
  return std::unique_ptr<StagedFile>(new StagedFile(path, file));
}

StagedFile::~StagedFile() {
  if (file_ != nullptr) std::fclose(file_);
}

Status StagedFile::flush() {
  if (buffer_.empty()) return Ok{};
  if (file_ == nullptr) return make_error(ErrorCode::kOutput, path_.string() + ": written after it was closed");
  if (std::fwrite(buffer_.data(), 1, buffer_.size(), file_) != buffer_.size()) {
    return make_error(ErrorCode::kOutput, path_.string() + ": write failed (" + output_errno_text(errno) + ")");
  }
  buffer_.clear();
  return Ok{};
}

Status StagedFile::write(std::string_view bytes) {
  buffer_.append(bytes);
  if (buffer_.size() >= kFlushBytes) return flush();
  return Ok{};
}

Status StagedFile::close() {
  if (file_ == nullptr) return Ok{};
  auto st = flush();
  const bool flushed = std::fflush(file_) == 0;
  const int saved_errno = errno;
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!st) return st;
  if (!flushed || !closed) {
    return make_error(ErrorCode::kOutput, path_.string() + ": write failed (" + output_errno_text(saved_errno) + ")");
  }
  return Ok{};
}

namespace {

// --- truth.csv, paths.csv ------------------------------------------------------------------------
constexpr const char* kTruthHeader =
    "time_gpst,receiver,sat,signal,status,az_deg,el_deg,range_m,range_rate_mps,sat_clock_m,relativistic_m,"
    "group_delay_m,iono_m,tropo_m,rx_clock_m,code_noise_m,phase_noise_m,doppler_noise_mps,ambiguity_cycles,"
    "pseudorange_m,carrier_phase_cycles,doppler_hz,cn0_dbhz,rx_x_m,rx_y_m,rx_z_m,rx_vx_mps,rx_vy_mps,rx_vz_mps,"
    "rx_clock_drift_mps,vegetation_attenuation_db,detail,path_type,code_multipath_m,phase_multipath_m,"
    "multipath_power_db,antenna_pc_m,foliage_code_m,foliage_phase_m,foliage_power_db\n";

// paths.csv (models.multipath): every path of every satellite-epoch with any path.
constexpr const char* kPathsHeader =
    "time_gpst,receiver,sat,path,type,reflections,excess_delay_m,relative_power_db,rhcp_power_db,lhcp_power_db,"
    "arrival_az_deg,arrival_el_deg,excess_delay_rate_mps,point_x_m,point_y_m,point_z_m,second_x_m,second_y_m,"
    "second_z_m,object,material,diffraction_v,diffraction_loss_db,vegetation_db\n";

std::string_view path_type_name(PathType type) {
  switch (type) {
    case PathType::kDirect: return "direct";
    case PathType::kReflected: return "reflected";
    case PathType::kDiffracted: return "diffracted";
    case PathType::kScattered: return "scattered";
  }
  return "?";
}

double power_db(std::complex<double> amplitude) { return 10.0 * std::log10(std::max(std::norm(amplitude), 1e-30)); }

std::string csv_text(const std::string& text);

void append_paths(std::string& out, const receiver::EpochObservations& epoch, const std::string& receiver_name,
                  std::map<std::string, std::set<SatelliteId>>& /*without_ephemeris*/) {
  const std::string time = epoch.true_time.to_iso8601(TimeScale::kGpst, 6);
  for (const auto& sat : epoch.satellites) {
    const std::string sat_name = sat.satellite.to_string();
    for (size_t k = 0; k < sat.paths.size(); ++k) {
      const SignalPath& p = sat.paths[k];
      CsvRow row(out);
      row.text(time).text(receiver_name).text(sat_name).integer(static_cast<std::int64_t>(k)).text(path_type_name(p.type));
      row.integer(p.reflections).fixed(p.excess_delay_m, 4).fixed(p.relative_power_db(), 2);
      row.fixed(power_db(p.rhcp_amplitude), 2).fixed(power_db(p.lhcp_amplitude), 2);
      row.fixed(sat.path_directions[k].azimuth_deg, 4).fixed(sat.path_directions[k].elevation_deg, 4);
      row.fixed(sat.path_delay_rates_mps[k], 5).fixed(p.point_m.x(), 3).fixed(p.point_m.y(), 3).fixed(p.point_m.z(), 3);
      // Two interactions: a double bounce, or a diffraction with a reflection.
      if (p.reflections >= 2 || (p.type == PathType::kDiffracted && p.reflections == 1)) {
        row.fixed(p.second_point_m.x(), 3).fixed(p.second_point_m.y(), 3).fixed(p.second_point_m.z(), 3);
      } else {
        row.empty(3);
      }
      row.text(csv_text(p.object)).text(p.type == PathType::kDirect ? std::string_view() : world::material_class_name(p.material));
      row.fixed(p.diffraction_v, 3).fixed(p.diffraction_loss_db, 2).fixed(p.vegetation_attenuation_db, 2);
      row.end();
    }
  }
}

// A CSV cell: quoted when it holds a comma or a quote.
std::string csv_text(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"') quoted += '"';
    quoted += c;
  }
  return quoted + "\"";
}

// `without_ephemeris`: receiver and satellite of the satellites whose last row said no_ephemeris.
// A satellite without a valid ephemeris has no geometry: one row when it enters that state (at
// the first epoch, or when its records end), not one at every epoch.
void append_truth(std::string& out, const receiver::EpochObservations& epoch, const std::string& receiver_name,
                  std::map<std::string, std::set<SatelliteId>>& without_ephemeris) {
  std::set<SatelliteId>& missing = without_ephemeris[receiver_name];
  const double c = constants::kSpeedOfLight_mps;
  const std::string time = epoch.true_time.to_iso8601(TimeScale::kGpst, 6);
  const auto& rx = epoch.receiver;
  // Cells shared by every row of the epoch, formatted once.
  std::string rx_clock;
  append_fixed(rx_clock, c * epoch.receiver_clock.bias_s, 4);
  std::string receiver_part;
  CsvRow(receiver_part)
      .fixed(rx.position_m.x(), 4)
      .fixed(rx.position_m.y(), 4)
      .fixed(rx.position_m.z(), 4)
      .fixed(rx.velocity_mps.x(), 5)
      .fixed(rx.velocity_mps.y(), 5)
      .fixed(rx.velocity_mps.z(), 5)
      .fixed(c * epoch.receiver_clock.drift_s_per_s, 6);
  constexpr std::string_view kNoGeometry = ",,,,,";  // 6 empty geometry cells
  constexpr int kSignalValueCells = 8;               // code noise to C/N0
  std::string geometry, signal_geometry;
  for (const auto& sat : epoch.satellites) {
    const std::string_view status = receiver::to_string(sat.status);
    const std::string sat_name = sat.satellite.to_string();
    const bool has_geometry = !(sat.status == receiver::SatelliteStatus::kNoEphemeris && !sat.waiting_for_ephemeris);
    if (!has_geometry) {
      if (!missing.insert(sat.satellite).second) continue;
    } else if (!missing.empty()) {
      missing.erase(sat.satellite);
    }
    // Geometry cells with a satellite clock: the satellite's, and in a signal's row the clock that
    // signal got (the same one unless the generator gave it another: formatted again only then).
    const auto geometry_with = [&](std::string& cells, double satellite_clock_m) {
      cells.clear();
      if (!has_geometry) {
        cells = kNoGeometry;
        return;
      }
      CsvRow(cells)
          .fixed(sat.direction.azimuth_deg, 4)
          .fixed(sat.direction.elevation_deg, 4)
          .fixed(sat.range_m, 4)
          .fixed(sat.range_rate_mps, 5)
          .fixed(satellite_clock_m, 4)
          .fixed(sat.relativistic_m, 4);
    };
    geometry_with(geometry, sat.satellite_clock_m);
    const std::string_view path_kind = receiver::to_string(sat.path_kind);
    // A row per signal its navigation record declares unusable (the others may be tracked).
    for (const auto& unhealthy : sat.unhealthy_signals) {
      CsvRow row(out);
      row.text(time).text(receiver_name).text(sat_name).text(unhealthy.signal.to_string()).text("unhealthy").raw(geometry);
      row.empty(2).fixed(sat.troposphere_m, 4).text(rx_clock).empty(kSignalValueCells).raw(receiver_part);
      row.fixed(sat.vegetation_attenuation_db, 2).text(csv_text(unhealthy.reason)).text(path_kind).empty(7).end();
    }
    if (sat.signals.empty() && sat.status == receiver::SatelliteStatus::kUnhealthy) continue;  // said above
    if (sat.signals.empty()) {
      // One row for the satellite: why it is not observed, with the geometry when known.
      CsvRow row(out);
      row.text(time).text(receiver_name).text(sat_name).empty().text(status).raw(geometry).empty();
      if (sat.status == receiver::SatelliteStatus::kTracked || sat.status == receiver::SatelliteStatus::kNoSignal ||
          sat.waiting_for_ephemeris) {
        row.fixed(sat.ionosphere_l1_m, 4).fixed(sat.troposphere_m, 4);
      } else {
        row.empty(2);
      }
      row.text(rx_clock).empty(kSignalValueCells).raw(receiver_part);
      row.fixed(sat.vegetation_attenuation_db, 2).text(csv_text(sat.detail)).text(path_kind).empty(7).end();
      continue;
    }
    for (const auto& m : sat.signals) {
      const bool own_clock = m.satellite_clock_m != sat.satellite_clock_m;
      if (own_clock) geometry_with(signal_geometry, m.satellite_clock_m);
      CsvRow row(out);
      row.text(time).text(receiver_name).text(sat_name).text(m.signal.to_string()).text(status);
      row.raw(own_clock ? signal_geometry : geometry);
      row.fixed(m.group_delay_m, 4).fixed(m.ionosphere_code_m, 4).fixed(sat.troposphere_m, 4).text(rx_clock);
      row.fixed(m.code_noise_m, 4).fixed(m.phase_noise_m, 5).fixed(m.doppler_noise_mps, 5).integer(m.ambiguity_cycles);
      row.fixed(m.pseudorange_m, 4).fixed(m.carrier_phase_cycles, 4).fixed(m.doppler_hz, 4).fixed(m.cn0_dbhz, 3);
      row.raw(receiver_part).fixed(sat.vegetation_attenuation_db, 2).empty().text(path_kind);
      row.fixed(m.code_multipath_m, 4).fixed(m.phase_multipath_m, 4).fixed(m.multipath_power_db, 2);
      row.fixed(m.antenna_phase_centre_m, 4);
      row.fixed(m.foliage_code_m, 4).fixed(m.foliage_phase_m, 4).fixed(m.foliage_power_db, 2).end();
    }
  }
}

// A table written zstd-compressed (output.truth_format csv.zst), compressed as it is written.
class CompressedFile final : public ByteStream {
 public:
  explicit CompressedFile(std::unique_ptr<io::ZstdFileWriter> writer) : writer_(std::move(writer)) {}
  Status write(std::string_view bytes) override { return writer_->write(bytes); }
  Status close() override { return writer_->close(); }
  std::string* append_buffer() override { return writer_->append_buffer(); }
  Status commit_appended() override { return writer_->commit_appended(); }

 private:
  std::unique_ptr<io::ZstdFileWriter> writer_;
};

// A table of the truth, rows per receiver epoch: truth.csv (every term of every signal of every
// receiver, RunOptions::write_truth) and paths.csv (models.multipath: every path of every
// satellite-epoch with any).
class TableSink final : public EpochSink {
 public:
  using AppendRows = void (*)(std::string&, const receiver::EpochObservations&, const std::string&,
                              std::map<std::string, std::set<SatelliteId>>&);
  TableSink(std::unique_ptr<ByteStream> file, AppendRows append_rows) : file_(std::move(file)), append_rows_(append_rows) {}
  Status add(const SinkEpoch& e) override {
    // Straight into the compressor's buffer when it has one (the truth with a compression thread).
    if (std::string* buffer = file_->append_buffer()) {
      append_rows_(*buffer, *e.observations, e.receiver->settings->name, state_);
      return file_->commit_appended();
    }
    text_.clear();
    append_rows_(text_, *e.observations, e.receiver->settings->name, state_);
    return file_->write(text_);
  }
  Status finish() override { return file_->close(); }

 private:
  std::unique_ptr<ByteStream> file_;
  AppendRows append_rows_;
  std::string text_;
  std::map<std::string, std::set<SatelliteId>> state_;  // what the row function carries from epoch to epoch
};

// --- obs.rnx -------------------------------------------------------------------------------------
class RinexObsSink final : public EpochSink {
 public:
  static Result<std::unique_ptr<EpochSink>> make(const RunContext& c) {
    auto sink = std::make_unique<RinexObsSink>();
    for (const SinkReceiver& rx : c.receivers) {
      auto& out = sink->receivers_.emplace_back();
      out.records = std::make_unique<RinexRecordMaker>(*rx.header);
      out.writer = std::make_unique<io::RinexObsWriter>();
      const auto path = c.staging_dir / ("obs" + rx.file_suffix + ".rnx");
      // The header can be written first when the epochs' span is known (the file is then not copied
      // behind a header at the end; the bytes are the same).
      io::RinexObsWriterOptions options;
      if (c.epoch_grid) {
        options.expected_first_obs = c.epoch_grid->first;
        options.expected_last_obs = c.epoch_grid->last;
        options.expected_interval_s = c.epoch_grid->interval_s;
      }
      if (auto st = out.writer->open(path, *rx.header, options); !st) return st.error();
    }
    return std::unique_ptr<EpochSink>(std::move(sink));
  }
  Status add(const SinkEpoch& e) override {
    Receiver& rx = receivers_[e.receiver_index];
    rx.records->record_into(*e.observations, rx.epoch);
    return rx.writer->write_epoch(rx.epoch);
  }
  Status finish() override {
    for (Receiver& rx : receivers_) {
      if (auto st = rx.writer->finish(); !st) return st;
    }
    return Ok{};
  }

 private:
  struct Receiver {
    std::unique_ptr<RinexRecordMaker> records;
    std::unique_ptr<io::RinexObsWriter> writer;
    io::ObservationEpoch epoch;  // the record of the epoch being written, its storage reused
  };
  std::vector<Receiver> receivers_;
};

// --- NMEA, RTCM 3, fix CSV encoders -------------------------------------------------------------
class NmeaEncoder final : public StreamEncoder {
 public:
  Result<std::string> encode(const SinkEpoch& e) override {
    std::string text;
    if (e.fix == nullptr) return text;
    for (const auto& sentence : io::nmea_epoch(*e.fix)) text += sentence;
    return text;
  }
};

class FixCsvEncoder final : public StreamEncoder {
 public:
  std::string header() const override { return io::fix_csv_header(); }
  Result<std::string> encode(const SinkEpoch& e) override {
    if (e.fix == nullptr) return std::string();
    return io::fix_csv_row(*e.fix);
  }
};

class Rtcm3Encoder final : public StreamEncoder {
 public:
  Rtcm3Encoder(const orbits::BroadcastEphemerides& ephemerides, const io::RtcmStation& station)
      : ephemerides_(ephemerides), stream_(io::Rtcm3StreamSettings{}, station) {}
  Result<std::string> encode(const SinkEpoch& e) override {
    auto bytes = rtcm3_epoch_bytes(stream_, *e.observations, records_in_use(ephemerides_, *e.observations));
    if (!bytes) return bytes.error();
    return std::string(reinterpret_cast<const char*>(bytes->data()), bytes->size());
  }

 private:
  const orbits::BroadcastEphemerides& ephemerides_;
  io::Rtcm3Stream stream_;
};

// One file per receiver: STEM[_NAME].EXT, each with its own encoder.
template <typename MakeEncoder>
Result<std::unique_ptr<EpochSink>> per_receiver_files(const RunContext& c, const std::string& stem,
                                                      const std::string& extension, MakeEncoder make_encoder) {
  auto group = std::make_unique<SinkGroup>();
  for (size_t i = 0; i < c.receivers.size(); ++i) {
    auto file = StagedFile::create(c.staging_dir / (stem + c.receivers[i].file_suffix + extension));
    if (!file) return file.error();
    group->add_sink(std::make_unique<StreamSink>(i, make_encoder(c.receivers[i]), std::move(*file)));
  }
  return std::unique_ptr<EpochSink>(std::move(group));
}

// --- report.html (every receiver), skyplot.svg of the first receiver ------------------------------------------------
class ReportSink final : public EpochSink {
 public:
  explicit ReportSink(const RunContext& c) : context_(c) {}
  Status add(const SinkEpoch& e) override {
    if (e.fix != nullptr) {
      // The fix against the true antenna position of the same epoch; the top view's frame is
      // east-north-up at the first true position the report sees.
      const Eigen::Vector3d& truth_m = e.observations->receiver.position_m;
      if (!origin_) {
        origin_ = truth_m;
        origin_rotation_ = ecef_to_enu_rotation(ecef_to_geodetic(truth_m));
      }
      io::ReportBuilder::FixError error;
      const bool positioned = e.fix->type != positioning::FixType::kNone && e.fix->position_ecef_m.allFinite();
      if (positioned) {
        const Eigen::Vector3d enu_error_m =
            ecef_to_enu_rotation(ecef_to_geodetic(truth_m)) * (e.fix->position_ecef_m - truth_m);
        const Eigen::Vector3d fix_view_m = origin_rotation_ * (e.fix->position_ecef_m - *origin_);
        const Eigen::Vector3d truth_view_m = origin_rotation_ * (truth_m - *origin_);
        error.east_m = enu_error_m.x();
        error.north_m = enu_error_m.y();
        error.up_m = enu_error_m.z();
        error.fix_east_m = fix_view_m.x();
        error.fix_north_m = fix_view_m.y();
        error.truth_east_m = truth_view_m.x();
        error.truth_north_m = truth_view_m.y();
        error.satellites_used = e.fix->satellites_used;
        error.hdop = e.fix->hdop;
      }
      report_.add_fix(e.receiver->settings->name, e.observations->receiver_time, positioning::to_string(e.fix->type),
                      positioned ? &error : nullptr);
    }
    const receiver::EpochObservations& epoch = *e.observations;
    for (const auto& sat : epoch.satellites) {
      if (sat.status == receiver::SatelliteStatus::kNoEphemeris && !sat.waiting_for_ephemeris) continue;
      io::ReportSample sample;
      sample.time = epoch.receiver_time;
      sample.satellite = sat.satellite;
      sample.azimuth_deg = sat.direction.azimuth_deg;
      sample.elevation_deg = sat.direction.elevation_deg;
      sample.status = std::string(receiver::to_string(sat.status));
      if (!sat.signals.empty()) sample.cn0_dbhz = sat.signals.front().cn0_dbhz;
      sample.vegetation_attenuation_db = sat.vegetation_attenuation_db;
      sample.path_kind = std::string(receiver::to_string(sat.path_kind));
      sample.receiver = e.receiver->settings->name;
      report_.add(sample);
    }
    return Ok{};
  }
  Status finish() override {
    const Scenario& s = *context_.scenario;
    const RunSummary& summary = *context_.summary;
    const SinkReceiver& first = context_.receivers.front();
    io::ReportMeta meta;
    meta.warnings = context_.resources->warnings;
    meta.scenario_name = s.name;
    meta.receiver_name = first.settings->name;
    meta.start = s.time.start;
    meta.end = s.time.start + s.time.duration_s;
    meta.interval_s = s.time.interval_s;
    meta.summary_rows = {{"epochs", std::to_string(summary.epochs)},
                         {"tracked satellite-epochs", std::to_string(summary.satellite_epochs)},
                         {"signal observations", std::to_string(summary.observations)},
                         {"receiver profile", first.settings->profile},
                         {"ionosphere", s.models.ionosphere},
                         {"troposphere", s.models.troposphere},
                         {"seed", std::to_string(s.seed)}};
    for (const auto& [system, count] : summary.satellite_epochs_per_system) {
      meta.summary_rows.emplace_back(system + " satellite-epochs", std::to_string(count));
    }
    if (const auto& world = context_.resources->world) {
      const LoadedWorld& w = *world;
      meta.summary_rows.emplace_back("world", w.name + " (" + std::to_string(w.objects) + " objects, " +
                                                  std::to_string(w.buildings) + " buildings, " + std::to_string(w.trees) +
                                                  " trees)");
      meta.warnings.insert(meta.warnings.end(), w.warnings.begin(), w.warnings.end());
      if (origin_) {
        // The world's objects in the frame of the fixes' top views.
        for (const auto& f : w.footprints) {
          io::ReportMeta::MapOutline outline;
          outline.kind = f.kind == world::ObjectKind::kBuilding ? io::ReportMeta::MapOutline::Kind::kBuilding
                         : f.kind == world::ObjectKind::kTree   ? io::ReportMeta::MapOutline::Kind::kTree
                                                                : io::ReportMeta::MapOutline::Kind::kOther;
          for (const auto& v : f.outline_m) {
            const Eigen::Vector3d en = origin_rotation_ * (w.frame.to_ecef(Eigen::Vector3d(v.x(), v.y(), 0.0)) - *origin_);
            outline.east_north_m.emplace_back(en.x(), en.y());
          }
          meta.world_outlines.push_back(std::move(outline));
        }
      }
      // Each receiver's sky mask where it starts.
      constexpr double kMaskStep_deg = 2.0;
      meta.sky_mask_azimuth_step_deg = kMaskStep_deg;
      for (size_t k = 0; k < context_.receivers.size(); ++k) {
        const SinkReceiver& rx = context_.receivers[k];
        auto start_position = rx.kinematics->at(s.time.start);
        if (!start_position) continue;
        if (auto mask = world_sky_mask_deg(w, start_position->position_m, kMaskStep_deg)) {
          if (k == 0) {
            meta.sky_mask_elevation_deg = std::move(*mask);
          } else {
            meta.receiver_sky_masks_deg[rx.settings->name] = std::move(*mask);
          }
        }
      }
    }
    if (auto st = write_file_atomically(context_.staging_dir / "report.html", report_.html(meta)); !st) return st;
    return write_file_atomically(context_.staging_dir / "skyplot.svg", report_.sky_plot_svg(meta));
  }

 private:
  const RunContext& context_;
  io::ReportBuilder report_;
  std::optional<Eigen::Vector3d> origin_;  // ECEF of the top view's origin
  Eigen::Matrix3d origin_rotation_ = Eigen::Matrix3d::Identity();
};

// A table of the truth (truth.csv, paths.csv): NAME.zst when output.truth_format is csv.zst, else NAME.
Result<std::unique_ptr<EpochSink>> make_table_sink(const RunContext& c, const char* name, const char* header,
                                                   TableSink::AppendRows append_rows) {
  std::unique_ptr<ByteStream> stream;
  if (c.scenario->output.truth_format == "csv") {
    auto file = StagedFile::create(c.staging_dir / name);
    if (!file) return file.error();
    stream = std::move(*file);
  } else {
    // With threads to spare, compressed on a thread of its own while the writer formats the next
    // rows (the writer thread sets the pace of a run with truth: docs/performance.md).
    io::ZstdWriteOptions options;
    options.background_thread = c.threads >= 2;
    auto file = io::ZstdFileWriter::create(c.staging_dir / (std::string(name) + ".zst"), options);
    if (!file) return file.error();
    stream = std::make_unique<CompressedFile>(std::move(*file));
  }
  if (auto st = stream->write(header); !st) return st.error();
  return std::unique_ptr<EpochSink>(std::make_unique<TableSink>(std::move(stream), append_rows));
}

}  // namespace

Result<std::unique_ptr<EpochSink>> make_rinex_obs_sink(const RunContext& context) { return RinexObsSink::make(context); }

std::unique_ptr<StreamEncoder> make_nmea_encoder() { return std::make_unique<NmeaEncoder>(); }
std::unique_ptr<StreamEncoder> make_fix_csv_encoder() { return std::make_unique<FixCsvEncoder>(); }
std::unique_ptr<StreamEncoder> make_rtcm3_encoder(const orbits::BroadcastEphemerides& ephemerides,
                                                  const io::RtcmStation& station) {
  return std::make_unique<Rtcm3Encoder>(ephemerides, station);
}

Status StreamSink::add(const SinkEpoch& epoch) {
  if (epoch.receiver_index != receiver_index_) return Ok{};
  if (!started_) {
    started_ = true;
    if (auto st = stream_->write(encoder_->header()); !st) return st;
  }
  auto bytes = encoder_->encode(epoch);
  if (!bytes) return bytes.error();
  if (bytes->empty()) return Ok{};
  return stream_->write(*bytes);
}

Status StreamSink::finish() {
  if (!started_) {
    started_ = true;
    if (auto st = stream_->write(encoder_->header()); !st) return st;
  }
  return stream_->close();
}

Status SinkGroup::add(const SinkEpoch& epoch) {
  for (auto& sink : sinks_) {
    if (auto st = sink->add(epoch); !st) return st;
  }
  return Ok{};
}

Status SinkGroup::finish() {
  for (auto& sink : sinks_) {
    if (auto st = sink->finish(); !st) return st;
  }
  return Ok{};
}

const std::vector<SinkKind>& run_sink_table() {
  static const std::vector<SinkKind> table = {
      {"obs.rnx", [](const RunContext&) { return true; }, false, &RinexObsSink::make},
      {"truth.csv(.zst)", [](const RunContext& c) { return c.write_truth; }, false,
       [](const RunContext& c) { return make_table_sink(c, "truth.csv", kTruthHeader, &append_truth); }},
      {"paths.csv(.zst)", [](const RunContext& c) { return c.write_truth && c.scenario->models.multipath; }, false,
       [](const RunContext& c) { return make_table_sink(c, "paths.csv", kPathsHeader, &append_paths); }},
      {"obs.rtcm3", [](const RunContext& c) { return c.scenario->output.rtcm3; }, false,
       [](const RunContext& c) {
         return per_receiver_files(c, "obs", ".rtcm3", [&](const SinkReceiver& rx) {
           return make_rtcm3_encoder(*c.resources->ephemerides, rtcm_station(rx.marker_m, *rx.settings));
         });
       }},
      {"fix.nmea", [](const RunContext& c) { return c.scenario->output.nmea; }, true,
       [](const RunContext& c) { return per_receiver_files(c, "fix", ".nmea", [](const SinkReceiver&) { return make_nmea_encoder(); }); }},
      {"fix.csv", [](const RunContext& c) { return c.scenario->output.fix; }, true,
       [](const RunContext& c) { return per_receiver_files(c, "fix", ".csv", [](const SinkReceiver&) { return make_fix_csv_encoder(); }); }},
      {"report.html", [](const RunContext&) { return true; }, false,
       [](const RunContext& c) -> Result<std::unique_ptr<EpochSink>> { return std::unique_ptr<EpochSink>(std::make_unique<ReportSink>(c)); }},
      {"bag (rosbag2, MCAP)", [](const RunContext& c) { return c.scenario->output.mcap; }, true, &make_mcap_sink},
      {"iq_L1 (IQ samples)", [](const RunContext& c) { return c.scenario->output.iq.has_value(); }, false, &make_iq_sink},
  };
  return table;
}

Result<std::vector<std::unique_ptr<EpochSink>>> make_run_sinks(const RunContext& context) {
  std::vector<std::unique_ptr<EpochSink>> sinks;
  for (const SinkKind& kind : run_sink_table()) {
    if (!kind.wanted(context)) continue;
    auto sink = kind.make(context);
    if (!sink) return sink.error();
    sinks.push_back(std::move(*sink));
  }
  return sinks;
}

bool run_needs_fixes(const RunContext& context) {
  for (const SinkKind& kind : run_sink_table()) {
    if (kind.needs_fixes && kind.wanted(context)) return true;
  }
  return false;
}

}  // namespace skytrace::sim

// IQ samples as a sink of the epoch stream (output.iq): the first receiver's incoming signals
// (GeneratorSettings::incoming_signals) become complex baseband samples between consecutive epochs,
// written as they come, and a GNSS-SDR configuration that processes the file as it is.
#include <fmt/format.h>

#include <algorithm>

#include "skytrace/baseband/l1ca_synthesizer.hpp"
#include "skytrace/sim/sinks.hpp"

namespace skytrace::sim {
namespace {

baseband::LnavCommon lnav_common(const orbits::BroadcastEphemerides& ephemerides, const GnssTime& start) {
  baseband::LnavCommon c;
  const orbits::NavigationData& nav = ephemerides.data();
  c.ionosphere = nav.ionosphere.gps;
  const WeekTow at = start.to_week_tow(TimeScale::kGpst);
  c.leap_seconds = nav.leap_seconds.value_or(gps_minus_utc_s(start));
  c.leap_seconds_future = c.leap_seconds;
  c.leap_week = at.week;
  c.leap_day = 1;
  c.utc_week = at.week;
  c.utc_tot_s = static_cast<int>(std::floor(at.tow_s / 4096.0)) * 4096;
  for (const auto& correction : nav.time_corrections) {
    if (correction.type != "GPUT") continue;
    c.utc_a0_s = correction.a0_s;
    c.utc_a1_s_per_s = correction.a1_s_per_s;
    const WeekTow ref = correction.reference_time.to_week_tow(TimeScale::kGpst);
    c.utc_week = ref.week;
    c.utc_tot_s = static_cast<int>(std::floor(ref.tow_s / 4096.0)) * 4096;
  }
  c.almanac_week = at.week;
  c.almanac_toa_s = static_cast<int>(std::floor(at.tow_s / 4096.0)) * 4096;
  for (int prn = 1; prn <= 32; ++prn) {
    c.almanac[static_cast<size_t>(prn)] =
        ephemerides.find_kepler(SatelliteId{GnssSystem::kGps, static_cast<std::uint8_t>(prn)}, start,
                                orbits::NavMessage::kGpsLnav);
  }
  return c;
}

class IqSink final : public EpochSink {
 public:
  static Result<std::unique_ptr<EpochSink>> make(const RunContext& c) {
    const IqSettings& iq = *c.scenario->output.iq;
    auto format = baseband::parse_sample_format(iq.format);
    if (!format) return format.error();
    auto sink = std::unique_ptr<IqSink>(new IqSink());
    sink->settings_ = iq;
    sink->staging_dir_ = c.staging_dir;
    sink->file_name_ = "iq_L1." + iq.format;
    auto file = StagedFile::create(c.staging_dir / sink->file_name_);
    if (!file) return file.error();
    sink->file_ = std::move(*file);
    const orbits::BroadcastEphemerides* ephemerides = c.resources->ephemerides.get();
    baseband::SynthesizerSettings s;
    s.sample_rate_hz = iq.sample_rate_hz;
    s.format = *format;
    s.start = c.scenario->time.start;
    s.seed = c.scenario->seed;
    s.noise = true;
    s.lnav = lnav_common(*ephemerides, c.scenario->time.start);
    s.record_at = [ephemerides](int prn, const GnssTime& t) {
      return ephemerides->find_kepler(SatelliteId{GnssSystem::kGps, static_cast<std::uint8_t>(prn)}, t,
                                      orbits::NavMessage::kGpsLnav);
    };
    sink->synthesizer_ = std::make_unique<baseband::L1caSynthesizer>(std::move(s));
    sink->start_ = c.scenario->time.start;
    return std::unique_ptr<EpochSink>(std::move(sink));
  }

  Status add(const SinkEpoch& e) override {
    if (e.receiver_index != 0) return Ok{};
    const receiver::EpochObservations& obs = *e.observations;
    arrivals_.clear();
    for (const receiver::SatelliteObservation& sat : obs.satellites) {
      if (sat.satellite.system != GnssSystem::kGps) continue;
      for (const receiver::IncomingSignal& in : sat.incoming) {
        if (in.signal.to_string() != "G1C") continue;
        baseband::L1caArrival a;
        a.prn = sat.satellite.prn();
        a.pseudorange_m = in.pseudorange_m;
        a.carrier_phase_cycles = in.carrier_phase_cycles;
        a.doppler_hz = in.doppler_hz;
        a.antenna_cn0_dbhz = in.antenna_cn0_dbhz;
        for (const receiver::IncomingPath& p : in.paths) {
          a.paths.push_back(baseband::ArrivalPath{p.excess_delay_m, p.excess_delay_rate_mps, p.amplitude});
        }
        arrivals_.push_back(std::move(a));
      }
    }
    buffer_.clear();
    if (auto st = synthesizer_->add_instant(obs.receiver_time - start_, arrivals_, buffer_); !st) return st;
    return file_->write(buffer_);
  }

  Status finish() override {
    if (auto st = file_->close(); !st) return st;
    auto conf = StagedFile::create(staging_dir_ / "gnss-sdr.conf");
    if (!conf) return conf.error();
    if (auto st = (*conf)->write(gnss_sdr_configuration()); !st) return st;
    return (*conf)->close();
  }

 private:
  IqSink() = default;

  // GNSS-SDR (0.0.17) reading the file as it is: GPS L1 C/A, one channel per satellite the file holds
  // at once (at least 4), its PVT writing RINEX and NMEA into gnss-sdr/ beside the file. Run it from
  // the output folder: gnss-sdr --config_file=gnss-sdr.conf
  [[nodiscard]] std::string gnss_sdr_configuration() const {
    const double fs = settings_.sample_rate_hz;
    const size_t channels = std::max<size_t>(4, synthesizer_->most_satellites());
    std::string t;
    t += "; GNSS-SDR configuration written by skytrace for " + file_name_ + "\n";
    t += fmt::format("; {} complex samples at {:.0f} samples/s ({} bytes each); run from this folder:\n",
                     synthesizer_->samples_written(), fs,
                     baseband::bytes_per_sample(*baseband::parse_sample_format(settings_.format)));
    t += ";   mkdir -p gnss-sdr && gnss-sdr --config_file=gnss-sdr.conf\n";
    t += "[GNSS-SDR]\n";
    t += fmt::format("GNSS-SDR.internal_fs_sps={:.0f}\n", fs);
    t += "SignalSource.implementation=File_Signal_Source\n";
    t += "SignalSource.filename=" + file_name_ + "\n";
    t += fmt::format("SignalSource.item_type={}\n",
                     baseband::gnss_sdr_item_type(*baseband::parse_sample_format(settings_.format)));
    t += fmt::format("SignalSource.sampling_frequency={:.0f}\n", fs);
    t += "SignalSource.samples=0\nSignalSource.repeat=false\nSignalSource.enable_throttle_control=false\n";
    t += "SignalSource.dump=false\n";
    t += "SignalConditioner.implementation=Signal_Conditioner\n";
    t += std::string("DataTypeAdapter.implementation=") +
         (settings_.format == "sc8"    ? "Ibyte_To_Complex"
          : settings_.format == "sc16" ? "Ishort_To_Complex"
                                       : "Pass_Through") +
         "\n";
    if (settings_.format == "gr_complex") t += "DataTypeAdapter.item_type=gr_complex\n";
    t += "InputFilter.implementation=Pass_Through\nInputFilter.item_type=gr_complex\n";
    t += "Resampler.implementation=Pass_Through\nResampler.item_type=gr_complex\n";
    t += "Channels_1C.count=" + std::to_string(channels) + "\n";
    t += "Channels.in_acquisition=1\nChannel.signal=1C\n";
    t += "Acquisition_1C.implementation=GPS_L1_CA_PCPS_Acquisition\nAcquisition_1C.item_type=gr_complex\n";
    t += "Acquisition_1C.coherent_integration_time_ms=1\nAcquisition_1C.pfa=0.01\n";
    t += "Acquisition_1C.doppler_max=6000\nAcquisition_1C.doppler_step=250\nAcquisition_1C.max_dwells=1\n";
    t += "Acquisition_1C.dump=false\n";
    t += "Tracking_1C.implementation=GPS_L1_CA_DLL_PLL_Tracking\nTracking_1C.item_type=gr_complex\n";
    // Wide loops to pull in, then 10 ms correlations with narrow ones (profiles/gnss-sdr.yaml).
    t += "Tracking_1C.pll_bw_hz=20.0\nTracking_1C.dll_bw_hz=2.0\nTracking_1C.early_late_space_chips=0.5\n";
    t += "Tracking_1C.extend_correlation_symbols=10\nTracking_1C.pll_bw_narrow_hz=5.0\n";
    t += "Tracking_1C.dll_bw_narrow_hz=0.5\n";
    t += "Tracking_1C.dump=false\n";
    t += "TelemetryDecoder_1C.implementation=GPS_L1_CA_Telemetry_Decoder\nTelemetryDecoder_1C.dump=false\n";
    // Carrier-smoothed pseudoranges, as receivers report them.
    t += "Observables.implementation=Hybrid_Observables\nObservables.dump=false\n";
    t += "Observables.enable_carrier_smoothing=true\nObservables.smoothing_factor=200\n";
    t += "PVT.implementation=RTKLIB_PVT\nPVT.positioning_mode=Single\nPVT.iono_model=Broadcast\n";
    t += "PVT.trop_model=Saastamoinen\nPVT.output_rate_ms=1000\nPVT.display_rate_ms=1000\n";
    t += "PVT.output_path=./gnss-sdr\nPVT.rinex_output_enabled=true\nPVT.rinex_version=3\n";
    t += "PVT.nmea_output_file_enabled=true\nPVT.nmea_dump_filename=gnss-sdr/gnss_sdr_pvt.nmea\n";
    t += "PVT.flag_nmea_tty_port=false\nPVT.flag_rtcm_server=false\nPVT.flag_rtcm_tty_port=false\n";
    t += "PVT.kml_output_enabled=false\nPVT.gpx_output_enabled=false\nPVT.geojson_output_enabled=false\n";
    t += "PVT.xml_output_enabled=false\nPVT.dump=false\n";
    return t;
  }

  IqSettings settings_;
  std::filesystem::path staging_dir_;
  std::string file_name_;
  std::unique_ptr<StagedFile> file_;
  std::unique_ptr<baseband::L1caSynthesizer> synthesizer_;
  GnssTime start_;
  std::vector<baseband::L1caArrival> arrivals_;
  std::string buffer_;
};

}  // namespace

Result<std::unique_ptr<EpochSink>> make_iq_sink(const RunContext& context) { return IqSink::make(context); }

}  // namespace skytrace::sim

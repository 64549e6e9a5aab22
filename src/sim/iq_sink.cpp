// IQ samples as a sink of the epoch stream (output.iq): the first receiver's incoming signals
// (GeneratorSettings::incoming_signals) become complex baseband samples between consecutive epochs,
// written as they come, and a GNSS-SDR configuration that processes the file as it is.
#include <fmt/format.h>

#include <algorithm>

#include "skytrace/baseband/synthesizer.hpp"
#include "skytrace/sim/sinks.hpp"

namespace skytrace::sim {
namespace {

// A navigation message's UTC terms: the header's correction of `type` (GPUT, GAUT), its reference
// time as GPS week and seconds rounded down to `tot_unit_s`; the start's week and time without one.
struct UtcTerms {
  double a0_s = 0.0, a1_s_per_s = 0.0;
  int week = 0, tot_s = 0;
};
UtcTerms utc_terms(const orbits::NavigationData& nav, const std::string& type, const GnssTime& start, int tot_unit_s) {
  UtcTerms u;
  WeekTow ref = start.to_week_tow(TimeScale::kGpst);
  for (const auto& correction : nav.time_corrections) {
    if (correction.type != type) continue;
    u.a0_s = correction.a0_s;
    u.a1_s_per_s = correction.a1_s_per_s;
    ref = correction.reference_time.to_week_tow(TimeScale::kGpst);
  }
  u.week = ref.week;
  u.tot_s = static_cast<int>(std::floor(ref.tow_s / tot_unit_s)) * tot_unit_s;
  return u;
}

baseband::LnavCommon lnav_common(const orbits::BroadcastEphemerides& ephemerides, const GnssTime& start) {
  baseband::LnavCommon c;
  const orbits::NavigationData& nav = ephemerides.data();
  c.ionosphere = nav.ionosphere.gps;
  const WeekTow at = start.to_week_tow(TimeScale::kGpst);
  c.leap_seconds = nav.leap_seconds.value_or(gps_minus_utc_s(start));
  c.leap_seconds_future = c.leap_seconds;
  c.leap_week = at.week;
  c.leap_day = 1;
  const UtcTerms utc = utc_terms(nav, "GPUT", start, 4096);
  c.utc_a0_s = utc.a0_s;
  c.utc_a1_s_per_s = utc.a1_s_per_s;
  c.utc_week = utc.week;
  c.utc_tot_s = utc.tot_s;
  c.almanac_week = at.week;
  c.almanac_toa_s = static_cast<int>(std::floor(at.tow_s / 4096.0)) * 4096;
  for (int prn = 1; prn <= 32; ++prn) {
    c.almanac[static_cast<size_t>(prn)] =
        ephemerides.find_kepler(SatelliteId{GnssSystem::kGps, static_cast<std::uint8_t>(prn)}, start,
                                orbits::NavMessage::kGpsLnav);
  }
  return c;
}

baseband::GnavCommon gnav_common(const orbits::BroadcastEphemerides& ephemerides) {
  baseband::GnavCommon c;
  for (const auto& correction : ephemerides.data().time_corrections) {
    if (correction.type == "GLUT") c.tau_c_s = correction.a0_s;
    if (correction.type == "GLGP") c.tau_gps_s = correction.a0_s;
  }
  return c;
}

baseband::InavCommon inav_common(const orbits::BroadcastEphemerides& ephemerides, const GnssTime& start) {
  baseband::InavCommon c;
  const orbits::NavigationData& nav = ephemerides.data();
  c.ionosphere = nav.ionosphere.galileo;
  const WeekTow at = start.to_week_tow(TimeScale::kGpst);
  c.leap_seconds = nav.leap_seconds.value_or(gps_minus_utc_s(start));
  c.leap_seconds_future = c.leap_seconds;
  c.leap_week = at.week - 1024;
  const UtcTerms utc = utc_terms(nav, "GAUT", start, 3600);
  c.utc_a0_s = utc.a0_s;
  c.utc_a1_s_per_s = utc.a1_s_per_s;
  c.utc_week = utc.week - 1024;  // GST weeks
  c.utc_tot_s = utc.tot_s;
  return c;
}

// One band of the samples: its file, its synthesizer and the signal of the observations it takes.
struct IqBand {
  std::string name;  // L1 | E1 | G1 | B1
  Signal signal;  // G1C | E1C | R1C | C2I: the observations it takes
  // What the samples carry beyond that signal's power: E1C is E1's pilot, half of E1 OS's power.
  double power_beyond_signal_db = 0.0;
  std::string file_name;
  std::unique_ptr<StagedFile> file;
  std::unique_ptr<baseband::BasebandSynthesizer> synthesizer;
};

class IqSink final : public EpochSink {
 public:
  static Result<std::unique_ptr<EpochSink>> make(const RunContext& c) {
    const IqSettings& iq = *c.scenario->output.iq;
    auto format = baseband::parse_sample_format(iq.format);
    if (!format) return format.error();
    auto sink = std::unique_ptr<IqSink>(new IqSink());
    sink->settings_ = iq;
    sink->format_ = *format;
    sink->staging_dir_ = c.staging_dir;
    sink->start_ = c.scenario->time.start;
    const orbits::BroadcastEphemerides* ephemerides = c.resources->ephemerides.get();
    const int first_week = c.scenario->time.start.to_week_tow(TimeScale::kGpst).week;
    for (const std::string& name : iq.bands) {
      IqBand band;
      band.name = name;
      // The observations the band takes: the signal scenario parsing checked the receiver lists.
      const sim::IqBand* known = sim::find_iq_band(name);
      if (known == nullptr) return make_error(ErrorCode::kInvalidArgument, "output.iq.bands: unknown band '" + name + "'");
      auto signal = Signal::parse(known->signal);
      if (!signal) return signal.error();
      band.signal = *signal;
      band.file_name = "iq_" + name + "." + iq.format;
      auto file = StagedFile::create(c.staging_dir / band.file_name);
      if (!file) return file.error();
      band.file = std::move(*file);
      baseband::SynthesizerSettings s;
      s.sample_rate_hz = iq.sample_rate_hz;
      s.format = *format;
      s.start = c.scenario->time.start;
      s.seed = c.scenario->seed + (name == "L1" ? 0 : name == "G1" ? 1 : name == "B1" ? 2 : 3);  // independent noise per band
      s.noise = true;
      std::unique_ptr<baseband::BandSignals> signals;
      if (name == "L1") {
        signals = baseband::make_gps_l1ca_signals(
            lnav_common(*ephemerides, c.scenario->time.start), first_week, [ephemerides](int prn, const GnssTime& t) {
              return ephemerides->find_kepler(SatelliteId{GnssSystem::kGps, static_cast<std::uint8_t>(prn)}, t,
                                              orbits::NavMessage::kGpsLnav);
            });
      } else if (name == "E1") {
        band.power_beyond_signal_db = 10.0 * std::log10(2.0);
        signals = baseband::make_galileo_e1_signals(
            inav_common(*ephemerides, c.scenario->time.start), first_week, [ephemerides](int prn, const GnssTime& t) {
              return ephemerides->find_kepler(SatelliteId{GnssSystem::kGalileo, static_cast<std::uint8_t>(prn)}, t,
                                              orbits::NavMessage::kGalileoInav);
            });
      } else if (name == "B1") {
        signals = baseband::make_beidou_b1i_signals(
            ephemerides->data().ionosphere, first_week, [ephemerides](int prn, const GnssTime& t) {
              // GEO satellites broadcast D2, the others D1: the record a receiver decodes from each.
              const SatelliteId sat{GnssSystem::kBeiDou, static_cast<std::uint8_t>(prn)};
              return ephemerides->find_kepler(sat, t, orbits::is_beidou_geo(sat) ? orbits::NavMessage::kBeiDouD2
                                                                                 : orbits::NavMessage::kBeiDouD1);
            });
      } else {
        signals = baseband::make_glonass_l1of_signals(
            gnav_common(*ephemerides), first_week, [ephemerides](int slot, const GnssTime& t) {
              return ephemerides->find_glonass(SatelliteId{GnssSystem::kGlonass, static_cast<std::uint8_t>(slot)}, t);
            });
      }
      band.synthesizer = std::make_unique<baseband::BasebandSynthesizer>(std::move(s), std::move(signals));
      sink->bands_.push_back(std::move(band));
    }
    return std::unique_ptr<EpochSink>(std::move(sink));
  }

  Status add(const SinkEpoch& e) override {
    if (e.receiver_index != 0) return Ok{};
    const receiver::EpochObservations& obs = *e.observations;
    for (IqBand& band : bands_) {
      arrivals_.clear();
      for (const receiver::SatelliteObservation& sat : obs.satellites) {
        for (const receiver::IncomingSignal& in : sat.incoming) {
          if (in.signal != band.signal) continue;  // compared as a value: no text per signal and epoch
          baseband::Arrival a;
          a.id = sat.satellite.prn();
          a.carrier_hz = in.carrier_hz;
          a.pseudorange_m = in.pseudorange_m;
          a.carrier_phase_cycles = in.carrier_phase_cycles;
          a.doppler_hz = in.doppler_hz;
          a.antenna_cn0_dbhz = in.antenna_cn0_dbhz + band.power_beyond_signal_db;
          for (const receiver::IncomingPath& p : in.paths) {
            a.paths.push_back(baseband::ArrivalPath{p.excess_delay_m, p.excess_delay_rate_mps, p.amplitude});
          }
          arrivals_.push_back(std::move(a));
        }
      }
      buffer_.clear();
      if (auto st = band.synthesizer->add_instant(obs.receiver_time - start_, arrivals_, buffer_); !st) return st;
      if (auto st = band.file->write(buffer_); !st) return st;
    }
    return Ok{};
  }

  Status finish() override {
    for (IqBand& band : bands_) {
      if (auto st = band.file->close(); !st) return st;
      auto conf = StagedFile::create(staging_dir_ / ("gnss-sdr-" + band.name + ".conf"));
      if (!conf) return conf.error();
      if (auto st = (*conf)->write(gnss_sdr_configuration(band)); !st) return st;
      if (auto st = (*conf)->close(); !st) return st;
    }
    return Ok{};
  }

 private:
  IqSink() = default;

  // GNSS-SDR (0.0.17) reading a band's file as it is: one channel per satellite the file holds at
  // once (at least 4), its PVT writing RINEX and NMEA into gnss-sdr-BAND/ beside the file. Run it
  // from the output folder: gnss-sdr --config_file=gnss-sdr-BAND.conf
  [[nodiscard]] std::string gnss_sdr_configuration(const IqBand& band) const {
    const double fs = settings_.sample_rate_hz;
    const size_t channels = std::max<size_t>(4, band.synthesizer->most_satellites());
    const bool gps = band.name == "L1";
    const bool galileo = band.name == "E1";
    const bool beidou = band.name == "B1";
    const std::string id = gps ? "1C" : galileo ? "1B" : beidou ? "B1" : "1G";
    const char* system = gps ? "GPS_L1_CA" : beidou ? "BEIDOU_B1I" : "GLONASS_L1_CA";
    const std::string out_dir = "gnss-sdr-" + band.name;
    std::string t;
    t += "; GNSS-SDR configuration written by skytrace for " + band.file_name + " (" +
         (gps       ? "GPS L1 C/A"
          : galileo ? "Galileo E1 OS: E1-B with I/NAV, E1-C pilot, CBOC(6,1,1/11)"
          : beidou  ? "BeiDou B1I: D1 of MEO and IGSO satellites, D2 of GEO ones"
                    : "GLONASS L1OF, centred on 1602 MHz") +
         ")\n";
    t += fmt::format("; {} complex samples at {:.0f} samples/s ({} bytes each); run from this folder:\n",
                     band.synthesizer->samples_written(), fs, baseband::bytes_per_sample(format_));
    t += ";   mkdir -p " + out_dir + " && gnss-sdr --config_file=gnss-sdr-" + band.name + ".conf\n";
    t += "[GNSS-SDR]\n";
    t += fmt::format("GNSS-SDR.internal_fs_sps={:.0f}\n", fs);
    t += "SignalSource.implementation=File_Signal_Source\n";
    t += "SignalSource.filename=" + band.file_name + "\n";
    t += fmt::format("SignalSource.item_type={}\n", baseband::gnss_sdr_item_type(format_));
    t += fmt::format("SignalSource.sampling_frequency={:.0f}\n", fs);
    t += "SignalSource.samples=0\nSignalSource.repeat=false\nSignalSource.enable_throttle_control=false\n";
    t += "SignalSource.dump=false\n";
    t += "SignalConditioner.implementation=Signal_Conditioner\n";
    t += std::string("DataTypeAdapter.implementation=") +
         (format_ == baseband::SampleFormat::kSc8    ? "Ibyte_To_Complex"
          : format_ == baseband::SampleFormat::kSc16 ? "Ishort_To_Complex"
                                                     : "Pass_Through") +
         "\n";
    if (format_ == baseband::SampleFormat::kGrComplex) t += "DataTypeAdapter.item_type=gr_complex\n";
    t += "InputFilter.implementation=Pass_Through\nInputFilter.item_type=gr_complex\n";
    t += "Resampler.implementation=Pass_Through\nResampler.item_type=gr_complex\n";
    t += "Channels_" + id + ".count=" + std::to_string(channels) + "\n";
    t += "Channels.in_acquisition=1\nChannel.signal=" + id + "\n";
    if (galileo) {
      // 4 ms coherent (one E1 code period) with a BOC(1,1) replica. Every period may flip the data
      // symbol and the pilot's secondary chip, and a flip inside the window splits the peak into
      // two lobes about 175 Hz either side; GNSS-SDR then pulled the PLL to a false lock 125 Hz off
      // and never synchronised to the secondary code. Searching both halves of 8 ms
      // (bit_transition_flag) in 50 Hz steps hands tracking a Doppler within 25 Hz.
      t += "Acquisition_1B.implementation=Galileo_E1_PCPS_Ambiguous_Acquisition\n";
      t += "Acquisition_1B.item_type=gr_complex\nAcquisition_1B.coherent_integration_time_ms=4\n";
      t += "Acquisition_1B.pfa=0.0001\nAcquisition_1B.acquire_pilot=true\nAcquisition_1B.bit_transition_flag=true\n";
      t += "Acquisition_1B.doppler_max=5000\nAcquisition_1B.doppler_step=50\n";
      t += "Acquisition_1B.max_dwells=1\nAcquisition_1B.dump=false\n";
      // VEML on the pilot: 4 ms correlations to pull in, then, synchronised to the secondary code
      // and with it wiped, 20 ms ones with narrow loops (4 ms left the Doppler's p68 at 0.047 m/s).
      t += "Tracking_1B.implementation=Galileo_E1_DLL_PLL_VEML_Tracking\nTracking_1B.item_type=gr_complex\n";
      t += "Tracking_1B.track_pilot=true\nTracking_1B.pll_bw_hz=15.0\nTracking_1B.dll_bw_hz=2.0\n";
      t += "Tracking_1B.early_late_space_chips=0.15\nTracking_1B.very_early_late_space_chips=0.5\n";
      t += "Tracking_1B.extend_correlation_symbols=5\nTracking_1B.pll_bw_narrow_hz=5.0\nTracking_1B.dll_bw_narrow_hz=0.5\n";
      t += "Tracking_1B.dump=false\n";
      t += "TelemetryDecoder_1B.implementation=Galileo_E1B_Telemetry_Decoder\nTelemetryDecoder_1B.dump=false\n";
    } else {
      t += "Acquisition_" + id + ".implementation=" + system + "_PCPS_Acquisition\n";
      t += "Acquisition_" + id + ".item_type=gr_complex\n";
      t += "Acquisition_" + id + ".coherent_integration_time_ms=1\nAcquisition_" + id + ".pfa=0.01\n";
      // B1I at 100 Hz steps: a GEO satellite (D2's 2 ms bits) is pulled in only from close to its
      // Doppler, and GNSS-SDR drops it when its bit synchronisation takes long.
      t += "Acquisition_" + id + ".doppler_max=6000\nAcquisition_" + id + ".doppler_step=" + (beidou ? "100" : "250") + "\n";
      t += "Acquisition_" + id + ".max_dwells=1\nAcquisition_" + id + ".dump=false\n";
      t += "Tracking_" + id + ".implementation=" + system + "_DLL_PLL_Tracking\n";
      t += "Tracking_" + id + ".item_type=gr_complex\n";
      // Wide loops to pull in, then 10 ms correlations with narrow ones (profiles/gnss-sdr.yaml).
      t += "Tracking_" + id + ".pll_bw_hz=20.0\nTracking_" + id + ".dll_bw_hz=2.0\n";
      t += "Tracking_" + id + ".early_late_space_chips=0.5\n";
      if (!beidou) {  // B1I's 1 ms symbols carry the Neumann-Hoffman code: plain loops
        t += "Tracking_" + id + ".extend_correlation_symbols=10\nTracking_" + id + ".pll_bw_narrow_hz=5.0\n";
        t += "Tracking_" + id + ".dll_bw_narrow_hz=0.5\n";
      }
      t += "Tracking_" + id + ".dump=false\n";
      t += "TelemetryDecoder_" + id + ".implementation=" + system + "_Telemetry_Decoder\n";
      t += "TelemetryDecoder_" + id + ".dump=false\n";
    }
    // Carrier-smoothed pseudoranges, as receivers report them.
    t += "Observables.implementation=Hybrid_Observables\nObservables.dump=false\n";
    t += "Observables.enable_carrier_smoothing=true\nObservables.smoothing_factor=200\n";
    // L1OF carries no ionosphere model: GLONASS alone is solved without one; GNSS-SDR's
    // "Broadcast" model is GPS's, absent from a BeiDou-only run.
    t += std::string("PVT.implementation=RTKLIB_PVT\nPVT.positioning_mode=Single\nPVT.iono_model=") +
         (gps ? "Broadcast" : "OFF") + "\n";
    t += "PVT.trop_model=Saastamoinen\nPVT.output_rate_ms=1000\nPVT.display_rate_ms=1000\n";
    t += "PVT.output_path=./" + out_dir + "\nPVT.rinex_output_enabled=true\nPVT.rinex_version=3\n";
    t += "PVT.nmea_output_file_enabled=true\nPVT.nmea_dump_filename=" + out_dir + "/gnss_sdr_pvt.nmea\n";
    t += "PVT.flag_nmea_tty_port=false\nPVT.flag_rtcm_server=false\nPVT.flag_rtcm_tty_port=false\n";
    t += "PVT.kml_output_enabled=false\nPVT.gpx_output_enabled=false\nPVT.geojson_output_enabled=false\n";
    t += "PVT.xml_output_enabled=false\nPVT.dump=false\n";
    return t;
  }

  IqSettings settings_;
  baseband::SampleFormat format_ = baseband::SampleFormat::kSc8;
  std::filesystem::path staging_dir_;
  GnssTime start_;
  std::vector<IqBand> bands_;
  std::vector<baseband::Arrival> arrivals_;
  std::string buffer_;
};

}  // namespace

Result<std::unique_ptr<EpochSink>> make_iq_sink(const RunContext& context) { return IqSink::make(context); }

}  // namespace skytrace::sim

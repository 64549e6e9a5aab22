// The bands' signals for the synthesizer: codes, data symbols by transmission time, FDMA offsets.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "skytrace/baseband/beidou_b1i.hpp"
#include "skytrace/baseband/galileo_e1.hpp"
#include "skytrace/baseband/synthesizer.hpp"

namespace skytrace::baseband {
namespace {

std::int64_t floor_div(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && ((a < 0) != (b < 0))) ? q - 1 : q;
}

class GpsL1caSignals final : public BandSignals {
 public:
  GpsL1caSignals(LnavCommon lnav, int first_week,
                 std::function<const orbits::KeplerEphemeris*(int, const GnssTime&)> record_at)
      : lnav_(std::move(lnav)), first_week_(first_week), record_at_(std::move(record_at)) {}

  int code_length() const override { return kCaCodeLength; }
  Result<const float*> code(int prn, int /*form*/) override {
    auto it = satellites_.find(prn);
    if (it == satellites_.end()) {
      auto code = gps_ca_code(prn);
      if (!code) return code.error();
      it = satellites_.emplace(prn, Satellite{}).first;
      std::copy(code->begin(), code->end(), it->second.code.begin());
    }
    return it->second.code.data();
  }
  double centre_hz() const override { return 1575.42e6; }
  // 20 code periods per LNAV bit, 300 bits per 6 s subframe aligned to the GPS week.
  int sign(int prn, std::int64_t period_ms) override {
    Satellite& s = satellites_.at(prn);
    const std::int64_t bit_in_run_weeks = floor_div(period_ms, 20);
    const std::int64_t subframe_index = floor_div(bit_in_run_weeks, kLnavBitsPerSubframe);
    const std::int64_t subframe_sow_total = subframe_index * 6;
    const int week = first_week_ + static_cast<int>(floor_div(subframe_sow_total, 604800));
    const int sow = static_cast<int>(subframe_sow_total - 604800 * floor_div(subframe_sow_total, 604800));
    if (sow != s.subframe_start_sow || week != s.subframe_week) {
      s.subframe_start_sow = sow;
      s.subframe_week = week;
      const orbits::KeplerEphemeris* record =
          record_at_ ? record_at_(prn, GnssTime::from_week_tow(TimeScale::kGpst, week, sow)) : nullptr;
      if (record != nullptr) {
        s.subframe = lnav_subframe(*record, lnav_, week, sow);
      } else {
        s.subframe.fill(0);
      }
    }
    const auto bit = static_cast<size_t>(bit_in_run_weeks - subframe_index * kLnavBitsPerSubframe);
    return s.subframe[bit] != 0 ? -1 : 1;
  }

 private:
  struct Satellite {
    std::array<float, kCaCodeLength> code{};
    int subframe_start_sow = -1;
    int subframe_week = -1;
    std::array<std::uint8_t, kLnavBitsPerSubframe> subframe{};
  };
  LnavCommon lnav_;
  int first_week_;
  std::function<const orbits::KeplerEphemeris*(int, const GnssTime&)> record_at_;
  std::map<int, Satellite> satellites_;
};

class GlonassL1ofSignals final : public BandSignals {
 public:
  GlonassL1ofSignals(GnavCommon gnav, int first_week,
                     std::function<const orbits::GlonassEphemeris*(int, const GnssTime&)> record_at)
      : gnav_(gnav), first_week_(first_week), record_at_(std::move(record_at)) {}

  int code_length() const override { return kGlonassCodeLength; }
  Result<const float*> code(int slot, int /*form*/) override {
    satellites_.try_emplace(slot);
    static const std::array<float, kGlonassCodeLength> kCode = [] {
      std::array<float, kGlonassCodeLength> c{};
      std::copy(glonass_ranging_code().begin(), glonass_ranging_code().end(), c.begin());
      return c;
    }();
    return kCode.data();
  }
  double centre_hz() const override { return kGlonassBandCentre_hz; }
  // Strings of 2 s aligned to the Moscow day (UTC(SU) + 3 h): 170 data symbols of 10 ms, then the
  // 30 of the time mark; 15 strings a 30 s frame.
  int sign(int slot, std::int64_t period_ms) override {
    Satellite& s = satellites_.at(slot);
    const std::int64_t gpst_ms = static_cast<std::int64_t>(first_week_) * 604800000LL + period_ms;
    const GnssTime gpst = GnssTime::from_gpst_seconds(floor_div(gpst_ms, 1000), 0.0);
    const std::int64_t mt_ms = gpst_ms + (10800 - gps_minus_utc_s(gpst)) * 1000LL;
    const std::int64_t string_index = floor_div(mt_ms, 2000);
    if (string_index != s.string_index) {
      s.string_index = string_index;
      const std::int64_t string_start_ms = string_index * 2000;
      const GnssTime string_start_gpst = GnssTime::from_gpst_seconds(
          floor_div(string_start_ms - (10800 - gps_minus_utc_s(gpst)) * 1000LL, 1000), 0.0);
      const orbits::GlonassEphemeris* record = record_at_ ? record_at_(slot, string_start_gpst) : nullptr;
      if (record != nullptr) {
        // Moscow day and date: GPST seconds count from 1980-01-06, a Sunday; the Moscow calendar
        // day number since 1996-01-01 gives N_4 and N_T.
        const std::int64_t mt_day = floor_div(string_start_ms, 86400000LL);
        const int second_of_day = static_cast<int>((string_start_ms - mt_day * 86400000LL) / 1000);
        const int frame_start = second_of_day / 30 * 30;
        const int string_number = (second_of_day % 30) / 2 + 1;
        // Days from 1980-01-06 to 1996-01-01: 5839.
        const std::int64_t days_since_1996 = mt_day - 5839;
        const int four_year = static_cast<int>(floor_div(days_since_1996, 1461)) + 1;
        const int day_in_four_years = static_cast<int>(days_since_1996 - (four_year - 1) * 1461LL) + 1;
        s.symbols = gnav_symbols(gnav_string(*record, gnav_, string_number, frame_start, day_in_four_years, four_year));
      } else {
        s.symbols.fill(1);
      }
    }
    const auto symbol = static_cast<size_t>((mt_ms - string_index * 2000) / 10);
    return s.symbols[symbol];
  }

 private:
  struct Satellite {
    std::int64_t string_index = std::numeric_limits<std::int64_t>::min();
    std::array<std::int8_t, kGlonassSymbolsPerString> symbols{};
  };
  GnavCommon gnav_;
  int first_week_;
  std::function<const orbits::GlonassEphemeris*(int, const GnssTime&)> record_at_;
  std::map<int, Satellite> satellites_;
};

class BeidouB1iSignals final : public BandSignals {
 public:
  BeidouB1iSignals(orbits::IonosphereCoefficients ionosphere, int first_week,
                   std::function<const orbits::KeplerEphemeris*(int, const GnssTime&)> record_at)
      : ionosphere_(std::move(ionosphere)), first_week_(first_week), record_at_(std::move(record_at)) {}

  int code_length() const override { return kB1iCodeLength; }
  Result<const float*> code(int prn, int /*form*/) override {
    auto it = satellites_.find(prn);
    if (it == satellites_.end()) {
      auto code = beidou_b1i_code(prn);
      if (!code) return code.error();
      it = satellites_.emplace(prn, Satellite{}).first;
      std::copy(code->begin(), code->end(), it->second.code.begin());
      it->second.geo = beidou_geo_prn(prn);
    }
    return it->second.code.data();
  }
  double centre_hz() const override { return kB1iCarrier_hz; }
  // BDT = GPST - 14 s, weeks from 2006-01-01 (GPS week 1356). D1 (MEO, IGSO): 6 s subframes of
  // 300 bits, each 20 ms bit spread by the Neumann-Hoffman code's 20 chips. D2 (GEO): 3 s frames of
  // five 0.6 s subframes, 2 ms bits (two code periods) and no secondary code.
  int sign(int prn, std::int64_t period_ms) override {
    Satellite& s = satellites_.at(prn);
    const std::int64_t bdt_ms = period_ms + (static_cast<std::int64_t>(first_week_ - 1356) * 604800 - 14) * 1000;
    const bool geo = s.geo;
    const std::int64_t bit_ms = geo ? 2 : 20;
    const std::int64_t bit_index = floor_div(bdt_ms, bit_ms);
    const std::int64_t subframe_index = floor_div(bit_index, 300);
    if (subframe_index != s.subframe_index) {
      s.subframe_index = subframe_index;
      // D1 subframes start every 6 s; D2's subframes carry the SOW of their frame (every 3 s).
      const std::int64_t frame_index = geo ? floor_div(subframe_index, 5) : subframe_index;
      const std::int64_t start_total_s = frame_index * (geo ? 3 : 6);
      const int week = static_cast<int>(floor_div(start_total_s, 604800));
      const int sow = static_cast<int>(start_total_s - 604800LL * week);
      const GnssTime t = GnssTime::from_week_tow(TimeScale::kBdt, week, sow);
      const orbits::KeplerEphemeris* record = record_at_ ? record_at_(prn, t) : nullptr;
      if (record == nullptr) {
        s.subframe.fill(0);
      } else if (geo) {
        s.subframe = d2_subframe(*record, ionosphere_, week, sow, static_cast<int>(subframe_index - frame_index * 5) + 1);
      } else {
        s.subframe = d1_subframe(*record, ionosphere_, week, sow);
      }
    }
    const auto bit = static_cast<size_t>(bit_index - subframe_index * 300);
    const int data = s.subframe[bit] != 0 ? -1 : 1;
    if (geo) return data;
    const auto nh_chip = static_cast<size_t>(bdt_ms - bit_index * 20);
    return data * beidou_nh_code()[nh_chip];
  }
 private:
  struct Satellite {
    std::array<float, kB1iCodeLength> code{};
    bool geo = false;  // D2 rather than D1, known once per satellite (sign() runs every millisecond)
    std::int64_t subframe_index = std::numeric_limits<std::int64_t>::min();  // the one `subframe` holds
    std::array<std::uint8_t, 300> subframe{};
  };
  orbits::IonosphereCoefficients ionosphere_;
  int first_week_;
  std::function<const orbits::KeplerEphemeris*(int, const GnssTime&)> record_at_;
  std::map<int, Satellite> satellites_;
};


class GalileoE1Signals final : public BandSignals {
 public:
  GalileoE1Signals(InavCommon inav, int first_week,
                   std::function<const orbits::KeplerEphemeris*(int, const GnssTime&)> record_at)
      : inav_(std::move(inav)), first_week_(first_week), record_at_(std::move(record_at)) {}

  int code_period_ms() const override { return kE1CodePeriod_ms; }
  int code_length() const override { return kE1ChipsPerCode * kE1SubchipsPerChip; }
  int forms() const override { return 2; }
  Result<const float*> code(int prn, int form) override {
    auto it = satellites_.find(prn);
    if (it == satellites_.end()) {
      auto b = galileo_e1_primary_code(prn, false);
      if (!b) return b.error();
      auto c = galileo_e1_primary_code(prn, true);
      if (!c) return c.error();
      it = satellites_.emplace(prn, Satellite{}).first;
      it->second.waveforms[0] = galileo_e1_cboc_waveform(*b, *c, 1);
      it->second.waveforms[1] = galileo_e1_cboc_waveform(*b, *c, -1);
    }
    return it->second.waveforms[static_cast<size_t>(form)].data();
  }
  double centre_hz() const override { return kE1Carrier_hz; }
  // GST runs with GPST (weeks from 1999-08-22, GPS week 1024): pages of 2 s (an even and an odd
  // part of 250 symbols, one per 4 ms code period), 15 a 30 s subframe. On E1-B the even parts
  // start at odd seconds of GST (E5b's at even ones), so a nominal subframe starts at TOW 1 (mod 30).
  int sign(int prn, std::int64_t period) override {
    Satellite& s = satellites_.at(prn);
    const std::int64_t page_index = floor_div(period - kInavSymbolsPerPagePart, 2 * kInavSymbolsPerPagePart);
    if (page_index != s.page_index) {
      s.page_index = page_index;
      const std::int64_t start_total_s = page_index * 2 + 1;
      const int week = first_week_ + static_cast<int>(floor_div(start_total_s, 604800));
      const int tow = static_cast<int>(start_total_s - 604800 * floor_div(start_total_s, 604800));
      const orbits::KeplerEphemeris* record =
          record_at_ ? record_at_(prn, GnssTime::from_week_tow(TimeScale::kGpst, week, tow)) : nullptr;
      if (record != nullptr) {
        const int type = inav_e1b_word_type((tow + 29) % 30 / 2);
        const auto parts = inav_page_parts(inav_word(type, *record, inav_, week - 1024, tow));
        s.symbols[0] = inav_part_symbols(parts[0]);
        s.symbols[1] = inav_part_symbols(parts[1]);
      } else {
        s.symbols[0].fill(1);
        s.symbols[1].fill(1);
      }
    }
    const std::int64_t in_page = period - kInavSymbolsPerPagePart - page_index * 2 * kInavSymbolsPerPagePart;
    return s.symbols[static_cast<size_t>(in_page / kInavSymbolsPerPagePart)]
                    [static_cast<size_t>(in_page % kInavSymbolsPerPagePart)];
  }
  // E1-C's secondary chip (one per code period, restarting every 100 ms of GST) against the symbol.
  int form(int prn, std::int64_t period) override {
    const int secondary = galileo_e1c_secondary_code()[static_cast<size_t>(period - 25 * floor_div(period, 25))];
    return secondary == sign(prn, period) ? 0 : 1;
  }

 private:
  struct Satellite {
    std::array<std::vector<float>, 2> waveforms;  // the pilot's chip agreeing with the symbol, or not
    std::int64_t page_index = std::numeric_limits<std::int64_t>::min();  // the page `symbols` holds
    std::array<std::array<std::int8_t, kInavSymbolsPerPagePart>, 2> symbols{};  // even part, odd part
  };
  InavCommon inav_;
  int first_week_;
  std::function<const orbits::KeplerEphemeris*(int, const GnssTime&)> record_at_;
  std::map<int, Satellite> satellites_;
};
}  // namespace

std::unique_ptr<BandSignals> make_gps_l1ca_signals(
    LnavCommon lnav, int first_week, std::function<const orbits::KeplerEphemeris*(int, const GnssTime&)> record_at) {
  return std::make_unique<GpsL1caSignals>(std::move(lnav), first_week, std::move(record_at));
}

std::unique_ptr<BandSignals> make_glonass_l1of_signals(
    GnavCommon gnav, int first_week, std::function<const orbits::GlonassEphemeris*(int, const GnssTime&)> record_at) {
  return std::make_unique<GlonassL1ofSignals>(gnav, first_week, std::move(record_at));
}

std::unique_ptr<BandSignals> make_galileo_e1_signals(
    InavCommon inav, int first_week, std::function<const orbits::KeplerEphemeris*(int, const GnssTime&)> record_at) {
  return std::make_unique<GalileoE1Signals>(std::move(inav), first_week, std::move(record_at));
}

std::unique_ptr<BandSignals> make_beidou_b1i_signals(
    orbits::IonosphereCoefficients ionosphere, int first_week,
    std::function<const orbits::KeplerEphemeris*(int, const GnssTime&)> record_at) {
  return std::make_unique<BeidouB1iSignals>(std::move(ionosphere), first_week, std::move(record_at));
}

}  // namespace skytrace::baseband

#include "skytrace/io/fix_csv.hpp"

#include <fmt/format.h>

#include <cmath>

namespace skytrace::io {
namespace {

constexpr const char* kFixCsvHeader =
    "time_gpst,week,tow_s,fix,satellites_used,latitude_deg,longitude_deg,height_m,x_m,y_m,z_m,"
    "sigma_east_m,sigma_north_m,sigma_up_m,velocity_east_mps,velocity_north_mps,velocity_up_mps,"
    "clock_bias_m,clock_drift_mps,gdop,pdop,hdop,vdop,tdop,system_clocks_m,rejected,message,"
    "ratio,fixed_ambiguities,age_s,baseline_east_m,baseline_north_m,baseline_up_m,heading_deg,pitch_deg,"
    "heading_sigma_deg,pitch_sigma_deg\n";

// The relative-positioning cells (empty without an RTK engine).
std::string relative_cells(const positioning::PositionFix& fix) {
  if (!fix.relative) return ",,,,,,,,,";
  const auto& r = *fix.relative;
  std::string out = fmt::format("{:.2f},{},{:.3f},", r.ratio, r.fixed_ambiguities, r.age_s);
  if (r.baseline_valid) {
    out += fmt::format("{:.4f},{:.4f},{:.4f}", r.baseline_enu_m.x(), r.baseline_enu_m.y(), r.baseline_enu_m.z());
  } else {
    out += ",,";
  }
  const auto cell = [](const std::optional<double>& v, int decimals) {
    return v ? fmt::format(",{:.{}f}", *v, decimals) : std::string(",");
  };
  out += cell(r.heading_deg, 3) + cell(r.pitch_deg, 3) + cell(r.heading_sigma_deg, 3) + cell(r.pitch_sigma_deg, 3);
  return out;
}

// A CSV field that may hold commas or quotes.
std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

}  // namespace

const char* fix_csv_header() { return kFixCsvHeader; }

std::string fix_csv_row(const positioning::PositionFix& fix) {
  // Rounded to 1 ms before the split into calendar, week and seconds of week: 604799.9996 s is
  // second 0.000 of the next week, never 604800.000 of this one.
  const GnssTime time = fix.receiver_time.rounded_to(3);
  const WeekTow week_tow = time.to_week_tow(TimeScale::kGpst);
  std::string row = fmt::format("{},{},{:.3f},{},{},", time.to_iso8601(TimeScale::kGpst, 3), week_tow.week,
                                week_tow.tow_s, positioning::to_string(fix.type), fix.satellites_used);
  std::string rejected;
  for (const auto& use : fix.satellites) {
    if (!use.rejected) continue;
    // Appended piece by piece: "a" + b here draws a false -Wrestrict from GCC 12.
    if (!rejected.empty()) rejected += ' ';
    rejected += use.satellite.to_string();
  }
  if (fix.type == positioning::FixType::kNone) {
    return row + std::string(20, ',') + csv_field(rejected) + "," + csv_field(fix.message) + "," +
           relative_cells(fix) + "\n";
  }
  const auto& p = fix.position;
  const auto& x = fix.position_ecef_m;
  const auto& c = fix.covariance_enu_m2;
  row += fmt::format("{:.9f},{:.9f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},{:.4f},", p.latitude_deg, p.longitude_deg,
                     p.height_m, x.x(), x.y(), x.z(), std::sqrt(c(0, 0)), std::sqrt(c(1, 1)), std::sqrt(c(2, 2)));
  if (fix.velocity_valid) {
    row += fmt::format("{:.5f},{:.5f},{:.5f},", fix.velocity_enu_mps.x(), fix.velocity_enu_mps.y(),
                       fix.velocity_enu_mps.z());
  } else {
    row += ",,,";
  }
  const double clock_m = fix.clock_bias_m.empty() ? 0.0 : fix.clock_bias_m.begin()->second;
  row += fmt::format("{:.4f},", clock_m);
  row += fix.velocity_valid ? fmt::format("{:.5f},", fix.clock_drift_mps) : std::string(",");
  row += fmt::format("{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},", fix.gdop, fix.pdop, fix.hdop, fix.vdop, fix.tdop);
  std::string clocks;
  for (const auto& [system, bias_m] : fix.clock_bias_m) {
    clocks += fmt::format("{}{}={:.4f}", clocks.empty() ? "" : " ", system_letter(system), bias_m);
  }
  return row + clocks + "," + csv_field(rejected) + "," + csv_field(fix.message) + "," + relative_cells(fix) + "\n";
}

}  // namespace skytrace::io

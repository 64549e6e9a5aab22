#include "skytrace/io/fix_csv.hpp"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "skytrace/core/decimal_text.hpp"

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
  // Numbers as fmt's "{:.Nf}" writes them (write_fixed), cell by cell.
  std::string row;
  row.reserve(400);
  const auto number = [&](double value, int decimals) {
    append_fixed(row, value, decimals);
    row += ',';
  };
  row += time.to_iso8601(TimeScale::kGpst, 3);
  row += ',';
  row += std::to_string(week_tow.week);
  row += ',';
  number(week_tow.tow_s, 3);
  row += positioning::to_string(fix.type);
  row += ',';
  row += std::to_string(fix.satellites_used);
  row += ',';
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
  number(p.latitude_deg, 9);
  number(p.longitude_deg, 9);
  number(p.height_m, 4);
  number(x.x(), 4);
  number(x.y(), 4);
  number(x.z(), 4);
  number(std::sqrt(c(0, 0)), 4);
  number(std::sqrt(c(1, 1)), 4);
  number(std::sqrt(c(2, 2)), 4);
  if (fix.velocity_valid) {
    number(fix.velocity_enu_mps.x(), 5);
    number(fix.velocity_enu_mps.y(), 5);
    number(fix.velocity_enu_mps.z(), 5);
  } else {
    row += ",,,";
  }
  number(fix.clock_bias_m.empty() ? 0.0 : fix.clock_bias_m.begin()->second, 4);
  if (fix.velocity_valid) {
    number(fix.clock_drift_mps, 5);
  } else {
    row += ',';
  }
  for (const double dop : {fix.gdop, fix.pdop, fix.hdop, fix.vdop, fix.tdop}) number(dop, 3);
  bool first_clock = true;
  for (const auto& [system, bias_m] : fix.clock_bias_m) {
    if (!first_clock) row += ' ';
    first_clock = false;
    row += system_letter(system);
    row += '=';
    append_fixed(row, bias_m, 4);
  }
  row += ',';
  row += csv_field(rejected);
  row += ',';
  row += csv_field(fix.message);
  row += ',';
  row += relative_cells(fix);
  row += '\n';
  return row;
}

}  // namespace skytrace::io

// The run report: HTML page and SVG sky plot (see report.hpp for the geometry).
#include "skytrace/io/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <string_view>

#include "skytrace/core/decimal_text.hpp"

namespace skytrace::io {
namespace {

constexpr double kSkyRadius = 100.0;  // horizon circle in SVG units
constexpr double kEpochTolerance_s = 1e-6;

// Escapes text for HTML/XML content and attribute values alike.
std::string escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

// Coordinates with two decimals: 0.01 unit is far below a pixel (and no "-0.00"); fmt's "{:.2f}"
// characters, written by write_fixed.
void append_num(std::string& out, double value) { append_fixed(out, std::abs(value) < 0.005 ? 0.0 : value, 2); }
std::string num(double value) {
  std::string text;
  append_num(text, value);
  return text;
}

size_t system_index(GnssSystem system) { return static_cast<size_t>(system); }

std::string_view system_colour(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGps: return "#1f77b4";
    case GnssSystem::kGlonass: return "#d62728";
    case GnssSystem::kGalileo: return "#2ca02c";
    case GnssSystem::kBeiDou: return "#ff7f0e";
    case GnssSystem::kQzss: return "#9467bd";
    case GnssSystem::kNavic: return "#8c564b";
    case GnssSystem::kSbas: return "#7f7f7f";
  }
  return "#000000";
}

struct ClassStyle {
  std::string_view colour;
  std::string_view label;
};
ClassStyle class_style(TrackClass track_class) {
  switch (track_class) {
    case TrackClass::kLineOfSight: return {"#1a9641", "line of sight"};
    case TrackClass::kVegetation: return {"#f28e1c", "through vegetation"};
    case TrackClass::kVegetationLost: return {"#8c510a", "lost in vegetation"};
    case TrackClass::kBlocked: return {"#d7191c", "blocked"};
    case TrackClass::kOther: return {"#9e9e9e", "other (mask, no ephemeris, ...)"};
    case TrackClass::kMultipath: return {"#2c7bb6", "multipath (direct + reflected)"};
    case TrackClass::kNlos: return {"#7b3294", "NLOS (reflected / diffracted only)"};
  }
  return {"#000000", "?"};
}
constexpr std::array<TrackClass, 7> kAllClasses = {TrackClass::kLineOfSight, TrackClass::kMultipath, TrackClass::kNlos,
                                                   TrackClass::kVegetation,   TrackClass::kVegetationLost,
                                                   TrackClass::kBlocked,      TrackClass::kOther};

struct Point2 {
  double x = 0.0;
  double y = 0.0;
};

// Zenith at (0, 0), horizon at radius 100, north up, east right.
Point2 sky_xy(double azimuth_deg, double elevation_deg) {
  const double clamped_deg = std::clamp(elevation_deg, 0.0, 90.0);
  const double r = kSkyRadius * (90.0 - clamped_deg) / 90.0;
  const double az_rad = azimuth_deg * std::numbers::pi / 180.0;
  return {r * std::sin(az_rad), -r * std::cos(az_rad)};
}

std::string points_attribute(const std::vector<Point2>& points) {
  std::string out;
  out.reserve(points.size() * 14);
  for (const auto& p : points) {
    if (!out.empty()) out += ' ';
    append_num(out, p.x);
    out += ',';
    append_num(out, p.y);
  }
  return out;
}

// Points of a track to draw: the kept history plus the newest sample when it was not kept.
std::vector<ReportBuilder::TrackPoint> drawn_points(const ReportBuilder::Track& track) {
  std::vector<ReportBuilder::TrackPoint> points = track.points;
  if (track.samples_seen > 0 && (points.empty() || track.latest.time_s > points.back().time_s)) {
    points.push_back(track.latest);
  }
  return points;
}

// Longest time step drawn as a continuous line: longer gaps (a satellite that set and rose
// again, a pause of the run) break it.
double gap_limit_s(double interval_s, size_t stride) {
  return interval_s > 0.0 ? 3.5 * interval_s * static_cast<double>(stride) : std::numeric_limits<double>::infinity();
}

// The grey area between the horizon and the obstruction elevation, per azimuth.
std::string sky_mask_path(const std::vector<double>& mask, double azimuth_step_deg) {
  if (mask.empty()) return {};
  const double step_deg = azimuth_step_deg > 0.0 ? azimuth_step_deg : 360.0 / static_cast<double>(mask.size());
  // Outer ring (horizon) as two arcs, inner boundary as the mask polygon: even-odd fill leaves
  // the open sky inside the mask curve empty.
  std::string d = fmt::format("M {0} 0 A {0} {0} 0 1 0 -{0} 0 A {0} {0} 0 1 0 {0} 0 Z ", num(kSkyRadius));
  for (size_t i = 0; i < mask.size(); ++i) {
    const double elevation_deg = std::isfinite(mask[i]) ? mask[i] : 0.0;
    const auto p = sky_xy(static_cast<double>(i) * step_deg, elevation_deg);
    d += fmt::format("{}{},{} ", i == 0 ? "M " : "L ", num(p.x), num(p.y));
  }
  d += "Z";
  return fmt::format(R"(<path d="{}" fill="#8a8a8a" fill-opacity="0.55" fill-rule="evenodd" stroke="#6a6a6a" stroke-width="0.4"/>)",
                     d) +
         "\n";
}

// The sky plot of one receiver; `id` names the SVG and prefixes its groups' ids (one page may hold
// several receivers' plots).
std::string draw_sky_plot(const ReportMeta& meta, const std::vector<double>& mask,
                          const std::map<SatelliteId, ReportBuilder::Track>& tracks, bool standalone,
                          const std::string& id = "skyplot", const std::string& receiver = "") {
  std::string svg;
  const double legend_top = kSkyRadius + 26.0;
  const double height = legend_top + 10.0 * static_cast<double>(kAllClasses.size()) + 4.0 + 125.0;
  if (standalone) svg += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  svg += fmt::format(
      R"(<svg xmlns="http://www.w3.org/2000/svg" id="{}" viewBox="-125 -125 250 {}" width="500" height="{}" font-family="sans-serif">)",
      id, num(height), num(2.0 * height));
  svg += "\n";
  svg += fmt::format("<title>Sky plot: {}{}</title>\n", escape(meta.scenario_name), receiver.empty() ? "" : ", " + escape(receiver));
  svg += "<rect x=\"-125\" y=\"-125\" width=\"250\" height=\"" + num(height) + "\" fill=\"#ffffff\"/>\n";
  svg += R"(<circle cx="0" cy="0" r="100" fill="#f4f8ff" stroke="none"/>)";
  svg += "\n";
  svg += "<g id=\"" + id + "-mask\">\n" + sky_mask_path(mask, meta.sky_mask_azimuth_step_deg) + "</g>\n";
  // Grid: elevation rings at 0/30/60 deg, the N-S and E-W lines.
  svg += "<g id=\"" + id + "-grid\" fill=\"none\" stroke=\"#555555\">\n";
  for (const double elevation_deg : {0.0, 30.0, 60.0}) {
    const double r = kSkyRadius * (90.0 - elevation_deg) / 90.0;
    svg += fmt::format(R"(<circle cx="0" cy="0" r="{}" stroke-width="{}"{}/>)", num(r), elevation_deg == 0.0 ? "0.8" : "0.4",
                       elevation_deg == 0.0 ? "" : R"( stroke-dasharray="2 2")");
    svg += "\n";
  }
  svg += R"(<line x1="0" y1="-100" x2="0" y2="100" stroke-width="0.3"/><line x1="-100" y1="0" x2="100" y2="0" stroke-width="0.3"/>)";
  svg += "\n</g>\n<g id=\"" + id + "-labels\" font-size=\"7\" fill=\"#333333\" text-anchor=\"middle\">\n";
  svg += R"(<text x="0" y="-104">N</text><text x="108" y="2.5">E</text><text x="0" y="110">S</text><text x="-108" y="2.5">W</text>)";
  svg += "\n";
  for (const double elevation_deg : {0.0, 30.0, 60.0}) {
    const double r = kSkyRadius * (90.0 - elevation_deg) / 90.0;
    svg += fmt::format(R"(<text x="{}" y="{}" font-size="5" text-anchor="start">{}&#176;</text>)", num(1.5), num(-r + 5.5),
                       static_cast<int>(elevation_deg));
    svg += "\n";
  }
  svg += "</g>\n";

  // Tracks: one polyline per run of samples of the same class; a run ends on a class change (the
  // segment to the next sample takes the earlier sample's class), below the horizon or on a gap.
  svg += "<g id=\"" + id + "-tracks\" fill=\"none\" stroke-width=\"1.2\" stroke-linecap=\"round\" stroke-linejoin=\"round\">\n";
  std::string labels;
  for (const auto& [satellite, track] : tracks) {
    const auto points = drawn_points(track);
    const double limit_s = gap_limit_s(meta.interval_s, track.stride);
    std::string group;
    std::vector<Point2> run;
    TrackClass run_class = TrackClass::kOther;
    const auto emit = [&]() {
      const auto colour = class_style(run_class).colour;
      if (run.size() >= 2) {
        group += fmt::format(R"(<polyline points="{}" stroke="{}"/>)", points_attribute(run), colour);
        group += "\n";
      } else if (run.size() == 1) {
        group += fmt::format(R"(<circle cx="{}" cy="{}" r="0.9" fill="{}" stroke="none"/>)", num(run[0].x), num(run[0].y),
                             colour);
        group += "\n";
      }
      run.clear();
    };
    const ReportBuilder::TrackPoint* last_visible = nullptr;
    const ReportBuilder::TrackPoint* previous = nullptr;
    for (const auto& point : points) {
      if (point.elevation_deg < 0.0F) {
        emit();
        previous = nullptr;
        continue;
      }
      const auto xy = sky_xy(point.azimuth_deg, point.elevation_deg);
      if (previous != nullptr && point.time_s - previous->time_s > limit_s) emit();
      if (run.empty()) {
        run_class = point.track_class;
        run.push_back(xy);
      } else if (point.track_class == run_class) {
        run.push_back(xy);
      } else {
        run.push_back(xy);
        emit();
        run_class = point.track_class;
        run.push_back(xy);
      }
      previous = &point;
      last_visible = &point;
    }
    emit();
    if (last_visible == nullptr) continue;
    const auto end = sky_xy(last_visible->azimuth_deg, last_visible->elevation_deg);
    const auto colour = class_style(last_visible->track_class).colour;
    svg += fmt::format("<g data-satellite=\"{0}\"><title>{0}</title>\n{1}", escape(satellite.to_string()), group);
    svg += fmt::format(R"(<circle class="track-end" cx="{}" cy="{}" r="2" fill="{}" stroke="#ffffff" stroke-width="0.4"/>)",
                       num(end.x), num(end.y), colour);
    svg += "\n</g>\n";
    labels += fmt::format(R"(<text x="{}" y="{}">{}</text>)", num(end.x + 2.6), num(end.y - 2.2),
                          escape(satellite.to_string()));
    labels += "\n";
  }
  svg += "</g>\n<g id=\"" + id + "-satellite-labels\" font-size=\"5.5\" fill=\"#111111\">\n" + labels + "</g>\n";

  // Legend below the plot.
  svg += "<g id=\"" + id + "-legend\" font-size=\"6\" fill=\"#333333\">\n";
  double y = legend_top;
  for (const auto track_class : kAllClasses) {
    const auto style = class_style(track_class);
    svg += fmt::format(R"(<line x1="-110" y1="{0}" x2="-100" y2="{0}" stroke="{1}" stroke-width="2"/><text x="-96" y="{2}">{3}</text>)",
                       num(y), style.colour, num(y + 2.0), escape(style.label));
    svg += "\n";
    y += 10.0;
  }
  if (!mask.empty()) {
    svg += fmt::format(R"(<rect x="20" y="{}" width="10" height="6" fill="#8a8a8a" fill-opacity="0.55"/><text x="34" y="{}">sky mask</text>)",
                       num(legend_top - 3.0), num(legend_top + 2.0));
    svg += "\n";
  }
  svg += "</g>\n</svg>\n";
  return svg;
}

// --- Line charts over time -------------------------------------------------------------------

struct Series {
  std::string colour;
  double opacity = 1.0;
  double width_px = 1.5;
  std::vector<std::vector<Point2>> segments;  // (time_s, value)
};

struct LegendEntry {
  std::string label;
  std::string colour;
};

struct ChartFrame {
  double left = 60.0;
  double top = 15.0;
  double width = 800.0;
  double height = 250.0;
  double t0_s = 0.0;
  double t1_s = 1.0;
  double y0 = 0.0;
  double y1 = 1.0;
  // The x axis counts GPST seconds (labels as times), or else plain numbers named x_label.
  bool time_axis = true;
  std::string x_label;
  [[nodiscard]] double x_of(double time_s) const { return left + width * (time_s - t0_s) / (t1_s - t0_s); }
  [[nodiscard]] double y_of(double value) const { return top + height * (1.0 - (value - y0) / (y1 - y0)); }
};

// A round tick step giving at most about max_ticks ticks over span.
double nice_step(double span, int max_ticks) {
  const double raw = span / max_ticks;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (const double factor : {1.0, 2.0, 5.0, 10.0}) {
    if (factor * magnitude >= raw) return factor * magnitude;
  }
  return 10.0 * magnitude;
}

double time_step_s(double span_s) {
  for (const double step_s : {1.0, 2.0, 5.0, 10.0, 15.0, 30.0, 60.0, 120.0, 300.0, 600.0, 900.0, 1800.0, 3600.0, 7200.0,
                              10800.0, 21600.0, 43200.0, 86400.0, 172800.0, 604800.0}) {
    if (span_s / step_s <= 8.0) return step_s;
  }
  return std::ceil(span_s / 8.0 / 604800.0) * 604800.0;
}

std::string line_chart(std::string_view id, std::string_view title, std::string_view y_label, const ChartFrame& frame,
                       const std::vector<Series>& series, const std::vector<LegendEntry>& legend, double y_step) {
  const double total_width = frame.left + frame.width + 150.0;
  const double total_height = frame.top + frame.height + 45.0;
  std::string svg = fmt::format(
      R"(<svg xmlns="http://www.w3.org/2000/svg" id="{}" viewBox="0 0 {} {}" width="{}" height="{}" font-family="sans-serif" font-size="11">)",
      escape(id), num(total_width), num(total_height), num(total_width), num(total_height));
  svg += fmt::format("\n<title>{}</title>\n", escape(title));
  svg += fmt::format(R"(<rect x="{}" y="{}" width="{}" height="{}" fill="#fbfbfb" stroke="#444444" stroke-width="0.8"/>)",
                     num(frame.left), num(frame.top), num(frame.width), num(frame.height));
  svg += "\n<g class=\"axes\" stroke=\"#dddddd\" stroke-width=\"0.6\">\n";
  std::string tick_labels;
  // Value axis.
  for (double value = std::ceil(frame.y0 / y_step) * y_step; value <= frame.y1 + 1e-9; value += y_step) {
    const double y = frame.y_of(value);
    svg += fmt::format(R"(<line x1="{}" y1="{}" x2="{}" y2="{}"/>)", num(frame.left), num(y), num(frame.left + frame.width),
                       num(y));
    svg += "\n";
    tick_labels += fmt::format(R"(<text x="{}" y="{}" text-anchor="end">{}</text>)", num(frame.left - 6.0), num(y + 4.0),
                               fmt::format("{:g}", std::abs(value) < 1e-9 ? 0.0 : value));
    tick_labels += "\n";
  }
  // Time axis: round GPST instants; a numeric axis: round numbers.
  const double span_s = frame.t1_s - frame.t0_s;
  const double step_s = frame.time_axis ? time_step_s(span_s) : nice_step(span_s, 8);
  for (double time_s = std::ceil(frame.t0_s / step_s) * step_s; time_s <= frame.t1_s + 1e-6 * step_s; time_s += step_s) {
    const double x = frame.x_of(time_s);
    svg += fmt::format(R"(<line x1="{0}" y1="{1}" x2="{0}" y2="{2}"/>)", num(x), num(frame.top), num(frame.top + frame.height));
    svg += "\n";
    const std::string label = frame.time_axis ? detail::time_axis_label(time_s, step_s, span_s)
                                              : fmt::format("{:g}", std::abs(time_s) < 1e-9 * step_s ? 0.0 : time_s);
    tick_labels += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle">{}</text>)", num(x),
                               num(frame.top + frame.height + 16.0), escape(label));
    tick_labels += "\n";
  }
  svg += "</g>\n<g class=\"tick-labels\" fill=\"#333333\">\n" + tick_labels;
  svg += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle">{}</text>)", num(frame.left + frame.width / 2.0),
                     num(frame.top + frame.height + 36.0), escape(frame.time_axis ? "time (GPST)" : frame.x_label));
  svg += fmt::format("\n<text x=\"14\" y=\"{0}\" text-anchor=\"middle\" transform=\"rotate(-90 14 {0})\">{1}</text>\n",
                     num(frame.top + frame.height / 2.0), escape(y_label));
  svg += "</g>\n<g class=\"series\" fill=\"none\" stroke-linejoin=\"round\">\n";
  for (const auto& s : series) {
    for (const auto& segment : s.segments) {
      std::vector<Point2> xy;
      xy.reserve(segment.size());
      for (const auto& p : segment) xy.push_back({frame.x_of(p.x), frame.y_of(p.y)});
      if (xy.size() >= 2) {
        svg += fmt::format(R"(<polyline points="{}" stroke="{}" stroke-width="{}" stroke-opacity="{}"/>)", points_attribute(xy),
                           s.colour, num(s.width_px), num(s.opacity));
      } else if (xy.size() == 1) {
        svg += fmt::format(R"(<circle cx="{}" cy="{}" r="{}" fill="{}" fill-opacity="{}"/>)", num(xy[0].x), num(xy[0].y),
                           num(s.width_px), s.colour, num(s.opacity));
      }
      svg += "\n";
    }
  }
  svg += "</g>\n<g class=\"legend\" fill=\"#333333\">\n";
  double y = frame.top + 10.0;
  const double x = frame.left + frame.width + 15.0;
  for (const auto& entry : legend) {
    svg += fmt::format(R"(<line x1="{0}" y1="{1}" x2="{2}" y2="{1}" stroke="{3}" stroke-width="3"/><text x="{4}" y="{5}">{6}</text>)",
                       num(x), num(y), num(x + 18.0), entry.colour, num(x + 24.0), num(y + 4.0), escape(entry.label));
    svg += "\n";
    y += 18.0;
  }
  svg += "</g>\n</svg>\n";
  return svg;
}

// The time axis covers the run and every sample.
std::pair<double, double> time_range(const ReportMeta& meta, double data_t0_s, double data_t1_s) {
  double t0_s = data_t0_s;
  double t1_s = data_t1_s;
  if (meta.end > meta.start) {
    t0_s = std::min(t0_s, meta.start.gpst_seconds_approx());
    t1_s = std::max(t1_s, meta.end.gpst_seconds_approx());
  }
  if (!(t1_s > t0_s)) {
    // Nothing (or a single instant) to show: one minute around it.
    const double centre_s = std::isfinite(t0_s) ? t0_s : meta.start.gpst_seconds_approx();
    return {centre_s - 30.0, centre_s + 30.0};
  }
  return {t0_s, t1_s};
}

std::string summary_table(const ReportMeta& meta) {
  std::string out = "<table id=\"summary\">\n<tbody>\n";
  for (const auto& [key, value] : meta.summary_rows) {
    out += fmt::format("<tr><th scope=\"row\">{}</th><td>{}</td></tr>\n", escape(key), escape(value));
  }
  out += "</tbody>\n</table>\n";
  return out;
}

constexpr std::string_view kStyle = R"(body { font-family: sans-serif; margin: 24px auto; max-width: 1100px; color: #222; }
h1 { font-size: 1.5em; margin-bottom: 0.2em; }
h2 { font-size: 1.15em; border-bottom: 1px solid #ccc; padding-bottom: 3px; margin-top: 1.6em; }
p.meta { color: #555; margin-top: 0; }
svg { max-width: 100%; height: auto; display: block; }
table { border-collapse: collapse; }
th, td { text-align: left; padding: 3px 12px 3px 0; border-bottom: 1px solid #eee; vertical-align: top; }
th { font-weight: 600; }
ul.warnings li { color: #8a4b00; }
footer { margin-top: 2em; color: #888; font-size: 0.85em; }
)";

}  // namespace

TrackClass classify(const ReportSample& sample) {
  if (sample.status == "tracked") {
    if (sample.path_kind == "nlos") return TrackClass::kNlos;
    if (sample.path_kind == "multipath") return TrackClass::kMultipath;
    return sample.vegetation_attenuation_db > 0.0 ? TrackClass::kVegetation : TrackClass::kLineOfSight;
  }
  if (sample.status == "blocked") return TrackClass::kBlocked;
  if (sample.status == "attenuated") return TrackClass::kVegetationLost;
  return TrackClass::kOther;
}

ReportBuilder::ReportBuilder(double max_points_per_track)
    : max_points_(std::isfinite(max_points_per_track)
                      ? static_cast<size_t>(std::clamp(std::llround(max_points_per_track), 16LL, 10'000'000LL))
                      : 2000) {}

size_t ReportBuilder::track_points(const SatelliteId& satellite) const {
  if (views_.empty()) return 0;
  const auto it = views_.front().tracks.find(satellite);
  return it == views_.front().tracks.end() ? 0 : it->second.points.size();
}

void ReportBuilder::add(const ReportSample& sample) {
  const double time_s = sample.time.gpst_seconds_approx();
  auto view_it = std::find_if(views_.begin(), views_.end(), [&](const SatelliteView& v) {
    return v.receiver == sample.receiver || (sample.receiver.empty() && &v == &views_.front());
  });
  if (view_it == views_.end()) {
    views_.emplace_back().receiver = sample.receiver;
    view_it = std::prev(views_.end());
  }
  SatelliteView& view = *view_it;
  auto& track = view.tracks[sample.satellite];
  if (track.samples_seen > 0 && time_s <= track.latest.time_s) {
    ++ignored_samples_;
    return;
  }
  const TrackPoint point{time_s, static_cast<float>(sample.azimuth_deg), static_cast<float>(sample.elevation_deg),
                         std::isfinite(sample.cn0_dbhz) ? static_cast<float>(sample.cn0_dbhz)
                                                        : std::numeric_limits<float>::quiet_NaN(),
                         classify(sample)};
  const bool on_stride = track.samples_seen % track.stride == 0;
  const bool class_change =
      track.keep_changes && !track.points.empty() && point.track_class != track.points.back().track_class;
  if (class_change && track.latest.time_s > track.points.back().time_s) {
    // Keep the last sample of the previous class too, so the change is drawn where it happened.
    track.points.push_back(track.latest);
  }
  if (on_stride || class_change || track.points.empty()) track.points.push_back(point);
  track.latest = point;
  ++track.samples_seen;
  if (track.points.size() >= max_points_) compact_track(track);

  // Tracked satellites per system at this epoch.
  const size_t system = system_index(sample.satellite.system);
  view.systems_seen[system] = true;
  const bool tracked = sample.status == "tracked";
  if (!view.has_pending) {
    view.pending = CountPoint{time_s, {}};
    view.has_pending = true;
  } else if (time_s > view.pending.time_s + kEpochTolerance_s) {
    flush_pending_epoch(view);
    view.pending = CountPoint{time_s, {}};
    view.has_pending = true;
  } else if (time_s < view.pending.time_s - kEpochTolerance_s) {
    // A late sample of an earlier epoch: counted if that epoch was kept.
    const auto it = std::lower_bound(view.counts.begin(), view.counts.end(), time_s - kEpochTolerance_s,
                                     [](const CountPoint& c, double t_s) { return c.time_s < t_s; });
    if (tracked && it != view.counts.end() && std::abs(it->time_s - time_s) <= kEpochTolerance_s) ++it->tracked[system];
    return;
  }
  if (tracked) ++view.pending.tracked[system];
}

void ReportBuilder::flush_pending_epoch(SatelliteView& view) const {
  if (!view.has_pending) return;
  if (view.epochs_seen % view.count_stride == 0) view.counts.push_back(view.pending);
  ++view.epochs_seen;
  view.has_pending = false;
  if (view.counts.size() >= max_points_) {
    // Keep epochs 0, 2 stride, 4 stride, ...: the series stays evenly sampled.
    size_t kept = 0;
    for (size_t i = 0; i < view.counts.size(); i += 2) view.counts[kept++] = view.counts[i];
    view.counts.resize(kept);
    view.count_stride *= 2;
  }
}

void ReportBuilder::compact_track(Track& track) const {
  auto& points = track.points;
  const size_t n = points.size();
  std::vector<TrackPoint> kept;
  kept.reserve(n / 2 + 2);
  for (size_t i = 0; i < n; ++i) {
    const bool change = (i > 0 && points[i].track_class != points[i - 1].track_class) ||
                        (i + 1 < n && points[i].track_class != points[i + 1].track_class);
    if (i % 2 == 0 || change || i + 1 == n) kept.push_back(points[i]);
  }
  if (kept.size() > 3 * max_points_ / 4) {
    // So many status changes that keeping them would not bound memory: plain halving.
    kept.clear();
    for (size_t i = 0; i < n; i += 2) kept.push_back(points[i]);
    if ((n - 1) % 2 != 0) kept.push_back(points[n - 1]);
    track.keep_changes = false;
  }
  points = std::move(kept);
  track.stride *= 2;
}

namespace {
// fix.csv's solution types from worst to best: the chart's levels 0-5.
constexpr std::array<std::string_view, 6> kFixTypes = {"none", "2d", "3d", "dgnss", "rtk_float", "rtk_fixed"};
constexpr std::array<std::string_view, 6> kFixTypeLabels = {"none", "2D", "3D", "DGNSS", "RTK float", "RTK fixed"};
// Colours of the solution types on the top view (none is not drawn).
constexpr std::array<std::string_view, 6> kFixTypeColours = {"#999999", "#d62728", "#ff7f0e", "#9467bd", "#1f77b4",
                                                             "#2ca02c"};
// Metres with three significant digits (0.0123, 1.23, 123); percentiles from the histogram with
// two, as precise as its bins.
std::string metres(double value_m) {
  if (!std::isfinite(value_m)) return "-";
  return fmt::format("{:.3g}", value_m);
}
std::string percentile_metres(const ErrorHistogram& histogram, double q) {
  const double value_m = histogram.quantile_m(q);
  if (!std::isfinite(value_m)) return "-";
  return fmt::format("{:.2g}", value_m);
}
constexpr std::array<std::string_view, 8> kReceiverColours = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                                              "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};
// Path type per satellite over time: one row per satellite that was ever received or blocked (not
// only below the mask or without ephemeris), coloured as on the sky plot; from the thinned tracks.
std::string path_timeline(const std::map<SatelliteId, std::vector<ReportBuilder::TrackPoint>>& drawn,
                          const std::map<SatelliteId, ReportBuilder::Track>& tracks, double t0_s, double t1_s,
                          double interval_s, const std::string& id = "path-timeline") {
  std::vector<const SatelliteId*> rows;
  for (const auto& [satellite, points] : drawn) {
    if (std::any_of(points.begin(), points.end(), [](const auto& p) { return p.track_class != TrackClass::kOther; })) {
      rows.push_back(&satellite);
    }
  }
  if (rows.empty()) return {};
  constexpr double kLeft = 60.0, kTop = 10.0, kWidth = 800.0, kRow = 9.0;
  const double height = kRow * static_cast<double>(rows.size());
  ChartFrame frame;
  frame.left = kLeft;
  frame.top = kTop;
  frame.width = kWidth;
  frame.t0_s = t0_s;
  frame.t1_s = t1_s;
  std::string svg = fmt::format(
      R"(<svg xmlns="http://www.w3.org/2000/svg" id="{2}" viewBox="0 0 {0} {1}" width="{0}" height="{1}" font-family="sans-serif" font-size="8">)",
      num(kLeft + kWidth + 200.0), num(kTop + height + 40.0), id);
  svg += "\n<title>Path type of each satellite over time</title>\n";
  std::array<bool, kAllClasses.size()> used{};
  for (size_t row = 0; row < rows.size(); ++row) {
    const SatelliteId& satellite = *rows[row];
    const auto& points = drawn.at(satellite);
    const double y = kTop + kRow * static_cast<double>(row);
    svg += fmt::format(R"(<text x="{}" y="{}" text-anchor="end" fill="#333333">{}</text>)", num(kLeft - 4.0),
                       num(y + kRow - 2.0), satellite.to_string());
    const double limit_s = gap_limit_s(interval_s, tracks.at(satellite).stride);
    for (size_t i = 0; i < points.size(); ++i) {
      // Each point holds until the next one (or one interval when it is the last or a gap follows).
      const double start_s = points[i].time_s;
      double end_s = start_s + std::max(interval_s, 0.0) * static_cast<double>(tracks.at(satellite).stride);
      if (i + 1 < points.size() && points[i + 1].time_s - start_s <= limit_s) end_s = points[i + 1].time_s;
      // Merge a run of one class into one rectangle.
      size_t j = i;
      while (j + 1 < points.size() && points[j + 1].track_class == points[i].track_class &&
             points[j + 1].time_s - points[j].time_s <= limit_s) {
        ++j;
        end_s = j + 1 < points.size() && points[j + 1].time_s - points[j].time_s <= limit_s
                    ? points[j + 1].time_s
                    : points[j].time_s + std::max(interval_s, 0.0) * static_cast<double>(tracks.at(satellite).stride);
      }
      const auto style = class_style(points[i].track_class);
      for (size_t c = 0; c < kAllClasses.size(); ++c) used[c] = used[c] || kAllClasses[c] == points[i].track_class;
      const double x0 = frame.x_of(std::max(start_s, t0_s)), x1 = frame.x_of(std::min(end_s, t1_s));
      svg += fmt::format(R"(<rect x="{}" y="{}" width="{}" height="{}" fill="{}"/>)", num(x0), num(y + 1.0),
                         num(std::max(x1 - x0, 0.5)), num(kRow - 2.0), style.colour);
      i = j;
    }
    svg += "\n";
  }
  // Time axis as the charts have it.
  const double span_s = t1_s - t0_s;
  const double step_s = time_step_s(span_s);
  svg += "<g fill=\"#333333\" font-size=\"11\">\n";
  for (double time_s = std::ceil(t0_s / step_s) * step_s; time_s <= t1_s + 1e-6; time_s += step_s) {
    svg += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle">{}</text>)", num(frame.x_of(time_s)),
                       num(kTop + height + 14.0), escape(detail::time_axis_label(time_s, step_s, span_s)));
  }
  svg += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle">time (GPST)</text>)", num(kLeft + kWidth / 2.0),
                     num(kTop + height + 32.0));
  double legend_y = kTop + 8.0;
  for (size_t c = 0; c < kAllClasses.size(); ++c) {
    if (!used[c]) continue;
    const auto style = class_style(kAllClasses[c]);
    svg += fmt::format(R"(<rect x="{}" y="{}" width="14" height="8" fill="{}"/><text x="{}" y="{}">{}</text>)",
                       num(kLeft + kWidth + 15.0), num(legend_y - 7.0), style.colour, num(kLeft + kWidth + 34.0),
                       num(legend_y), escape(style.label));
    legend_y += 16.0;
  }
  svg += "</g>\n</svg>\n";
  return svg;
}

// East and north bounds of the receivers' true tracks; infinite bounds when there is no point.
struct TrackExtent {
  double east0 = std::numeric_limits<double>::infinity(), east1 = -std::numeric_limits<double>::infinity();
  double north0 = std::numeric_limits<double>::infinity(), north1 = -std::numeric_limits<double>::infinity();
  [[nodiscard]] bool empty() const { return !std::isfinite(east0); }
};
TrackExtent truth_extent(std::span<const ReportBuilder::FixRuns> receivers) {
  TrackExtent x;
  for (const auto& r : receivers) {
    for (const auto& p : r.points) {
      x.east0 = std::min(x.east0, static_cast<double>(p.truth_east_m));
      x.east1 = std::max(x.east1, static_cast<double>(p.truth_east_m));
      x.north0 = std::min(x.north0, static_cast<double>(p.truth_north_m));
      x.north1 = std::max(x.north1, static_cast<double>(p.truth_north_m));
    }
  }
  return x;
}

// The top view of one receiver: its true track (grey line) and its fixes coloured by solution type,
// east and north metres at one scale. The view spans the true track plus a margin of twice the
// 95th percentile of the horizontal error; fixes beyond it are counted, not drawn.
std::string top_view(const ReportBuilder::FixRuns& receiver, size_t index) {
  const std::span<const ReportBuilder::FixRuns> receivers(&receiver, 1);
  auto [east0, east1, north0, north1] = truth_extent(receivers);
  if (!std::isfinite(east0)) return {};
  double margin_m = 0.02;  // a static receiver's view: its scatter, at least 4 cm across
  const double p95_m = receiver.horizontal_histogram.quantile_m(0.95);
  if (std::isfinite(p95_m)) margin_m = std::max(margin_m, 2.0 * p95_m);
  east0 -= margin_m;
  east1 += margin_m;
  north0 -= margin_m;
  north1 += margin_m;
  constexpr double kSize = 520.0, kLeft = 60.0, kTop = 15.0;
  const double span_m = std::max(east1 - east0, north1 - north0);
  const double scale = kSize / span_m;  // px per metre, the same both ways
  const double east_mid = 0.5 * (east0 + east1), north_mid = 0.5 * (north0 + north1);
  auto x_of = [&](double e) { return kLeft + kSize / 2.0 + (e - east_mid) * scale; };
  auto y_of = [&](double n) { return kTop + kSize / 2.0 - (n - north_mid) * scale; };
  std::string svg = fmt::format(
      R"(<svg xmlns="http://www.w3.org/2000/svg" id="fix-top-view-{2}" viewBox="0 0 {0} {1}" width="{0}" height="{1}" font-family="sans-serif" font-size="11">)",
      num(kLeft + kSize + 170.0), num(kTop + kSize + 45.0), index + 1);
  svg += fmt::format("\n<title>The fixes of {} seen from above</title>\n", escape(receiver.receiver));
  svg += fmt::format(R"(<rect x="{}" y="{}" width="{}" height="{}" fill="#fbfbfb" stroke="#444444" stroke-width="0.8"/>)",
                     num(kLeft), num(kTop), num(kSize), num(kSize));
  // Grid in round metres, labelled relative to the view's centre.
  const double step_m = nice_step(span_m, 6);
  std::string grid = "\n<g class=\"axes\" stroke=\"#dddddd\" stroke-width=\"0.6\">\n", labels = "<g fill=\"#333333\">\n";
  for (double d = std::ceil(-span_m / 2.0 / step_m) * step_m; d <= span_m / 2.0 + 1e-9; d += step_m) {
    const double x = x_of(east_mid + d), y = y_of(north_mid + d);
    grid += fmt::format(R"(<line x1="{0}" y1="{1}" x2="{0}" y2="{2}"/><line x1="{3}" y1="{4}" x2="{5}" y2="{4}"/>)", num(x),
                        num(kTop), num(kTop + kSize), num(kLeft), num(y), num(kLeft + kSize));
    grid += "\n";
    labels += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle">{:g}</text><text x="{}" y="{}" text-anchor="end">{:g}</text>)",
                          num(x), num(kTop + kSize + 16.0), std::abs(d) < 1e-9 ? 0.0 : d, num(kLeft - 6.0), num(y + 4.0),
                          std::abs(d) < 1e-9 ? 0.0 : d);
    labels += "\n";
  }
  svg += grid + "</g>\n" + labels;
  svg += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle">east (m, from the view's centre)</text>)",
                     num(kLeft + kSize / 2.0), num(kTop + kSize + 36.0));
  svg += fmt::format("\n<text x=\"14\" y=\"{0}\" text-anchor=\"middle\" transform=\"rotate(-90 14 {0})\">north (m)</text>\n</g>\n",
                     num(kTop + kSize / 2.0));
  size_t outside = 0;
  std::array<bool, 6> types_drawn{};
  for (const auto& r : receivers) {
    std::vector<Point2> truth;
    for (const auto& p : r.points) truth.push_back({x_of(p.truth_east_m), y_of(p.truth_north_m)});
    if (truth.size() >= 2) {
      svg += fmt::format(R"(<polyline class="truth" points="{}" fill="none" stroke="#555555" stroke-width="1.5"/>)",
                         points_attribute(truth));
      svg += "\n";
    }
    svg += "<g class=\"fixes\" fill-opacity=\"0.7\">\n";
    for (const auto& p : r.points) {
      const double x = x_of(p.fix_east_m), y = y_of(p.fix_north_m);
      if (x < kLeft || x > kLeft + kSize || y < kTop || y > kTop + kSize) {
        ++outside;
        continue;
      }
      types_drawn[p.type] = true;
      svg += fmt::format(R"(<circle cx="{}" cy="{}" r="1.8" fill="{}"/>)", num(x), num(y), kFixTypeColours[p.type]);
    }
    svg += "\n</g>\n";
  }
  double y = kTop + 10.0;
  const double x = kLeft + kSize + 15.0;
  svg += "<g class=\"legend\" fill=\"#333333\">\n";
  svg += fmt::format(R"(<line x1="{0}" y1="{1}" x2="{2}" y2="{1}" stroke="#555555" stroke-width="2"/><text x="{3}" y="{4}">true track</text>)",
                     num(x), num(y), num(x + 18.0), num(x + 24.0), num(y + 4.0));
  svg += "\n";
  for (size_t i = kFixTypes.size(); i-- > 1;) {
    if (!types_drawn[i]) continue;
    y += 18.0;
    svg += fmt::format(R"(<circle cx="{}" cy="{}" r="4" fill="{}"/><text x="{}" y="{}">{}</text>)", num(x + 9.0), num(y),
                       kFixTypeColours[i], num(x + 24.0), num(y + 4.0), kFixTypeLabels[i]);
    svg += "\n";
  }
  if (outside > 0) {
    y += 22.0;
    svg += fmt::format(R"(<text x="{}" y="{}">{} fixes outside the view</text>)", num(x), num(y + 4.0), outside);
    svg += "\n";
  }
  svg += "</g>\n</svg>\n";
  return svg;
}

// The world seen from above around the receivers' true tracks: buildings, trees and other objects
// as their outlines, each receiver's track (a dot where it stood still) and its start. The view
// spans the tracks plus 100 m (the reach of the reflections that matter), at one scale.
std::string world_map(const std::vector<ReportMeta::MapOutline>& outlines,
                      const std::vector<ReportBuilder::FixRuns>& receivers) {
  const auto [east0, east1, north0, north1] = truth_extent(receivers);
  if (!std::isfinite(east0) || outlines.empty()) return {};
  constexpr double kMargin_m = 100.0, kSize = 620.0, kLeft = 60.0, kTop = 15.0;
  const double span_m = std::max(east1 - east0, north1 - north0) + 2.0 * kMargin_m;
  const double scale = kSize / span_m;
  const double east_mid = 0.5 * (east0 + east1), north_mid = 0.5 * (north0 + north1);
  auto x_of = [&](double e) { return kLeft + kSize / 2.0 + (e - east_mid) * scale; };
  auto y_of = [&](double n) { return kTop + kSize / 2.0 - (n - north_mid) * scale; };
  std::string svg = fmt::format(
      R"(<svg xmlns="http://www.w3.org/2000/svg" id="world-map" viewBox="0 0 {0} {1}" width="{0}" height="{1}" font-family="sans-serif" font-size="11">)",
      num(kLeft + kSize + 170.0), num(kTop + kSize + 45.0));
  svg += "\n<title>The world seen from above with the receivers' tracks</title>\n";
  svg += fmt::format(R"(<defs><clipPath id="world-map-clip"><rect x="{0}" y="{1}" width="{2}" height="{2}"/></clipPath></defs>)",
                     num(kLeft), num(kTop), num(kSize));
  svg += fmt::format(R"(<rect x="{}" y="{}" width="{}" height="{}" fill="#fbfbfb" stroke="#444444" stroke-width="0.8"/>)",
                     num(kLeft), num(kTop), num(kSize), num(kSize));
  svg += "\n<g clip-path=\"url(#world-map-clip)\" stroke-width=\"0.6\">\n";
  const double half_m = span_m / 2.0;
  size_t drawn_buildings = 0, drawn_trees = 0;
  for (const auto& o : outlines) {
    // Only what reaches into the view.
    bool inside = false;
    for (const auto& [e, n] : o.east_north_m) {
      inside = inside || (std::abs(e - east_mid) <= half_m * 1.5 && std::abs(n - north_mid) <= half_m * 1.5);
    }
    if (!inside || o.east_north_m.size() < 3) continue;
    std::vector<Point2> xy;
    for (const auto& [e, n] : o.east_north_m) xy.push_back({x_of(e), y_of(n)});
    const char* style = o.kind == ReportMeta::MapOutline::Kind::kBuilding ? R"(fill="#b0b0b0" stroke="#707070")"
                        : o.kind == ReportMeta::MapOutline::Kind::kTree   ? R"(fill="#9ccf8c" fill-opacity="0.8" stroke="#4f8f3f")"
                                                                           : R"(fill="#dddddd" stroke="#aaaaaa")";
    svg += fmt::format(R"(<polygon points="{}" {}/>)", points_attribute(xy), style);
    svg += "\n";
    drawn_buildings += o.kind == ReportMeta::MapOutline::Kind::kBuilding ? 1 : 0;
    drawn_trees += o.kind == ReportMeta::MapOutline::Kind::kTree ? 1 : 0;
  }
  for (size_t k = 0; k < receivers.size(); ++k) {
    const auto& r = receivers[k];
    if (r.points.empty()) continue;
    const std::string colour(kReceiverColours[k % kReceiverColours.size()]);
    std::vector<Point2> track;
    for (const auto& p : r.points) track.push_back({x_of(p.truth_east_m), y_of(p.truth_north_m)});
    if (track.size() >= 2) {
      svg += fmt::format(R"(<polyline points="{}" fill="none" stroke="{}" stroke-width="2"/>)", points_attribute(track), colour);
    }
    svg += fmt::format(R"(<circle cx="{}" cy="{}" r="4" fill="{}" stroke="#ffffff" stroke-width="1"/>)", num(track.front().x),
                       num(track.front().y), colour);
    svg += "\n";
  }
  svg += "</g>\n";
  // Scale bar: a round length of about a fifth of the view.
  const double bar_m = nice_step(span_m / 5.0, 1);
  const double bar_y = kTop + kSize + 20.0;
  svg += fmt::format(R"(<g fill="#333333"><line x1="{0}" y1="{1}" x2="{2}" y2="{1}" stroke="#333333" stroke-width="2"/><text x="{3}" y="{4}">{5:g} m</text>)",
                     num(kLeft), num(bar_y), num(kLeft + bar_m * scale), num(kLeft + bar_m * scale + 6.0), num(bar_y + 4.0),
                     bar_m);
  svg += fmt::format(R"(<text x="{}" y="{}" text-anchor="end">north up</text>)", num(kLeft + kSize), num(bar_y + 4.0));
  double y = kTop + 10.0;
  const double x = kLeft + kSize + 15.0;
  for (size_t k = 0; k < receivers.size(); ++k) {
    if (receivers[k].points.empty()) continue;
    svg += fmt::format(R"(<line x1="{0}" y1="{1}" x2="{2}" y2="{1}" stroke="{3}" stroke-width="3"/><text x="{4}" y="{5}">{6}</text>)",
                       num(x), num(y), num(x + 18.0), kReceiverColours[k % kReceiverColours.size()], num(x + 24.0), num(y + 4.0),
                       escape(receivers[k].receiver));
    y += 18.0;
  }
  svg += fmt::format(R"(<rect x="{}" y="{}" width="16" height="10" fill="#b0b0b0"/><text x="{}" y="{}">buildings ({})</text>)",
                     num(x), num(y - 5.0), num(x + 24.0), num(y + 4.0), drawn_buildings);
  y += 18.0;
  svg += fmt::format(R"(<rect x="{}" y="{}" width="16" height="10" fill="#9ccf8c"/><text x="{}" y="{}">trees ({})</text>)",
                     num(x), num(y - 5.0), num(x + 24.0), num(y + 4.0), drawn_trees);
  svg += "\n</g>\n</svg>\n";
  return svg;
}

// The fix against the truth: a table of error percentiles per receiver, the errors over time, their
// distribution, satellites used and HDOP over time, and the top view.
std::string fix_error_section(const std::vector<ReportBuilder::FixRuns>& receivers, double t0_s, double t1_s,
                              double interval_s) {
  bool any = false;
  for (const auto& r : receivers) any = any || r.compared > 0;
  if (!any) return {};
  std::string out = "</section>\n<section>\n<h2>Position fix</h2>\n";
  out += "<p class=\"meta\">The fix against the receiver's true antenna position at the same epoch (epochs with a fix; "
         "percentiles of every epoch, charts thinned).</p>\n";
  out += "<table id=\"fix-errors\">\n<thead><tr><th>receiver</th><th>fixes</th><th>horizontal p50 (m)</th>"
         "<th>p95 (m)</th><th>max (m)</th><th>vertical p50 (m)</th><th>p95 (m)</th><th>max (m)</th>"
         "<th>satellites used (mean)</th><th>HDOP (mean)</th></tr></thead>\n<tbody>\n";
  double horizontal_top_m = 0.0, vertical_top_m = 0.0, distribution_top_m = 0.0;
  int max_satellites = 0;
  double max_hdop = 0.0;
  for (const auto& r : receivers) {
    if (r.compared == 0) continue;
    const double n = static_cast<double>(r.compared);
    out += fmt::format("<tr><th scope=\"row\">{}</th><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
                       "<td>{}</td><td>{:.1f}</td><td>{:.2f}</td></tr>\n",
                       escape(r.receiver), r.compared, percentile_metres(r.horizontal_histogram, 0.5),
                       percentile_metres(r.horizontal_histogram, 0.95), metres(r.horizontal_histogram.max_m()),
                       percentile_metres(r.vertical_histogram, 0.5), percentile_metres(r.vertical_histogram, 0.95),
                       metres(r.vertical_histogram.max_m()),
                       r.satellites_used_sum / n, r.hdop_sum / n);
    // Chart ranges from the 99th percentiles: an outlier is drawn at the edge, not allowed to
    // flatten the rest.
    horizontal_top_m = std::max(horizontal_top_m, r.horizontal_histogram.quantile_m(0.99));
    vertical_top_m = std::max(vertical_top_m, r.vertical_histogram.quantile_m(0.99));
    distribution_top_m = std::max({distribution_top_m, r.horizontal_histogram.quantile_m(0.99),
                                   r.vertical_histogram.quantile_m(0.99)});
    for (const auto& p : r.points) {
      max_satellites = std::max(max_satellites, static_cast<int>(p.satellites_used));
      if (std::isfinite(p.hdop)) max_hdop = std::max(max_hdop, static_cast<double>(p.hdop));
    }
  }
  out += "</tbody>\n</table>\n";
  const auto round_up = [](double value) {
    const double step = nice_step(std::max(value, 1e-3), 5);
    return std::max(step, std::ceil(value * 1.1 / step) * step);
  };
  horizontal_top_m = round_up(horizontal_top_m);
  vertical_top_m = round_up(vertical_top_m);
  distribution_top_m = round_up(distribution_top_m);

  std::vector<Series> horizontal, vertical, satellites, hdop, distribution;
  std::vector<LegendEntry> legend, distribution_legend;
  for (size_t k = 0; k < receivers.size(); ++k) {
    const auto& r = receivers[k];
    if (r.compared == 0) continue;
    const std::string colour(kReceiverColours[k % kReceiverColours.size()]);
    const double gap_s = gap_limit_s(interval_s, r.point_stride);
    Series h{colour, 0.9, 1.4, {{}}}, v{colour, 0.9, 1.4, {{}}}, n{colour, 0.9, 1.4, {{}}}, d{colour, 0.9, 1.4, {{}}};
    for (size_t i = 0; i < r.points.size(); ++i) {
      const ReportBuilder::FixPoint& p = r.points[i];
      if (i > 0 && p.time_s - r.points[i - 1].time_s > gap_s) {
        for (Series* s : {&h, &v, &n, &d}) s->segments.emplace_back();
      }
      h.segments.back().push_back({p.time_s, std::min(static_cast<double>(p.horizontal_m), horizontal_top_m)});
      v.segments.back().push_back({p.time_s, std::clamp(static_cast<double>(p.up_m), -vertical_top_m, vertical_top_m)});
      n.segments.back().push_back({p.time_s, static_cast<double>(p.satellites_used)});
      d.segments.back().push_back({p.time_s, std::isfinite(p.hdop) ? static_cast<double>(p.hdop) : 0.0});
    }
    horizontal.push_back(std::move(h));
    vertical.push_back(std::move(v));
    satellites.push_back(std::move(n));
    hdop.push_back(std::move(d));
    legend.push_back({r.receiver, colour});
    // Distribution functions from the histograms: horizontal solid, vertical lighter.
    for (const bool is_vertical : {false, true}) {
      const auto& histogram = is_vertical ? r.vertical_histogram : r.horizontal_histogram;
      Series cdf{colour, is_vertical ? 0.45 : 0.95, 1.8, {{}}};
      std::uint64_t below = 0;
      cdf.segments.back().push_back({0.0, 0.0});
      const auto& bins = histogram.bins();
      for (size_t i = 0; i < bins.size(); ++i) {
        if (bins[i] == 0) continue;
        below += bins[i];
        const double upper_m = ErrorHistogram::bin_upper_m(i);
        cdf.segments.back().push_back({std::min(upper_m, distribution_top_m), 100.0 * static_cast<double>(below) / static_cast<double>(r.compared)});
      }
      distribution.push_back(std::move(cdf));
      distribution_legend.push_back({r.receiver + (is_vertical ? " vertical" : " horizontal"), colour});
    }
  }
  ChartFrame frame;
  frame.t0_s = t0_s;
  frame.t1_s = t1_s;
  frame.y0 = 0.0;
  frame.y1 = horizontal_top_m;
  out += line_chart("fix-horizontal-error", "Horizontal error of the fix over time", "horizontal error (m)", frame, horizontal,
                    legend, nice_step(horizontal_top_m, 5));
  frame.y0 = -vertical_top_m;
  frame.y1 = vertical_top_m;
  out += line_chart("fix-vertical-error", "Vertical error of the fix over time (fix minus truth, up)", "vertical error (m)", frame,
                    vertical, legend, nice_step(2.0 * vertical_top_m, 6));
  ChartFrame cdf_frame;
  cdf_frame.time_axis = false;
  cdf_frame.x_label = "error (m)";
  cdf_frame.t0_s = 0.0;
  cdf_frame.t1_s = distribution_top_m;
  cdf_frame.y0 = 0.0;
  cdf_frame.y1 = 100.0;
  out += line_chart("fix-error-cdf", "Distribution of the errors (share of fixes with a smaller error)", "fixes (%)", cdf_frame,
                    distribution, distribution_legend, 20.0);
  frame.y0 = 0.0;
  frame.y1 = std::max(4.0, static_cast<double>(max_satellites) + 1.0);
  out += line_chart("fix-satellites-used", "Satellites used in the fix", "satellites used", frame, satellites, legend,
                    std::max(1.0, nice_step(frame.y1, 6)));
  frame.y1 = round_up(std::max(max_hdop, 1.0));
  out += line_chart("fix-hdop", "Horizontal dilution of precision", "HDOP", frame, hdop, legend, nice_step(frame.y1, 5));
  for (size_t k = 0; k < receivers.size(); ++k) {
    if (receivers[k].compared == 0) continue;
    out += fmt::format("<h2>The fixes of {} seen from above</h2>\n", escape(receivers[k].receiver));
    out += top_view(receivers[k], k);
  }
  return out;
}

}  // namespace

void ReportBuilder::add_fix(const std::string& receiver, const GnssTime& time, std::string_view type,
                            const FixError* error) {
  auto it = std::find_if(fix_runs_.begin(), fix_runs_.end(), [&](const FixRuns& r) { return r.receiver == receiver; });
  if (it == fix_runs_.end()) {
    fix_runs_.push_back(FixRuns{});
    it = std::prev(fix_runs_.end());
    it->receiver = receiver;
  }
  FixRuns& r = *it;
  int level = 0;
  for (size_t i = 0; i < kFixTypes.size(); ++i) {
    if (kFixTypes[i] == type) level = static_cast<int>(i);
  }
  const double t = time.gpst_seconds_approx();
  ++r.epochs_per_type[static_cast<size_t>(level)];
  if (std::isnan(r.first_time_s)) r.first_time_s = t;
  if (level >= 1 && std::isnan(r.first_fix_time_s)) r.first_fix_time_s = t;
  if (level == 5 && std::isnan(r.first_fixed_time_s)) r.first_fixed_time_s = t;
  r.last_time_s = t;
  if (r.runs.empty() || r.runs.back().second != level) {
    if (r.runs.size() < kMaxFixRuns) {
      r.runs.emplace_back(t, level);
    } else {
      r.truncated = true;
    }
  }
  if (error == nullptr || level == 0) return;
  const double horizontal_m = std::hypot(error->east_m, error->north_m);
  const double vertical_m = std::abs(error->up_m);
  if (!std::isfinite(horizontal_m) || !std::isfinite(vertical_m)) return;
  r.horizontal_histogram.add(horizontal_m);
  r.vertical_histogram.add(vertical_m);
  r.satellites_used_sum += error->satellites_used;
  r.hdop_sum += std::isfinite(error->hdop) ? error->hdop : 0.0;
  if (r.compared++ % r.point_stride != 0) return;
  FixPoint p;
  p.time_s = t;
  p.horizontal_m = static_cast<float>(horizontal_m);
  p.up_m = static_cast<float>(error->up_m);
  p.fix_east_m = static_cast<float>(error->fix_east_m);
  p.fix_north_m = static_cast<float>(error->fix_north_m);
  p.truth_east_m = static_cast<float>(error->truth_east_m);
  p.truth_north_m = static_cast<float>(error->truth_north_m);
  p.hdop = static_cast<float>(error->hdop);
  p.satellites_used = static_cast<std::uint8_t>(std::clamp(error->satellites_used, 0, 255));
  p.type = static_cast<std::uint8_t>(level);
  r.points.push_back(p);
  if (r.points.size() >= 2 * static_cast<size_t>(max_points_) + 2) {
    // Full: keep every other point and take every other one from now on.
    std::vector<FixPoint> kept;
    kept.reserve(r.points.size() / 2 + 1);
    for (size_t i = 0; i < r.points.size(); i += 2) kept.push_back(r.points[i]);
    r.points = std::move(kept);
    r.point_stride *= 2;
  }
}

std::string ReportBuilder::sky_plot_svg(const ReportMeta& meta) const {
  static const std::map<SatelliteId, Track> kNoTracks;
  return draw_sky_plot(meta, meta.sky_mask_elevation_deg, views_.empty() ? kNoTracks : views_.front().tracks, true);
}

// The sky plot, tracked satellites, C/N0 and path types of one receiver: sections with the
// receiver's name in their titles and ids when the report has several.
std::string ReportBuilder::satellite_sections(const SatelliteView& view, size_t index, const ReportMeta& meta, double t0_s,
                                              double t1_s) const {
  // Satellite counts, including the epoch still being filled.
  std::vector<CountPoint> counts = view.counts;
  if (view.has_pending && view.epochs_seen % view.count_stride == 0) counts.push_back(view.pending);

  float cn0_min = std::numeric_limits<float>::infinity();
  float cn0_max = -std::numeric_limits<float>::infinity();
  std::map<SatelliteId, std::vector<TrackPoint>> drawn;
  for (const auto& [satellite, track] : view.tracks) {
    auto points = drawn_points(track);
    for (const auto& p : points) {
      if (std::isfinite(p.cn0_dbhz)) {
        cn0_min = std::min(cn0_min, p.cn0_dbhz);
        cn0_max = std::max(cn0_max, p.cn0_dbhz);
      }
    }
    drawn.emplace(satellite, std::move(points));
  }

  // Tracked satellites per system, and all together.
  std::vector<Series> count_series;
  std::vector<LegendEntry> count_legend;
  const double count_gap_s = gap_limit_s(meta.interval_s, view.count_stride);
  int max_count = 0;
  const auto count_segments = [&](auto value_of) {
    std::vector<std::vector<Point2>> segments(1);
    for (size_t i = 0; i < counts.size(); ++i) {
      if (i > 0 && counts[i].time_s - counts[i - 1].time_s > count_gap_s) segments.emplace_back();
      const int value = value_of(counts[i]);
      max_count = std::max(max_count, value);
      segments.back().push_back({counts[i].time_s, static_cast<double>(value)});
    }
    return segments;
  };
  for (const auto system : kAllSystems) {
    if (!view.systems_seen[system_index(system)]) continue;
    count_series.push_back(
        {std::string(system_colour(system)), 1.0, 1.6,
         count_segments([system](const CountPoint& c) { return static_cast<int>(c.tracked[system_index(system)]); })});
    count_legend.push_back({std::string(system_name(system)), std::string(system_colour(system))});
  }
  count_series.push_back({"#000000", 0.85, 2.0, count_segments([](const CountPoint& c) {
                            int total = 0;
                            for (const auto n : c.tracked) total += n;
                            return total;
                          })});
  count_legend.push_back({"all systems", "#000000"});
  ChartFrame count_frame;
  count_frame.t0_s = t0_s;
  count_frame.t1_s = t1_s;
  count_frame.y0 = 0.0;
  count_frame.y1 = std::max(4.0, static_cast<double>(max_count) + 1.0);
  const double count_step = std::max(1.0, nice_step(count_frame.y1, 6));

  // C/N0 per satellite, light lines coloured by system.
  std::vector<Series> cn0_series;
  std::vector<LegendEntry> cn0_legend;
  std::array<bool, kAllSystems.size()> cn0_systems{};
  for (const auto& [satellite, points] : drawn) {
    Series s{std::string(system_colour(satellite.system)), 0.45, 1.0, {{}}};
    const double limit_s = gap_limit_s(meta.interval_s, view.tracks.at(satellite).stride);
    const TrackPoint* previous = nullptr;
    for (const auto& p : points) {
      if (!std::isfinite(p.cn0_dbhz)) {
        if (!s.segments.back().empty()) s.segments.emplace_back();
        previous = nullptr;
        continue;
      }
      if (previous != nullptr && p.time_s - previous->time_s > limit_s && !s.segments.back().empty()) s.segments.emplace_back();
      s.segments.back().push_back({p.time_s, static_cast<double>(p.cn0_dbhz)});
      previous = &p;
    }
    if (s.segments.back().empty()) s.segments.pop_back();
    if (s.segments.empty()) continue;
    cn0_systems[system_index(satellite.system)] = true;
    cn0_series.push_back(std::move(s));
  }
  for (const auto system : kAllSystems) {
    if (cn0_systems[system_index(system)]) {
      cn0_legend.push_back({std::string(system_name(system)), std::string(system_colour(system))});
    }
  }
  ChartFrame cn0_frame;
  cn0_frame.t0_s = t0_s;
  cn0_frame.t1_s = t1_s;
  if (std::isfinite(cn0_min)) {
    cn0_frame.y0 = std::floor(static_cast<double>(cn0_min) / 5.0) * 5.0;
    cn0_frame.y1 = std::max(cn0_frame.y0 + 5.0, std::ceil(static_cast<double>(cn0_max) / 5.0) * 5.0);
  } else {
    cn0_frame.y0 = 20.0;
    cn0_frame.y1 = 55.0;
  }
  const double cn0_step = nice_step(cn0_frame.y1 - cn0_frame.y0, 7);

  const bool several = views_.size() > 1;
  std::string suffix;  // ids of the first receiver's charts stay as they were with one receiver
  if (index > 0) {
    suffix = "-";
    for (const char c : view.receiver) suffix += std::isalnum(static_cast<unsigned char>(c)) || c == '_' ? c : '-';
    if (suffix == "-") suffix += std::to_string(index);
  }
  const std::string name = view.receiver.empty() ? meta.receiver_name : view.receiver;
  const std::string of = several ? ": " + escape(name) : "";
  const std::vector<double>* mask = &meta.sky_mask_elevation_deg;
  if (index > 0) {
    static const std::vector<double> kOpenSky;
    const auto it = meta.receiver_sky_masks_deg.find(view.receiver);
    mask = it != meta.receiver_sky_masks_deg.end() ? &it->second : &kOpenSky;
  }
  std::string out = "<section>\n<h2>Sky plot" + of + "</h2>\n";
  out += draw_sky_plot(meta, *mask, view.tracks, false, "skyplot" + suffix, several ? name : "");
  out += "</section>\n<section>\n<h2>Tracked satellites" + of + "</h2>\n";
  out += line_chart("satellite-count" + suffix, "Tracked satellites per system" + (several ? ", " + name : ""),
                    "tracked satellites", count_frame, count_series, count_legend, count_step);
  out += "</section>\n<section>\n<h2>C/N0 (first signal)" + of + "</h2>\n";
  out += line_chart("cn0-chart" + suffix, "C/N0 of the first signal per satellite" + (several ? ", " + name : ""),
                    "C/N0 (dB-Hz)", cn0_frame, cn0_series, cn0_legend, cn0_step);
  if (std::string timeline = path_timeline(drawn, view.tracks, t0_s, t1_s, meta.interval_s, "path-timeline" + suffix);
      !timeline.empty()) {
    out += "</section>\n<section>\n<h2>Path type per satellite" + of + "</h2>\n" + timeline;
  }
  return out;
}

std::string ReportBuilder::html(const ReportMeta& meta) const {
  // One time axis for every chart: the span of every receiver's samples.
  double data_t0_s = std::numeric_limits<double>::infinity();
  double data_t1_s = -std::numeric_limits<double>::infinity();
  size_t satellites_seen = 0;
  std::string receivers;
  for (const SatelliteView& view : views_) {
    for (const auto& [satellite, track] : view.tracks) {
      // Points are in time order; the newest sample may not be among them.
      if (track.samples_seen == 0) continue;
      data_t0_s = std::min(data_t0_s, track.points.empty() ? track.latest.time_s : track.points.front().time_s);
      data_t1_s = std::max(data_t1_s, track.latest.time_s);
    }
    satellites_seen = std::max(satellites_seen, view.tracks.size());
    receivers += (receivers.empty() ? "" : ", ") + (view.receiver.empty() ? meta.receiver_name : view.receiver);
  }
  if (receivers.empty()) receivers = meta.receiver_name;
  const auto [t0_s, t1_s] = time_range(meta, data_t0_s, data_t1_s);

  std::string out;
  out.reserve(1 << 16);
  out += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  out += fmt::format("<title>skytrace report: {}</title>\n<style>\n{}</style>\n</head>\n<body>\n", escape(meta.scenario_name),
                     kStyle);
  out += fmt::format("<h1>skytrace run report: {}</h1>\n", escape(meta.scenario_name));
  out += fmt::format("<p class=\"meta\">{} {} &#183; {} to {} GPST &#183; interval {:g} s &#183; {} satellites seen</p>\n",
                     views_.size() > 1 ? "Receivers" : "Receiver", escape(receivers),
                     escape(meta.start.to_iso8601(TimeScale::kGpst, 0)), escape(meta.end.to_iso8601(TimeScale::kGpst, 0)),
                     meta.interval_s, satellites_seen);
  if (views_.empty()) {
    out += satellite_sections(SatelliteView{}, 0, meta, t0_s, t1_s);
  }
  for (size_t k = 0; k < views_.size(); ++k) {
    if (k > 0) out += "</section>\n";
    out += satellite_sections(views_[k], k, meta, t0_s, t1_s);
  }
  if (!fix_runs_.empty()) {
    // Solution type per receiver: a table of shares and first fixes, and the type over time.
    out += "</section>\n<section>\n<h2>Solution type</h2>\n<table id=\"solution-types\">\n<thead><tr><th>receiver</th><th>epochs</th>";
    for (size_t i = kFixTypes.size(); i-- > 0;) out += fmt::format("<th>{}</th>", kFixTypeLabels[i]);
    out += "<th>first fix (s)</th><th>first RTK fixed (s)</th></tr></thead>\n<tbody>\n";
    std::vector<Series> fix_series;
    std::vector<LegendEntry> fix_legend;
    for (size_t k = 0; k < fix_runs_.size(); ++k) {
      const FixRuns& r = fix_runs_[k];
      size_t total = 0;
      for (const auto n : r.epochs_per_type) total += n;
      out += fmt::format("<tr><th scope=\"row\">{}</th><td>{}</td>", escape(r.receiver), total);
      for (size_t i = kFixTypes.size(); i-- > 0;) {
        out += fmt::format("<td>{:.1f} %</td>", total > 0 ? 100.0 * static_cast<double>(r.epochs_per_type[i]) / static_cast<double>(total) : 0.0);
      }
      auto after_start = [&](double t) { return std::isnan(t) ? std::string("never") : fmt::format("{:g}", t - r.first_time_s); };
      out += fmt::format("<td>{}</td><td>{}</td></tr>\n", after_start(r.first_fix_time_s), after_start(r.first_fixed_time_s));
      const std::string colour(kReceiverColours[k % kReceiverColours.size()]);
      Series series{colour, 0.9, 1.8, {{}}};
      for (size_t i = 0; i < r.runs.size(); ++i) {
        const double end_s = i + 1 < r.runs.size() ? r.runs[i + 1].first : r.last_time_s;
        // Offset per receiver so that equal types stay visible side by side.
        const double level = r.runs[i].second + 0.06 * static_cast<double>(k);
        series.segments.back().push_back({r.runs[i].first, level});
        series.segments.back().push_back({end_s, level});
      }
      fix_series.push_back(std::move(series));
      fix_legend.push_back({r.receiver + (r.truncated ? " (chart truncated)" : ""), colour});
    }
    out += "</tbody>\n</table>\n";
    out += "<p class=\"meta\">Chart levels: 0 none, 1 2D, 2 3D, 3 DGNSS, 4 RTK float, 5 RTK fixed.</p>\n";
    ChartFrame fix_frame;
    fix_frame.t0_s = t0_s;
    fix_frame.t1_s = t1_s;
    fix_frame.y0 = 0.0;
    fix_frame.y1 = 5.5;
    out += line_chart("solution-type", "Solution type over time", "solution type", fix_frame, fix_series, fix_legend, 1.0);
    out += fix_error_section(fix_runs_, t0_s, t1_s, meta.interval_s);
    if (std::string map = world_map(meta.world_outlines, fix_runs_); !map.empty()) {
      out += "</section>\n<section>\n<h2>The world from above</h2>\n" + map;
    }
  }
  out += "</section>\n<section>\n<h2>Scenario</h2>\n";
  out += summary_table(meta);
  out += "</section>\n<section>\n<h2>Warnings</h2>\n";
  std::vector<std::string> warnings = meta.warnings;
  if (ignored_samples_ > 0) {
    warnings.push_back(fmt::format("report: {} samples out of time order were left out", ignored_samples_));
  }
  if (warnings.empty()) {
    out += "<p id=\"warnings\">None.</p>\n";
  } else {
    out += "<ul id=\"warnings\" class=\"warnings\">\n";
    for (const auto& warning : warnings) out += fmt::format("<li>{}</li>\n", escape(warning));
    out += "</ul>\n";
  }
  out += "</section>\n<footer>Written by skytrace. Self-contained: no scripts, no external resources.</footer>\n";
  out += "</body>\n</html>\n";
  return out;
}

namespace detail {

std::string time_axis_label(double time_s, double step_s, double span_s) {
  // Rounded to the second on the timeline first, then split: 23:59:59.9999995 is the next day's
  // 00:00:00 (and 00:00 or its date), never 23:59:60.
  const auto whole_s = static_cast<std::int64_t>(std::floor(time_s));
  const RoundedCalendarTime calendar = GnssTime::from_gpst_seconds(whole_s, time_s - static_cast<double>(whole_s))
                                           .to_rounded_calendar(TimeScale::kGpst, 0);
  if (step_s >= 86400.0) return fmt::format("{:04}-{:02}-{:02}", calendar.year, calendar.month, calendar.day);
  if (span_s > 86400.0) return fmt::format("{:02}-{:02} {:02}:{:02}", calendar.month, calendar.day, calendar.hour, calendar.minute);
  if (std::fmod(step_s, 60.0) == 0.0) return fmt::format("{:02}:{:02}", calendar.hour, calendar.minute);
  return fmt::format("{:02}:{:02}:{:02}", calendar.hour, calendar.minute, calendar.second);
}

}  // namespace detail

}  // namespace skytrace::io

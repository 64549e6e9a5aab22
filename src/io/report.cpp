// The run report: HTML page and SVG sky plot (see report.hpp for the geometry).
#include "skytrace/io/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string_view>

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

// Coordinates with two decimals: 0.01 unit is far below a pixel (and no "-0.00").
std::string num(double value) { return fmt::format("{:.2f}", std::abs(value) < 0.005 ? 0.0 : value); }

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
    out += num(p.x);
    out += ',';
    out += num(p.y);
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
std::string sky_mask_path(const ReportMeta& meta) {
  const auto& mask = meta.sky_mask_elevation_deg;
  if (mask.empty()) return {};
  const double step_deg =
      meta.sky_mask_azimuth_step_deg > 0.0 ? meta.sky_mask_azimuth_step_deg : 360.0 / static_cast<double>(mask.size());
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

std::string draw_sky_plot(const ReportMeta& meta, const std::map<SatelliteId, ReportBuilder::Track>& tracks,
                          bool standalone) {
  std::string svg;
  const double legend_top = kSkyRadius + 26.0;
  const double height = legend_top + 10.0 * static_cast<double>(kAllClasses.size()) + 4.0 + 125.0;
  if (standalone) svg += "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  svg += fmt::format(
      R"(<svg xmlns="http://www.w3.org/2000/svg" id="skyplot" viewBox="-125 -125 250 {}" width="500" height="{}" font-family="sans-serif">)",
      num(height), num(2.0 * height));
  svg += "\n";
  svg += fmt::format("<title>Sky plot: {}</title>\n", escape(meta.scenario_name));
  svg += "<rect x=\"-125\" y=\"-125\" width=\"250\" height=\"" + num(height) + "\" fill=\"#ffffff\"/>\n";
  svg += R"(<circle cx="0" cy="0" r="100" fill="#f4f8ff" stroke="none"/>)";
  svg += "\n";
  svg += "<g id=\"skyplot-mask\">\n" + sky_mask_path(meta) + "</g>\n";
  // Grid: elevation rings at 0/30/60 deg, the N-S and E-W lines.
  svg += "<g id=\"skyplot-grid\" fill=\"none\" stroke=\"#555555\">\n";
  for (const double elevation_deg : {0.0, 30.0, 60.0}) {
    const double r = kSkyRadius * (90.0 - elevation_deg) / 90.0;
    svg += fmt::format(R"(<circle cx="0" cy="0" r="{}" stroke-width="{}"{}/>)", num(r), elevation_deg == 0.0 ? "0.8" : "0.4",
                       elevation_deg == 0.0 ? "" : R"( stroke-dasharray="2 2")");
    svg += "\n";
  }
  svg += R"(<line x1="0" y1="-100" x2="0" y2="100" stroke-width="0.3"/><line x1="-100" y1="0" x2="100" y2="0" stroke-width="0.3"/>)";
  svg += "\n</g>\n<g id=\"skyplot-labels\" font-size=\"7\" fill=\"#333333\" text-anchor=\"middle\">\n";
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
  svg += "<g id=\"skyplot-tracks\" fill=\"none\" stroke-width=\"1.2\" stroke-linecap=\"round\" stroke-linejoin=\"round\">\n";
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
  svg += "</g>\n<g id=\"skyplot-satellite-labels\" font-size=\"5.5\" fill=\"#111111\">\n" + labels + "</g>\n";

  // Legend below the plot.
  svg += "<g id=\"skyplot-legend\" font-size=\"6\" fill=\"#333333\">\n";
  double y = legend_top;
  for (const auto track_class : kAllClasses) {
    const auto style = class_style(track_class);
    svg += fmt::format(R"(<line x1="-110" y1="{0}" x2="-100" y2="{0}" stroke="{1}" stroke-width="2"/><text x="-96" y="{2}">{3}</text>)",
                       num(y), style.colour, num(y + 2.0), escape(style.label));
    svg += "\n";
    y += 10.0;
  }
  if (!meta.sky_mask_elevation_deg.empty()) {
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
  // Time axis: round GPST instants.
  const double span_s = frame.t1_s - frame.t0_s;
  const double step_s = time_step_s(span_s);
  for (double time_s = std::ceil(frame.t0_s / step_s) * step_s; time_s <= frame.t1_s + 1e-6; time_s += step_s) {
    const double x = frame.x_of(time_s);
    svg += fmt::format(R"(<line x1="{0}" y1="{1}" x2="{0}" y2="{2}"/>)", num(x), num(frame.top), num(frame.top + frame.height));
    svg += "\n";
    tick_labels += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle">{}</text>)", num(x),
                               num(frame.top + frame.height + 16.0), escape(detail::time_axis_label(time_s, step_s, span_s)));
    tick_labels += "\n";
  }
  svg += "</g>\n<g class=\"tick-labels\" fill=\"#333333\">\n" + tick_labels;
  svg += fmt::format(R"(<text x="{}" y="{}" text-anchor="middle">time (GPST)</text>)", num(frame.left + frame.width / 2.0),
                     num(frame.top + frame.height + 36.0));
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
  const auto it = tracks_.find(satellite);
  return it == tracks_.end() ? 0 : it->second.points.size();
}

void ReportBuilder::add(const ReportSample& sample) {
  const double time_s = sample.time.gpst_seconds_approx();
  auto& track = tracks_[sample.satellite];
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
  systems_seen_[system] = true;
  const bool tracked = sample.status == "tracked";
  if (!has_pending_) {
    pending_ = CountPoint{time_s, {}};
    has_pending_ = true;
  } else if (time_s > pending_.time_s + kEpochTolerance_s) {
    flush_pending_epoch();
    pending_ = CountPoint{time_s, {}};
    has_pending_ = true;
  } else if (time_s < pending_.time_s - kEpochTolerance_s) {
    // A late sample of an earlier epoch: counted if that epoch was kept.
    const auto it = std::lower_bound(counts_.begin(), counts_.end(), time_s - kEpochTolerance_s,
                                     [](const CountPoint& c, double t_s) { return c.time_s < t_s; });
    if (tracked && it != counts_.end() && std::abs(it->time_s - time_s) <= kEpochTolerance_s) ++it->tracked[system];
    return;
  }
  if (tracked) ++pending_.tracked[system];
}

void ReportBuilder::flush_pending_epoch() {
  if (!has_pending_) return;
  if (epochs_seen_ % count_stride_ == 0) counts_.push_back(pending_);
  ++epochs_seen_;
  has_pending_ = false;
  if (counts_.size() >= max_points_) {
    // Keep epochs 0, 2 stride, 4 stride, ...: the series stays evenly sampled.
    size_t kept = 0;
    for (size_t i = 0; i < counts_.size(); i += 2) counts_[kept++] = counts_[i];
    counts_.resize(kept);
    count_stride_ *= 2;
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
constexpr std::array<std::string_view, 8> kReceiverColours = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                                                              "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};
}  // namespace

void ReportBuilder::add_fix(const std::string& receiver, const GnssTime& time, std::string_view type) {
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
}

std::string ReportBuilder::sky_plot_svg(const ReportMeta& meta) const { return draw_sky_plot(meta, tracks_, true); }

std::string ReportBuilder::html(const ReportMeta& meta) const {
  // Satellite counts, including the epoch still being filled.
  std::vector<CountPoint> counts = counts_;
  if (has_pending_ && epochs_seen_ % count_stride_ == 0) counts.push_back(pending_);

  double data_t0_s = std::numeric_limits<double>::infinity();
  double data_t1_s = -std::numeric_limits<double>::infinity();
  float cn0_min = std::numeric_limits<float>::infinity();
  float cn0_max = -std::numeric_limits<float>::infinity();
  std::map<SatelliteId, std::vector<TrackPoint>> drawn;
  for (const auto& [satellite, track] : tracks_) {
    auto points = drawn_points(track);
    for (const auto& p : points) {
      data_t0_s = std::min(data_t0_s, p.time_s);
      data_t1_s = std::max(data_t1_s, p.time_s);
      if (std::isfinite(p.cn0_dbhz)) {
        cn0_min = std::min(cn0_min, p.cn0_dbhz);
        cn0_max = std::max(cn0_max, p.cn0_dbhz);
      }
    }
    drawn.emplace(satellite, std::move(points));
  }
  const auto [t0_s, t1_s] = time_range(meta, data_t0_s, data_t1_s);

  // Tracked satellites per system, and all together.
  std::vector<Series> count_series;
  std::vector<LegendEntry> count_legend;
  const double count_gap_s = gap_limit_s(meta.interval_s, count_stride_);
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
    if (!systems_seen_[system_index(system)]) continue;
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
    const double limit_s = gap_limit_s(meta.interval_s, tracks_.at(satellite).stride);
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

  std::string out;
  out.reserve(1 << 16);
  out += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  out += fmt::format("<title>skytrace report: {}</title>\n<style>\n{}</style>\n</head>\n<body>\n", escape(meta.scenario_name),
                     kStyle);
  out += fmt::format("<h1>skytrace run report: {}</h1>\n", escape(meta.scenario_name));
  out += fmt::format("<p class=\"meta\">Receiver {} &#183; {} to {} GPST &#183; interval {:g} s &#183; {} satellites seen</p>\n",
                     escape(meta.receiver_name), escape(meta.start.to_iso8601(TimeScale::kGpst, 0)),
                     escape(meta.end.to_iso8601(TimeScale::kGpst, 0)), meta.interval_s, tracks_.size());
  out += "<section>\n<h2>Sky plot</h2>\n";
  out += draw_sky_plot(meta, tracks_, false);
  out += "</section>\n<section>\n<h2>Tracked satellites</h2>\n";
  out += line_chart("satellite-count", "Tracked satellites per system", "tracked satellites", count_frame, count_series,
                    count_legend, count_step);
  out += "</section>\n<section>\n<h2>C/N0 (first signal)</h2>\n";
  out += line_chart("cn0-chart", "C/N0 of the first signal per satellite", "C/N0 (dB-Hz)", cn0_frame, cn0_series, cn0_legend,
                    cn0_step);
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

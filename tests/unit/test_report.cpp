// The run report: structure of the page (ids, no external URL, balanced tags, escaping), sky-plot
// geometry against hand-computed coordinates, status colours, and the memory bound of decimation.
#include <gtest/gtest.h>

#include <cmath>
#include <iterator>
#include <map>
#include <regex>
#include <string>
#include <vector>

#include "skytrace/io/report.hpp"
#include "time_boundaries.hpp"

namespace skytrace::io {
namespace {

constexpr std::string_view kGreen = "#1a9641";
constexpr std::string_view kOrange = "#f28e1c";
constexpr std::string_view kRed = "#d7191c";

GnssTime t0() { return GnssTime::from_calendar({2020, 6, 25, 10, 0, 0.0}, TimeScale::kGpst); }

ReportSample sample(double dt_s, const char* satellite, double azimuth_deg, double elevation_deg, const std::string& status,
                    double attenuation_db = 0.0) {
  ReportSample s;
  s.time = t0() + dt_s;
  s.satellite = SatelliteId::parse(satellite).value();
  s.azimuth_deg = azimuth_deg;
  s.elevation_deg = elevation_deg;
  s.status = status;
  s.cn0_dbhz = status == "tracked" ? 45.0 - attenuation_db + 0.1 * elevation_deg : std::nan("");
  s.vegetation_attenuation_db = attenuation_db;
  return s;
}

// Two satellites crossing the sky over an hour at 60 s: G05 north to south over the zenith side,
// blocked for ten minutes; E11 west to east, through vegetation for ten minutes.
ReportBuilder crossing_builder() {
  ReportBuilder builder;
  for (int k = 0; k <= 60; ++k) {
    const double dt_s = 60.0 * k;
    const double f = k / 60.0;
    const std::string g_status = (k >= 20 && k < 30) ? "blocked" : "tracked";
    builder.add(sample(dt_s, "G05", f < 0.5 ? 10.0 : 170.0, 5.0 + 75.0 * (1.0 - std::abs(2.0 * f - 1.0)), g_status));
    const double veg_db = (k >= 35 && k < 45) ? 6.0 : 0.0;
    builder.add(sample(dt_s, "E11", f < 0.5 ? 270.0 : 90.0, 10.0 + 40.0 * (1.0 - std::abs(2.0 * f - 1.0)), "tracked", veg_db));
  }
  return builder;
}

ReportMeta crossing_meta() {
  ReportMeta meta;
  meta.scenario_name = "courtyard";
  meta.receiver_name = "rover";
  meta.start = t0();
  meta.end = t0() + 3600.0;
  meta.interval_s = 60.0;
  meta.summary_rows = {{"world", "courtyard.sdf"}, {"signals", "G1C E1C"}};
  // 36 azimuths at 10 deg: a 30 deg wall to the east (60..120 deg), 5 deg elsewhere.
  for (int i = 0; i < 36; ++i) meta.sky_mask_elevation_deg.push_back(i >= 6 && i <= 12 ? 30.0 : 5.0);
  meta.sky_mask_azimuth_step_deg = 10.0;
  meta.warnings = {"model tree_3 skipped: mesh not found"};
  return meta;
}

// Checks that every element opened is closed in order (HTML void elements excepted); returns
// an empty string or the first problem.
std::string tag_balance_problem(const std::string& text) {
  std::vector<std::string> stack;
  size_t pos = 0;
  while ((pos = text.find('<', pos)) != std::string::npos) {
    const size_t end = text.find('>', pos);
    if (end == std::string::npos) return "unterminated tag at " + std::to_string(pos);
    const std::string tag = text.substr(pos + 1, end - pos - 1);
    pos = end + 1;
    if (tag.empty()) return "empty tag";
    if (tag[0] == '!' || tag[0] == '?') continue;
    if (tag[0] == '/') {
      const std::string name = tag.substr(1);
      if (stack.empty() || stack.back() != name) {
        return "closing </" + name + "> does not match <" + (stack.empty() ? std::string("none") : stack.back()) + ">";
      }
      stack.pop_back();
      continue;
    }
    const std::string name = tag.substr(0, tag.find_first_of(" \t\n/"));
    if (tag.back() == '/' || name == "meta") continue;
    stack.push_back(name);
  }
  if (!stack.empty()) return "unclosed <" + stack.back() + ">";
  return {};
}

size_t count_of(const std::string& text, std::string_view what) {
  size_t n = 0;
  for (size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++n;
  return n;
}

// Every "points" attribute's coordinate pairs, summed over the fragment.
size_t polyline_points(const std::string& text) {
  size_t n = 0;
  static const std::regex points_re(R"re(points="([^"]*)")re");
  for (std::sregex_iterator it(text.begin(), text.end(), points_re), end; it != end; ++it) {
    n += count_of((*it)[1].str(), ",");
  }
  return n;
}

std::string svg_part(const std::string& html, std::string_view id) {
  const size_t begin = html.find("id=\"" + std::string(id) + "\"");
  const size_t end = html.find("</svg>", begin);
  return begin == std::string::npos ? std::string() : html.substr(begin, end - begin);
}
std::string skyplot_part(const std::string& html) { return svg_part(html, "skyplot"); }

TEST(Report, PageHasThePlotsTheTableAndNoExternalResource) {
  const auto builder = crossing_builder();
  const auto html = builder.html(crossing_meta());
  for (const char* id : {"id=\"skyplot\"", "id=\"satellite-count\"", "id=\"cn0-chart\"", "id=\"summary\"", "id=\"warnings\""}) {
    EXPECT_EQ(count_of(html, id), 1U) << id;
  }
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0U);
  EXPECT_EQ(tag_balance_problem(html), "");
  // The only URL is the SVG namespace; nothing to load, nothing to run.
  for (const std::string_view scheme : {"http://", "https://"}) {
    for (size_t pos = html.find(scheme); pos != std::string::npos; pos = html.find(scheme, pos + 1)) {
      EXPECT_EQ(html.compare(pos, 26, "http://www.w3.org/2000/svg"), 0) << html.substr(pos, 60);
    }
  }
  for (const char* forbidden : {"<script", "src=", "href=", "url(", "@import", "<link", "<img"}) {
    EXPECT_EQ(html.find(forbidden), std::string::npos) << forbidden;
  }
  EXPECT_NE(html.find("courtyard.sdf"), std::string::npos);
  EXPECT_NE(html.find("model tree_3 skipped"), std::string::npos);
  // Two tracks labelled, lines in all three plots.
  EXPECT_NE(html.find(">G05</text>"), std::string::npos);
  EXPECT_NE(html.find(">E11</text>"), std::string::npos);
  EXPECT_GE(count_of(html, "<polyline"), 2U + 3U + 2U);
  EXPECT_EQ(count_of(html, "class=\"track-end\""), 2U);
}

size_t polylines_coloured(const std::string& text, std::string_view colour) {
  const std::regex re("<polyline points=\"[^\"]*\" stroke=\"" + std::string(colour) + "\"");
  return static_cast<size_t>(std::distance(std::sregex_iterator(text.begin(), text.end(), re), std::sregex_iterator()));
}

TEST(Report, TracksAreColouredByStatus) {
  const auto sky = skyplot_part(crossing_builder().html(crossing_meta()));
  // G05: green, red (blocked), green; E11: green, orange (vegetation), green.
  EXPECT_EQ(polylines_coloured(sky, kGreen), 4U);
  EXPECT_EQ(polylines_coloured(sky, kRed), 1U);
  EXPECT_EQ(polylines_coloured(sky, kOrange), 1U);
  // The blocked run starts at G05's 21st sample: azimuth 10 deg, elevation 55 deg, so
  // r = 100 * 35 / 90 = 38.889, x = r sin 10 deg = 6.75, y = -r cos 10 deg = -38.30.
  EXPECT_NE(sky.find("<polyline points=\"6.75,-38.30 "), std::string::npos);
}

TEST(Report, SkyPlotGeometryNorthUpEastRight) {
  ReportBuilder builder;
  builder.add(sample(0, "G01", 90.0, 0.0, "tracked"));    // east horizon: (100, 0)
  builder.add(sample(0, "G02", 180.0, 60.0, "tracked"));  // south, r = 33.33: (0, 33.33)
  builder.add(sample(0, "G03", 225.0, 45.0, "tracked"));  // south-west, r = 50: (-35.36, 35.36)
  builder.add(sample(0, "G04", 0.0, 90.0, "tracked"));    // zenith: (0, 0)
  builder.add(sample(0, "G06", 0.0, 30.0, "tracked"));    // north, r = 66.67: (0, -66.67)
  builder.add(sample(0, "G07", 10.0, -5.0, "below_mask"));  // below the horizon: not drawn
  const auto svg = builder.sky_plot_svg(ReportMeta{});
  for (const char* expected : {R"(class="track-end" cx="100.00" cy="0.00")", R"(class="track-end" cx="0.00" cy="33.33")",
                               R"(class="track-end" cx="-35.36" cy="35.36")", R"(class="track-end" cx="0.00" cy="0.00")",
                               R"(class="track-end" cx="0.00" cy="-66.67")"}) {
    EXPECT_NE(svg.find(expected), std::string::npos) << expected;
  }
  EXPECT_EQ(count_of(svg, "class=\"track-end\""), 5U);
  EXPECT_EQ(svg.find(">G07<"), std::string::npos);
}

TEST(Report, SkyMaskIsAGreyAreaFromTheHorizonToTheMask) {
  const auto meta = crossing_meta();
  const auto sky = skyplot_part(crossing_builder().html(meta));
  // Azimuth 0: 5 deg, r = 94.44 at the top; azimuth 90: 30 deg, r = 66.67 to the right.
  EXPECT_NE(sky.find("fill-rule=\"evenodd\""), std::string::npos);
  EXPECT_NE(sky.find("M 0.00,-94.44 "), std::string::npos);
  EXPECT_NE(sky.find("L 66.67,0.00 "), std::string::npos);
  ReportMeta open_sky = meta;
  open_sky.sky_mask_elevation_deg.clear();
  EXPECT_EQ(skyplot_part(crossing_builder().html(open_sky)).find("fill-rule"), std::string::npos);
}

TEST(Report, StandaloneSkyPlotIsAnSvgDocument) {
  const auto svg = crossing_builder().sky_plot_svg(crossing_meta());
  EXPECT_EQ(svg.rfind("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\"", 0), 0U);
  EXPECT_EQ(tag_balance_problem(svg), "");
  EXPECT_EQ(count_of(svg, "<svg"), 1U);
  // Same drawing as in the page.
  const auto html = crossing_builder().html(crossing_meta());
  EXPECT_NE(html.find(svg.substr(svg.find("<svg"))), std::string::npos);
}

TEST(Report, TextIsEscaped) {
  ReportMeta meta = crossing_meta();
  meta.scenario_name = "a<b & \"c\"";
  meta.receiver_name = "<script>alert(1)</script>";
  meta.summary_rows = {{"<key>", "x & y"}};
  meta.warnings = {"'quoted' <warning>"};
  const auto html = crossing_builder().html(meta);
  EXPECT_EQ(tag_balance_problem(html), "");
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<key>"), std::string::npos);
  EXPECT_EQ(html.find("<warning>"), std::string::npos);
  EXPECT_NE(html.find("a&lt;b &amp; &quot;c&quot;"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
  EXPECT_NE(html.find("<th scope=\"row\">&lt;key&gt;</th><td>x &amp; y</td>"), std::string::npos);
  EXPECT_NE(html.find("&#39;quoted&#39; &lt;warning&gt;"), std::string::npos);
  const auto svg = crossing_builder().sky_plot_svg(meta);
  EXPECT_NE(svg.find("<title>Sky plot: a&lt;b &amp; &quot;c&quot;</title>"), std::string::npos);
}

// One satellite circling at 1 Hz for n seconds; status_of(k) gives each sample's status.
template <typename StatusOf>
ReportBuilder circling(double max_points, int n, StatusOf status_of) {
  ReportBuilder builder(max_points);
  for (int k = 0; k < n; ++k) {
    builder.add(sample(k, "C20", std::fmod(0.05 * k, 360.0), 30.0 + 20.0 * std::sin(k * 1e-3), status_of(k)));
  }
  return builder;
}

TEST(Report, DecimationBoundsMemoryAndOutput) {
  const auto tracked = [](int) { return std::string("tracked"); };
  const auto small = circling(200, 2000, tracked);
  const auto large = circling(200, 200000, tracked);
  EXPECT_LE(large.track_points(SatelliteId::parse("C20").value()), 200U);
  EXPECT_GE(large.track_points(SatelliteId::parse("C20").value()), 50U);
  ReportMeta meta;
  meta.interval_s = 1.0;
  meta.start = t0();
  meta.end = t0() + 200000.0;
  const auto large_html = large.html(meta);
  meta.end = t0() + 2000.0;
  const auto small_html = small.html(meta);
  // 100 times the samples, about the same page.
  EXPECT_LT(static_cast<double>(large_html.size()), 1.3 * static_cast<double>(small_html.size()))
      << small_html.size() << " -> " << large_html.size();
  EXPECT_LE(polyline_points(skyplot_part(large_html)), 202U);
  // Counts: two series (BeiDou and all) of at most 200 epochs.
  EXPECT_LE(polyline_points(svg_part(large_html, "satellite-count")), 2U * 201U);
  EXPECT_GE(polyline_points(svg_part(large_html, "satellite-count")), 2U * 50U);
  EXPECT_EQ(tag_balance_problem(large_html), "");
}

TEST(Report, DecimationKeepsShortStatusChangesAndStaysBoundedWhenStatusFlickers) {
  // One-sample blockages among 100,000 samples still show on the plot.
  const auto blip = circling(100, 100000, [](int k) {
    return std::string(k == 30001 || k == 50000 || k == 70003 || k == 90010 ? "blocked" : "tracked");
  });
  EXPECT_LE(blip.track_points(SatelliteId::parse("C20").value()), 100U);
  ReportMeta meta;
  meta.interval_s = 1.0;
  EXPECT_EQ(polylines_coloured(blip.sky_plot_svg(meta), kRed), 4U);
  // A status changing at every sample cannot grow memory either.
  const auto flicker = circling(100, 100000, [](int k) { return std::string(k % 2 == 0 ? "blocked" : "tracked"); });
  EXPECT_LE(flicker.track_points(SatelliteId::parse("C20").value()), 100U);
}

TEST(Report, SatelliteCountsPerSystem) {
  ReportBuilder builder;
  // Epoch 0: G01, G02, E01 tracked; epoch 1: G01 tracked, G02 blocked, E01 tracked; epoch 2: G01,
  // G02 tracked, E01 below the mask.
  const std::vector<std::vector<std::string>> status = {
      {"tracked", "tracked", "tracked"}, {"tracked", "blocked", "tracked"}, {"tracked", "tracked", "below_mask"}};
  for (int k = 0; k < 3; ++k) {
    builder.add(sample(30.0 * k, "G01", 40.0, 40.0, status[k][0]));
    builder.add(sample(30.0 * k, "G02", 140.0, 40.0, status[k][1]));
    builder.add(sample(30.0 * k, "E01", 240.0, 40.0, status[k][2]));
  }
  ReportMeta meta;
  meta.interval_s = 30.0;
  const auto chart = svg_part(builder.html(meta), "satellite-count");
  // GPS, Galileo and all systems: three lines of three epochs. The value axis runs 0..4 over
  // 250 px from y = 15: value v at y = 15 + 250 (1 - v / 4).
  EXPECT_EQ(count_of(chart, "<polyline"), 3U);
  const std::regex re(R"re(<polyline points="([^"]*)" stroke="([^"]*)")re");
  std::map<std::string, std::vector<double>> y_by_colour;
  for (std::sregex_iterator it(chart.begin(), chart.end(), re), end; it != end; ++it) {
    std::string points = (*it)[1].str();
    std::vector<double> ys;
    for (size_t pos = points.find(','); pos != std::string::npos; pos = points.find(',', pos + 1)) {
      ys.push_back(std::stod(points.substr(pos + 1)));
    }
    y_by_colour[(*it)[2].str()] = ys;
  }
  const auto y_of = [](double v) { return 15.0 + 250.0 * (1.0 - v / 4.0); };
  const std::map<std::string, std::vector<double>> expected = {
      {"#1f77b4", {y_of(2), y_of(1), y_of(2)}}, {"#2ca02c", {y_of(1), y_of(1), y_of(0)}}, {"#000000", {y_of(3), y_of(2), y_of(2)}}};
  for (const auto& [colour, ys] : expected) {
    ASSERT_EQ(y_by_colour[colour].size(), 3U) << colour;
    for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(y_by_colour[colour][i], ys[i], 0.006) << colour << " epoch " << i;
  }
}

TEST(Report, EmptyRunGivesAValidPage) {
  const ReportBuilder builder;
  ReportMeta meta;
  meta.start = t0();
  meta.end = t0();
  const auto html = builder.html(meta);
  EXPECT_EQ(tag_balance_problem(html), "");
  EXPECT_NE(html.find("id=\"skyplot\""), std::string::npos);
  EXPECT_EQ(html.find("nan"), std::string::npos);
  EXPECT_EQ(html.find("inf"), std::string::npos);
  EXPECT_EQ(tag_balance_problem(builder.sky_plot_svg(meta)), "");
}

TEST(Report, OutOfOrderSamplesAreCountedAndReported) {
  ReportBuilder builder;
  builder.add(sample(60, "G01", 40.0, 40.0, "tracked"));
  builder.add(sample(0, "G01", 40.0, 40.0, "tracked"));
  builder.add(sample(60, "G01", 40.0, 40.0, "tracked"));
  EXPECT_EQ(builder.ignored_samples(), 2U);
  EXPECT_NE(builder.html(ReportMeta{}).find("2 samples out of time order"), std::string::npos);
}

TEST(Report, StartAndEndRoundedToTheSecondCarryIntoMinuteHourDayMonthAndYear) {
  const auto builder = crossing_builder();
  for (const auto& b : test::time_boundaries()) {
    for (const double fraction : test::fractions_rounding_up(0)) {
      ReportMeta meta = crossing_meta();
      meta.start = test::boundary_time(b, TimeScale::kGpst, fraction);
      meta.end = meta.start + 3600.0;
      const std::string end_text = (GnssTime::parse_iso8601(b.next, TimeScale::kGpst).value() + 3600.0).to_iso8601(TimeScale::kGpst, 0);
      const auto html = builder.html(meta);
      EXPECT_NE(html.find(std::string("&#183; ") + b.next + " to " + end_text + " GPST &#183;"), std::string::npos)
          << b.name << ", fraction 1 - " << 1.0 - fraction;
      EXPECT_EQ(html.find(":60 "), std::string::npos) << b.name;
    }
  }
}

TEST(Report, TimeAxisLabelsRoundedToTheSecondCarryIntoMinuteHourDayMonthAndYear) {
  for (const auto& b : test::time_boundaries()) {
    const GnssTime last = GnssTime::parse_iso8601(b.last_second, TimeScale::kGpst).value();
    const std::string next(b.next);
    for (const double fraction : {0.6, 0.9999995}) {
      const double time_s = static_cast<double>(last.whole_seconds()) + fraction;
      EXPECT_EQ(detail::time_axis_label(time_s, 1.0, 600.0), next.substr(11, 8)) << b.name << ", fraction " << fraction;
      EXPECT_EQ(detail::time_axis_label(time_s, 60.0, 3600.0), next.substr(11, 5)) << b.name << ", fraction " << fraction;
      EXPECT_EQ(detail::time_axis_label(time_s, 3600.0, 172800.0), next.substr(5, 5) + " " + next.substr(11, 5))
          << b.name << ", fraction " << fraction;
      EXPECT_EQ(detail::time_axis_label(time_s, 86400.0, 604800.0), next.substr(0, 10)) << b.name << ", fraction " << fraction;
    }
    EXPECT_EQ(detail::time_axis_label(static_cast<double>(last.whole_seconds()), 1.0, 600.0),
              std::string(b.last_second).substr(11, 8));
  }
}

}  // namespace
}  // namespace skytrace::io

namespace skytrace::io {
namespace {

// Several receivers: each gets its own sky plot (with its own sky mask), satellite counts, C/N0 and
// path types, titled with its name; the first receiver's ids stay as with one receiver.
TEST(Report, EveryReceiverHasItsOwnSkyAndCharts) {
  ReportBuilder report;
  for (int k = 0; k <= 60; ++k) {
    const double dt_s = 60.0 * k;
    auto base = sample(dt_s, "G05", 100.0, 40.0, "tracked");
    base.receiver = "BASE";
    report.add(base);
    auto rover = sample(dt_s, "G05", 100.0, 40.0, k < 30 ? "blocked" : "tracked");
    rover.receiver = "ROVR";
    report.add(rover);
    auto rover_e = sample(dt_s, "E11", 200.0, 20.0, "tracked");
    rover_e.receiver = "ROVR";
    report.add(rover_e);
  }
  ReportMeta meta = crossing_meta();
  meta.receiver_sky_masks_deg["ROVR"] = std::vector<double>(36, 25.0);
  const std::string html = report.html(meta);
  for (const char* id : {"skyplot", "satellite-count", "cn0-chart", "path-timeline", "skyplot-ROVR", "satellite-count-ROVR",
                         "cn0-chart-ROVR", "path-timeline-ROVR", "skyplot-ROVR-mask"}) {
    EXPECT_EQ(count_of(html, std::string("id=\"") + id + "\""), 1u) << id;
  }
  EXPECT_NE(html.find("<h2>Sky plot: BASE</h2>"), std::string::npos);
  EXPECT_NE(html.find("<h2>Path type per satellite: ROVR</h2>"), std::string::npos);
  EXPECT_NE(html.find("Receivers BASE, ROVR"), std::string::npos);
  // The rover's blocked G05 is drawn red (blocked) on its own plot only.
  const size_t base_at = html.find("id=\"skyplot\"");
  const size_t rover_at = html.find("id=\"skyplot-ROVR\"");
  const auto tracks_of = [&](size_t from) {
    const size_t begin = html.find("-tracks\"", from);
    return html.substr(begin, html.find("</g>", begin) - begin);
  };
  EXPECT_NE(tracks_of(rover_at).find("#d7191c"), std::string::npos);
  EXPECT_EQ(tracks_of(base_at).find("#d7191c"), std::string::npos);
  // The standalone skyplot.svg is the first receiver's.
  EXPECT_NE(report.sky_plot_svg(meta).find("id=\"skyplot\""), std::string::npos);
  EXPECT_EQ(report.track_points(SatelliteId{GnssSystem::kGalileo, 11}), 0u);  // E11 only on the rover
}

// Solution types per receiver: shares, first fix and first RTK fixed after the start, one run per
// change (so a flickering rover does not grow memory beyond kMaxFixRuns).
TEST(Report, SolutionTypesPerReceiverWithFirstFixes) {
  ReportBuilder report;
  for (int k = 0; k < 100; ++k) {
    report.add_fix("BASE", t0() + k, "3d");
    report.add_fix("ROVR", t0() + k, k < 10 ? "none" : k < 40 ? "rtk_float" : "rtk_fixed");
  }
  ReportMeta meta;
  meta.scenario_name = "pair";
  meta.start = t0();
  meta.end = t0() + 99.0;
  meta.interval_s = 1.0;
  const std::string html = report.html(meta);
  EXPECT_NE(html.find("id=\"solution-types\""), std::string::npos);
  EXPECT_NE(html.find("<th scope=\"row\">ROVR</th><td>100</td><td>60.0 %</td><td>30.0 %</td>"), std::string::npos) << html;
  EXPECT_NE(html.find("<td>10</td><td>40</td></tr>"), std::string::npos);  // first fix, first RTK fixed (s)
  EXPECT_NE(html.find("<th scope=\"row\">BASE</th><td>100</td><td>0.0 %</td>"), std::string::npos);
  EXPECT_NE(html.find("id=\"solution-type\""), std::string::npos);

  ReportBuilder flicker;
  for (size_t k = 0; k < 2 * ReportBuilder::kMaxFixRuns + 10; ++k) {
    flicker.add_fix("X", t0() + static_cast<double>(k), k % 2 == 0 ? "rtk_fixed" : "rtk_float");
  }
  EXPECT_NE(flicker.html(meta).find("X (chart truncated)"), std::string::npos);
  // Without fixes the section is left out.
  EXPECT_EQ(ReportBuilder().html(meta).find("solution-types"), std::string::npos);
}

// The fix against the truth: percentiles from every epoch (histogram bins 2.3 % wide), charts of
// errors, distribution, satellites used and HDOP, one top view per receiver; epochs without a
// position are not compared; points stay bounded however long the run.
TEST(Report, FixErrorsPercentilesChartsAndTopViews) {
  ReportBuilder report(100.0);
  // ROVR drives east at 1 m/s; its horizontal error cycles 0.01, 0.02, ..., 1.00 m (due north),
  // vertical -0.5 m; BASE stands still 3 cm off. The first 5 s ROVR has no fix.
  for (int k = 0; k < 1000; ++k) {
    ReportBuilder::FixError rover;
    rover.north_m = 0.01 * static_cast<double>(k % 100 + 1);
    rover.up_m = -0.5;
    rover.truth_east_m = k;
    rover.fix_east_m = k;
    rover.fix_north_m = rover.north_m;
    rover.satellites_used = 12;
    rover.hdop = 0.8;
    report.add_fix("ROVR", t0() + k, k < 5 ? "none" : "rtk_fixed", k < 5 ? nullptr : &rover);
    ReportBuilder::FixError base;
    base.east_m = 0.03;
    base.fix_east_m = 0.03;
    base.satellites_used = 20;
    base.hdop = 0.6;
    report.add_fix("BASE", t0() + k, "3d", &base);
  }
  ReportMeta meta;
  meta.scenario_name = "pair";
  meta.start = t0();
  meta.end = t0() + 999.0;
  meta.interval_s = 1.0;
  const std::string html = report.html(meta);
  for (const char* id : {"fix-errors", "fix-horizontal-error", "fix-vertical-error", "fix-error-cdf", "fix-satellites-used",
                         "fix-hdop", "fix-top-view-1", "fix-top-view-2"}) {
    EXPECT_NE(html.find(std::string("id=\"") + id + "\""), std::string::npos) << id;
  }
  // ROVR: 995 fixes; errors uniform on 0.01..1.00 m: p50 0.5, p95 0.95 (to the bins' 2.3 %, two
  // significant digits); the maxima exact.
  const std::regex row("<th scope=\"row\">ROVR</th><td>995</td><td>([0-9.]+)</td><td>([0-9.]+)</td><td>1</td>"
                       "<td>([0-9.]+)</td><td>([0-9.]+)</td><td>0.5</td><td>12.0</td><td>0.80</td>");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(html, m, row)) << html.substr(html.find("fix-errors"), 1200);
  EXPECT_NEAR(std::stod(m[1]), 0.50, 0.02);
  EXPECT_NEAR(std::stod(m[2]), 0.95, 0.03);
  EXPECT_NEAR(std::stod(m[3]), 0.50, 0.012);
  EXPECT_NEAR(std::stod(m[4]), 0.50, 0.012);
  EXPECT_NE(html.find("<th scope=\"row\">BASE</th><td>1000</td><td>0.03</td><td>0.03</td><td>0.03</td>"), std::string::npos);
  // Thinned to at most about twice the point budget per receiver, the percentiles still exact.
  ReportBuilder long_run(100.0);
  ReportBuilder::FixError e;
  e.north_m = 1.0;
  for (int k = 0; k < 100000; ++k) long_run.add_fix("X", t0() + k, "3d", &e);
  const std::string long_html = long_run.html(meta);
  const size_t top_view = long_html.find("id=\"fix-top-view-1\"");
  ASSERT_NE(top_view, std::string::npos);
  size_t circles = 0;
  for (size_t at = long_html.find("<circle", top_view); at != std::string::npos; at = long_html.find("<circle", at + 1)) {
    ++circles;
  }
  EXPECT_LE(circles, 205U);
  EXPECT_GE(circles, 100U);
  EXPECT_NE(long_html.find("<td>100000</td><td>1</td><td>1</td><td>1</td>"), std::string::npos);
  // A fix far off the track is counted, not drawn.
  ReportBuilder outlier;
  e.north_m = 0.01;
  for (int k = 0; k < 100; ++k) outlier.add_fix("Y", t0() + k, "3d", &e);
  e.fix_north_m = 5000.0;
  outlier.add_fix("Y", t0() + 100.0, "3d", &e);
  EXPECT_NE(outlier.html(meta).find("1 fixes outside the view"), std::string::npos);
  // Solution types without positions (no truth given): no fix section.
  ReportBuilder types_only;
  types_only.add_fix("Z", t0(), "3d");
  EXPECT_EQ(types_only.html(meta).find("fix-errors"), std::string::npos);
}

}  // namespace
}  // namespace skytrace::io

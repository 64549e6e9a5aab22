// Polygon triangulation and extrusion, and OpenStreetMap worlds through libosmium: building
// footprints (closed ways and multipolygons, assembled by osmium) extruded to their height, trees
// and woods as vegetation volumes, projected on the tangent plane of the origin.
// GCC 12 sees a false string over-read inside libosmium's area builder (inlined from the
// assembler). clang has no such warning.
#pragma GCC diagnostic push
#if !defined(__clang__)
#pragma GCC diagnostic ignored "-Wstringop-overread"
#endif
#include <osmium/area/assembler.hpp>
#include <osmium/area/multipolygon_manager.hpp>
#include <osmium/area/problem_reporter.hpp>
#include <osmium/handler.hpp>
#include <osmium/handler/node_locations_for_ways.hpp>
#include <osmium/index/map/flex_mem.hpp>
#include <osmium/io/any_input.hpp>
#include <osmium/relations/relations_manager.hpp>
#include <osmium/tags/tags_filter.hpp>
#include <osmium/visitor.hpp>
#pragma GCC diagnostic pop

#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "skytrace/core/input_limits.hpp"
#include "skytrace/core/text_file.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::world {

namespace {

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  // Twice the signed area of triangle abc: positive when counter-clockwise.
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

// The input's points concatenated (outer, holes...) and the rings as index lists: repeated
// consecutive points and the closing point dropped, outer counter-clockwise, holes clockwise.
struct PreparedPolygon {
  std::vector<Eigen::Vector2d> points;
  std::vector<std::vector<int>> rings;  // [0] outer
  double eps_area_m2 = 0.0;             // areas below this are zero
  double flat_m = 0.0;                  // a vertex this close to the line of its neighbours is flat
};

std::vector<int> clean_ring(const std::vector<Eigen::Vector2d>& points, int begin, int end) {
  std::vector<int> ring;
  for (int i = begin; i < end; ++i) {
    if (!ring.empty() &&
        points[static_cast<std::size_t>(ring.back())] == points[static_cast<std::size_t>(i)])
      continue;
    ring.push_back(i);
  }
  while (ring.size() > 1 && points[static_cast<std::size_t>(ring.front())] ==
                                points[static_cast<std::size_t>(ring.back())]) {
    ring.pop_back();
  }
  return ring;
}

double ring_area(const std::vector<Eigen::Vector2d>& points, const std::vector<int>& ring) {
  double twice = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const auto& a = points[static_cast<std::size_t>(ring[i])];
    const auto& b = points[static_cast<std::size_t>(ring[(i + 1) % ring.size()])];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * twice;
}

Result<PreparedPolygon> prepare_polygon(const PolygonWithHoles& polygon) {
  PreparedPolygon prepared;
  std::vector<std::pair<int, int>> spans;
  auto append = [&](const Ring2& ring) {
    const int begin = static_cast<int>(prepared.points.size());
    prepared.points.insert(prepared.points.end(), ring.begin(), ring.end());
    spans.emplace_back(begin, static_cast<int>(prepared.points.size()));
  };
  append(polygon.outer);
  for (const auto& hole : polygon.holes) append(hole);
  if (prepared.points.size() > input_limits().max_way_nodes) {
    return make_error(ErrorCode::kInvalidArgument,
                      "polygon: " + std::to_string(prepared.points.size()) + " nodes, more than a footprint may have " +
                          limit_hint(input_limits().max_way_nodes, "SKYTRACE_MAX_WAY_NODES"));
  }
  for (const auto& p : prepared.points) {
    if (!p.allFinite()) return make_error(ErrorCode::kInvalidArgument, "polygon: non-finite point");
  }
  if (polygon.outer.empty())
    return make_error(ErrorCode::kInvalidArgument, "polygon: empty outer ring");
  Eigen::Vector2d low = prepared.points.front();
  Eigen::Vector2d high = low;
  for (const auto& p : prepared.points) {
    low = low.cwiseMin(p);
    high = high.cwiseMax(p);
  }
  const double size_m = std::max((high - low).norm(), 1e-300);
  prepared.eps_area_m2 = 1e-12 * size_m * size_m;
  // Geographic projections bend straight runs of nodes by micrometres: such vertices (and
  // zero-width spikes) are removed when clipping stalls, not left to block every ear.
  prepared.flat_m = 1e-6 * size_m;

  for (std::size_t r = 0; r < spans.size(); ++r) {
    std::vector<int> ring = clean_ring(prepared.points, spans[r].first, spans[r].second);
    const double area = ring.size() >= 3 ? ring_area(prepared.points, ring) : 0.0;
    if (std::abs(area) <= prepared.eps_area_m2) {
      if (r == 0) {
        return make_error(ErrorCode::kInvalidArgument, "polygon: the outer ring has " +
                                                           std::to_string(ring.size()) +
                                                           " distinct points and no area");
      }
      continue;  // a hole without area removes nothing
    }
    const bool want_ccw = r == 0;
    if ((area > 0.0) != want_ccw) std::reverse(ring.begin(), ring.end());
    prepared.rings.push_back(std::move(ring));
  }
  return prepared;
}

// Ear clipping on doubly linked rings of nodes. Holes are joined to the outer ring by bridges
// from their leftmost vertex (Eberly 2002); stalls are handled by removing degenerate vertices,
// cutting local self-intersections and splitting the ring along a valid diagonal (the passes
// popularised by Mapbox's earcut). Orientation: counter-clockwise, interior on the left.
class EarClipper {
 public:
  explicit EarClipper(const PreparedPolygon& prepared) : prepared_(prepared) {}

  Result<std::vector<std::array<int, 3>>> run() {
    int outer = ring(prepared_.rings.front());
    std::vector<int> holes;
    for (std::size_t r = 1; r < prepared_.rings.size(); ++r) {
      const int start = ring(prepared_.rings[r]);
      int leftmost = start;
      int p = start;
      do {
        if (x(p) < x(leftmost) || (x(p) == x(leftmost) && y(p) < y(leftmost))) leftmost = p;
        p = nodes_[static_cast<std::size_t>(p)].next;
      } while (p != start);
      holes.push_back(leftmost);
    }
    std::sort(holes.begin(), holes.end(),
              [&](int a, int b) { return x(a) != x(b) ? x(a) < x(b) : y(a) < y(b); });
    for (std::size_t h = 0; h < holes.size(); ++h) {
      const int bridge = find_bridge(holes[h], outer);
      if (bridge < 0) {
        return make_error(ErrorCode::kInvalidArgument,
                          "polygon: a hole is not inside the outer ring");
      }
      const int reverse = split(bridge, holes[h]);
      filter(reverse, next(reverse));
      outer = filter(bridge, next(bridge));
    }
    clip(outer, 0);
    return std::move(triangles_);
  }

 private:
  struct Node {
    int index = 0;  // into prepared.points (copies made by bridges share it)
    int prev = -1;
    int next = -1;
  };

  const Eigen::Vector2d& at(int n) const {
    return prepared_.points[static_cast<std::size_t>(nodes_[static_cast<std::size_t>(n)].index)];
  }
  double x(int n) const { return at(n).x(); }
  double y(int n) const { return at(n).y(); }
  int next(int n) const { return nodes_[static_cast<std::size_t>(n)].next; }
  int prev(int n) const { return nodes_[static_cast<std::size_t>(n)].prev; }
  int index(int n) const { return nodes_[static_cast<std::size_t>(n)].index; }
  bool same_place(int a, int b) const { return at(a) == at(b); }
  double area(int a, int b, int c) const { return cross2(at(a), at(b), at(c)); }

  int add(int point_index) {
    nodes_.push_back({point_index, -1, -1});
    return static_cast<int>(nodes_.size()) - 1;
  }
  int ring(const std::vector<int>& indices) {
    const int first = static_cast<int>(nodes_.size());
    for (std::size_t k = 0; k < indices.size(); ++k) {
      const int n = add(indices[k]);
      nodes_[static_cast<std::size_t>(n)].prev =
          k == 0 ? first + static_cast<int>(indices.size()) - 1 : n - 1;
      nodes_[static_cast<std::size_t>(n)].next = k + 1 == indices.size() ? first : n + 1;
    }
    return first;
  }
  void remove(int n) {
    nodes_[static_cast<std::size_t>(prev(n))].next = next(n);
    nodes_[static_cast<std::size_t>(next(n))].prev = prev(n);
  }
  // Links a to b with a bridge (two coincident edges); returns the copy of b on the other side.
  int split(int a, int b) {
    const int a2 = add(index(a));
    const int b2 = add(index(b));
    const int an = next(a);
    const int bp = prev(b);
    nodes_[static_cast<std::size_t>(a)].next = b;
    nodes_[static_cast<std::size_t>(b)].prev = a;
    nodes_[static_cast<std::size_t>(a2)].next = an;
    nodes_[static_cast<std::size_t>(an)].prev = a2;
    nodes_[static_cast<std::size_t>(b2)].next = a2;
    nodes_[static_cast<std::size_t>(a2)].prev = b2;
    nodes_[static_cast<std::size_t>(bp)].next = b2;
    nodes_[static_cast<std::size_t>(b2)].prev = bp;
    return b2;
  }
  // Removes repeated and collinear vertices between start and end.
  int filter(int start, int end) {
    int p = start;
    bool again = false;
    do {
      again = false;
      if (next(p) != p &&
          (same_place(p, next(p)) || std::abs(area(prev(p), p, next(p))) <=
                                         prepared_.flat_m * (at(next(p)) - at(prev(p))).norm())) {
        remove(p);
        p = end = prev(p);
        if (p == next(p)) break;
        again = true;
      } else {
        p = next(p);
      }
    } while (again || p != end);
    return end;
  }

  static bool inside_triangle(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                              const Eigen::Vector2d& c, const Eigen::Vector2d& p) {
    return cross2(a, b, p) >= 0.0 && cross2(b, c, p) >= 0.0 && cross2(c, a, p) >= 0.0;
  }
  // The diagonal a-b leaves a into the polygon's interior.
  bool locally_inside(int a, int b) const {
    return area(prev(a), a, next(a)) > 0.0
               ? area(a, b, next(a)) <= 0.0 && area(a, prev(a), b) <= 0.0
               : area(a, b, prev(a)) > 0.0 || area(a, next(a), b) > 0.0;
  }
  // At one place, the corner of m contains the corner of p.
  bool sector_contains(int m, int p) const {
    return area(prev(m), m, prev(p)) > 0.0 && area(next(p), m, next(m)) > 0.0;
  }
  static int sign(double v) { return (v > 0.0) - (v < 0.0); }
  static bool on_segment(const Eigen::Vector2d& p, const Eigen::Vector2d& q,
                         const Eigen::Vector2d& r) {
    return q.x() <= std::max(p.x(), r.x()) && q.x() >= std::min(p.x(), r.x()) &&
           q.y() <= std::max(p.y(), r.y()) && q.y() >= std::min(p.y(), r.y());
  }
  static bool intersects(const Eigen::Vector2d& p1, const Eigen::Vector2d& q1,
                         const Eigen::Vector2d& p2, const Eigen::Vector2d& q2) {
    const int o1 = sign(cross2(p1, q1, p2));
    const int o2 = sign(cross2(p1, q1, q2));
    const int o3 = sign(cross2(p2, q2, p1));
    const int o4 = sign(cross2(p2, q2, q1));
    if (o1 != o2 && o3 != o4) return true;
    return (o1 == 0 && on_segment(p1, p2, q1)) || (o2 == 0 && on_segment(p1, q2, q1)) ||
           (o3 == 0 && on_segment(p2, p1, q2)) || (o4 == 0 && on_segment(p2, q1, q2));
  }
  bool intersects_ring(int a, int b) const {
    int p = a;
    do {
      if (index(p) != index(a) && index(next(p)) != index(a) && index(p) != index(b) &&
          index(next(p)) != index(b) && intersects(at(p), at(next(p)), at(a), at(b))) {
        return true;
      }
      p = next(p);
    } while (p != a);
    return false;
  }
  bool middle_inside(int a, int b) const {
    const Eigen::Vector2d mid = 0.5 * (at(a) + at(b));
    bool inside = false;
    int p = a;
    do {
      const Eigen::Vector2d& u = at(p);
      const Eigen::Vector2d& v = at(next(p));
      if ((u.y() > mid.y()) != (v.y() > mid.y()) && v.y() != u.y() &&
          mid.x() < (v.x() - u.x()) * (mid.y() - u.y()) / (v.y() - u.y()) + u.x()) {
        inside = !inside;
      }
      p = next(p);
    } while (p != a);
    return inside;
  }
  bool valid_diagonal(int a, int b) const {
    return index(next(a)) != index(b) && index(prev(a)) != index(b) && !intersects_ring(a, b) &&
           ((locally_inside(a, b) && locally_inside(b, a) && middle_inside(a, b) &&
             (area(prev(a), a, prev(b)) != 0.0 || area(a, prev(b), b) != 0.0)) ||
            (same_place(a, b) && area(prev(a), a, next(a)) < 0.0 &&
             area(prev(b), b, next(b)) < 0.0));
  }

  // Bridge for the hole vertex h: the nearest outer vertex seen along a ray towards -x.
  int find_bridge(int h, int outer) const {
    const double hx = x(h);
    const double hy = y(h);
    double qx = -std::numeric_limits<double>::infinity();
    int m = -1;
    int p = outer;
    if (same_place(h, p)) return p;
    do {
      if (same_place(h, next(p))) return next(p);
      // Only edges going down (interior on their right, facing the hole) can be hit first.
      if (hy <= y(p) && hy >= y(next(p)) && y(next(p)) != y(p)) {
        const double cross_x = x(p) + (hy - y(p)) * (x(next(p)) - x(p)) / (y(next(p)) - y(p));
        if (cross_x <= hx && cross_x > qx) {
          qx = cross_x;
          m = x(p) < x(next(p)) ? p : next(p);
          if (cross_x == hx) return m;  // the hole touches the edge
        }
      }
      p = next(p);
    } while (p != outer);
    if (m < 0) return -1;
    // Vertices inside the triangle (hole vertex, ray hit, m) would hide m: take the one closest in
    // angle to the ray, and among copies at one place the one whose corner faces the hole.
    const int stop = m;
    const double mx = x(m);
    const double my = y(m);
    double best_tangent = std::numeric_limits<double>::infinity();
    p = m;
    do {
      const Eigen::Vector2d first(hy < my ? hx : qx, hy);
      const Eigen::Vector2d third(hy < my ? qx : hx, hy);
      if (hx >= x(p) && x(p) >= mx && hx != x(p) &&
          inside_triangle(first, Eigen::Vector2d(mx, my), third, at(p))) {
        const double tangent = std::abs(hy - y(p)) / (hx - x(p));
        if (locally_inside(p, h) && (tangent < best_tangent ||
                                     (tangent == best_tangent &&
                                      (x(p) > x(m) || (x(p) == x(m) && sector_contains(m, p)))))) {
          m = p;
          best_tangent = tangent;
        }
      }
      p = next(p);
    } while (p != stop);
    return m;
  }

  // Ear clipping is quadratic on good rings but can go cubic on pathological ones (100,000
  // self-intersecting nodes took minutes): every vertex test counts against a budget, and a ring
  // that spends it is given up as not triangulable.
  static constexpr std::uint64_t kWorkBudget = 300'000'000;
  [[nodiscard]] bool over_budget() const { return work_ > kWorkBudget; }

  bool is_ear(int ear) {
    const int a = prev(ear);
    const int c = next(ear);
    if (area(a, ear, c) <= 0.0) return false;  // reflex or flat
    for (int p = next(c); p != a; p = next(p)) {
      if (++work_ > kWorkBudget) return false;
      // A reflex (or flat) vertex inside the triangle blocks it; copies of its corners do not.
      if (same_place(p, a) || same_place(p, ear) || same_place(p, c)) continue;
      if (inside_triangle(at(a), at(ear), at(c), at(p)) && area(prev(p), p, next(p)) <= 0.0)
        return false;
    }
    return true;
  }

  // Cuts off a - p - p.next - b where edges a-p and p.next-b cross.
  int cure_local_intersections(int start) {
    int p = start;
    do {
      const int a = prev(p);
      const int b = next(next(p));
      if (!same_place(a, b) && intersects(at(a), at(p), at(next(p)), at(b)) &&
          locally_inside(a, b) && locally_inside(b, a)) {
        triangles_.push_back({index(a), index(p), index(b)});
        remove(p);
        remove(next(p));
        p = start = b;
      }
      p = next(p);
    } while (p != start);
    return filter(p, p);
  }

  void split_and_clip(int start, int depth) {
    int a = start;
    do {
      for (int b = next(next(a)); b != prev(a); b = next(b)) {
        work_ += 64;  // valid_diagonal walks the ring
        if (over_budget()) {
          stuck_ = true;
          return;
        }
        if (index(a) != index(b) && valid_diagonal(a, b)) {
          int c = split(a, b);
          a = filter(a, next(a));
          c = filter(c, next(c));
          clip(a, 0, depth + 1);
          clip(c, 0, depth + 1);
          return;
        }
      }
      a = next(a);
    } while (a != start);
    stuck_ = true;  // no ear, no cure, no diagonal: the ring is not a polygon
  }

  void clip(int ear, int pass, int depth = 0) {
    if (depth > 64) {
      stuck_ = true;
      return;
    }
    int stop = ear;
    while (prev(ear) != next(ear)) {
      if (over_budget()) {
        stuck_ = true;
        return;
      }
      const int a = prev(ear);
      const int c = next(ear);
      if (is_ear(ear)) {
        triangles_.push_back({index(a), index(ear), index(c)});
        remove(ear);
        ear = next(c);  // skipping a vertex gives fewer slivers
        stop = ear;
        continue;
      }
      ear = c;
      if (ear == stop) {
        if (pass == 0) {
          clip(filter(ear, ear), 1, depth);
        } else if (pass == 1) {
          clip(cure_local_intersections(filter(ear, ear)), 2, depth);
        } else {
          split_and_clip(ear, depth);
        }
        break;
      }
    }
  }

  const PreparedPolygon& prepared_;
  std::vector<Node> nodes_;
  std::vector<std::array<int, 3>> triangles_;
  bool stuck_ = false;
  std::uint64_t work_ = 0;

 public:
  [[nodiscard]] bool stuck() const { return stuck_; }
  [[nodiscard]] bool spent_budget() const { return over_budget(); }
};

}  // namespace

double signed_area_m2(const Ring2& ring) {
  double twice = 0.0;
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const auto& a = ring[i];
    const auto& b = ring[(i + 1) % ring.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * twice;
}

Result<std::vector<std::array<int, 3>>> triangulate_polygon(const PolygonWithHoles& polygon) {
  auto prepared = prepare_polygon(polygon);
  if (!prepared.ok()) return prepared.error();
  EarClipper clipper(*prepared);
  auto triangles = clipper.run();
  if (triangles.ok() && clipper.stuck()) {
    return make_error(ErrorCode::kInvalidArgument,
                      clipper.spent_budget() ? "polygon: too complex to triangulate within the work limit (self-intersecting?)"
                            : "polygon: cannot triangulate the rings (self-intersecting?)");
  }
  return triangles;
}

Result<TriangleMesh> extrude_polygon(const PolygonWithHoles& polygon, double bottom_m,
                                     double top_m) {
  if (!(top_m > bottom_m) || !std::isfinite(bottom_m) || !std::isfinite(top_m)) {
    return make_error(ErrorCode::kInvalidArgument, "extrusion: the top (" + std::to_string(top_m) +
                                                       " m) must be above the bottom (" +
                                                       std::to_string(bottom_m) + " m)");
  }
  auto prepared = prepare_polygon(polygon);
  if (!prepared.ok()) return prepared.error();
  auto cap = triangulate_polygon(polygon);
  if (!cap.ok()) return cap.error();

  // Vertex i at the bottom, i + n at the top, for every input point (unused ones are harmless).
  TriangleMesh mesh;
  const int n = static_cast<int>(prepared->points.size());
  mesh.vertices_m.reserve(2 * static_cast<std::size_t>(n));
  for (const double z : {bottom_m, top_m}) {
    for (const auto& p : prepared->points) {
      mesh.vertices_m.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()),
                                   static_cast<float>(z));
    }
  }
  // Walls stand on the roof's boundary: the edges of its triangles without a twin (bridges and
  // inner diagonals come in pairs). Boundary edges run counter-clockwise around the solid seen
  // from above (outer ring counter-clockwise, holes clockwise), so (a, b, b') faces outward, and
  // walls follow the roof exactly even where clipping dropped a spike or a flat vertex.
  std::set<std::pair<int, int>> edges;
  for (const auto& t : *cap) {
    for (int k = 0; k < 3; ++k)
      edges.emplace(t[static_cast<std::size_t>(k)], t[static_cast<std::size_t>((k + 1) % 3)]);
  }
  for (const auto& [a, b] : edges) {
    if (edges.count({b, a}) != 0) continue;
    mesh.triangles.emplace_back(a, b, b + n);
    mesh.triangles.emplace_back(a, b + n, a + n);
  }
  for (const auto& t : *cap) {
    mesh.triangles.emplace_back(t[0] + n, t[1] + n, t[2] + n);  // roof, facing up
    mesh.triangles.emplace_back(t[0], t[2], t[1]);              // floor, facing down
  }
  return mesh;
}

Result<double> parse_osm_length_m(std::string_view text) {
  const auto fail = [&]() -> Result<double> {
    return make_error(ErrorCode::kParse,
                      "length '" + std::string(text) +
                          "' not understood (expected e.g. 12, 12 m, 40 ft, 12'6\")");
  };
  std::string s(text);
  std::replace(s.begin(), s.end(), ',', '.');  // "12,5" is common in some regions
  const auto trim = [](std::string& v) {
    const auto first = v.find_first_not_of(" \t");
    const auto last = v.find_last_not_of(" \t");
    v = first == std::string::npos ? std::string() : v.substr(first, last - first + 1);
  };
  trim(s);
  if (s.empty()) return fail();
  const auto number = [](const std::string& v, std::size_t& used) -> std::optional<double> {
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), value);
    if (ec != std::errc() || !std::isfinite(value)) return std::nullopt;
    used = static_cast<std::size_t>(ptr - v.data());
    return value;
  };
  std::size_t used = 0;
  const auto first = number(s, used);
  if (!first || *first < 0.0) return fail();
  std::string unit = s.substr(used);
  trim(unit);
  constexpr double kFootM = 0.3048;
  constexpr double kInchM = 0.0254;
  if (unit.empty() || unit == "m" || unit == "meter" || unit == "meters" || unit == "metre" ||
      unit == "metres") {
    return *first;
  }
  if (unit == "ft" || unit == "feet" || unit == "foot" || unit == "'") return *first * kFootM;
  if (unit.front() == '\'') {  // 12'6"
    std::string rest = unit.substr(1);
    trim(rest);
    if (rest.empty() || rest.back() != '"') return fail();
    rest.pop_back();
    std::size_t used_inches = 0;
    const auto inches = number(rest, used_inches);
    if (!inches || used_inches != rest.size() || *inches < 0.0) return fail();
    return *first * kFootM + *inches * kInchM;
  }
  return fail();
}

// -------------------------------------------------------------------------------------------------
// OpenStreetMap

namespace {

struct LatLonRing {
  std::vector<std::pair<double, double>> points_deg;  // (lat, lon)
};
struct LatLonPolygon {
  LatLonRing outer;
  std::vector<LatLonRing> holes;
};

struct OsmArea {
  std::string name;  // "way/1", "relation/2"
  std::map<std::string, std::string> tags;
  std::vector<LatLonPolygon> polygons;
  std::string rejected;  // "way/1 (...): osmium rejected it (why)" when built from the raw outline
};

struct OsmTree {
  std::string name;
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  std::map<std::string, std::string> tags;
};

// First problem osmium's assembler reports for each object, to explain skipped areas.
class ProblemCollector final : public osmium::area::ProblemReporter {
 public:
  std::map<std::string, std::string> problems;

  void report_ring_not_closed(const osmium::NodeRef& nr, const osmium::Way* /*way*/) override {
    note("ring not closed at node " + std::to_string(nr.ref()));
  }
  void report_intersection(osmium::object_id_type way1_id, osmium::Location /*s1*/,
                           osmium::Location /*e1*/, osmium::object_id_type way2_id,
                           osmium::Location /*s2*/, osmium::Location /*e2*/,
                           osmium::Location /*at*/) override {
    note("segments of ways " + std::to_string(way1_id) + " and " + std::to_string(way2_id) +
         " intersect");
  }
  void report_duplicate_segment(const osmium::NodeRef& nr1, const osmium::NodeRef& nr2) override {
    note("duplicate segment between nodes " + std::to_string(nr1.ref()) + " and " +
         std::to_string(nr2.ref()));
  }
  void report_invalid_location(osmium::object_id_type way_id,
                               osmium::object_id_type node_id) override {
    note("node " + std::to_string(node_id) + " of way " + std::to_string(way_id) +
         " is missing from the file");
  }
  void report_role_should_be_outer(osmium::object_id_type way_id, osmium::Location /*s*/,
                                   osmium::Location /*e*/) override {
    note("way " + std::to_string(way_id) + " should have role outer");
  }

 private:
  void note(const std::string& message) {
    const std::string key =
        std::string(m_object_type == osmium::item_type::relation ? "relation/" : "way/") +
        std::to_string(m_object_id);
    problems.emplace(key, message);  // keeps the first
  }
};

std::map<std::string, std::string> tags_of(const osmium::TagList& tags) {
  std::map<std::string, std::string> out;
  for (const auto& tag : tags) out.emplace(tag.key(), tag.value());
  return out;
}

bool is_building(const std::map<std::string, std::string>& tags) {
  const auto it = tags.find("building");
  return it != tags.end() && it->second != "no";
}

bool is_wood(const std::map<std::string, std::string>& tags) {
  const auto natural = tags.find("natural");
  const auto landuse = tags.find("landuse");
  return (natural != tags.end() && natural->second == "wood") ||
         (landuse != tags.end() && landuse->second == "forest");
}

struct Collector : osmium::handler::Handler {
  std::vector<OsmArea> areas;
  std::vector<OsmTree> trees;
  // Candidates that should give an area, to name those that did not.
  std::map<std::string, std::string> candidates;  // name -> description
  // Closed candidate ways as drawn, for those osmium's assembler rejects (a self-touching outline
  // is still an obstacle).
  std::map<std::string, OsmArea> raw_ways;
  osmium::Box data_box;
  bool load_woods = true;
  bool load_trees = true;

  void node(const osmium::Node& node) {
    if (!node.location().valid()) return;
    const char* natural = node.tags()["natural"];
    if (load_trees && natural != nullptr && std::string_view(natural) == "tree") {
      trees.push_back({"node/" + std::to_string(node.id()), node.location().lat(),
                       node.location().lon(), tags_of(node.tags())});
      data_box.extend(node.location());
    }
  }
  void way(const osmium::Way& way) {
    const auto tags = tags_of(way.tags());
    if (is_building(tags) || (load_woods && is_wood(tags))) {
      const std::string name = "way/" + std::to_string(way.id());
      const bool closed = way.nodes().size() >= 4 && way.is_closed();
      candidates.emplace(
          name, (is_building(tags) ? "building=" + tags.at("building") : std::string("wood")) +
                    ", " + std::to_string(way.nodes().size()) + " node(s), " +
                    (closed ? "closed" : "not a closed ring"));
      if (!closed) return;
      OsmArea raw;
      raw.name = name;
      raw.tags = tags;
      raw.polygons.emplace_back();
      for (const auto& nr : way.nodes()) {
        if (!nr.location().valid()) return;
        raw.polygons.back().outer.points_deg.emplace_back(nr.location().lat(), nr.location().lon());
      }
      for (const auto& nr : way.nodes()) data_box.extend(nr.location());
      raw_ways.emplace(name, std::move(raw));
    }
  }
  void relation(const osmium::Relation& relation) {
    const auto tags = tags_of(relation.tags());
    const auto type = tags.find("type");
    if (type == tags.end() || (type->second != "multipolygon" && type->second != "boundary"))
      return;
    if (is_building(tags) || (load_woods && is_wood(tags))) {
      candidates.emplace(
          "relation/" + std::to_string(relation.id()),
          (is_building(tags) ? "building=" + tags.at("building") : std::string("wood")) +
              " multipolygon of " + std::to_string(relation.members().size()) + " member(s)");
    }
  }
  void area(const osmium::Area& area) {
    OsmArea out;
    out.name = std::string(area.from_way() ? "way/" : "relation/") + std::to_string(area.orig_id());
    out.tags = tags_of(area.tags());
    if (!is_building(out.tags) && !(load_woods && is_wood(out.tags))) return;
    for (const auto& outer : area.outer_rings()) {
      LatLonPolygon polygon;
      for (const auto& nr : outer) {
        polygon.outer.points_deg.emplace_back(nr.location().lat(), nr.location().lon());
        data_box.extend(nr.location());
      }
      for (const auto& inner : area.inner_rings(outer)) {
        LatLonRing hole;
        for (const auto& nr : inner)
          hole.points_deg.emplace_back(nr.location().lat(), nr.location().lon());
        polygon.holes.push_back(std::move(hole));
      }
      out.polygons.push_back(std::move(polygon));
    }
    if (!out.polygons.empty()) areas.push_back(std::move(out));
  }
};

std::optional<double> tag_length(const std::map<std::string, std::string>& tags,
                                 const std::string& key, const std::string& object,
                                 std::vector<std::string>& warnings) {
  const auto it = tags.find(key);
  if (it == tags.end()) return std::nullopt;
  auto value = parse_osm_length_m(it->second);
  if (!value.ok()) {
    warnings.push_back(object + ": tag " + key + "=" + it->second +
                       " ignored: " + value.error().message);
    return std::nullopt;
  }
  return *value;
}

std::optional<double> tag_number(const std::map<std::string, std::string>& tags,
                                 const std::string& key, const std::string& object,
                                 std::vector<std::string>& warnings) {
  const auto it = tags.find(key);
  if (it == tags.end()) return std::nullopt;
  double value = 0.0;
  const std::string& text = it->second;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(value) ||
      value < 0.0) {
    warnings.push_back(object + ": tag " + key + "=" + text +
                       " ignored: not a non-negative number");
    return std::nullopt;
  }
  return value;
}

}  // namespace

namespace {

// libosmium's XML coordinate parser scales the digits by the exponent in a 64-bit integer without
// an overflow check (osmium/osm/location.hpp; fuzzing found lat="48.135E5744"): a lat or lon
// attribute with more digits than a coordinate has, or an exponent beyond 10^3, is refused here,
// naming its line, before libosmium reads the file.
bool plausible_coordinate_text(std::string_view value) {
  constexpr int kMaxDigits = 18;      // 7 decimals in OSM, 15-17 from converters
  constexpr int kMaxExponent = 3;     // 1.8e2 is still a longitude
  constexpr int kMinExponent = -30;   // tiny values near the equator or the meridian
  int digits = 0;
  size_t i = 0;
  if (i < value.size() && (value[i] == '-' || value[i] == '+')) ++i;
  for (; i < value.size() && (std::isdigit(static_cast<unsigned char>(value[i])) || value[i] == '.'); ++i) {
    if (value[i] != '.') ++digits;
  }
  if (digits > kMaxDigits) return false;
  if (i < value.size() && (value[i] == 'e' || value[i] == 'E')) {
    ++i;
    const bool negative = i < value.size() && value[i] == '-';
    if (i < value.size() && (value[i] == '-' || value[i] == '+')) ++i;
    int exponent = 0;
    for (; i < value.size() && std::isdigit(static_cast<unsigned char>(value[i])); ++i) {
      exponent = std::min(exponent * 10 + (value[i] - '0'), 1000);
    }
    if (negative ? -exponent < kMinExponent : exponent > kMaxExponent) return false;
  }
  return true;  // anything else malformed is libosmium's to report
}

// XML extracts (plain or gzip) are read into memory once: checked here, then parsed by libosmium
// from the buffer in both of its passes. PBF and O5M carry integers; bz2 XML is left to libosmium.
bool read_as_xml_text(const std::filesystem::path& path) {
  const std::string name = path.filename().string();
  return name.ends_with(".osm") || name.ends_with(".osm.gz") || name.ends_with(".xml");
}

Status check_osm_xml_coordinates(const std::filesystem::path& path, const std::string& t) {
  for (const char* attribute : {"lat=", "lon="}) {
    for (size_t at = t.find(attribute); at != std::string::npos; at = t.find(attribute, at + 4)) {
      const bool quoted = at + 4 < t.size() && (t[at + 4] == '"' || t[at + 4] == '\'');
      const bool whole_name = at == 0 || std::isspace(static_cast<unsigned char>(t[at - 1]));
      if (!quoted || !whole_name) continue;
      const size_t end = t.find(t[at + 4], at + 5);
      if (end == std::string::npos) break;
      const std::string_view value(t.data() + at + 5, end - at - 5);
      if (!plausible_coordinate_text(value)) {
        const auto line = std::count(t.begin(), t.begin() + static_cast<std::ptrdiff_t>(at), '\n') + 1;
        return make_error(ErrorCode::kParse, path.string() + ":" + std::to_string(line) + ": " +
                                                 std::string(attribute, 3) + "=\"" + std::string(value.substr(0, 40)) +
                                                 "\" is no coordinate (at most 18 digits and an exponent up to 3)");
      }
    }
  }
  return Ok{};
}

}  // namespace

Result<WorldModel> load_osm_world(const std::filesystem::path& path,
                                  const OsmLoadOptions& options) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return make_error(ErrorCode::kIo, path.string() + ": OSM file not found");
  }
  if (!(options.level_height_m > 0.0) || !(options.default_building_height_m > 0.0) ||
      !(options.tree_height_m > 0.0) || !(options.tree_crown_diameter_m > 0.0) ||
      !(options.wood_height_m > 0.0) ||
      !(options.tree_crown_base_fraction >= 0.0 && options.tree_crown_base_fraction < 1.0)) {
    return make_error(
        ErrorCode::kInvalidArgument,
        path.string() +
            ": OSM options: heights and diameters must be positive, crown base fraction in [0, 1)");
  }

  std::optional<std::string> xml_text;
  if (read_as_xml_text(path)) {
    auto text = read_text_file(path);
    if (!text) return text.error();
    if (auto st = check_osm_xml_coordinates(path, *text); !st) return st.error();
    xml_text = std::move(*text);
  }
  Collector collector;
  collector.load_woods = options.load_woods;
  collector.load_trees = options.load_trees;
  ProblemCollector problems;
  osmium::Box header_box;
  try {
    // From memory, libosmium neither reads the file again nor zeroes a fresh read buffer per block.
    const osmium::io::File input = xml_text ? osmium::io::File{xml_text->data(), xml_text->size(), "osm"}
                                            : osmium::io::File{path.string()};
    osmium::TagsFilter filter{false};
    filter.add_rule(false, osmium::TagMatcher{"building", "no"});
    filter.add_rule(true, osmium::TagMatcher{"building"});
    if (options.load_woods) {
      filter.add_rule(true, osmium::TagMatcher{"natural", "wood"});
      filter.add_rule(true, osmium::TagMatcher{"landuse", "forest"});
    }
    osmium::area::Assembler::config_type config;
    config.problem_reporter = &problems;
    osmium::area::MultipolygonManager<osmium::area::Assembler> manager{config, filter};
    osmium::relations::read_relations(input, manager);

    using Index = osmium::index::map::FlexMem<osmium::unsigned_object_id_type, osmium::Location>;
    Index index;
    osmium::handler::NodeLocationsForWays<Index> locations{index};
    locations.ignore_errors();  // ways with nodes outside the extract: the assembler reports them
    osmium::io::Reader reader{input};
    header_box = reader.header().box();
    osmium::apply(reader, locations, collector,
                  manager.handler([&collector](osmium::memory::Buffer&& buffer) {
                    osmium::apply(buffer, collector);
                  }));
    reader.close();
  } catch (const std::exception& e) {
    return make_error(ErrorCode::kParse, path.string() + ": cannot read the OSM data: " + e.what());
  }

  WorldModel world;
  world.name = path.filename().string();
  for (const auto& area : collector.areas) collector.candidates.erase(area.name);
  for (const auto& [name, description] : collector.candidates) {
    const auto problem = problems.problems.find(name);
    const std::string reason =
        problem != problems.problems.end()
            ? problem->second
            : std::string("no area could be built (members missing from the extract?)");
    if (auto raw = collector.raw_ways.find(name); raw != collector.raw_ways.end()) {
      raw->second.rejected = name + " (" + description + "): osmium rejected it (" + reason + ")";
      collector.areas.push_back(std::move(raw->second));
      continue;
    }
    world.warnings.push_back(name + " (" + description + ") skipped: " + reason);
  }

  // Origin: given, else the file's bounds, else the data.
  Geodetic origin;
  if (options.origin) {
    origin = *options.origin;
  } else {
    const osmium::Box& box = header_box.valid() ? header_box : collector.data_box;
    if (!box.valid()) {
      return make_error(ErrorCode::kNotFound,
                        path.string() + ": no buildings, trees or woods in the OSM data");
    }
    origin.latitude_deg = 0.5 * (box.bottom_left().lat() + box.top_right().lat());
    origin.longitude_deg = 0.5 * (box.bottom_left().lon() + box.top_right().lon());
    origin.height_m = options.ground_height_m;
  }
  world.geo_origin = GeoOrigin{origin, 0.0};
  const GeographicLib::LocalCartesian projection(origin.latitude_deg, origin.longitude_deg,
                                                 origin.height_m);
  const double ground_z_m = options.ground_height_m - origin.height_m;
  // East and north on the tangent plane; the curvature drop (8 cm at 1 km) is left out so that
  // walls stay vertical in the world frame.
  const auto project = [&](const LatLonRing& ring) {
    Ring2 out;
    out.reserve(ring.points_deg.size());
    for (const auto& [lat, lon] : ring.points_deg) {
      double x = 0.0;
      double y = 0.0;
      double z = 0.0;
      projection.Forward(lat, lon, options.ground_height_m, x, y, z);
      out.emplace_back(x, y);
    }
    return out;
  };

  std::size_t buildings = 0;
  for (const auto& area : collector.areas) {
    const bool building = is_building(area.tags);
    std::vector<std::string>& warnings = world.warnings;
    double bottom_m = 0.0;
    double top_m = 0.0;
    Material material;
    if (building) {
      const auto height = tag_length(area.tags, "height", area.name, warnings);
      const auto levels = tag_number(area.tags, "building:levels", area.name, warnings);
      if (height) {
        top_m = *height;
      } else if (levels) {
        double roof_m = 0.0;
        if (const auto roof_height = tag_length(area.tags, "roof:height", area.name, warnings)) {
          roof_m = *roof_height;
        } else if (const auto roof_levels =
                       tag_number(area.tags, "roof:levels", area.name, warnings)) {
          roof_m = *roof_levels * options.level_height_m;
        }
        top_m = *levels * options.level_height_m + roof_m;
      } else {
        top_m = options.default_building_height_m;
      }
      if (const auto min_height = tag_length(area.tags, "min_height", area.name, warnings)) {
        bottom_m = *min_height;
      } else if (const auto min_level =
                     tag_number(area.tags, "building:min_level", area.name, warnings)) {
        bottom_m = *min_level * options.level_height_m;
      }
      material = options.building_material;
      if (const auto it = area.tags.find("building:material"); it != area.tags.end()) {
        if (auto parsed = parse_material_class(it->second); parsed.ok()) {
          material.material_class = *parsed;
        } else {
          warnings.push_back(area.name + ": building:material=" + it->second +
                             " ignored: " + parsed.error().message);
        }
      }
    } else {
      top_m = tag_length(area.tags, "height", area.name, warnings).value_or(options.wood_height_m);
      material = Material{MaterialClass::kVegetation, options.vegetation_attenuation_db_per_m};
    }
    std::vector<std::string> names = {area.name};
    if (const auto it = area.tags.find("name"); it != area.tags.end()) names.push_back(it->second);
    const MaterialRule* rule = match_material_rule(options.material_rules, names);
    if (rule != nullptr) material = rule->material;
    if (!(top_m > bottom_m)) {
      warnings.push_back(area.name + " skipped: top " + std::to_string(top_m) +
                         " m is not above its base " + std::to_string(bottom_m) + " m");
      continue;
    }

    WorldObject object;
    object.name = area.name;
    object.material = material;
    object.kind = rule != nullptr && rule->kind ? *rule->kind
                  : material.is_vegetation()    ? ObjectKind::kTree
                  : building                    ? ObjectKind::kBuilding
                                                : ObjectKind::kOther;
    bool failed = false;
    for (const auto& polygon : area.polygons) {
      PolygonWithHoles projected;
      projected.outer = project(polygon.outer);
      for (const auto& hole : polygon.holes) projected.holes.push_back(project(hole));
      auto prism = extrude_polygon(projected, ground_z_m + bottom_m, ground_z_m + top_m);
      if (!prism.ok()) {
        warnings.push_back(area.rejected.empty()
                               ? area.name + " skipped: " + prism.error().message
                               : area.rejected + " and its outline as drawn fails too (" +
                                     prism.error().message + "): skipped");
        failed = true;
        break;
      }
      const int base = static_cast<int>(object.mesh.vertices_m.size());
      object.mesh.vertices_m.insert(object.mesh.vertices_m.end(), prism->vertices_m.begin(),
                                    prism->vertices_m.end());
      for (const auto& t : prism->triangles)
        object.mesh.triangles.push_back(t + Eigen::Vector3i::Constant(base));
    }
    if (failed) continue;
    if (!area.rejected.empty())
      warnings.push_back(area.rejected + "; built from its outline as drawn");
    centre_mesh_horizontally(object);
    if (object.kind == ObjectKind::kBuilding) ++buildings;
    world.objects.push_back(std::move(object));
  }

  for (const auto& tree : collector.trees) {
    std::vector<std::string>& warnings = world.warnings;
    const double height_m =
        tag_length(tree.tags, "height", tree.name, warnings).value_or(options.tree_height_m);
    const double diameter_m = tag_length(tree.tags, "diameter_crown", tree.name, warnings)
                                  .value_or(options.tree_crown_diameter_m);
    if (!(height_m > 0.0) || !(diameter_m > 0.0)) {
      warnings.push_back(tree.name + " skipped: zero height or crown diameter");
      continue;
    }
    const double crown_bottom_m = options.tree_crown_base_fraction * height_m;
    const double crown_height_m = height_m - crown_bottom_m;
    WorldObject object;
    object.name = tree.name;
    object.kind = ObjectKind::kTree;
    object.material = Material{MaterialClass::kVegetation, options.vegetation_attenuation_db_per_m};
    if (const MaterialRule* rule = match_material_rule(options.material_rules, {tree.name});
        rule != nullptr) {
      object.material = rule->material;
      if (rule->kind) object.kind = *rule->kind;
    }
    // Trees are many: a coarser tessellation than SDF primitives keeps the scene small.
    object.mesh =
        options.tree_crown_shape == TreeCrownShape::kEllipsoid
            ? make_ellipsoid(
                  Eigen::Vector3d(0.5 * diameter_m, 0.5 * diameter_m, 0.5 * crown_height_m), 16, 8)
            : make_cylinder(0.5 * diameter_m, crown_height_m, 16);
    double x = 0.0;
    double y = 0.0;
    double z = 0.0;
    projection.Forward(tree.lat_deg, tree.lon_deg, options.ground_height_m, x, y, z);
    object.pose = Eigen::Translation3d(x, y, ground_z_m + crown_bottom_m + 0.5 * crown_height_m);
    world.objects.push_back(std::move(object));
  }

  if (buildings == 0 && !options.allow_no_buildings) {
    std::ostringstream message;
    message << path.string()
            << ": no buildings in the OSM data (no building=* way or multipolygon could be built";
    if (!world.warnings.empty()) message << "; " << world.warnings.front();
    message << ")";
    return make_error(ErrorCode::kNotFound, message.str());
  }
  return world;
}

}  // namespace skytrace::world

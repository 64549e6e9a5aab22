// EmbreeScene: the only file of skytrace that sees Embree.
//
// Layout. The main top-level scene holds every object, opaque and vegetation. Without movable
// objects the static objects are triangle geometries directly in it (vertices already in the world
// frame). With movable objects the static geometries go into one child scene instanced once, and
// every movable object is a scene of its own with an instance in the top level: a new pose then
// rebuilds only the top-level structure over a handful of instances, not the static BVH.
//
// Vegetation. A closed convex volume (a tree crown as a convex hull: the common case) is one Embree
// user primitive, its bounding box; a ray entering one only notes the volume, and the part
// of the ray inside is then computed exactly from the volume's face planes (ConvexVolume). Other
// vegetation volumes are triangles with a filter that records each crossing and rejects it, so the
// traversal goes on.
//
// One Embree query per ray: rtcIntersect1 for trace() (the closest opaque hit, every vegetation
// crossing before it), rtcOccluded1 for trace_line_of_sight() (any opaque hit ends the ray; a free
// ray meets all its vegetation on the way).
//
// Whether the origin lies inside a vegetation volume traced as triangles is decided once per batch
// (all rays of a batch share the origin) in a second scene of those volumes only: the number of
// crossings of a closed volume along a ray to infinity is odd from inside, whatever the mesh's
// winding; three rays vote. Each ray's pieces inside a volume then follow from that state and its
// crossings before the first opaque hit. Convex volumes need no vote: their exact chord starts
// inside.
#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <tuple>
#include <unordered_map>
#include <type_traits>
#include <utility>

#include "skytrace/world/scene.hpp"

namespace skytrace::world {

namespace {

constexpr unsigned kInvalidId = RTC_INVALID_GEOMETRY_ID;
constexpr std::uint32_t kNoObject = std::numeric_limits<std::uint32_t>::max();
constexpr double kInfinity = std::numeric_limits<double>::infinity();
// Two crossings of one volume closer than this along the ray and facing the same way are one
// crossing reported twice (a ray through an edge shared by two triangles).
constexpr double kDuplicateCrossingM = 1e-4;

struct VegetationCrossing {
  unsigned instance = kInvalidId;  // instance id in the top-level scene, or invalid
  unsigned geometry = kInvalidId;  // geometry id in the scene holding the triangles
  unsigned triangle = kInvalidId;
  std::uint32_t object = kNoObject;
  double t_m = 0.0;
  bool facing_ray = false;  // the triangle's winding normal points against the ray
};

// The filter and the convex-volume callbacks receive a pointer to the RTCIntersectContext given to
// the query; this struct starts with it so they reach the current ray's records (on the caller's
// stack).
struct VegetationContext {
  RTCIntersectContext base;
  std::vector<VegetationCrossing>* crossings;       // triangle crossings of non-convex volumes
  std::vector<std::uint32_t>* convex_candidates;  // convex volumes whose bounds the ray entered
  // Occlusion queries: the opaque hit that ended the ray (any on the path, not the nearest).
  unsigned blocker_instance = kInvalidId;
  unsigned blocker_geometry = kInvalidId;
};
static_assert(std::is_standard_layout_v<VegetationContext>);

void record_vegetation_crossing(const RTCFilterFunctionNArguments* args) {
  const auto* context = reinterpret_cast<const VegetationContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    // Normal and direction are both in the object space of the hit geometry.
    const float normal_dot_direction =
        RTCHitN_Ng_x(args->hit, args->N, i) * RTCRayN_dir_x(args->ray, args->N, i) +
        RTCHitN_Ng_y(args->hit, args->N, i) * RTCRayN_dir_y(args->ray, args->N, i) +
        RTCHitN_Ng_z(args->hit, args->N, i) * RTCRayN_dir_z(args->ray, args->N, i);
    VegetationCrossing crossing;
    crossing.instance = RTCHitN_instID(args->hit, args->N, i, 0);
    crossing.geometry = RTCHitN_geomID(args->hit, args->N, i);
    crossing.triangle = RTCHitN_primID(args->hit, args->N, i);
    crossing.t_m = RTCRayN_tfar(args->ray, args->N, i);  // rigid instances keep distances
    crossing.facing_ray = normal_dot_direction < 0.0F;
    context->crossings->push_back(crossing);
    args->valid[i] = 0;  // rejected: traversal goes on to the next crossing
  }
}

// Occlusion queries: notes which opaque object ended the ray (the hit is accepted).
void record_blocker(const RTCFilterFunctionNArguments* args) {
  auto* context = reinterpret_cast<VegetationContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    context->blocker_instance = RTCHitN_instID(args->hit, args->N, i, 0);
    context->blocker_geometry = RTCHitN_geomID(args->hit, args->N, i);
  }
}

// The plane of a triangle in double precision (object frame): normal . x = offset_m. One compact
// record per triangle, so that refining a hit costs one memory access, not four.
struct TrianglePlane {
  Eigen::Vector3d normal;  // unit, along the winding's normal
  double offset_m = 0.0;
};

// Convex vegetation volumes (tree crowns as convex hulls, the common case) are not traced as
// triangles: each is one Embree user primitive (its bounding box) and the part of a ray inside it
// is computed exactly, in double, from its face planes. A ray through a tree then costs one box
// test and one callback instead of a triangle traversal with a filter call per face it crosses.
// (Boxes per horizontal slab of a crown hug it better but cost more in the BVH than they save.)
struct ConvexVolumes {
  std::vector<std::uint32_t> object_of_primitive;  // primID -> index in objects
  std::vector<Eigen::AlignedBox3d> bounds_m;       // per primID, frame of the Embree geometry
};

void convex_volume_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* volumes = static_cast<const ConvexVolumes*>(args->geometryUserPtr);
  const Eigen::AlignedBox3d& box = volumes->bounds_m[args->primID];
  // Rounded outwards by a margin, so that float traversal never misses a ray grazing the volume.
  const double margin_m = 1e-4 * std::max(1.0, box.diagonal().norm());
  args->bounds_o->lower_x = static_cast<float>(box.min().x() - margin_m);
  args->bounds_o->lower_y = static_cast<float>(box.min().y() - margin_m);
  args->bounds_o->lower_z = static_cast<float>(box.min().z() - margin_m);
  args->bounds_o->upper_x = static_cast<float>(box.max().x() + margin_m);
  args->bounds_o->upper_y = static_cast<float>(box.max().y() + margin_m);
  args->bounds_o->upper_z = static_cast<float>(box.max().z() + margin_m);
}

// Both queries only note the volume as a candidate; it never ends the ray (vegetation does not
// block). The exact part inside is computed later, once per volume and ray.
void note_convex_candidate(const int* valid, unsigned count, RTCIntersectContext* base, const void* user, unsigned primitive) {
  bool any_valid = false;
  for (unsigned i = 0; i < count; ++i) any_valid = any_valid || valid[i] != 0;
  if (!any_valid) return;
  const auto* context = reinterpret_cast<const VegetationContext*>(base);
  context->convex_candidates->push_back(static_cast<const ConvexVolumes*>(user)->object_of_primitive[primitive]);
}
void convex_volume_intersect(const RTCIntersectFunctionNArguments* args) {
  note_convex_candidate(args->valid, args->N, args->context, args->geometryUserPtr, args->primID);
}
void convex_volume_occluded(const RTCOccludedFunctionNArguments* args) {
  note_convex_candidate(args->valid, args->N, args->context, args->geometryUserPtr, args->primID);
}

// The face planes of a closed convex mesh, facing outwards (normal . x <= offset_m inside), or
// nothing when the mesh is not closed (every edge in exactly two triangles) or not convex (a vertex
// outside a face plane) or flat. Coplanar faces give one plane.
std::vector<TrianglePlane> convex_volume_planes(const std::vector<Eigen::Vector3d>& vertices_m,
                                                const std::vector<Eigen::Vector3i>& triangles,
                                                const std::vector<TrianglePlane>& triangle_planes) {
  if (triangles.size() < 4 || vertices_m.empty()) return {};
  std::vector<std::pair<int, int>> edges;
  edges.reserve(3 * triangles.size());
  for (const auto& tri : triangles) {
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k];
      const int b = tri[(k + 1) % 3];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size(); i += 2) {
    const bool pair = i + 1 < edges.size() && edges[i] == edges[i + 1];
    const bool triple = i + 2 < edges.size() && edges[i] == edges[i + 2];
    if (!pair || triple) return {};
  }
  Eigen::Vector3d centroid_m = Eigen::Vector3d::Zero();
  Eigen::AlignedBox3d box;
  for (const auto& v : vertices_m) {
    centroid_m += v;
    box.extend(v);
  }
  centroid_m /= static_cast<double>(vertices_m.size());
  // Vertices are float in the world model: faces of a hull of float points bend by ~1e-7 relative.
  const double tolerance_m = 1e-6 * std::max(1.0, box.diagonal().norm());
  std::vector<TrianglePlane> planes;
  planes.reserve(triangle_planes.size());
  for (TrianglePlane plane : triangle_planes) {
    const double centroid_side_m = plane.normal.dot(centroid_m) - plane.offset_m;
    if (std::abs(centroid_side_m) <= tolerance_m) return {};  // flat, or the centroid on a face
    if (centroid_side_m > 0.0) {
      plane.normal = -plane.normal;
      plane.offset_m = -plane.offset_m;
    }
    for (const auto& v : vertices_m) {
      if (plane.normal.dot(v) - plane.offset_m > tolerance_m) return {};
    }
    planes.push_back(plane);
  }
  std::sort(planes.begin(), planes.end(), [](const TrianglePlane& x, const TrianglePlane& y) {
    return std::tie(x.normal.x(), x.normal.y(), x.normal.z(), x.offset_m) <
           std::tie(y.normal.x(), y.normal.y(), y.normal.z(), y.offset_m);
  });
  std::vector<TrianglePlane> unique;
  for (const auto& plane : planes) {
    if (!unique.empty() && unique.back().normal.dot(plane.normal) > 1.0 - 1e-12 &&
        std::abs(unique.back().offset_m - plane.offset_m) <= tolerance_m) {
      continue;
    }
    unique.push_back(plane);
  }
  return unique;
}

// Eight floats processed at once (GCC vector extensions: SSE pairs by default, one AVX register
// in the x86-64-v3 (AVX2, FMA) and x86-64-v4 (AVX-512, 32 registers) clones of the kernel below).
using FloatLanes = float __attribute__((vector_size(32)));
using IntLanes = std::int32_t __attribute__((vector_size(32)));
// The same in memory with the alignment of a float: loads are unaligned (as cheap on current
// CPUs), so that standard containers can hold them.
using StoredFloatLanes = float __attribute__((vector_size(32), aligned(4)));
constexpr int kLanes = 8;

// Eight face planes of a convex volume in float, relative to the volume's centre (so that float
// keeps ~1e-6 m over a tree-sized volume). Padding planes (zero normal, offset 1) never bind.
struct PlaneLanes {
  StoredFloatLanes nx, ny, nz, offset_m;
};

// Lanes permuted by constant indices: GCC's __builtin_shuffle takes them as a vector, clang's
// __builtin_shufflevector as arguments (GCC keeps the form its kernel was tuned with).
#if defined(__clang__)
#define SKYTRACE_PERMUTE_LANES(v, a, b, c, d, e, f, g, h) __builtin_shufflevector(v, v, a, b, c, d, e, f, g, h)
#else
#define SKYTRACE_PERMUTE_LANES(v, a, b, c, d, e, f, g, h) __builtin_shuffle(v, IntLanes{a, b, c, d, e, f, g, h})
#endif
// clang checks the vector calling convention even of always-inlined calls, and refuses it in the
// clone without AVX; a reference has none. GCC keeps the by-value form.
#if defined(__clang__)
using FloatLanesArg = const FloatLanes&;
using IntLanesArg = const IntLanes&;
#else
using FloatLanesArg = FloatLanes;
using IntLanesArg = IntLanes;
#endif
// Lane-wise maximum and minimum, and the same over all lanes (every lane holds the result).
// Always inlined into the kernel's clones, so the vector calling convention (-Wpsabi) never applies.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpragmas"
#pragma GCC diagnostic ignored "-Wunknown-warning-option"
#pragma GCC diagnostic ignored "-Wpsabi"
// Butterflies over the eight lanes: after the three steps every lane holds the result.
[[gnu::always_inline]] inline float max_over_lanes(FloatLanesArg lanes) {
  FloatLanes v = lanes;
  FloatLanes o = SKYTRACE_PERMUTE_LANES(v, 4, 5, 6, 7, 0, 1, 2, 3);
  v = v > o ? v : o;
  o = SKYTRACE_PERMUTE_LANES(v, 2, 3, 0, 1, 6, 7, 4, 5);
  v = v > o ? v : o;
  o = SKYTRACE_PERMUTE_LANES(v, 1, 0, 3, 2, 5, 4, 7, 6);
  return std::max(v[0], o[0]);
}
[[gnu::always_inline]] inline float min_over_lanes(FloatLanesArg lanes) {
  FloatLanes v = lanes;
  FloatLanes o = SKYTRACE_PERMUTE_LANES(v, 4, 5, 6, 7, 0, 1, 2, 3);
  v = v < o ? v : o;
  o = SKYTRACE_PERMUTE_LANES(v, 2, 3, 0, 1, 6, 7, 4, 5);
  v = v < o ? v : o;
  o = SKYTRACE_PERMUTE_LANES(v, 1, 0, 3, 2, 5, 4, 7, 6);
  return std::min(v[0], o[0]);
}
[[gnu::always_inline]] inline std::int32_t min_over_lanes(IntLanesArg lanes) {
  IntLanes v = lanes;
  IntLanes o = SKYTRACE_PERMUTE_LANES(v, 4, 5, 6, 7, 0, 1, 2, 3);
  v = v < o ? v : o;
  o = SKYTRACE_PERMUTE_LANES(v, 2, 3, 0, 1, 6, 7, 4, 5);
  v = v < o ? v : o;
  o = SKYTRACE_PERMUTE_LANES(v, 1, 0, 3, 2, 5, 4, 7, 6);
  return std::min(v[0], o[0]);
}
// A ray parallel to a face outside it, or entering after it has left: a miss.
[[gnu::always_inline]] inline bool misses(FloatLanesArg best_entry, FloatLanesArg best_exit,
                                          IntLanesArg parallel_outside) {
  return min_over_lanes(parallel_outside) != 0 || max_over_lanes(best_entry) > min_over_lanes(best_exit);
}
#pragma GCC diagnostic pop
#undef SKYTRACE_PERMUTE_LANES

// The faces that bound the part of a ray inside a convex volume: the entering face with the
// largest distance and the leaving face with the smallest (-1: none), found in float over all
// faces at once; false when the ray misses the volume (then the faces are not set). Branch-free
// over the faces, with one early test: the many rays that only graze a volume's bounding box are
// known to miss after the first faces, which are spread over all directions.
__attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default"))) bool binding_faces(
    const PlaneLanes* chunks, std::size_t chunk_count, const float origin_m[3], const float direction[3],
    int& entry_face, int& exit_face) {
  constexpr float kFar = 3.0e38F;
  const FloatLanes ox = FloatLanes{} + origin_m[0];
  const FloatLanes oy = FloatLanes{} + origin_m[1];
  const FloatLanes oz = FloatLanes{} + origin_m[2];
  const FloatLanes dx = FloatLanes{} + direction[0];
  const FloatLanes dy = FloatLanes{} + direction[1];
  const FloatLanes dz = FloatLanes{} + direction[2];
  FloatLanes best_entry = FloatLanes{} - kFar;
  FloatLanes best_exit = FloatLanes{} + kFar;
  IntLanes entry_index = IntLanes{} - 1;
  IntLanes exit_index = IntLanes{} - 1;
  IntLanes parallel_outside = IntLanes{};
  IntLanes index = {0, 1, 2, 3, 4, 5, 6, 7};
  // The first faces alone bound a coarse polytope around the volume (ConvexVolume::from_faces).
  constexpr std::size_t kCoarseChunks = 2;
  for (std::size_t c = 0; c < chunk_count; ++c, index += kLanes) {
    if (c == kCoarseChunks && misses(best_entry, best_exit, parallel_outside)) return false;
    const FloatLanes nx = chunks[c].nx;
    const FloatLanes ny = chunks[c].ny;
    const FloatLanes nz = chunks[c].nz;
    const FloatLanes offset_m = chunks[c].offset_m;
    const FloatLanes inside_m = offset_m - (nx * ox + ny * oy + nz * oz);  // >= 0: inner side
    const FloatLanes rate = nx * dx + ny * dy + nz * dz;
    const FloatLanes t_m = inside_m / rate;  // +-inf or NaN where rate == 0, masked out below
    const IntLanes better_entry = (rate < 0.0F) & (t_m > best_entry);
    const IntLanes better_exit = (rate > 0.0F) & (t_m < best_exit);
    best_entry = better_entry ? t_m : best_entry;
    entry_index = better_entry ? index : entry_index;
    best_exit = better_exit ? t_m : best_exit;
    exit_index = better_exit ? index : exit_index;
    parallel_outside |= (rate == 0.0F) & (inside_m < 0.0F);  // all bits set where true
  }
  if (misses(best_entry, best_exit, parallel_outside)) return false;
  // The lowest face index among the lanes holding the extreme distance.
  constexpr std::int32_t kNone = std::numeric_limits<std::int32_t>::max();
  const FloatLanes entry_m = FloatLanes{} + max_over_lanes(best_entry);
  const FloatLanes exit_m = FloatLanes{} + min_over_lanes(best_exit);
  const std::int32_t entry = min_over_lanes(((entry_index >= 0) & (best_entry == entry_m)) ? entry_index : kNone);
  const std::int32_t exit = min_over_lanes(((exit_index >= 0) & (best_exit == exit_m)) ? exit_index : kNone);
  entry_face = entry == kNone ? -1 : entry;
  exit_face = exit == kNone ? -1 : exit;
  return true;
}

// Where a ray enters a box (negative from inside), infinity when it misses it.
double box_entry_m(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) {
  constexpr double kMiss = std::numeric_limits<double>::infinity();
  double entry_m = -kMiss;
  double exit_m = kMiss;
  for (int k = 0; k < 3; ++k) {
    if (direction[k] == 0.0) {
      if (origin[k] < box.min()[k] || origin[k] > box.max()[k]) return kMiss;
      continue;
    }
    double near_m = (box.min()[k] - origin[k]) / direction[k];
    double far_m = (box.max()[k] - origin[k]) / direction[k];
    if (near_m > far_m) std::swap(near_m, far_m);
    entry_m = std::max(entry_m, near_m);
    exit_m = std::min(exit_m, far_m);
  }
  return entry_m <= exit_m ? entry_m : kMiss;
}

// A convex vegetation volume: its outward face planes (normal . x <= offset_m inside) in double,
// the same in float lanes relative to its centre, and its bounding box (frame of its geometry:
// world for static objects, object for movable ones).
struct ConvexVolume {
  std::vector<TrianglePlane> faces;
  std::vector<PlaneLanes> lanes;
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();
  Eigen::AlignedBox3d bounds_m;

  [[nodiscard]] bool empty() const { return faces.empty(); }

  static ConvexVolume from_faces(std::vector<TrianglePlane> faces, const Eigen::AlignedBox3d& bounds_m) {
    ConvexVolume volume;
    // Farthest-point order on the sphere of normals: each next face is the one whose normal is
    // farthest from all faces before it, so any first few faces bound the volume from all sides.
    for (std::size_t next = 1; next < faces.size(); ++next) {
      std::size_t best = next;
      double best_closeness = std::numeric_limits<double>::infinity();
      for (std::size_t candidate = next; candidate < faces.size(); ++candidate) {
        double closeness = -1.0;
        for (std::size_t chosen = 0; chosen < next; ++chosen) {
          closeness = std::max(closeness, faces[candidate].normal.dot(faces[chosen].normal));
        }
        if (closeness < best_closeness) {
          best_closeness = closeness;
          best = candidate;
        }
      }
      std::swap(faces[next], faces[best]);
    }
    volume.faces = std::move(faces);
    volume.bounds_m = bounds_m;
    volume.centre_m = bounds_m.center();
    const std::size_t chunks = (volume.faces.size() + kLanes - 1) / kLanes;
    volume.lanes.resize(chunks);
    for (std::size_t c = 0; c < chunks; ++c) {
      PlaneLanes& lanes = volume.lanes[c];
      for (int k = 0; k < kLanes; ++k) {
        const std::size_t face = c * kLanes + static_cast<std::size_t>(k);
        if (face < volume.faces.size()) {
          const TrianglePlane& plane = volume.faces[face];
          lanes.nx[k] = static_cast<float>(plane.normal.x());
          lanes.ny[k] = static_cast<float>(plane.normal.y());
          lanes.nz[k] = static_cast<float>(plane.normal.z());
          lanes.offset_m[k] = static_cast<float>(plane.offset_m - plane.normal.dot(volume.centre_m));
        } else {
          lanes.nx[k] = lanes.ny[k] = lanes.nz[k] = 0.0F;
          lanes.offset_m[k] = 1.0F;
        }
      }
    }
    return volume;
  }

  // The part [entry_m, exit_m] of the line origin + t direction inside the volume (frame of the
  // volume); false when the line misses it. Entry is negative when the origin is inside. The
  // binding faces are found in float, their distances computed in double.
  bool chord(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double& entry_m, double& exit_m) const {
    const Eigen::Vector3d relative_m = origin - centre_m;
    const float origin_f[3] = {static_cast<float>(relative_m.x()), static_cast<float>(relative_m.y()),
                               static_cast<float>(relative_m.z())};
    const float direction_f[3] = {static_cast<float>(direction.x()), static_cast<float>(direction.y()),
                                  static_cast<float>(direction.z())};
    int entry_face = -1;
    int exit_face = -1;
    if (!binding_faces(lanes.data(), lanes.size(), origin_f, direction_f, entry_face, exit_face)) return false;
    auto distance_m = [&](int face) {
      const TrianglePlane& plane = faces[static_cast<std::size_t>(face)];
      return (plane.offset_m - plane.normal.dot(origin)) / plane.normal.dot(direction);
    };
    entry_m = entry_face >= 0 ? distance_m(entry_face) : -std::numeric_limits<double>::infinity();
    exit_m = exit_face >= 0 ? distance_m(exit_face) : std::numeric_limits<double>::infinity();
    return entry_m <= exit_m;
  }
};

// The convex volumes of the meshes of a world, one per distinct mesh (Gazebo worlds place the same
// tree model many times). Meshes that are not closed and convex get nullptr.
class ConvexShapes {
 public:
  std::shared_ptr<const ConvexVolume> shape_of(const TriangleMesh& mesh) {
    std::size_t key = mesh.vertices_m.size() * 1000003U + mesh.triangles.size();
    for (const auto& v : mesh.vertices_m) key = key * 31U + std::hash<float>{}(v.x() + 3.0F * v.y() + 7.0F * v.z());
    auto& bucket = shapes_[key];
    for (const auto& [known, volume] : bucket) {
      if (same_mesh(*known, mesh)) return volume;
    }
    std::vector<Eigen::Vector3d> vertices_m;
    vertices_m.reserve(mesh.vertices_m.size());
    for (const auto& v : mesh.vertices_m) vertices_m.push_back(v.cast<double>());
    std::vector<Eigen::Vector3i> triangles;
    std::vector<TrianglePlane> planes;
    Eigen::AlignedBox3d bounds_m;
    for (const auto& v : vertices_m) bounds_m.extend(v);
    for (const auto& tri : mesh.triangles) {
      const Eigen::Vector3d& p0 = vertices_m[static_cast<std::size_t>(tri[0])];
      const Eigen::Vector3d& p1 = vertices_m[static_cast<std::size_t>(tri[1])];
      const Eigen::Vector3d& p2 = vertices_m[static_cast<std::size_t>(tri[2])];
      if (triangle_is_degenerate(p0, p1, p2)) continue;
      triangles.push_back(tri);
      const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0).normalized();
      planes.push_back(TrianglePlane{normal, normal.dot(p0)});
    }
    auto faces = convex_volume_planes(vertices_m, triangles, planes);
    std::shared_ptr<const ConvexVolume> volume;
    if (!faces.empty()) volume = std::make_shared<const ConvexVolume>(ConvexVolume::from_faces(std::move(faces), bounds_m));
    bucket.emplace_back(&mesh, volume);
    return volume;
  }

 private:
  static bool same_mesh(const TriangleMesh& a, const TriangleMesh& b) {
    if (a.vertices_m.size() != b.vertices_m.size() || a.triangles.size() != b.triangles.size()) return false;
    for (std::size_t i = 0; i < a.vertices_m.size(); ++i) {
      if (a.vertices_m[i] != b.vertices_m[i]) return false;
    }
    for (std::size_t i = 0; i < a.triangles.size(); ++i) {
      if (a.triangles[i] != b.triangles[i]) return false;
    }
    return true;
  }
  std::unordered_map<std::size_t, std::vector<std::pair<const TriangleMesh*, std::shared_ptr<const ConvexVolume>>>> shapes_;
};

struct SceneObject {
  std::string name;
  Material material;
  bool is_static = true;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  // World frame for static objects (pose applied once), object frame for movable ones; only kept
  // until Embree has its own copy.
  std::vector<Eigen::Vector3d> vertices_m;
  std::vector<Eigen::Vector3i> triangles;  // non-degenerate only; the index is Embree's primID
  std::size_t triangle_count = 0;
  std::vector<TrianglePlane> planes;  // per Embree primID
  // A convex vegetation volume, traced as a user primitive (ConvexVolumes), not as triangles:
  // its shape in the frame of the world model's mesh (shared by all objects with the same mesh, so
  // that a forest of one tree model keeps one set of faces in cache), the transform into that frame,
  // and its bounding box in the frame of the Embree geometry. nullptr otherwise.
  std::shared_ptr<const ConvexVolume> volume;
  Eigen::Isometry3d volume_from_world = Eigen::Isometry3d::Identity();
  Eigen::AlignedBox3d volume_bounds_m;  // of its user primitive
  std::unique_ptr<ConvexVolumes> own_volume;  // movable convex volumes: their user geometry's data
  RTCGeometry geometry = nullptr;     // during the build only
  RTCScene own_scene = nullptr;       // movable objects: their scene, instanced in the layers
};

void set_instance_transform(RTCGeometry instance, const Eigen::Isometry3d& pose) {
  float column_major[12];
  const Eigen::Matrix<double, 3, 4> m = pose.matrix().topRows<3>();
  for (int col = 0; col < 4; ++col) {
    for (int row = 0; row < 3; ++row) column_major[col * 3 + row] = static_cast<float>(m(row, col));
  }
  rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, column_major);
}

std::string device_error_text(RTCError code) {
  switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "unknown error";
  }
}

// Unit direction of a ray; false for a non-finite or zero direction.
inline bool unit_direction(const Eigen::Vector3d& direction, Eigen::Vector3d& unit) {
  if (!direction.allFinite()) return false;
  // Callers mostly pass unit vectors already: no square root and division for those.
  const double squared_norm = direction.squaredNorm();
  if (std::abs(squared_norm - 1.0) <= 4.0 * std::numeric_limits<double>::epsilon()) {
    unit = direction;
    return true;
  }
  const double norm = std::sqrt(squared_norm);
  if (!(norm > 0.0) || !std::isfinite(norm)) return false;
  unit = direction / norm;
  return true;
}

void init_ray(RTCRayHit& ray_hit, const Eigen::Vector3f& origin, const Eigen::Vector3d& direction) {
  ray_hit.ray.org_x = origin.x();
  ray_hit.ray.org_y = origin.y();
  ray_hit.ray.org_z = origin.z();
  ray_hit.ray.tnear = 0.0F;
  ray_hit.ray.dir_x = static_cast<float>(direction.x());
  ray_hit.ray.dir_y = static_cast<float>(direction.y());
  ray_hit.ray.dir_z = static_cast<float>(direction.z());
  ray_hit.ray.time = 0.0F;
  ray_hit.ray.tfar = std::numeric_limits<float>::infinity();
  ray_hit.ray.mask = 0xFFFFFFFFU;
  ray_hit.ray.id = 0;
  ray_hit.ray.flags = 0;
  ray_hit.hit.geomID = kInvalidId;
  ray_hit.hit.primID = kInvalidId;
  ray_hit.hit.instID[0] = kInvalidId;
}

// One top-level scene and how its ids lead back to world objects.
struct Layer {
  RTCScene top = nullptr;
  RTCScene static_scene = nullptr;        // the static child scene when the layer has movables
  unsigned static_instance = kInvalidId;  // its instance id in `top`
  std::vector<std::uint32_t> object_of_static_geometry;  // geometry id -> index in objects
  std::vector<std::uint32_t> object_of_instance;         // top-level instance id -> index in objects
  std::vector<unsigned> instance_of_object;              // index in objects -> instance id
  bool empty = true;

  Layer() = default;
  Layer(const Layer&) = delete;
  Layer& operator=(const Layer&) = delete;
  ~Layer() {
    if (static_scene != nullptr) rtcReleaseScene(static_scene);
    if (top != nullptr) rtcReleaseScene(top);
  }

  [[nodiscard]] std::uint32_t object_index(unsigned instance, unsigned geometry) const {
    if (instance == kInvalidId || instance == static_instance) return object_of_static_geometry[geometry];
    return object_of_instance[instance];
  }
};

void map_id(std::vector<std::uint32_t>& table, unsigned id, std::size_t object) {
  if (table.size() <= id) table.resize(static_cast<std::size_t>(id) + 1, kNoObject);
  table[id] = static_cast<std::uint32_t>(object);
}

// Crossing directions of the per-batch test of the origin inside vegetation: up and two skewed
// directions (unlikely to run along a modelled edge), unit vectors.
const std::array<Eigen::Vector3d, 3> kInsideTestDirections = {
    Eigen::Vector3d(0.0, 0.0, 1.0), Eigen::Vector3d(0.5773502691896258, 0.4082482904638631, 0.7071067811865475),
    Eigen::Vector3d(-0.6123724356957945, -0.3535533905932738, 0.7071067811865476)};

// Owns the device; declared first in Impl so that it is released after the scenes.
struct DeviceHandle {
  RTCDevice device = nullptr;
  DeviceHandle() = default;
  DeviceHandle(const DeviceHandle&) = delete;
  DeviceHandle& operator=(const DeviceHandle&) = delete;
  ~DeviceHandle() {
    if (device != nullptr) rtcReleaseDevice(device);
  }
};

}  // namespace

struct EmbreeScene::Impl {
  // What one batch of queries keeps on the stack: the recording context and what it records.
  struct QueryState {
    Eigen::Vector3f origin_f = Eigen::Vector3f::Zero();
    std::vector<VegetationCrossing> crossings;
    std::vector<std::uint32_t> convex_candidates;
    std::vector<std::uint32_t> around;  // vegetation volumes (traced as triangles) around the origin
    VegetationContext context{};
  };
  template <typename Answer>
  std::vector<RayOutcome> for_each_ray(const Eigen::Vector3d& origin_m, const std::vector<Eigen::Vector3d>& directions,
                                       Answer answer) const;
  // The recording context of a query, ready for its rays (whatever their origin).
  void start_query(QueryState& state) const;
  // The line-of-sight answer for one valid ray (unit direction) from origin_m, state.origin_f and
  // state.around being that origin's.
  void answer_line_of_sight(QueryState& state, const Eigen::Vector3d& origin_m, const Eigen::Vector3d& direction,
                            RayOutcome& outcome) const;

  DeviceHandle device_handle;  // first: released after everything else
  RTCDevice device = nullptr;
  Layer main;
  Layer vegetation;  // vegetation traced as triangles only, for the test of the origin inside a volume
  ConvexVolumes static_volumes;  // static convex vegetation volumes (one user geometry in `main`)
  bool has_vegetation = false;
  std::vector<SceneObject> objects;
  SceneStats stats;
  EmbreeSceneOptions options;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    for (auto& object : objects) {
      if (object.own_scene != nullptr) rtcReleaseScene(object.own_scene);
    }
  }

  Status check_device(const std::string& step) const {
    const RTCError code = rtcGetDeviceError(device);
    if (code == RTC_ERROR_NONE) return Ok{};
    return make_error(ErrorCode::kInvalidArgument, "Embree failed while " + step + ": " + device_error_text(code));
  }

  RTCScene new_scene(bool top_with_instances) const {
    RTCScene scene = rtcNewScene(device);
    // Robust traversal: watertight edges, so rays never slip between two triangles of a wall.
    rtcSetSceneFlags(scene, top_with_instances ? RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_DYNAMIC : RTC_SCENE_FLAG_ROBUST);
    if (top_with_instances) rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_LOW);
    return scene;
  }

  // The committed user geometry of convex volumes (one primitive each).
  RTCGeometry new_convex_geometry(ConvexVolumes& volumes) const {
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry, static_cast<unsigned>(volumes.object_of_primitive.size()));
    rtcSetGeometryUserData(geometry, &volumes);
    rtcSetGeometryBoundsFunction(geometry, convex_volume_bounds, &volumes);
    rtcSetGeometryIntersectFunction(geometry, convex_volume_intersect);
    rtcSetGeometryOccludedFunction(geometry, convex_volume_occluded);
    rtcCommitGeometry(geometry);
    return geometry;
  }

  // The committed Embree geometry of an object (world frame for static objects), and for a movable
  // object its own committed scene. Static convex volumes share one user geometry (made in build).
  void make_geometry(SceneObject& object, std::uint32_t index) const {
    if (object.volume != nullptr) {
      if (object.is_static) return;
      object.own_volume = std::make_unique<ConvexVolumes>();
      object.own_volume->object_of_primitive = {index};
      object.own_volume->bounds_m = {object.volume_bounds_m};
      object.geometry = new_convex_geometry(*object.own_volume);
      object.own_scene = new_scene(false);
      rtcAttachGeometry(object.own_scene, object.geometry);
      rtcCommitScene(object.own_scene);
      return;
    }
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), object.vertices_m.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), object.triangles.size()));
    if (vertices != nullptr && indices != nullptr) {  // otherwise reported by check_device
      for (std::size_t i = 0; i < object.vertices_m.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
          vertices[3 * i + static_cast<std::size_t>(k)] = static_cast<float>(object.vertices_m[i][k]);
        }
      }
      for (std::size_t i = 0; i < object.triangles.size(); ++i) {
        for (int k = 0; k < 3; ++k) {
          indices[3 * i + static_cast<std::size_t>(k)] = static_cast<unsigned>(object.triangles[i][k]);
        }
      }
    }
    if (object.material.is_vegetation()) {
      rtcSetGeometryIntersectFilterFunction(geometry, record_vegetation_crossing);
      rtcSetGeometryOccludedFilterFunction(geometry, record_vegetation_crossing);
    } else {
      rtcSetGeometryOccludedFilterFunction(geometry, record_blocker);
    }
    rtcCommitGeometry(geometry);
    object.geometry = geometry;
    if (!object.is_static) {
      object.own_scene = new_scene(false);
      rtcAttachGeometry(object.own_scene, geometry);
      rtcCommitScene(object.own_scene);
    }
  }

  RTCGeometry new_instance(RTCScene child, const Eigen::Isometry3d& pose) const {
    RTCGeometry instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(instance, child);
    rtcSetGeometryTimeStepCount(instance, 1);
    set_instance_transform(instance, pose);
    rtcCommitGeometry(instance);
    return instance;
  }

  // Builds a layer of the objects for which `wanted` is true (their geometries already made).
  template <typename Wanted>
  // `static_convex`: the shared user geometry of the static convex volumes, or nullptr.
  void build_layer(Layer& layer, Wanted wanted, RTCGeometry static_convex) const {
    bool has_movable = false;
    layer.empty = static_convex == nullptr;
    for (const auto& object : objects) {
      if (object.triangle_count == 0 || !wanted(object)) continue;
      layer.empty = false;
      has_movable = has_movable || !object.is_static;
    }
    layer.instance_of_object.assign(objects.size(), kInvalidId);
    layer.top = new_scene(has_movable);
    RTCScene static_target = layer.top;
    if (has_movable) {
      layer.static_scene = new_scene(false);
      static_target = layer.static_scene;
    }
    if (static_convex != nullptr) rtcAttachGeometry(static_target, static_convex);
    for (std::size_t index = 0; index < objects.size(); ++index) {
      const SceneObject& object = objects[index];
      if (object.triangle_count == 0 || !wanted(object)) continue;
      if (object.is_static && object.volume != nullptr) continue;  // in static_convex
      if (object.is_static) {
        map_id(layer.object_of_static_geometry, rtcAttachGeometry(static_target, object.geometry), index);
        continue;
      }
      RTCGeometry instance = new_instance(object.own_scene, object.pose);
      layer.instance_of_object[index] = rtcAttachGeometry(layer.top, instance);
      rtcReleaseGeometry(instance);
      map_id(layer.object_of_instance, layer.instance_of_object[index], index);
    }
    if (layer.static_scene != nullptr) {
      rtcCommitScene(layer.static_scene);
      RTCGeometry instance = new_instance(layer.static_scene, Eigen::Isometry3d::Identity());
      layer.static_instance = rtcAttachGeometry(layer.top, instance);
      rtcReleaseGeometry(instance);
    }
    rtcCommitScene(layer.top);
  }

  // The distance to a triangle hit by Embree recomputed in double precision on the triangle's plane,
  // and the triangle's unit normal turned towards the ray origin. Embree's float ray (origin and
  // direction rounded to ~6e-8) misses the double one by up to 2e-4 m at grazing incidence 100 m
  // away; the plane gives ~1e-10 m.
  static double refine_hit(const SceneObject& object, unsigned triangle, const Eigen::Vector3d& origin,
                           const Eigen::Vector3d& direction, double embree_t_m, Eigen::Vector3d& normal) {
    const TrianglePlane& plane = object.planes[triangle];
    Eigen::Vector3d n = plane.normal;
    double offset_m = plane.offset_m;
    if (!object.is_static) {
      n = object.pose.linear() * n;
      offset_m += n.dot(object.pose.translation());
    }
    const double cos_incidence = n.dot(direction);
    normal = cos_incidence > 0.0 ? Eigen::Vector3d(-n) : n;
    // A ray grazing the plane keeps Embree's distance (the plane is then ill-conditioned).
    if (std::abs(cos_incidence) <= 1e-6) return embree_t_m;
    const double refined_m = (offset_m - n.dot(origin)) / cos_incidence;
    const bool consistent = std::abs(refined_m - embree_t_m) <= 1e-3 * std::max(1.0, embree_t_m);
    return std::isfinite(refined_m) && refined_m >= 0.0 && consistent ? refined_m : embree_t_m;
  }

  // Fills the opaque part of the outcome from Embree's closest hit.
  void describe_blocking(const RTCRayHit& ray_hit, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                         RayOutcome& outcome) const {
    const SceneObject& object = objects[main.object_index(ray_hit.hit.instID[0], ray_hit.hit.geomID)];
    Eigen::Vector3d normal;
    const double distance_m =
        refine_hit(object, ray_hit.hit.primID, origin, direction, static_cast<double>(ray_hit.ray.tfar), normal);
    outcome.blocked = true;
    outcome.blocking_distance_m = distance_m;
    outcome.blocking_object = object.name;
    outcome.blocking_material = object.material.material_class;
    outcome.blocking_point_m = origin + distance_m * direction;
    outcome.blocking_normal = normal;
  }

  // Sorts the crossings by object and distance (refined), and merges the duplicates a ray through
  // an edge shared by two triangles produces. Returns the number kept (at the front).
  std::size_t sort_crossings(const Layer& layer, std::vector<VegetationCrossing>& crossings,
                             const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    Eigen::Vector3d normal;
    for (auto& crossing : crossings) {
      crossing.object = layer.object_index(crossing.instance, crossing.geometry);
      crossing.t_m = refine_hit(objects[crossing.object], crossing.triangle, origin, direction, crossing.t_m, normal);
    }
    std::sort(crossings.begin(), crossings.end(), [](const VegetationCrossing& x, const VegetationCrossing& y) {
      return x.object != y.object ? x.object < y.object : x.t_m < y.t_m;
    });
    std::size_t kept = 0;
    for (std::size_t i = 0; i < crossings.size(); ++i) {
      if (kept > 0) {
        const VegetationCrossing& last = crossings[kept - 1];
        if (last.object == crossings[i].object && crossings[i].t_m - last.t_m <= kDuplicateCrossingM &&
            last.facing_ray == crossings[i].facing_ray) {
          continue;
        }
      }
      crossings[kept++] = crossings[i];
    }
    return kept;
  }

  // The vegetation objects that contain `origin` (sorted indices): an odd number of crossings to
  // infinity along at least two of three directions.
  std::vector<std::uint32_t> vegetation_around(const Eigen::Vector3d& origin) const {
    std::vector<std::uint32_t> inside;
    if (vegetation.empty) return inside;
    std::vector<VegetationCrossing> crossings;
    std::vector<std::uint32_t> no_convex_volumes;  // none in this layer
    VegetationContext context{};
    rtcInitIntersectContext(&context.base);
    context.crossings = &crossings;
    context.convex_candidates = &no_convex_volumes;
    std::vector<std::pair<std::uint32_t, int>> votes;  // object, number of rays with odd crossings
    const Eigen::Vector3f origin_f = origin.cast<float>();
    for (const auto& direction : kInsideTestDirections) {
      crossings.clear();
      RTCRayHit ray_hit;
      init_ray(ray_hit, origin_f, direction);
      rtcIntersect1(vegetation.top, &context.base, &ray_hit);
      const std::size_t kept = sort_crossings(vegetation, crossings, origin, direction);
      for (std::size_t begin = 0; begin < kept;) {
        std::size_t end = begin;
        while (end < kept && crossings[end].object == crossings[begin].object) ++end;
        if ((end - begin) % 2 == 1) {
          auto it = std::find_if(votes.begin(), votes.end(), [&](const auto& v) { return v.first == crossings[begin].object; });
          if (it == votes.end()) {
            votes.emplace_back(crossings[begin].object, 1);
          } else {
            ++it->second;
          }
        }
        begin = end;
      }
    }
    for (const auto& [object, count] : votes) {
      if (count >= 2) inside.push_back(object);
    }
    std::sort(inside.begin(), inside.end());
    return inside;
  }

  // The part of a ray inside a convex volume before stop_m (m).
  double convex_path_m(const SceneObject& object, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                       double stop_m) const {
    const Eigen::Vector3d volume_origin = object.volume_from_world * origin;
    const Eigen::Vector3d volume_direction = object.volume_from_world.linear() * direction;
    // Closest-hit queries meet crowns beyond the opaque hit before they find it: a crown whose
    // bounding box the ray enters only after the hit is skipped without its faces.
    if (std::isfinite(stop_m) && box_entry_m(object.volume->bounds_m, volume_origin, volume_direction) >= stop_m) {
      return 0.0;
    }
    double entry_m = 0.0;
    double exit_m = 0.0;
    if (!object.volume->chord(volume_origin, volume_direction, entry_m, exit_m)) return 0.0;
    return std::max(0.0, std::min(exit_m, stop_m) - std::max(entry_m, 0.0));
  }

  // Adds the vegetation met by one ray before `stop_m` (the first opaque hit, or infinity), from
  // its crossings of volumes traced as triangles, the volumes of those around the origin, and the
  // convex volumes whose bounds it entered.
  void add_vegetation(std::vector<VegetationCrossing>& crossings, const std::vector<std::uint32_t>& around,
                      std::vector<std::uint32_t>& convex_candidates, const Eigen::Vector3d& origin,
                      const Eigen::Vector3d& direction, double stop_m, RayOutcome& outcome) const {
    if (crossings.empty() && around.empty() && convex_candidates.empty()) return;  // most rays
    if (!convex_candidates.empty()) {
      // A volume may be noted more than once by one traversal (Embree may split references).
      std::sort(convex_candidates.begin(), convex_candidates.end());
      convex_candidates.erase(std::unique(convex_candidates.begin(), convex_candidates.end()), convex_candidates.end());
      for (const std::uint32_t index : convex_candidates) {
        const double length_m = convex_path_m(objects[index], origin, direction, stop_m);
        outcome.vegetation_path_m += length_m;
        outcome.vegetation_attenuation_db += length_m * objects[index].material.attenuation_db_per_m;
      }
    }
    if (crossings.empty() && around.empty()) return;
    // Crossings found before the traversal met the closest opaque hit may lie beyond it.
    std::erase_if(crossings, [&](const VegetationCrossing& c) { return !(c.t_m <= stop_m * (1.0 + 1e-6) + 1e-6); });
    const std::size_t kept = sort_crossings(main, crossings, origin, direction);
    auto add = [&](std::uint32_t object, double length_m) {
      outcome.vegetation_path_m += length_m;
      outcome.vegetation_attenuation_db += length_m * objects[object].material.attenuation_db_per_m;
    };
    std::size_t begin = 0;
    std::size_t next_around = 0;
    // Volumes around the origin that this ray never leaves before stop_m.
    auto add_untouched_around = [&](std::uint32_t below) {
      for (; next_around < around.size() && around[next_around] < below; ++next_around) {
        if (std::isfinite(stop_m)) add(around[next_around], stop_m);
      }
    };
    while (begin < kept) {
      const std::uint32_t object = crossings[begin].object;
      std::size_t end = begin;
      while (end < kept && crossings[end].object == object) ++end;
      add_untouched_around(object);
      bool inside = next_around < around.size() && around[next_around] == object;
      if (inside) ++next_around;
      double entry_m = 0.0;
      double length_m = 0.0;
      for (std::size_t i = begin; i < end; ++i) {
        const double t_m = std::min(crossings[i].t_m, stop_m);
        if (inside) length_m += std::max(0.0, t_m - entry_m);
        entry_m = t_m;
        inside = !inside;
      }
      // Still inside at the opaque hit (a trunk or a wall within the crown).
      if (inside && std::isfinite(stop_m)) length_m += std::max(0.0, stop_m - entry_m);
      add(object, length_m);
      begin = end;
    }
    add_untouched_around(kNoObject);
  }
};

EmbreeScene::EmbreeScene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
EmbreeScene::~EmbreeScene() = default;

Result<std::unique_ptr<EmbreeScene>> EmbreeScene::build(const WorldModel& world, const EmbreeSceneOptions& options) {
  if (auto status = validate_world_for_scene(world); !status.ok()) return status.error();
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->device = impl->device_handle.device = rtcNewDevice(nullptr);
  if (impl->device == nullptr) {
    return make_error(ErrorCode::kUnsupported, "Embree device could not be created: " +
                                                   device_error_text(rtcGetDeviceError(nullptr)));
  }
  impl->objects.reserve(world.objects.size());
  ConvexShapes convex_shapes;
  for (const auto& source : world.objects) {
    SceneObject object;
    object.name = source.name;
    object.material = source.material;
    object.is_static = source.is_static;
    object.pose = source.pose;
    object.vertices_m.reserve(source.mesh.vertices_m.size());
    for (const auto& v : source.mesh.vertices_m) object.vertices_m.push_back(v.cast<double>());
    if (object.is_static) {
      for (auto& v : object.vertices_m) v = object.pose * v;
    }
    object.triangles.reserve(source.mesh.triangles.size());
    for (const auto& tri : source.mesh.triangles) {
      const Eigen::Vector3d& p0 = object.vertices_m[static_cast<std::size_t>(tri[0])];
      const Eigen::Vector3d& p1 = object.vertices_m[static_cast<std::size_t>(tri[1])];
      const Eigen::Vector3d& p2 = object.vertices_m[static_cast<std::size_t>(tri[2])];
      // Judged in the world frame, as BruteForceScene does.
      const bool degenerate = object.is_static
                                  ? triangle_is_degenerate(p0, p1, p2)
                                  : triangle_is_degenerate(object.pose * p0, object.pose * p1, object.pose * p2);
      if (degenerate) {
        ++impl->stats.degenerate_triangles;
        continue;
      }
      object.triangles.push_back(tri);
      // The plane in the frame of the Embree geometry (world for static, object for movable).
      const Eigen::Vector3d normal = (p1 - p0).cross(p2 - p0).normalized();
      object.planes.push_back(TrianglePlane{normal, normal.dot(p0)});
    }
    object.triangle_count = object.triangles.size();
    if (object.material.is_vegetation() && options.convex_vegetation_volumes && object.triangle_count > 0) {
      object.volume = convex_shapes.shape_of(source.mesh);
      if (object.volume != nullptr) {
        object.volume_from_world = object.pose.inverse();
        for (const auto& v : object.vertices_m) object.volume_bounds_m.extend(v);
      }
    }
    ++impl->stats.objects;
    if (!object.is_static) ++impl->stats.movable_objects;
    if (object.material.is_vegetation()) ++impl->stats.vegetation_objects;
    if (object.volume != nullptr) ++impl->stats.convex_vegetation_objects;
    impl->stats.triangles += object.triangle_count;
    impl->objects.push_back(std::move(object));
  }
  RTCGeometry static_convex = nullptr;
  for (std::size_t index = 0; index < impl->objects.size(); ++index) {
    SceneObject& object = impl->objects[index];
    if (object.triangle_count == 0) continue;
    impl->make_geometry(object, static_cast<std::uint32_t>(index));
    impl->has_vegetation = impl->has_vegetation || object.material.is_vegetation();
    if (object.is_static && object.volume != nullptr) {
      impl->static_volumes.object_of_primitive.push_back(static_cast<std::uint32_t>(index));
      impl->static_volumes.bounds_m.push_back(object.volume_bounds_m);
    }
  }
  if (!impl->static_volumes.object_of_primitive.empty()) static_convex = impl->new_convex_geometry(impl->static_volumes);
  impl->build_layer(impl->main, [](const SceneObject&) { return true; }, static_convex);
  // The inside-a-volume vote is only needed for volumes traced as triangles.
  impl->build_layer(
      impl->vegetation,
      [](const SceneObject& object) { return object.material.is_vegetation() && object.volume == nullptr; },
      nullptr);
  if (static_convex != nullptr) rtcReleaseGeometry(static_convex);
  // The layers hold the geometries now; our copies of the meshes are no longer needed.
  for (auto& object : impl->objects) {
    if (object.geometry != nullptr) rtcReleaseGeometry(object.geometry);
    object.geometry = nullptr;
    object.vertices_m = {};
    object.triangles = {};
  }
  if (auto status = impl->check_device("building the scene of world '" + world.name + "'"); !status.ok()) {
    return status.error();
  }
  return std::unique_ptr<EmbreeScene>(new EmbreeScene(std::move(impl)));
}

Status EmbreeScene::set_object_pose(const std::string& name, const Eigen::Isometry3d& pose) {
  if (!pose.matrix().allFinite()) {
    return make_error(ErrorCode::kInvalidArgument, "pose of world object '" + name + "' is not finite");
  }
  Impl& impl = *impl_;
  for (std::size_t index = 0; index < impl.objects.size(); ++index) {
    SceneObject& object = impl.objects[index];
    if (object.name != name || object.is_static) continue;
    object.pose = pose;
    object.volume_from_world = pose.inverse();
    for (Layer* layer : {&impl.main, &impl.vegetation}) {
      if (layer->instance_of_object.empty() || layer->instance_of_object[index] == kInvalidId) continue;
      RTCGeometry instance = rtcGetGeometry(layer->top, layer->instance_of_object[index]);
      set_instance_transform(instance, pose);
      rtcCommitGeometry(instance);
      rtcCommitScene(layer->top);
    }
    return impl.check_device("moving world object '" + name + "'");
  }
  const bool exists =
      std::any_of(impl.objects.begin(), impl.objects.end(), [&](const SceneObject& o) { return o.name == name; });
  return make_error(exists ? ErrorCode::kInvalidArgument : ErrorCode::kNotFound,
                    exists ? "world object '" + name + "' is static and cannot be moved"
                           : "no world object named '" + name + "'");
}

SceneStats EmbreeScene::stats() const { return impl_->stats; }

// Both queries: every ray with its outcome, where `answer` casts the valid ones (unit direction),
// with the recording context and the vegetation volumes around the origin ready.
template <typename Answer>
std::vector<RayOutcome> EmbreeScene::Impl::for_each_ray(const Eigen::Vector3d& origin_m,
                                                        const std::vector<Eigen::Vector3d>& directions,
                                                        Answer answer) const {
  // Copies of one default outcome: cheaper than value-initialising each (a rep stos per element).
  static const RayOutcome kDefaultOutcome{};
  std::vector<RayOutcome> outcomes(directions.size(), kDefaultOutcome);
  const bool origin_finite = origin_m.allFinite();
  const bool answerable = !main.empty && origin_finite;
  QueryState state;
  if (answerable) {
    state.origin_f = origin_m.cast<float>();
    start_query(state);
    state.around = vegetation_around(origin_m);
  }
  for (std::size_t i = 0; i < directions.size(); ++i) {
    Eigen::Vector3d direction;
    if (!origin_finite || !unit_direction(directions[i], direction)) {
      outcomes[i].blocked = true;
      outcomes[i].blocking_object = kInvalidRayObject;
      continue;
    }
    if (!answerable) continue;  // an empty world: free
    state.crossings.clear();
    state.convex_candidates.clear();
    answer(state, direction, outcomes[i]);
  }
  return outcomes;
}

void EmbreeScene::Impl::start_query(QueryState& state) const {
  if (!vegetation.empty) state.crossings.reserve(32);
  if (!static_volumes.object_of_primitive.empty()) state.convex_candidates.reserve(16);
  rtcInitIntersectContext(&state.context.base);
  state.context.base.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // the rays of a batch leave one point, or go one way
  state.context.crossings = &state.crossings;
  state.context.convex_candidates = &state.convex_candidates;
}

std::vector<RayOutcome> EmbreeScene::trace(const Eigen::Vector3d& origin_m,
                                           const std::vector<Eigen::Vector3d>& directions) const {
  const Impl& impl = *impl_;
  return impl.for_each_ray(origin_m, directions, [&](Impl::QueryState& state, const Eigen::Vector3d& direction,
                                                     RayOutcome& outcome) {
    RTCRayHit ray_hit;
    init_ray(ray_hit, state.origin_f, direction);
    rtcIntersect1(impl.main.top, &state.context.base, &ray_hit);
    if (ray_hit.hit.geomID != kInvalidId) impl.describe_blocking(ray_hit, origin_m, direction, outcome);
    impl.add_vegetation(state.crossings, state.around, state.convex_candidates, origin_m, direction,
                        outcome.blocked ? outcome.blocking_distance_m : kInfinity, outcome);
  });
}

std::vector<RayOutcome> EmbreeScene::trace_line_of_sight(const Eigen::Vector3d& origin_m,
                                                         const std::vector<Eigen::Vector3d>& directions) const {
  const Impl& impl = *impl_;
  return impl.for_each_ray(origin_m, directions, [&](Impl::QueryState& state, const Eigen::Vector3d& direction,
                                                     RayOutcome& outcome) {
    impl.answer_line_of_sight(state, origin_m, direction, outcome);
  });
}

std::vector<RayOutcome> EmbreeScene::trace_line_of_sight_from(const std::vector<Eigen::Vector3d>& origins_m,
                                                              const Eigen::Vector3d& direction) const {
  const Impl& impl = *impl_;
  // As trace_line_of_sight from each origin alone, with the query's context made once.
  static const RayOutcome kDefaultOutcome{};
  std::vector<RayOutcome> outcomes(origins_m.size(), kDefaultOutcome);
  Eigen::Vector3d unit;
  const bool valid_direction = unit_direction(direction, unit);
  Impl::QueryState state;
  if (!impl.main.empty) impl.start_query(state);
  for (std::size_t i = 0; i < origins_m.size(); ++i) {
    const Eigen::Vector3d& origin_m = origins_m[i];
    if (!origin_m.allFinite() || !valid_direction) {
      outcomes[i].blocked = true;
      outcomes[i].blocking_object = kInvalidRayObject;
      continue;
    }
    if (impl.main.empty) continue;  // an empty world: free
    state.origin_f = origin_m.cast<float>();
    state.around = impl.vegetation_around(origin_m);
    state.crossings.clear();
    state.convex_candidates.clear();
    impl.answer_line_of_sight(state, origin_m, unit, outcomes[i]);
  }
  return outcomes;
}

void EmbreeScene::Impl::answer_line_of_sight(QueryState& state, const Eigen::Vector3d& origin_m, const Eigen::Vector3d& direction,
                                             RayOutcome& outcome) const {
  // One occlusion query: it stops at the first opaque hit it finds and meets all the vegetation
  // of a free ray on its way.
  RTCRayHit ray_hit;
  init_ray(ray_hit, state.origin_f, direction);
  state.context.blocker_instance = kInvalidId;
  state.context.blocker_geometry = kInvalidId;
  rtcOccluded1(main.top, &state.context.base, &ray_hit.ray);
  if (ray_hit.ray.tfar < 0.0F) {  // Embree's mark of an occluded ray
    outcome.blocked = true;
    // Every opaque triangle geometry has the filter that names it (make_geometry).
    if (state.context.blocker_geometry != kInvalidId) {
      const SceneObject& blocker = objects[main.object_index(state.context.blocker_instance, state.context.blocker_geometry)];
      outcome.blocking_object = blocker.name;
      outcome.blocking_material = blocker.material.material_class;
    }
  } else {
    add_vegetation(state.crossings, state.around, state.convex_candidates, origin_m, direction, kInfinity, outcome);
  }
}

}  // namespace skytrace::world

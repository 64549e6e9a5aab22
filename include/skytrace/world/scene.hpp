// Scenes that answer PathQuery for a WorldModel: EmbreeScene (fast, Embree 3 in single precision)
// and BruteForceScene (every triangle in double precision, the reference the tests compare
// against), plus the sky mask built on any PathQuery.
//
// Conventions shared by both scenes:
// - World frame: ENU metres of the world origin. Directions are unit vectors (east, north, up);
//   other lengths are normalised, so distances are always metres along the ray.
// - A ray starts at the origin itself (t >= 0) and goes to infinity (a satellite).
// - Opaque objects block: the outcome reports the first opaque hit (object name, material, distance,
//   point, and the unit normal of the hit triangle turned towards the ray origin, whatever the
//   mesh's winding). EmbreeScene finds the hit in float and recomputes the distance in double on
//   the hit triangle's plane (agreement with BruteForceScene ~1e-10 m, except rays grazing a plane).
// - Vegetation objects never block. They must be closed meshes (volumes): the path length inside
//   every vegetation volume between the origin and the first opaque hit (or infinity) is summed,
//   including a volume that contains the origin, and multiplied by each volume's
//   attenuation_db_per_m.
// - Triangles of zero area (see triangle_is_degenerate) are skipped; an empty world answers free.
// - An invalid ray (non-finite origin, non-finite or zero direction) is answered as blocked by
//   kInvalidRayObject at distance 0, so that a bad direction never looks like open sky; use
//   trace_checked() to get an error naming the ray instead.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/world/world_model.hpp"

namespace skytrace::world {

// blocking_object of the outcome of an invalid ray.
inline constexpr std::string_view kInvalidRayObject = "(invalid ray)";

// True for triangles whose area is zero to double precision relative to their size (collinear or
// repeated vertices). Such triangles are skipped by both scenes.
[[nodiscard]] bool triangle_is_degenerate(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c);

// Checks what a scene needs from a world: finite vertices and poses, triangle indices in range,
// unique names among movable (non-static) objects. The message names the object and the element.
[[nodiscard]] Status validate_world_for_scene(const WorldModel& world);

// PathQuery::trace with its input checked first: an error names the first invalid ray
// (non-finite origin, non-finite or zero direction) instead of answering it as blocked.
[[nodiscard]] Result<std::vector<RayOutcome>> trace_checked(const PathQuery& query, const Eigen::Vector3d& origin_m,
                                                            const std::vector<Eigen::Vector3d>& directions);

// Unit ENU direction of an azimuth (clockwise from north) and an elevation.
[[nodiscard]] Eigen::Vector3d enu_direction(double azimuth_deg, double elevation_deg);

struct SceneStats {
  std::size_t objects = 0;
  std::size_t movable_objects = 0;
  std::size_t vegetation_objects = 0;
  std::size_t convex_vegetation_objects = 0;  // EmbreeScene: traced as exact convex volumes
  std::size_t triangles = 0;             // used by the scene
  std::size_t degenerate_triangles = 0;  // skipped
};

struct EmbreeSceneOptions {
  // true: closed convex vegetation volumes (tree crowns as convex hulls) are traced as one Embree
  // user primitive each, the path inside computed exactly from their face planes; false: as
  // triangles, like any other vegetation volume (the general method, kept for comparison).
  bool convex_vegetation_volumes = true;
};

// The Embree 3 scene: one Embree query per ray, a closest hit for trace() and an occlusion test
// for trace_line_of_sight(); the vegetation met is recorded during that same query (crossings of
// volumes traced as triangles by a filter, convex volumes as user primitives, their paths exact).
// Static objects are one triangle geometry each; each movable object (is_static == false) is its
// own Embree scene, instanced in the top level, and the static geometry then sits in one child
// scene instanced once, so that set_object_pose() only rebuilds the top level (a few microseconds).
// trace() is const and keeps all its state on the stack: any number of threads may trace at once,
// but set_object_pose() must not run concurrently with trace().
class EmbreeScene final : public PathQuery {
 public:
  [[nodiscard]] static Result<std::unique_ptr<EmbreeScene>> build(const WorldModel& world,
                                                                 const EmbreeSceneOptions& options = {});

  ~EmbreeScene() override;
  EmbreeScene(const EmbreeScene&) = delete;
  EmbreeScene& operator=(const EmbreeScene&) = delete;

  [[nodiscard]] std::vector<RayOutcome> trace(const Eigen::Vector3d& origin_m,
                                              const std::vector<Eigen::Vector3d>& directions) const override;
  // One occlusion test per ray (Embree's cheapest query): see PathQuery::trace_line_of_sight.
  [[nodiscard]] std::vector<RayOutcome> trace_line_of_sight(const Eigen::Vector3d& origin_m,
                                                            const std::vector<Eigen::Vector3d>& directions) const override;
  [[nodiscard]] std::vector<RayOutcome> trace_line_of_sight_from(const std::vector<Eigen::Vector3d>& origins_m,
                                                                 const Eigen::Vector3d& direction) const override;

  // Moves a movable object (is_static == false in the world model) to a new pose in the world
  // frame. Errors: unknown name, a static object, a non-finite pose.
  [[nodiscard]] Status set_object_pose(const std::string& name, const Eigen::Isometry3d& pose);

  [[nodiscard]] SceneStats stats() const;

  struct Impl;

 private:
  explicit EmbreeScene(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// The reference: every ray against every triangle (Moller-Trumbore in double precision); vegetation
// path from the sorted crossings of each volume, each piece classified inside or outside by the
// winding number of its midpoint (independent of how EmbreeScene counts crossings). Slow: for tests.
class BruteForceScene final : public PathQuery {
 public:
  [[nodiscard]] static Result<BruteForceScene> build(const WorldModel& world);

  [[nodiscard]] std::vector<RayOutcome> trace(const Eigen::Vector3d& origin_m,
                                              const std::vector<Eigen::Vector3d>& directions) const override;

  [[nodiscard]] Status set_object_pose(const std::string& name, const Eigen::Isometry3d& pose);

  [[nodiscard]] SceneStats stats() const;

 private:
  struct Object {
    std::string name;
    Material material;
    bool is_static = true;
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    std::vector<Eigen::Vector3d> local_vertices_m;
    std::vector<Eigen::Vector3i> triangles;         // non-degenerate only
    std::vector<Eigen::Vector3d> world_vertices_m;  // pose applied
  };

  BruteForceScene() = default;
  std::vector<Object> objects_;
  SceneStats stats_;
};

struct SkyMaskOptions {
  // Lowest elevation searched: an azimuth free at this elevation gets this value.
  double min_elevation_deg = 0.0;
  // First pass: every azimuth is sampled at this elevation step (obstacles thinner than this in
  // elevation, such as a cable, may be missed); then bisection between the highest blocked sample
  // and the free one above it.
  double coarse_step_deg = 1.0;
  double tolerance_deg = 0.01;
};

// For azimuths 0, step, 2 step, ... (< 360 deg, clockwise from north), the elevation below which the
// sky is blocked by opaque objects seen from `origin_m` (vegetation does not count): the top of the
// highest obstruction, min_elevation_deg when free, 90 when even the zenith is blocked. All rays of
// a pass go through one batched trace() call.
[[nodiscard]] Result<std::vector<double>> sky_mask_elevation_deg(const PathQuery& query, const Eigen::Vector3d& origin_m,
                                                                 double azimuth_step_deg,
                                                                 const SkyMaskOptions& options = {});

}  // namespace skytrace::world

// EmbreeScene: the only file of skytrace that sees Embree.
//
// Layout: two top-level scenes, one for opaque objects and one for vegetation, so that the common
// case (no vegetation) costs exactly one Embree query per ray. Static objects are triangle
// geometries directly in their top-level scene (vertices already in the world frame); each movable
// object is a scene of its own, instanced in the top level, so a new pose only rebuilds the
// top-level structure.
//
// Vegetation: an intersection filter records every crossing and rejects it, so one traversal per
// ray collects all crossings to infinity. The number of crossings of a closed volume tells whether
// the origin is inside (odd) whatever the mesh's winding; the pieces inside are then clipped at
// the first opaque hit.
#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

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
  unsigned top_id = kInvalidId;  // geometry id in the top-level vegetation scene (geometry or instance)
  unsigned triangle = kInvalidId;
  double t_m = 0.0;
  bool facing_ray = false;  // the triangle's winding normal points against the ray
};

// The filter receives a pointer to the RTCIntersectContext given to rtcIntersect1; this struct
// starts with it so the filter reaches the crossings of the current ray (on the caller's stack).
struct VegetationContext {
  RTCIntersectContext base;
  std::vector<VegetationCrossing>* crossings;
};
static_assert(std::is_standard_layout_v<VegetationContext>);

void record_vegetation_crossing(const RTCFilterFunctionNArguments* args) {
  const auto* context = reinterpret_cast<const VegetationContext*>(args->context);
  for (unsigned i = 0; i < args->N; ++i) {
    if (args->valid[i] == 0) continue;
    const unsigned instance = RTCHitN_instID(args->hit, args->N, i, 0);
    const unsigned geometry = RTCHitN_geomID(args->hit, args->N, i);
    // Normal and direction are both in the object space of the hit geometry.
    const float normal_dot_direction =
        RTCHitN_Ng_x(args->hit, args->N, i) * RTCRayN_dir_x(args->ray, args->N, i) +
        RTCHitN_Ng_y(args->hit, args->N, i) * RTCRayN_dir_y(args->ray, args->N, i) +
        RTCHitN_Ng_z(args->hit, args->N, i) * RTCRayN_dir_z(args->ray, args->N, i);
    context->crossings->push_back(VegetationCrossing{instance != kInvalidId ? instance : geometry,
                                                     RTCHitN_primID(args->hit, args->N, i),
                                                     RTCRayN_tfar(args->ray, args->N, i), normal_dot_direction < 0.0F});
    args->valid[i] = 0;  // rejected: traversal goes on to the next crossing
  }
}

struct SceneObject {
  std::string name;
  Material material;
  bool is_static = true;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> local_vertices_m;
  std::vector<Eigen::Vector3i> triangles;  // non-degenerate only; the index is Embree's primID
  unsigned top_id = kInvalidId;            // geometry or instance id in its top-level scene
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

// Unit direction of a valid ray; false for a non-finite origin or a non-finite or zero direction.
bool unit_direction(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, Eigen::Vector3d& unit) {
  if (!origin.allFinite() || !direction.allFinite()) return false;
  const double norm = direction.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return false;
  unit = direction / norm;
  return true;
}

void init_ray(RTCRayHit& ray_hit, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) {
  ray_hit.ray.org_x = static_cast<float>(origin.x());
  ray_hit.ray.org_y = static_cast<float>(origin.y());
  ray_hit.ray.org_z = static_cast<float>(origin.z());
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

}  // namespace

struct EmbreeScene::Impl {
  RTCDevice device = nullptr;
  RTCScene opaque = nullptr;
  RTCScene vegetation = nullptr;
  std::vector<RTCScene> movable_scenes;
  std::vector<SceneObject> objects;
  std::vector<std::uint32_t> opaque_object_of_id;      // top-level id -> index in objects
  std::vector<std::uint32_t> vegetation_object_of_id;  // top-level id -> index in objects
  bool has_opaque = false;
  bool has_vegetation = false;
  SceneStats stats;

  Impl() = default;
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
  ~Impl() {
    for (RTCScene scene : movable_scenes) rtcReleaseScene(scene);
    if (opaque != nullptr) rtcReleaseScene(opaque);
    if (vegetation != nullptr) rtcReleaseScene(vegetation);
    if (device != nullptr) rtcReleaseDevice(device);
  }

  Status check_device(const std::string& step) const {
    const RTCError code = rtcGetDeviceError(device);
    if (code == RTC_ERROR_NONE) return Ok{};
    return make_error(ErrorCode::kInvalidArgument, "Embree failed while " + step + ": " + device_error_text(code));
  }

  // A triangle geometry of the object's mesh, in the world frame when `world_frame`.
  RTCGeometry make_triangles(const SceneObject& object, bool world_frame) const {
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), object.local_vertices_m.size()));
    auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(
        geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), object.triangles.size()));
    if (vertices == nullptr || indices == nullptr) return geometry;  // reported by check_device
    for (std::size_t i = 0; i < object.local_vertices_m.size(); ++i) {
      const Eigen::Vector3d v = world_frame ? Eigen::Vector3d(object.pose * object.local_vertices_m[i])
                                            : object.local_vertices_m[i];
      for (int k = 0; k < 3; ++k) vertices[3 * i + static_cast<std::size_t>(k)] = static_cast<float>(v[k]);
    }
    for (std::size_t i = 0; i < object.triangles.size(); ++i) {
      for (int k = 0; k < 3; ++k) indices[3 * i + static_cast<std::size_t>(k)] = static_cast<unsigned>(object.triangles[i][k]);
    }
    if (object.material.is_vegetation()) rtcSetGeometryIntersectFilterFunction(geometry, record_vegetation_crossing);
    rtcCommitGeometry(geometry);
    return geometry;
  }

  // Adds the object to its top-level scene and returns its id there.
  unsigned add_object(const SceneObject& object) {
    RTCScene top = object.material.is_vegetation() ? vegetation : opaque;
    RTCGeometry triangles = make_triangles(object, object.is_static);
    if (object.is_static) {
      const unsigned id = rtcAttachGeometry(top, triangles);
      rtcReleaseGeometry(triangles);
      return id;
    }
    RTCScene own = rtcNewScene(device);
    rtcSetSceneFlags(own, RTC_SCENE_FLAG_ROBUST);
    rtcAttachGeometry(own, triangles);
    rtcReleaseGeometry(triangles);
    rtcCommitScene(own);
    movable_scenes.push_back(own);
    RTCGeometry instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
    rtcSetGeometryInstancedScene(instance, own);
    rtcSetGeometryTimeStepCount(instance, 1);
    set_instance_transform(instance, object.pose);
    rtcCommitGeometry(instance);
    const unsigned id = rtcAttachGeometry(top, instance);
    rtcReleaseGeometry(instance);
    return id;
  }

  // The distance to a triangle hit by Embree, recomputed in double precision on the triangle's
  // plane (Embree's float distance carries ~1e-7 relative rounding), and the triangle's unit normal
  // turned towards the ray origin.
  static double refine_hit(const SceneObject& object, unsigned triangle, const Eigen::Vector3d& origin,
                           const Eigen::Vector3d& direction, double embree_t_m, Eigen::Vector3d& normal) {
    const Eigen::Vector3i& tri = object.triangles[triangle];
    const Eigen::Vector3d a = object.pose * object.local_vertices_m[static_cast<std::size_t>(tri[0])];
    const Eigen::Vector3d b = object.pose * object.local_vertices_m[static_cast<std::size_t>(tri[1])];
    const Eigen::Vector3d c = object.pose * object.local_vertices_m[static_cast<std::size_t>(tri[2])];
    normal = (b - a).cross(c - a).normalized();
    const double cos_incidence = normal.dot(direction);
    if (cos_incidence > 0.0) normal = -normal;
    // A ray grazing the plane keeps Embree's distance.
    if (std::abs(cos_incidence) <= 1e-6) return embree_t_m;
    const double refined_m = (a - origin).dot(normal) / direction.dot(normal);
    return std::isfinite(refined_m) && refined_m >= 0.0 ? refined_m : embree_t_m;
  }

  // Fills the opaque part of the outcome from Embree's closest hit.
  void describe_blocking(const RTCRayHit& ray_hit, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                         RayOutcome& outcome) const {
    const unsigned top_id = ray_hit.hit.instID[0] != kInvalidId ? ray_hit.hit.instID[0] : ray_hit.hit.geomID;
    const SceneObject& object = objects[opaque_object_of_id[top_id]];
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

  // Sums the vegetation crossed by one ray before `stop_m` (first opaque hit or infinity).
  void add_vegetation(std::vector<VegetationCrossing>& crossings, const Eigen::Vector3d& origin,
                      const Eigen::Vector3d& direction, double stop_m, RayOutcome& outcome) const {
    Eigen::Vector3d normal;
    for (auto& crossing : crossings) {
      const SceneObject& object = objects[vegetation_object_of_id[crossing.top_id]];
      crossing.t_m = refine_hit(object, crossing.triangle, origin, direction, crossing.t_m, normal);
    }
    std::sort(crossings.begin(), crossings.end(), [](const VegetationCrossing& x, const VegetationCrossing& y) {
      return x.top_id != y.top_id ? x.top_id < y.top_id : x.t_m < y.t_m;
    });
    std::size_t begin = 0;
    while (begin < crossings.size()) {
      std::size_t end = begin;
      while (end < crossings.size() && crossings[end].top_id == crossings[begin].top_id) ++end;
      // Distinct crossings of one volume, in order along the ray.
      std::size_t count = 0;
      double previous_m = -kInfinity;
      bool previous_facing = false;
      for (std::size_t i = begin; i < end; ++i) {
        const double t_m = crossings[i].t_m;
        if (count > 0 && t_m - previous_m <= kDuplicateCrossingM && crossings[i].facing_ray == previous_facing) continue;
        crossings[begin + count] = crossings[i];
        ++count;
        previous_m = t_m;
        previous_facing = crossings[i].facing_ray;
      }
      // An odd number of crossings to infinity: the origin is inside the volume.
      bool inside = count % 2 == 1;
      double entry_m = 0.0;
      double length_m = 0.0;
      for (std::size_t i = begin; i < begin + count; ++i) {
        const double t_m = crossings[i].t_m;
        if (inside) {
          length_m += std::max(0.0, std::min(t_m, stop_m) - std::min(entry_m, stop_m));
        } else {
          entry_m = t_m;
        }
        inside = !inside;
      }
      const SceneObject& object = objects[vegetation_object_of_id[crossings[begin].top_id]];
      outcome.vegetation_path_m += length_m;
      outcome.vegetation_attenuation_db += length_m * object.material.attenuation_db_per_m;
      begin = end;
    }
  }
};

EmbreeScene::EmbreeScene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
EmbreeScene::~EmbreeScene() = default;

Result<std::unique_ptr<EmbreeScene>> EmbreeScene::build(const WorldModel& world) {
  if (auto status = validate_world_for_scene(world); !status.ok()) return status.error();
  auto impl = std::make_unique<Impl>();
  impl->device = rtcNewDevice(nullptr);
  if (impl->device == nullptr) {
    return make_error(ErrorCode::kUnsupported, "Embree device could not be created: " +
                                                   device_error_text(rtcGetDeviceError(nullptr)));
  }
  impl->opaque = rtcNewScene(impl->device);
  impl->vegetation = rtcNewScene(impl->device);
  // Robust traversal: watertight edges, so rays never slip between two triangles of a wall.
  rtcSetSceneFlags(impl->opaque, RTC_SCENE_FLAG_ROBUST);
  rtcSetSceneFlags(impl->vegetation, RTC_SCENE_FLAG_ROBUST);

  for (const auto& source : world.objects) {
    SceneObject object;
    object.name = source.name;
    object.material = source.material;
    object.is_static = source.is_static;
    object.pose = source.pose;
    object.local_vertices_m.reserve(source.mesh.vertices_m.size());
    for (const auto& v : source.mesh.vertices_m) object.local_vertices_m.push_back(v.cast<double>());
    object.triangles.reserve(source.mesh.triangles.size());
    for (const auto& tri : source.mesh.triangles) {
      // Degeneracy is judged in the world frame, as BruteForceScene does.
      const Eigen::Vector3d a = object.pose * object.local_vertices_m[static_cast<std::size_t>(tri[0])];
      const Eigen::Vector3d b = object.pose * object.local_vertices_m[static_cast<std::size_t>(tri[1])];
      const Eigen::Vector3d c = object.pose * object.local_vertices_m[static_cast<std::size_t>(tri[2])];
      if (triangle_is_degenerate(a, b, c)) {
        ++impl->stats.degenerate_triangles;
        continue;
      }
      object.triangles.push_back(tri);
    }
    ++impl->stats.objects;
    if (!object.is_static) ++impl->stats.movable_objects;
    if (object.material.is_vegetation()) ++impl->stats.vegetation_objects;
    impl->stats.triangles += object.triangles.size();
    impl->objects.push_back(std::move(object));
  }

  for (std::size_t index = 0; index < impl->objects.size(); ++index) {
    SceneObject& object = impl->objects[index];
    // An object without triangles still answers set_object_pose but needs no geometry.
    if (object.triangles.empty()) continue;
    object.top_id = impl->add_object(object);
    auto& table = object.material.is_vegetation() ? impl->vegetation_object_of_id : impl->opaque_object_of_id;
    if (table.size() <= object.top_id) table.resize(object.top_id + 1, kNoObject);
    table[object.top_id] = static_cast<std::uint32_t>(index);
    (object.material.is_vegetation() ? impl->has_vegetation : impl->has_opaque) = true;
  }
  rtcCommitScene(impl->opaque);
  rtcCommitScene(impl->vegetation);
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
  for (auto& object : impl.objects) {
    if (object.name != name || object.is_static) continue;
    object.pose = pose;
    if (object.top_id == kInvalidId) return Ok{};
    RTCScene top = object.material.is_vegetation() ? impl.vegetation : impl.opaque;
    RTCGeometry instance = rtcGetGeometry(top, object.top_id);
    set_instance_transform(instance, pose);
    rtcCommitGeometry(instance);
    rtcCommitScene(top);
    return impl.check_device("moving world object '" + name + "'");
  }
  const bool exists =
      std::any_of(impl.objects.begin(), impl.objects.end(), [&](const SceneObject& o) { return o.name == name; });
  return make_error(exists ? ErrorCode::kInvalidArgument : ErrorCode::kNotFound,
                    exists ? "world object '" + name + "' is static and cannot be moved"
                           : "no world object named '" + name + "'");
}

SceneStats EmbreeScene::stats() const { return impl_->stats; }

std::vector<RayOutcome> EmbreeScene::trace(const Eigen::Vector3d& origin_m,
                                           const std::vector<Eigen::Vector3d>& directions) const {
  const Impl& impl = *impl_;
  std::vector<RayOutcome> outcomes(directions.size());
  if (!impl.has_opaque && !impl.has_vegetation) {
    for (std::size_t i = 0; i < directions.size(); ++i) {
      Eigen::Vector3d unit;
      if (!unit_direction(origin_m, directions[i], unit)) {
        outcomes[i].blocked = true;
        outcomes[i].blocking_object = std::string(kInvalidRayObject);
      }
    }
    return outcomes;
  }

  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // every ray of a batch leaves the same point
  std::vector<VegetationCrossing> crossings;
  VegetationContext vegetation_context{};
  rtcInitIntersectContext(&vegetation_context.base);
  vegetation_context.crossings = &crossings;

  for (std::size_t i = 0; i < directions.size(); ++i) {
    RayOutcome& outcome = outcomes[i];
    Eigen::Vector3d direction;
    if (!unit_direction(origin_m, directions[i], direction)) {
      outcome.blocked = true;
      outcome.blocking_object = std::string(kInvalidRayObject);
      continue;
    }
    RTCRayHit ray_hit;
    double stop_m = kInfinity;
    if (impl.has_opaque) {
      init_ray(ray_hit, origin_m, direction);
      rtcIntersect1(impl.opaque, &context, &ray_hit);
      if (ray_hit.hit.geomID != kInvalidId) {
        impl.describe_blocking(ray_hit, origin_m, direction, outcome);
        stop_m = outcome.blocking_distance_m;
      }
    }
    if (impl.has_vegetation) {
      crossings.clear();
      init_ray(ray_hit, origin_m, direction);
      rtcIntersect1(impl.vegetation, &vegetation_context.base, &ray_hit);
      if (!crossings.empty()) impl.add_vegetation(crossings, origin_m, direction, stop_m, outcome);
    }
  }
  return outcomes;
}

}  // namespace skytrace::world

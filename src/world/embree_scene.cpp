// EmbreeScene: the only file of skytrace that sees Embree.
//
// Layout. The main top-level scene holds every object, opaque and vegetation. Without movable
// objects the static objects are triangle geometries directly in it (vertices already in the world
// frame). With movable objects the static geometries go into one child scene instanced once, and
// every movable object is a scene of its own with an instance in the top level: a new pose then
// rebuilds only the top-level structure over a handful of instances, not the static BVH.
//
// One Embree query per ray. Without vegetation: rtcIntersect1 (closest hit, for the details) or
// rtcOccluded1 (visibility only). With vegetation: rtcIntersect1 in the main scene, where an
// intersection filter on the vegetation geometries records each crossing and rejects it, so the
// traversal goes on to the closest opaque hit and meets every vegetation crossing before it.
//
// Whether the origin lies inside a vegetation volume is decided once per batch (all rays of a batch
// share the origin) in a second, vegetation-only scene: the number of crossings of a closed volume
// along a ray to infinity is odd from inside, whatever the mesh's winding; three rays vote. Each
// ray's pieces inside a volume then follow from that state and its crossings before the first
// opaque hit.
#include <embree3/rtcore.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <type_traits>

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

// The plane of a triangle in double precision (object frame): normal . x = offset_m. One compact
// record per triangle, so that refining a hit costs one memory access, not four.
struct TrianglePlane {
  Eigen::Vector3d normal;  // unit, along the winding's normal
  double offset_m = 0.0;
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

// Unit direction of a valid ray; false for a non-finite origin or a non-finite or zero direction.
bool unit_direction(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, Eigen::Vector3d& unit) {
  if (!origin.allFinite() || !direction.allFinite()) return false;
  const double norm = direction.norm();
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
  DeviceHandle device_handle;  // first: released after everything else
  RTCDevice device = nullptr;
  Layer main;
  Layer vegetation;  // vegetation only, for the test of the origin inside a volume
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

  // The committed triangle geometry of an object (world frame for static objects), and for a
  // movable object its own committed scene.
  void make_geometry(SceneObject& object) const {
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
    if (object.material.is_vegetation()) rtcSetGeometryIntersectFilterFunction(geometry, record_vegetation_crossing);
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
  void build_layer(Layer& layer, Wanted wanted) const {
    bool has_movable = false;
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
    for (std::size_t index = 0; index < objects.size(); ++index) {
      const SceneObject& object = objects[index];
      if (object.triangle_count == 0 || !wanted(object)) continue;
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
    VegetationContext context{};
    rtcInitIntersectContext(&context.base);
    context.crossings = &crossings;
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

  // Adds the vegetation met by one ray before `stop_m` (the first opaque hit, or infinity), from
  // its crossings and the volumes around the origin.
  void add_vegetation(std::vector<VegetationCrossing>& crossings, const std::vector<std::uint32_t>& around,
                      const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double stop_m,
                      RayOutcome& outcome) const {
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
    ++impl->stats.objects;
    if (!object.is_static) ++impl->stats.movable_objects;
    if (object.material.is_vegetation()) ++impl->stats.vegetation_objects;
    impl->stats.triangles += object.triangle_count;
    impl->objects.push_back(std::move(object));
  }
  for (auto& object : impl->objects) {
    if (object.triangle_count > 0) impl->make_geometry(object);
  }
  impl->build_layer(impl->main, [](const SceneObject&) { return true; });
  impl->build_layer(impl->vegetation, [](const SceneObject& object) { return object.material.is_vegetation(); });
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

std::vector<RayOutcome> EmbreeScene::trace(const Eigen::Vector3d& origin_m,
                                           const std::vector<Eigen::Vector3d>& directions) const {
  const Impl& impl = *impl_;
  std::vector<RayOutcome> outcomes(directions.size());
  if (impl.main.empty || !origin_m.allFinite()) {
    for (std::size_t i = 0; i < directions.size(); ++i) {
      Eigen::Vector3d unit;
      if (!unit_direction(origin_m, directions[i], unit)) {
        outcomes[i].blocked = true;
        outcomes[i].blocking_object = std::string(kInvalidRayObject);
      }
    }
    return outcomes;
  }
  const Eigen::Vector3f origin_f = origin_m.cast<float>();
  std::vector<VegetationCrossing> crossings;
  if (!impl.vegetation.empty) crossings.reserve(32);
  VegetationContext context{};
  rtcInitIntersectContext(&context.base);
  context.base.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;  // every ray of a batch leaves the same point
  context.crossings = &crossings;
  const bool with_vegetation = !impl.vegetation.empty;
  const std::vector<std::uint32_t> around = impl.vegetation_around(origin_m);

  for (std::size_t i = 0; i < directions.size(); ++i) {
    RayOutcome& outcome = outcomes[i];
    Eigen::Vector3d direction;
    if (!unit_direction(origin_m, directions[i], direction)) {
      outcome.blocked = true;
      outcome.blocking_object = std::string(kInvalidRayObject);
      continue;
    }
    RTCRayHit ray_hit;
    init_ray(ray_hit, origin_f, direction);
    if (!with_vegetation && !impl.options.blocking_details) {
      rtcOccluded1(impl.main.top, &context.base, &ray_hit.ray);
      outcome.blocked = ray_hit.ray.tfar < 0.0F;  // Embree's mark of an occluded ray
      continue;
    }
    crossings.clear();
    rtcIntersect1(impl.main.top, &context.base, &ray_hit);
    if (ray_hit.hit.geomID != kInvalidId) impl.describe_blocking(ray_hit, origin_m, direction, outcome);
    if (!crossings.empty() || !around.empty()) {
      impl.add_vegetation(crossings, around, origin_m, direction, outcome.blocked ? outcome.blocking_distance_m : kInfinity,
                          outcome);
    }
  }
  return outcomes;
}

}  // namespace skytrace::world

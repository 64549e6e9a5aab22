// Line-of-sight cost: rays per second through EmbreeScene::trace (the PathQuery API: name,
// material, distance, point and normal of the blocking surface, vegetation) against raw Embree
// rtcOccluded1 (a yes/no answer) on the same geometry, one batch = 40 sky directions from one
// street-level point. Synthetic city: a grid of a few hundred box buildings plus a ~100k-triangle
// soup of clutter. Also the cost of moving an object between epochs and of building the scene.
#include <benchmark/benchmark.h>

#include "bench_support.hpp"
#include <embree3/rtcore.h>

#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string>
#include <limits>
#include <memory>
#include <numbers>
#include <vector>

#include "skytrace/core/random.hpp"
#include "skytrace/world/loaders.hpp"
#include "skytrace/world/scene.hpp"

namespace {

using namespace skytrace;
using namespace skytrace::world;

constexpr int kDirectionsPerBatch = 40;
constexpr int kBatches = 256;

world::TriangleMesh box_mesh(const Eigen::Vector3d& low, const Eigen::Vector3d& high) {
  world::TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    mesh.vertices_m.emplace_back(static_cast<float>((i & 1) != 0 ? high.x() : low.x()),
                                 static_cast<float>((i & 2) != 0 ? high.y() : low.y()),
                                 static_cast<float>((i & 4) != 0 ? high.z() : low.z()));
  }
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    mesh.triangles.emplace_back(q[0], q[1], q[2]);
    mesh.triangles.emplace_back(q[0], q[2], q[3]);
  }
  return mesh;
}

// 18 x 18 blocks of 40 m with 12 m streets: 324 buildings 6-45 m high; 100k clutter triangles
// (0.3-3 m, signs, balconies, street furniture) along the facades up to 30 m; optionally trees
// (vegetation boxes) along the streets and one movable truck.
struct City {
  WorldModel world;
  std::vector<Eigen::Vector3d> origins;  // street crossings at 1.5 m
  std::vector<std::vector<Eigen::Vector3d>> batches;
};

City make_city(int trees, bool truck) {
  City city;
  RandomStream random(stream_key(42, {1}));
  constexpr int kBlocks = 18;
  constexpr double kPitch = 52.0;
  constexpr double kBlock = 40.0;
  for (int i = 0; i < kBlocks; ++i) {
    for (int j = 0; j < kBlocks; ++j) {
      WorldObject building;
      building.name = "building_" + std::to_string(i) + "_" + std::to_string(j);
      building.kind = ObjectKind::kBuilding;
      const double x0 = i * kPitch;
      const double y0 = j * kPitch;
      building.mesh = box_mesh({x0, y0, 0}, {x0 + kBlock, y0 + kBlock, 6 + 39 * random.uniform()});
      city.world.objects.push_back(std::move(building));
    }
  }
  WorldObject clutter;
  clutter.name = "clutter";
  clutter.material.material_class = MaterialClass::kMetal;
  for (int t = 0; t < 100000; ++t) {
    // Near a facade: a random block, a random side, up to 3 m out.
    const double x0 = static_cast<double>(random.uniform_int(0, kBlocks - 1)) * kPitch;
    const double y0 = static_cast<double>(random.uniform_int(0, kBlocks - 1)) * kPitch;
    const double along = kBlock * random.uniform();
    const double out = 3.0 * random.uniform();
    Eigen::Vector3d centre;
    switch (random.uniform_int(0, 3)) {
      case 0: centre = {x0 + along, y0 - out, 0}; break;
      case 1: centre = {x0 + along, y0 + kBlock + out, 0}; break;
      case 2: centre = {x0 - out, y0 + along, 0}; break;
      default: centre = {x0 + kBlock + out, y0 + along, 0}; break;
    }
    centre.z() = 30.0 * random.uniform();
    const double size_m = 0.3 + 2.7 * random.uniform();
    const int first = static_cast<int>(clutter.mesh.vertices_m.size());
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d offset(random.uniform() - 0.5, random.uniform() - 0.5, random.uniform() - 0.5);
      clutter.mesh.vertices_m.push_back((centre + size_m * offset).cast<float>());
    }
    clutter.mesh.triangles.emplace_back(first, first + 1, first + 2);
  }
  city.world.objects.push_back(std::move(clutter));
  for (int t = 0; t < trees; ++t) {
    // Crowns 5 m wide, 3-8 m up, in the middle of the streets.
    const double x = (static_cast<double>(random.uniform_int(0, kBlocks - 1)) + 0.5) * kPitch;
    const double y = static_cast<double>(random.uniform_int(1, kBlocks - 1)) * kPitch - 6.0;
    WorldObject tree;
    tree.name = "tree_" + std::to_string(t);
    tree.kind = ObjectKind::kTree;
    tree.material = Material{MaterialClass::kVegetation, 1.0};
    tree.mesh = box_mesh({x - 2.5, y - 2.5, 3}, {x + 2.5, y + 2.5, 8});
    city.world.objects.push_back(std::move(tree));
  }
  if (truck) {
    WorldObject moving;
    moving.name = "truck";
    moving.is_static = false;
    moving.material.material_class = MaterialClass::kMetal;
    moving.mesh = box_mesh({-1.2, -4, 0}, {1.2, 4, 3.5});
    moving.pose = Eigen::Translation3d(kBlock + 3, 100, 0) * Eigen::Isometry3d::Identity();
    city.world.objects.push_back(std::move(moving));
  }
  for (int b = 0; b < kBatches; ++b) {
    // A street crossing, away from the facades.
    const double x = static_cast<double>(random.uniform_int(1, kBlocks - 1)) * kPitch - 6.0 + 4.0 * (random.uniform() - 0.5);
    const double y = static_cast<double>(random.uniform_int(1, kBlocks - 1)) * kPitch - 6.0 + 4.0 * (random.uniform() - 0.5);
    city.origins.emplace_back(x, y, 1.5);
    std::vector<Eigen::Vector3d> directions;
    for (int d = 0; d < kDirectionsPerBatch; ++d) {
      directions.push_back(enu_direction(360.0 * random.uniform(), 5.0 + 85.0 * random.uniform()));
    }
    city.batches.push_back(std::move(directions));
  }
  return city;
}

const City& plain_city() {
  static const City city = make_city(0, false);
  return city;
}
const City& city_with_truck() {
  static const City city = make_city(0, true);
  return city;
}
const City& green_city() {
  static const City city = make_city(400, false);
  return city;
}

void report_rays(benchmark::State& state, int rays_per_iteration, int blocked) {
  state.SetItemsProcessed(state.iterations() * rays_per_iteration);
  state.counters["blocked_share"] = static_cast<double>(blocked) / rays_per_iteration;
}

// details:1 = EmbreeScene::trace (nearest hit with point and normal), details:0 =
// trace_line_of_sight (blocked by what, or the vegetation crossed).
void trace_batches(benchmark::State& state, const City& city) {
  const bool details = state.range(0) != 0;
  auto scene = EmbreeScene::build(city.world);
  if (!scene.ok()) return state.SkipWithError(scene.error().message.c_str());
  int blocked = 0;
  for (auto _ : state) {
    blocked = 0;
    for (std::size_t b = 0; b < city.batches.size(); ++b) {
      const auto out = details ? (*scene)->trace(city.origins[b], city.batches[b])
                               : (*scene)->trace_line_of_sight(city.origins[b], city.batches[b]);
      for (const auto& o : out) blocked += o.blocked ? 1 : 0;
      benchmark::DoNotOptimize(out.data());
    }
  }
  report_rays(state, kBatches * kDirectionsPerBatch, blocked);
}

void BM_SceneTrace(benchmark::State& state) { trace_batches(state, plain_city()); }
BENCHMARK(BM_SceneTrace)->Unit(benchmark::kMillisecond)->Arg(1)->Arg(0)->ArgName("details");

void BM_SceneTraceWithTrees(benchmark::State& state) { trace_batches(state, green_city()); }
BENCHMARK(BM_SceneTraceWithTrees)->Unit(benchmark::kMillisecond)->Arg(1)->Arg(0)->ArgName("details");

// One movable object: the static geometry is then traversed through an instance.
void BM_SceneTraceWithMovable(benchmark::State& state) { trace_batches(state, city_with_truck()); }
BENCHMARK(BM_SceneTraceWithMovable)->Unit(benchmark::kMillisecond)->Arg(1)->Arg(0)->ArgName("details");

// Raw Embree on the same triangles, as one would write it by hand: one geometry per object in the
// world frame, the same robust scene flag, one rtcOccluded1 or rtcIntersect1 per ray.
class RawEmbree {
 public:
  explicit RawEmbree(const WorldModel& world, RTCSceneFlags flags = RTC_SCENE_FLAG_ROBUST,
                     RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM)
      : device_(rtcNewDevice(nullptr)), scene_(rtcNewScene(device_)) {
    rtcSetSceneFlags(scene_, flags);
    rtcSetSceneBuildQuality(scene_, quality);
    // Every object, vegetation included, as plain triangles: the same scene the API traverses.
    for (const auto& object : world.objects) {
      RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                   3 * sizeof(float), object.mesh.vertices_m.size()));
      auto* indices = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                     3 * sizeof(unsigned), object.mesh.triangles.size()));
      for (std::size_t i = 0; i < object.mesh.vertices_m.size(); ++i) {
        const Eigen::Vector3f v = (object.pose * object.mesh.vertices_m[i].cast<double>()).cast<float>();
        for (int k = 0; k < 3; ++k) vertices[3 * i + static_cast<std::size_t>(k)] = v[k];
      }
      for (std::size_t i = 0; i < object.mesh.triangles.size(); ++i) {
        for (int k = 0; k < 3; ++k) indices[3 * i + static_cast<std::size_t>(k)] = static_cast<unsigned>(object.mesh.triangles[i][k]);
      }
      rtcSetGeometryBuildQuality(geometry, quality);
      rtcCommitGeometry(geometry);
      rtcAttachGeometry(scene_, geometry);
      rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(scene_);
  }
  ~RawEmbree() {
    rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  RawEmbree(const RawEmbree&) = delete;
  RawEmbree& operator=(const RawEmbree&) = delete;

  static void fill(RTCRay& ray, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) {
    ray.org_x = static_cast<float>(origin.x());
    ray.org_y = static_cast<float>(origin.y());
    ray.org_z = static_cast<float>(origin.z());
    ray.dir_x = static_cast<float>(direction.x());
    ray.dir_y = static_cast<float>(direction.y());
    ray.dir_z = static_cast<float>(direction.z());
    ray.tnear = 0.0F;
    ray.tfar = std::numeric_limits<float>::infinity();
    ray.time = 0.0F;
    ray.mask = 0xFFFFFFFFU;
    ray.id = 0;
    ray.flags = 0;
  }
  bool occluded(RTCIntersectContext& context, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    RTCRay ray;
    fill(ray, origin, direction);
    rtcOccluded1(scene_, &context, &ray);
    return ray.tfar < 0.0F;  // Embree marks an occluded ray with tfar = -inf
  }
  bool intersected(RTCIntersectContext& context, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    RTCRayHit ray_hit;
    fill(ray_hit.ray, origin, direction);
    ray_hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    ray_hit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(scene_, &context, &ray_hit);
    return ray_hit.hit.geomID != RTC_INVALID_GEOMETRY_ID;
  }

 RTCScene scene() const { return scene_; }

 private:
  RTCDevice device_;
  RTCScene scene_;
};

template <bool kOccluded>
void raw_batches(benchmark::State& state) {
  const City& city = plain_city();
  const RawEmbree raw(city.world, static_cast<RTCSceneFlags>(state.range(0)), static_cast<RTCBuildQuality>(state.range(1)));
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  int blocked = 0;
  for (auto _ : state) {
    blocked = 0;
    for (std::size_t b = 0; b < city.batches.size(); ++b) {
      for (const auto& direction : city.batches[b]) {
        const bool hit = kOccluded ? raw.occluded(context, city.origins[b], direction)
                                   : raw.intersected(context, city.origins[b], direction);
        blocked += hit ? 1 : 0;
      }
    }
    benchmark::DoNotOptimize(blocked);
  }
  report_rays(state, kBatches * kDirectionsPerBatch, blocked);
}

void BM_RawEmbreeOccluded1(benchmark::State& state) { raw_batches<true>(state); }
// Arguments: scene flags (4 = robust, as EmbreeScene; 0 = Embree's faster default), build quality.
BENCHMARK(BM_RawEmbreeOccluded1)
    ->Unit(benchmark::kMillisecond)
    ->Args({RTC_SCENE_FLAG_ROBUST, RTC_BUILD_QUALITY_MEDIUM})
    ->Args({RTC_SCENE_FLAG_NONE, RTC_BUILD_QUALITY_MEDIUM})
    ->ArgNames({"flags", "quality"});

void BM_RawEmbreeIntersect1(benchmark::State& state) { raw_batches<false>(state); }
BENCHMARK(BM_RawEmbreeIntersect1)
    ->Unit(benchmark::kMillisecond)
    ->Args({RTC_SCENE_FLAG_ROBUST, RTC_BUILD_QUALITY_MEDIUM})
    ->ArgNames({"flags", "quality"});

// A batch as one Embree ray stream: the 40 directions of a point are too spread for packets to
// pay (measured slower than 40 rtcIntersect1), which is why EmbreeScene traces ray by ray.

void BM_RawEmbreeIntersect1M(benchmark::State& state) {
  const City& city = plain_city();
  const RawEmbree raw(city.world);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  std::vector<RTCRayHit> rays(kDirectionsPerBatch);
  int blocked = 0;
  for (auto _ : state) {
    blocked = 0;
    for (std::size_t b = 0; b < city.batches.size(); ++b) {
      for (int d = 0; d < kDirectionsPerBatch; ++d) {
        RawEmbree::fill(rays[d].ray, city.origins[b], city.batches[b][d]);
        rays[d].hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rays[d].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      }
      rtcIntersect1M(raw.scene(), &context, rays.data(), kDirectionsPerBatch, sizeof(RTCRayHit));
      for (const auto& r : rays) blocked += r.hit.geomID != RTC_INVALID_GEOMETRY_ID ? 1 : 0;
    }
  }
  report_rays(state, kBatches * kDirectionsPerBatch, blocked);
}
BENCHMARK(BM_RawEmbreeIntersect1M)->Unit(benchmark::kMillisecond);



// CPU time of this thread: the machine is shared, wall time would count the waits.
double thread_cpu_s() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// The goal figure in one run, robust to a loaded machine: each iteration traces every batch
// through EmbreeScene::trace (details:1) or trace_line_of_sight (details:0), then through raw rtcOccluded1 on the same triangles (same scene
// flags), then raw rtcIntersect1 (the raw query that finds what details report), and reports
// api_over_raw = rtcOccluded1 time / API time (goal >= 0.7) and api_over_raw_intersect.
// convex:0 traces convex vegetation volumes as triangles (EmbreeSceneOptions), for comparison.
void api_over_raw(benchmark::State& state, const City& city) {
  const bool details = state.range(0) != 0;
  EmbreeSceneOptions options;
  options.convex_vegetation_volumes = state.range(1) != 0;
  auto scene = EmbreeScene::build(city.world, options);
  if (!scene.ok()) return state.SkipWithError(scene.error().message.c_str());
  const RawEmbree raw(city.world);
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  double api_s = 0.0;
  double raw_s = 0.0;
  double raw_intersect_s = 0.0;
  int api_blocked = 0;
  int raw_blocked = 0;
  int through_vegetation = 0;
  for (auto _ : state) {
    const double start_s = thread_cpu_s();
    api_blocked = 0;
    through_vegetation = 0;
    for (std::size_t b = 0; b < city.batches.size(); ++b) {
      const auto out = details ? (*scene)->trace(city.origins[b], city.batches[b])
                               : (*scene)->trace_line_of_sight(city.origins[b], city.batches[b]);
      for (const auto& o : out) {
        api_blocked += o.blocked ? 1 : 0;
        through_vegetation += o.vegetation_path_m > 0.0 ? 1 : 0;
      }
    }
    const double middle_s = thread_cpu_s();
    raw_blocked = 0;
    for (std::size_t b = 0; b < city.batches.size(); ++b) {
      for (const auto& direction : city.batches[b]) raw_blocked += raw.occluded(context, city.origins[b], direction) ? 1 : 0;
    }
    const double end_s = thread_cpu_s();
    for (std::size_t b = 0; b < city.batches.size(); ++b) {
      for (const auto& direction : city.batches[b]) {
        benchmark::DoNotOptimize(raw.intersected(context, city.origins[b], direction));
      }
    }
    const double after_s = thread_cpu_s();
    api_s += middle_s - start_s;
    raw_s += end_s - middle_s;
    raw_intersect_s += after_s - end_s;
  }
  const double rays = static_cast<double>(state.iterations()) * kBatches * kDirectionsPerBatch;
  state.counters["api_rays_per_s"] = rays / api_s;
  state.counters["raw_rays_per_s"] = rays / raw_s;
  state.counters["api_over_raw"] = raw_s / api_s;
  state.counters["api_over_raw_intersect"] = raw_intersect_s / api_s;
  // Raw Embree sees vegetation as plain triangles: it also "blocks" the rays through trees.
  constexpr double kRays = kBatches * kDirectionsPerBatch;
  state.counters["blocked_share"] = api_blocked / kRays;
  state.counters["raw_blocked_share"] = raw_blocked / kRays;
  state.counters["vegetation_share"] = through_vegetation / kRays;
}

void BM_ApiOverRawOccluded(benchmark::State& state) { api_over_raw(state, plain_city()); }
BENCHMARK(BM_ApiOverRawOccluded)->Unit(benchmark::kMillisecond)->ArgsProduct({{1, 0}, {1}})->ArgNames({"details", "convex"});


// The citysim world of ../shared/data (Gazebo's simple_city.world with its models: terrain,
// buildings, trees as vegetation hulls), receivers 1.5 m above whatever is below a random point of
// the central part of the world. Empty world when the data is absent.
const City& citysim() {
  static const City city = [] {
    City out;
    auto world = skytrace::bench::load_citysim();
    if (!world) return out;
    out.world = std::move(*world);
    auto scene = EmbreeScene::build(out.world);
    if (!scene.ok()) return City{};
    const auto [low, high] = world_bounds(out.world);
    RandomStream random(stream_key(42, {2}));
    while (static_cast<int>(out.origins.size()) < kBatches) {
      const double x = low.x() + (high.x() - low.x()) * (0.25 + 0.5 * random.uniform());
      const double y = low.y() + (high.y() - low.y()) * (0.25 + 0.5 * random.uniform());
      const Eigen::Vector3d above(x, y, high.z() + 10.0);
      const auto down = (*scene)->trace(above, {Eigen::Vector3d(0, 0, -1)});
      if (!down[0].blocked) continue;
      out.origins.push_back(down[0].blocking_point_m + Eigen::Vector3d(0, 0, 1.5));
      std::vector<Eigen::Vector3d> directions;
      for (int d = 0; d < kDirectionsPerBatch; ++d) {
        directions.push_back(enu_direction(360.0 * random.uniform(), 5.0 + 85.0 * random.uniform()));
      }
      out.batches.push_back(std::move(directions));
    }
    return out;
  }();
  return city;
}

void BM_CitysimApiOverRawOccluded(benchmark::State& state) {
  const City& city = citysim();
  if (city.batches.empty()) return state.SkipWithError("citysim world absent or not loadable (set SKYTRACE_SHARED_DATA)");
  auto scene = EmbreeScene::build(city.world);
  if (!scene.ok()) return state.SkipWithError(scene.error().message.c_str());
  const SceneStats stats = (*scene)->stats();
  state.counters["objects"] = static_cast<double>(stats.objects);
  state.counters["movable"] = static_cast<double>(stats.movable_objects);
  state.counters["vegetation"] = static_cast<double>(stats.vegetation_objects);
  state.counters["triangles"] = static_cast<double>(stats.triangles);
  state.counters["convex_vegetation"] = static_cast<double>(stats.convex_vegetation_objects);
  api_over_raw(state, city);
}
BENCHMARK(BM_CitysimApiOverRawOccluded)
    ->Unit(benchmark::kMillisecond)
    ->ArgsProduct({{1, 0}, {1, 0}})
    ->ArgNames({"details", "convex"});

// Moving one truck between epochs in the full city: new instance transform and a top-level commit.
void BM_SetObjectPose(benchmark::State& state) {
  const City& city = city_with_truck();
  auto scene = EmbreeScene::build(city.world);
  if (!scene.ok()) return state.SkipWithError(scene.error().message.c_str());
  double y_m = 100.0;
  for (auto _ : state) {
    y_m = y_m > 400.0 ? 100.0 : y_m + 0.5;
    const auto status = (*scene)->set_object_pose("truck", Eigen::Isometry3d(Eigen::Translation3d(43, y_m, 0)));
    if (!status.ok()) return state.SkipWithError(status.error().message.c_str());
  }
}
BENCHMARK(BM_SetObjectPose)->Unit(benchmark::kMicrosecond);

void BM_BuildScene(benchmark::State& state) {
  const City& city = plain_city();
  for (auto _ : state) benchmark::DoNotOptimize(EmbreeScene::build(city.world));
}
BENCHMARK(BM_BuildScene)->Unit(benchmark::kMillisecond);

// The sky mask of one street crossing at 1 deg azimuth steps (360 x 91 coarse rays + bisection).
void BM_SkyMask(benchmark::State& state) {
  const City& city = plain_city();
  auto scene = EmbreeScene::build(city.world);
  if (!scene.ok()) return state.SkipWithError(scene.error().message.c_str());
  for (auto _ : state) benchmark::DoNotOptimize(sky_mask_elevation_deg(**scene, city.origins[0], 1.0));
}
BENCHMARK(BM_SkyMask)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

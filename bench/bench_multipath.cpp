// Multipath cost per epoch in the citysim world of ../shared/data (Gazebo's simple_city.world:
// heightmap terrain, building meshes, trees as vegetation hulls): PropagationScene::paths for 40
// satellite directions (all constellations above the horizon) from a street-level antenna -- the
// direct ray, first-order reflections off every facet within 150 m, knife-edge diffraction -- for a
// static antenna (the facet and edge candidates cached) and a moving one (new candidates every
// epoch), the second order as an option; and the receiver side, the code/phase/power errors of 4
// signals per satellite from those paths. One epoch = one iteration; goal 1,000 epochs/s, one core.
#include <benchmark/benchmark.h>

#include "bench_support.hpp"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "skytrace/core/allocator.hpp"
#include "skytrace/core/random.hpp"
#include "skytrace/receiver/multipath.hpp"
#include "skytrace/world/loaders.hpp"
#include "skytrace/world/propagation.hpp"
#include "skytrace/world/scene.hpp"

namespace {

using namespace skytrace;
using namespace skytrace::world;

constexpr int kSatellites = 40;
constexpr int kReceivers = 64;


struct City {
  WorldModel world;
  std::shared_ptr<const PathQuery> embree;
  std::unique_ptr<PropagationScene> scene;
  std::vector<Eigen::Vector3d> origins;  // 1.5 m above the terrain, not on a roof
  std::vector<Eigen::Vector3d> sky;      // azimuth/elevation of the satellites at the first epoch (deg)
};

const City& citysim() {
  static const City city = [] {
    City out;
    auto world = skytrace::bench::load_citysim();
    if (!world) return out;
    out.world = std::move(*world);
    auto embree = EmbreeScene::build(out.world);
    if (!embree.ok()) return City{};
    out.embree = std::shared_ptr<const PathQuery>(std::move(*embree));
    auto scene = PropagationScene::build(out.world, out.embree);
    if (!scene.ok()) return City{};
    out.scene = std::move(*scene);
    const auto [low, high] = world_bounds(out.world);
    RandomStream random(stream_key(7, {3}));
    for (int tries = 0; static_cast<int>(out.origins.size()) < kReceivers && tries < 100000; ++tries) {
      const double x = low.x() + (high.x() - low.x()) * (0.3 + 0.4 * random.uniform());
      const double y = low.y() + (high.y() - low.y()) * (0.3 + 0.4 * random.uniform());
      const auto down = out.embree->trace(Eigen::Vector3d(x, y, high.z() + 10.0), {Eigen::Vector3d(0, 0, -1)});
      if (!down[0].blocked || down[0].blocking_material != MaterialClass::kGround) continue;
      out.origins.push_back(down[0].blocking_point_m + Eigen::Vector3d(0, 0, 1.5));
    }
    for (int k = 0; k < kSatellites; ++k) {
      out.sky.emplace_back(360.0 * random.uniform(), 5.0 + 85.0 * random.uniform(), 0.0);
    }
    return out;
  }();
  return city;
}

// The satellites' directions at epoch k (1 s apart): each moves ~0.008 deg/s in azimuth and elevation.
std::vector<Eigen::Vector3d> directions_at(const City& city, long k) {
  std::vector<Eigen::Vector3d> d;
  d.reserve(city.sky.size());
  for (std::size_t i = 0; i < city.sky.size(); ++i) {
    const double sign = i % 2 == 0 ? 1.0 : -1.0;
    const double el = std::clamp(city.sky[i].y() + sign * 0.008 * static_cast<double>(k % 3600), 1.0, 89.0);
    d.push_back(enu_direction(city.sky[i].x() + 0.008 * static_cast<double>(k % 3600), el));
  }
  return d;
}

// nlos_models: also double bounces between facets within 40 m and directive diffuse scattering
// (S = 0.4, n = 4), as the Berlin validation scenarios take them (docs/validation.md).
// sky_cell_deg: PathSearchSettings::static_sky_cell_deg (what the simulator gives a receiver at a fixed position).
// moving_cell_m: PathSearchSettings::moving_cell_m (what the simulator gives a moving receiver).
void run_paths(benchmark::State& state, bool moving, int order, bool diffraction, bool nlos_models = false,
               double sky_cell_deg = 0.0, double moving_cell_m = 0.0) {
  const City& city = citysim();
  if (!city.scene) return state.SkipWithError("citysim world absent or not loadable (set SKYTRACE_SHARED_DATA)");
  PathSearchSettings settings;
  settings.max_reflection_order = order;
  settings.diffraction = diffraction;
  if (nlos_models) {
    settings.max_reflection_order = 2;
    settings.second_order_radius_m = 40.0;
    settings.scattering_coefficient = 0.4;
    settings.scattering_lobe_exponent = 4;
  }
  settings.static_sky_cell_deg = sky_cell_deg;
  settings.moving_cell_m = moving_cell_m;
  // Epochs kept per sky cell would come back from the cache if a repetition started the sky again:
  // with cells, each repetition goes on where the last one stopped.
  static std::map<long, long> next_epoch;  // per receiver
  long k = sky_cell_deg > 0.0 ? next_epoch[state.range(0)] : 0;
  double paths = 0.0, reflected = 0.0, diffracted = 0.0, scattered = 0.0, nlos = 0.0, sets = 0.0;
  for (auto _ : state) {
    // A static antenna stays at one point of a street; a moving one advances 1 m per epoch.
    const std::size_t receiver = moving ? static_cast<std::size_t>(k / 50) % city.origins.size()
                                        : static_cast<std::size_t>(state.range(0)) % city.origins.size();
    Eigen::Vector3d origin = city.origins[receiver];
    if (moving) origin.x() += static_cast<double>(k % 50);
    const auto out = city.scene->paths(origin, directions_at(city, k), settings);
    for (const PathSet& set : out) {
      sets += 1.0;
      paths += static_cast<double>(set.paths.size());
      for (const SignalPath& p : set.paths) {
        reflected += p.type == PathType::kReflected ? 1.0 : 0.0;
        diffracted += p.type == PathType::kDiffracted ? 1.0 : 0.0;
        scattered += p.type == PathType::kScattered ? 1.0 : 0.0;
      }
      nlos += set.direct.blocked && !set.paths.empty() ? 1.0 : 0.0;
    }
    benchmark::DoNotOptimize(out);
    ++k;
  }
  if (sky_cell_deg > 0.0) next_epoch[state.range(0)] = k;
  state.SetItemsProcessed(state.iterations());  // epochs
  state.counters["facets"] = static_cast<double>(city.scene->facets().size());
  {
    // Facets and edges within the search radius of the first antenna.
    const Eigen::Vector3d o = city.origins[static_cast<std::size_t>(state.range(0)) % city.origins.size()];
    double near_facets = 0.0, near_large = 0.0, near_edges = 0.0;
    for (const Facet& f : city.scene->facets()) {
      if ((o.cwiseMax(f.min_m).cwiseMin(f.max_m) - o).norm() > settings.radius_m) continue;
      near_facets += 1.0;
      near_large += f.area_m2 >= settings.min_facet_area_m2 ? 1.0 : 0.0;
    }
    for (const DiffractionEdge& e : city.scene->edges()) near_edges += (0.5 * (e.start_m + e.end_m) - o).norm() < settings.radius_m ? 1.0 : 0.0;
    state.counters["near_facets"] = near_facets;
    state.counters["near_facets_1m2"] = near_large;
    state.counters["near_edges"] = near_edges;
  }
  state.counters["edges"] = static_cast<double>(city.scene->edges().size());
  state.counters["paths_per_sat"] = paths / std::max(sets, 1.0);
  state.counters["reflected_per_sat"] = reflected / std::max(sets, 1.0);
  state.counters["diffracted_per_sat"] = diffracted / std::max(sets, 1.0);
  state.counters["scattered_per_sat"] = scattered / std::max(sets, 1.0);
  state.counters["nlos_share"] = nlos / std::max(sets, 1.0);
}

void BM_CitysimPathsStatic(benchmark::State& state) { run_paths(state, false, 1, true); }
BENCHMARK(BM_CitysimPathsStatic)->Unit(benchmark::kMicrosecond)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->ArgName("receiver");

// The parts: direct only, direct + reflections, direct + diffraction.
void BM_CitysimDirectOnly(benchmark::State& state) { run_paths(state, false, 0, false); }
BENCHMARK(BM_CitysimDirectOnly)->Unit(benchmark::kMicrosecond)->Arg(0);
void BM_CitysimReflectionsOnly(benchmark::State& state) { run_paths(state, false, 1, false); }
BENCHMARK(BM_CitysimReflectionsOnly)->Unit(benchmark::kMicrosecond)->Arg(0);
void BM_CitysimDiffractionOnly(benchmark::State& state) { run_paths(state, false, 0, true); }
BENCHMARK(BM_CitysimDiffractionOnly)->Unit(benchmark::kMicrosecond)->Arg(0);

void BM_CitysimPathsMoving(benchmark::State& state) { run_paths(state, true, 1, true); }
BENCHMARK(BM_CitysimPathsMoving)->Unit(benchmark::kMicrosecond)->Arg(0);

void BM_CitysimPathsSecondOrder(benchmark::State& state) { run_paths(state, false, 2, true); }
BENCHMARK(BM_CitysimPathsSecondOrder)->Unit(benchmark::kMicrosecond)->Arg(0)->Arg(1);

// With the NLOS models of the Berlin validation: double bounces within 40 m, diffuse scattering.
void BM_CitysimPathsNlosModelsStatic(benchmark::State& state) { run_paths(state, false, 1, true, true); }
// A fixed 100 epochs (the satellites move, the moving antenna covers two streets), so that two
// builds are compared on the same sky and the same places.
BENCHMARK(BM_CitysimPathsNlosModelsStatic)->Unit(benchmark::kMicrosecond)->Arg(0)->Arg(1)->Iterations(100);
void BM_CitysimPathsNlosModelsMoving(benchmark::State& state) { run_paths(state, true, 1, true, true); }
BENCHMARK(BM_CitysimPathsNlosModelsMoving)->Unit(benchmark::kMicrosecond)->Arg(0)->Iterations(100);
// A static antenna as the simulator runs one at a fixed position: its paths kept per sky cell of
// 0.05 deg (models.static_sky_cell_deg), the satellites moving about 0.01 deg per 1 s epoch.
void BM_CitysimPathsNlosModelsStaticCells(benchmark::State& state) { run_paths(state, false, 1, true, true, 0.05); }
BENCHMARK(BM_CitysimPathsNlosModelsStaticCells)->Unit(benchmark::kMicrosecond)->Arg(0)->Arg(1)->Iterations(100);
// A moving antenna as the simulator runs one on a trajectory: its second-order and scattered paths
// kept per cube of models.moving_cell_m (the argument, in dm) and sky cell.
void BM_CitysimPathsNlosModelsMovingCells(benchmark::State& state) {
  run_paths(state, true, 1, true, true, 0.0, 0.1 * static_cast<double>(state.range(1)));
}
BENCHMARK(BM_CitysimPathsNlosModelsMovingCells)->Unit(benchmark::kMicrosecond)->Args({0, 10})->Args({0, 20})->Args({0, 30})->Args({0, 40})->Iterations(100);

// Receiver side: 40 satellites x 4 signals (BPSK(1), BOC(1,1), BPSK(2), BPSK(10)) from the paths
// the static antenna sees.
void BM_CitysimObservableErrors(benchmark::State& state) {
  const City& city = citysim();
  if (!city.scene) return state.SkipWithError("citysim world absent or not loadable (set SKYTRACE_SHARED_DATA)");
  const auto sets = city.scene->paths(city.origins[0], directions_at(city, 0), PathSearchSettings{});
  std::vector<std::vector<receiver::ReceivedPath>> received;
  for (const PathSet& set : sets) {
    std::vector<receiver::ReceivedPath> r;
    for (const SignalPath& p : set.paths) r.push_back({p.excess_delay_m, 0.0, p.rhcp_amplitude + 0.1 * p.lhcp_amplitude});
    received.push_back(std::move(r));
  }
  const double c = 299792458.0;
  const std::vector<std::pair<receiver::CorrelationFunction, double>> signals = {
      {receiver::CorrelationFunction::bpsk(), c / 1.023e6},
      {receiver::CorrelationFunction::boc(1, 1), c / 1.023e6},
      {receiver::CorrelationFunction::bpsk(), c / 2.046e6},
      {receiver::CorrelationFunction::bpsk(), c / 10.23e6}};
  for (auto _ : state) {
    for (const auto& r : received) {
      for (const auto& [correlation, chip_m] : signals) {
        benchmark::DoNotOptimize(receiver::multipath_errors(correlation, chip_m, 0.19, 0.1, r));
      }
    }
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_CitysimObservableErrors)->Unit(benchmark::kMicrosecond);

}  // namespace

// As skytrace and the live nodes run the path search: with the allocator set for per-epoch buffers.
int main(int argc, char** argv) {
  skytrace::tune_allocator_for_epochs();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

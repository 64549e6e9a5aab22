#include "skytrace/sim/world_setup.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>

#include "skytrace/world/loaders.hpp"
#include "skytrace/world/propagation.hpp"
#include "skytrace/world/scene.hpp"

namespace skytrace::sim {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

world::ObjectKind kind_from_name(const std::string& name) {
  if (name == "building") return world::ObjectKind::kBuilding;
  if (name == "tree") return world::ObjectKind::kTree;
  if (name == "ground") return world::ObjectKind::kGround;
  return world::ObjectKind::kOther;
}

std::vector<world::MaterialRule> material_rules(const WorldSettings& w, double vegetation_db_per_m) {
  std::vector<world::MaterialRule> rules;
  for (const auto& r : w.materials) {
    world::MaterialRule rule;
    rule.pattern = r.match;
    rule.material.material_class = r.material_class;
    if (r.material_class == MaterialClass::kVegetation) {
      rule.material.attenuation_db_per_m = r.attenuation_db_per_m.value_or(vegetation_db_per_m);
    }
    if (r.kind) rule.kind = kind_from_name(*r.kind);
    rules.push_back(std::move(rule));
  }
  return rules;
}

// Objects of `part` appended to `into`, moved by `placement` (world frame of `into`).
void append_world(world::WorldModel& into, world::WorldModel&& part, const Eigen::Isometry3d& placement) {
  for (auto& object : part.objects) {
    object.pose = placement * object.pose;
    into.objects.push_back(std::move(object));
  }
  for (auto& [name, pose] : part.model_poses) into.model_poses[name] = placement * pose;
  for (auto& w : part.warnings) into.warnings.push_back(std::move(w));
}

// The objects of a model: named `model` itself or `model/...`.
bool belongs_to(const std::string& object, const std::string& model) {
  return object == model || (object.size() > model.size() && object.compare(0, model.size(), model) == 0 &&
                             object[model.size()] == '/');
}

}  // namespace

Result<std::optional<LoadedWorld>> load_world(const Scenario& s) {
  const WorldSettings& w = s.world;
  if (!w.any()) return std::optional<LoadedWorld>{};
  const double vegetation_db_per_m = w.vegetation_attenuation_db_per_m.value_or(world::kDefaultVegetationAttenuationDbPerM);
  const std::vector<world::MaterialRule> rules = material_rules(w, vegetation_db_per_m);
  std::optional<LocalFrame> frame;
  if (w.latitude_deg && w.longitude_deg) {
    frame = LocalFrame{Geodetic{*w.latitude_deg, *w.longitude_deg, w.elevation_m.value_or(0.0)}, w.heading_deg.value_or(0.0)};
  }

  world::WorldModel model;
  if (w.sdf) {
    world::SdfLoadOptions options;
    options.model_paths = w.model_paths;
    options.geo_origin = frame;
    options.material_rules = rules;
    options.vegetation_attenuation_db_per_m = vegetation_db_per_m;
    options.vegetation_hull_tolerance_m = w.vegetation_hull_tolerance_m.value_or(world::kDefaultVegetationHullToleranceM);
    auto sdf = world::load_sdf_world(*w.sdf, options);
    if (!sdf) return sdf.error();
    if (!sdf->geo_origin) {
      return make_error(ErrorCode::kParse,
                        w.sdf->string() + ": the world has no <spherical_coordinates>; give world.latitude_deg "
                                          "and world.longitude_deg (and elevation_m, heading_deg) in the scenario");
    }
    frame = sdf->geo_origin;
    model = std::move(*sdf);
  }
  // OpenStreetMap, footprints, CityJSON, CityGML and elevation models load east-north-up around an origin (the world's when it
  // has one already, else theirs); the world x axis is `heading` counter-clockwise from east.
  const auto append_enu_world = [&](world::WorldModel&& part) {
    if (!frame) frame = part.geo_origin;
    const Eigen::Isometry3d enu_to_world(Eigen::AngleAxisd(-frame->heading_deg * kDegToRad, Eigen::Vector3d::UnitZ()));
    if (model.name.empty()) model.name = part.name;
    append_world(model, std::move(part), enu_to_world);
  };
  if (w.osm) {
    world::OsmLoadOptions options;
    if (frame) {
      // Buildings stand on the world's z = 0: the origin's height.
      options.origin = frame->origin;
      options.ground_height_m = frame->origin.height_m;
    } else {
      options.ground_height_m = w.elevation_m.value_or(0.0);
    }
    options.material_rules = rules;
    options.vegetation_attenuation_db_per_m = vegetation_db_per_m;
    // A park without buildings is a valid world; an extract with nothing usable is not.
    options.allow_no_buildings = true;
    auto osm = world::load_osm_world(*w.osm, options);
    if (!osm) return osm.error();
    if (osm->objects.empty()) {
      std::string message = w.osm->string() + ": no buildings, trees or woods in the OSM data";
      if (!osm->warnings.empty()) message += " (" + osm->warnings.front() + ")";
      return make_error(ErrorCode::kNotFound, message);
    }
    if (world::summarize_world(*osm).buildings == 0) {
      osm->warnings.push_back(w.osm->string() + ": no buildings in the OSM data, only vegetation (" +
                              std::to_string(osm->objects.size()) + " trees or woods)");
    }
    append_enu_world(std::move(*osm));
  }
  if (w.footprints) {
    world::FootprintLoadOptions options;
    if (frame) {
      options.origin = frame->origin;
      options.ground_height_m = frame->origin.height_m;
    } else {
      options.ground_height_m = w.elevation_m.value_or(0.0);
    }
    options.height_field = w.footprint_height_field;
    options.material_rules = rules;
    auto footprints = world::load_footprint_world(*w.footprints, options);
    if (!footprints) return footprints.error();
    append_enu_world(std::move(*footprints));
  }
  // City models (CityJSON, CityGML): the same options, their own reader.
  const auto append_city_model = [&](const std::filesystem::path& path, const std::optional<double>& height_offset_m,
                                     auto load) -> Status {
    world::CityModelLoadOptions options;
    if (frame) options.origin = frame->origin;
    options.height_offset_m = height_offset_m;
    options.material_rules = rules;
    options.vegetation_attenuation_db_per_m = vegetation_db_per_m;
    auto city = load(path, options);
    if (!city) return city.error();
    append_enu_world(std::move(*city));
    return Ok{};
  };
  if (w.cityjson) {
    if (auto st = append_city_model(*w.cityjson, w.cityjson_height_offset_m, world::load_cityjson_world); !st) return st.error();
  }
  if (w.citygml) {
    if (auto st = append_city_model(*w.citygml, w.citygml_height_offset_m, world::load_citygml_world); !st) return st.error();
  }
  if (w.dem) {
    world::DemLoadOptions options;
    if (frame) options.origin = frame->origin;
    options.height_offset_m = w.dem_height_offset_m;
    auto terrain = world::load_dem_world(*w.dem, options);
    if (!terrain) return terrain.error();
    append_enu_world(std::move(*terrain));
  }
  if (!frame) {
    return make_error(ErrorCode::kParse,
                      s.source.string() + ": world.meshes need a geographic origin: give world.latitude_deg and "
                                          "world.longitude_deg");
  }
  for (const MeshSetting& m : w.meshes) {
    world::MeshLoadOptions options;
    options.up_axis = m.up_axis == "y" ? world::UpAxis::kY : m.up_axis == "z" ? world::UpAxis::kZ : world::UpAxis::kAuto;
    options.scale = m.scale;
    // Roll, pitch, yaw as in an SDF <pose>: R = Rz(yaw) Ry(pitch) Rx(roll).
    options.pose = Eigen::Translation3d(m.position_m) *
                   Eigen::AngleAxisd(m.rpy_deg.z() * kDegToRad, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(m.rpy_deg.y() * kDegToRad, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(m.rpy_deg.x() * kDegToRad, Eigen::Vector3d::UnitX());
    options.default_kind = kind_from_name(m.kind);
    options.default_material.material_class = m.material;
    if (m.kind == "tree") options.default_material = Material{MaterialClass::kVegetation, vegetation_db_per_m};
    if (m.kind == "ground") options.default_material.material_class = MaterialClass::kGround;
    options.material_rules = rules;
    options.vegetation_attenuation_db_per_m = vegetation_db_per_m;
    options.vegetation_hull_tolerance_m = w.vegetation_hull_tolerance_m.value_or(world::kDefaultVegetationHullToleranceM);
    options.name = m.name;
    auto mesh = world::load_mesh_world(m.file, *frame, options);
    if (!mesh) return mesh.error().with_context("world.meshes");
    if (model.model_poses.count(m.name) != 0) {
      return make_error(ErrorCode::kParse, s.source.string() + ": world.meshes: the name '" + m.name +
                                                         "' is already a model of the world; give the mesh another name");
    }
    if (model.name.empty()) model.name = m.name;
    append_world(model, std::move(*mesh), Eigen::Isometry3d::Identity());
  }
  model.geo_origin = frame;

  LoadedWorld loaded;
  // Models that move: every object of a world.moving model becomes movable.
  for (const MovingModelSetting& m : w.moving) {
    bool found = false;
    for (auto& object : model.objects) {
      if (!belongs_to(object.name, m.model)) continue;
      object.is_static = false;
      found = true;
    }
    if (!found) {
      std::string known;
      size_t listed = 0;
      for (const auto& [name, pose] : model.model_poses) {
        if (listed++ < 12) known += (known.empty() ? "" : ", ") + name;
      }
      if (listed > 12) known += ", ...";
      return make_error(ErrorCode::kNotFound, s.source.string() + ": world.moving: no model named '" + m.model +
                                                  "' in the world (models: " + (known.empty() ? "none" : known) + ")");
    }
    auto trajectory = ModelTrajectory::read_csv(m, s.time.start);
    if (!trajectory) return trajectory.error();
    loaded.moving.emplace_back(m.model, std::move(*trajectory));
  }
  // Movable objects are moved by name: parts of one object (a mesh's submeshes) get #2, #3...
  {
    std::map<std::string, int> seen;
    for (auto& object : model.objects) {
      if (object.is_static) continue;
      const int count = ++seen[object.name];
      if (count > 1) object.name += "#" + std::to_string(count);
    }
  }
  for (const auto& object : model.objects) {
    if (object.is_static) continue;
    for (const auto& [name, pose] : model.model_poses) {
      if (!belongs_to(object.name, name)) continue;
      loaded.movable_models[name].push_back(LoadedWorld::ModelPart{object.name, pose.inverse() * object.pose});
      break;
    }
  }

  // The model's extent, before a ground plane or surroundings are added to it.
  const auto model_bounds = model.objects.empty() ? std::pair<Eigen::Vector3d, Eigen::Vector3d>{}
                                                  : world::world_bounds(model);
  // OpenStreetMap, footprints and CityJSON without a terrain have no ground: a plane at the world's
  // z = 0 (its ground height) under everything and 200 m beyond, so that the ground reflects
  // (models.multipath) and blocks what is below the horizon, as Gazebo worlds' ground planes do.
  const bool has_ground = std::any_of(model.objects.begin(), model.objects.end(),
                                      [](const world::WorldObject& o) { return o.kind == world::ObjectKind::kGround; });
  if (!has_ground && !model.objects.empty() && (w.osm || w.footprints || w.cityjson || w.citygml)) {
    const auto [low, high] = world::world_bounds(model);
    constexpr double kBeyond_m = 200.0;
    world::WorldObject ground;
    ground.name = "ground plane";
    ground.kind = world::ObjectKind::kGround;
    ground.material.material_class = MaterialClass::kGround;
    ground.mesh = world::make_plane(Eigen::Vector3d::UnitZ(),
                                    Eigen::Vector2d(high.x() - low.x() + 2.0 * kBeyond_m, high.y() - low.y() + 2.0 * kBeyond_m));
    ground.pose = Eigen::Translation3d(0.5 * (low.x() + high.x()), 0.5 * (low.y() + high.y()), 0.0);
    model.objects.push_back(std::move(ground));
  }
  // The city beyond the model (world.surroundings_height_m): a 1 m thick wall around the objects'
  // horizontal bounds, its inner face on them, from below their lowest base to the height above the
  // ground, so that a receiver inside sees no open horizon where the model merely ends.
  if (w.surroundings_height_m && !model.objects.empty()) {
    // Not a structured binding: clang 14 cannot capture one in the lambda below.
    const Eigen::Vector3d& low = model_bounds.first;
    const Eigen::Vector3d& high = model_bounds.second;
    const double bottom_m = std::min(low.z(), 0.0) - 1.0;
    constexpr double kWallThickness_m = 1.0;
    const auto rectangle = [&](double out_m) {
      return world::Ring2{{low.x() - out_m, low.y() - out_m}, {high.x() + out_m, low.y() - out_m},
                          {high.x() + out_m, high.y() + out_m}, {low.x() - out_m, high.y() + out_m}};
    };
    if (*w.surroundings_height_m > bottom_m) {
      auto ring = world::extrude_polygon(world::PolygonWithHoles{rectangle(kWallThickness_m), {rectangle(0.0)}},
                                         bottom_m, *w.surroundings_height_m);
      if (!ring) return ring.error().with_context("world.surroundings_height_m");
      world::WorldObject surroundings;
      surroundings.name = "surroundings";
      surroundings.kind = world::ObjectKind::kSurroundings;
      surroundings.mesh = std::move(*ring);
      model.objects.push_back(std::move(surroundings));
    }
  }
  auto scene = world::EmbreeScene::build(model);
  if (!scene) {
    // A world the scene refuses (non-finite vertices, bad indices) is bad input, not a bad command.
    return make_error(ErrorCode::kParse, (w.sdf ? w.sdf->string() : s.source.string()) + ": " + scene.error().message);
  }
  loaded.name = model.name;
  loaded.frame = *frame;
  const world::WorldSummary summary = world::summarize_world(model);
  loaded.objects = model.objects.size();
  loaded.buildings = summary.buildings;
  loaded.trees = summary.trees;
  loaded.triangles = (*scene)->stats().triangles;
  loaded.warnings = model.warnings;
  {
    world::WorldModel above_ground;
    for (const auto& object : model.objects) {
      if (object.kind == world::ObjectKind::kGround || object.kind == world::ObjectKind::kSurroundings) continue;
      if (auto f = world::footprint(object); f.outline_m.size() >= 3) loaded.footprints.push_back(std::move(f));
      above_ground.objects.push_back(world::WorldObject{object.name, object.kind, object.material, object.mesh, object.pose,
                                                        object.is_static});
    }
    if (!above_ground.objects.empty()) {
      std::tie(loaded.low_m, loaded.high_m) = world::world_bounds(above_ground);
      loaded.has_objects = true;
    }
  }
  std::shared_ptr<world::EmbreeScene> shared_scene(std::move(*scene));
  loaded.move_object = [shared_scene](const std::string& name, const Eigen::Isometry3d& pose) {
    return shared_scene->set_object_pose(name, pose);
  };
  loaded.scene = std::move(shared_scene);
  if (s.models.multipath) {
    // Reflections and diffraction off the static objects; the Embree scene still casts every ray.
    auto propagation = world::PropagationScene::build(model, loaded.scene);
    if (!propagation) return propagation.error().with_context(w.sdf ? w.sdf->string() : s.source.string());
    loaded.scene = std::shared_ptr<const PathQuery>(std::move(*propagation));
  }
  if (auto st = move_models_to(loaded, s.time.start); !st) return st.error();
  return std::optional<LoadedWorld>(std::move(loaded));
}

Status set_object_pose(LoadedWorld& world, const std::string& name, const Eigen::Isometry3d& pose_world) {
  if (!world.move_object) return make_error(ErrorCode::kInvalidArgument, "the world '" + world.name + "' has no movable objects");
  if (const auto model = world.movable_models.find(name); model != world.movable_models.end()) {
    for (const auto& part : model->second) {
      if (auto moved = world.move_object(part.object, pose_world * part.pose_in_model); !moved) {
        return moved.error().with_context("world '" + world.name + "', model '" + name + "'");
      }
    }
    return Ok{};
  }
  if (auto moved = world.move_object(name, pose_world); !moved) return moved.error().with_context("world '" + world.name + "'");
  return Ok{};
}

Status move_models_to(LoadedWorld& world, const GnssTime& time) {
  for (const auto& [model, trajectory] : world.moving) {
    if (auto st = set_object_pose(world, model, trajectory.at(time)); !st) return st;
  }
  return Ok{};
}

Status check_outside_objects(const LoadedWorld& world, const Eigen::Vector3d& position_ecef_m, const std::string& receiver_name) {
  // 26 directions: the faces, edges and corners of a cube, the zenith first.
  std::vector<Eigen::Vector3d> directions = {Eigen::Vector3d::UnitZ()};
  for (int x = -1; x <= 1; ++x) {
    for (int y = -1; y <= 1; ++y) {
      for (int z = -1; z <= 1; ++z) {
        if ((x != 0 || y != 0 || z != 0) && !(x == 0 && y == 0 && z == 1)) {
          directions.push_back(Eigen::Vector3d(x, y, z).normalized());
        }
      }
    }
  }
  const Eigen::Vector3d origin = world.frame.from_ecef(position_ecef_m);
  const auto outcomes = world.scene->trace(origin, directions);
  // Inside a closed object every ray first meets that object. Scene outcomes give the normal turned
  // towards the origin, not the winding, so the test is: the zenith and nearly every other
  // direction end on the same object (a doorway or a slit may let one or two rays out).
  if (!outcomes.front().blocked) return Ok{};
  const std::string roof(outcomes.front().blocking_object);
  const auto same = std::count_if(outcomes.begin(), outcomes.end(),
                                  [&](const RayOutcome& o) { return o.blocked && o.blocking_object == roof; });
  if (same >= 24) {
    return make_error(ErrorCode::kParse, "receiver '" + receiver_name + "' is inside the object '" + roof +
                                             "' of the world (world frame " + std::to_string(origin.x()) + ", " +
                                             std::to_string(origin.y()) + ", " + std::to_string(origin.z()) + " m)");
  }
  return Ok{};
}

Result<std::vector<double>> world_sky_mask_deg(const LoadedWorld& world, const Eigen::Vector3d& position_ecef_m,
                                               double azimuth_step_deg) {
  // The sky mask is drawn in the receiver's azimuths; the world frame's x axis is `heading` from east.
  auto mask = world::sky_mask_elevation_deg(*world.scene, world.frame.from_ecef(position_ecef_m), azimuth_step_deg);
  if (!mask || world.frame.heading_deg == 0.0) return mask;
  // Rotate: world-frame azimuths are measured from the world's y axis; shift to north.
  const auto n = static_cast<long>(mask->size());
  std::vector<double> rotated(mask->size());
  const long shift = std::lround(-world.frame.heading_deg / azimuth_step_deg);
  for (long i = 0; i < n; ++i) rotated[static_cast<size_t>(((i + shift) % n + n) % n)] = (*mask)[static_cast<size_t>(i)];
  return rotated;
}

}  // namespace skytrace::sim

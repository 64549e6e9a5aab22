#include "skytrace/sim/scenario.hpp"

#include "skytrace/core/yaml_field.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

#include "skytrace/core/text_file.hpp"
#include "skytrace/world/loaders.hpp"

namespace skytrace::sim {

const std::vector<IqBand>& iq_bands() {
  // Main lobes: L1 C/A 2.046 MHz; E1's BOC(1,1) +-2.046 MHz; GLONASS L1OF's channels -7..+6 at
  // 562.5 kHz around 1602 MHz with +-0.511 MHz each (-4.45 to +3.89 MHz); B1I 2.046 Mchip/s.
  static const std::vector<IqBand> bands = {
      {"L1", "G1C", "GPS L1 C/A", 2.046e6},
      {"E1", "E1C", "Galileo E1 OS", 4.092e6},
      {"G1", "R1C", "GLONASS L1OF", 8.9e6},
      {"B1", "C2I", "BeiDou B1I", 4.092e6},
  };
  return bands;
}

const IqBand* find_iq_band(const std::string& name) {
  for (const IqBand& band : iq_bands()) {
    if (name == band.name) return &band;
  }
  return nullptr;
}

namespace {

// Scenario keys with their path and line in every message (core/yaml_field.hpp).
using Node = YamlField;

std::filesystem::path resolve(const std::filesystem::path& base, const std::string& text) {
  std::filesystem::path p(text);
  if (p.is_relative()) p = base / p;
  return p.lexically_normal();
}

std::filesystem::path existing_file(const Node& node, const std::filesystem::path& base) {
  const auto p = resolve(base, node.as_string());
  if (std::string why = why_not_an_input_file(p); !why.empty()) {
    std::error_code ec;
    node.fail(std::filesystem::exists(p, ec) ? why : "file not found: " + p.string());  // a folder, a device
  }
  return p;
}

PositionSetting parse_position(const Node& node) {
  node.expect_keys({"ecef_m", "lla_deg_m", "world_enu_m"});
  PositionSetting position;
  int forms = 0;
  if (auto c = node.child("ecef_m")) {
    position = {PositionSetting::Kind::kEcef, c->as_vector3()};
    const double radius_m = position.value.norm();
    if (radius_m < 6.3e6) c->fail("position is below the Earth's surface (|r| = " + std::to_string(radius_m) + " m)");
    if (radius_m > 5e7) c->fail("position is farther than 50000 km from the Earth's centre");
    ++forms;
  }
  if (auto c = node.child("lla_deg_m")) {
    position = {PositionSetting::Kind::kLla, c->as_vector3()};
    if (std::fabs(position.value.x()) > 90.0) c->fail("latitude must be within [-90, 90] degrees");
    if (std::fabs(position.value.y()) > 360.0) c->fail("longitude must be within [-360, 360] degrees");
    if (position.value.z() < -500.0) c->fail("height " + std::to_string(position.value.z()) + " m is below the Earth's surface");
    if (position.value.z() > 4.4e7) c->fail("height " + std::to_string(position.value.z()) + " m is above the GNSS orbits");
    ++forms;
  }
  if (auto c = node.child("world_enu_m")) {
    position = {PositionSetting::Kind::kWorldEnu, c->as_vector3()};
    if (position.value.norm() > kMaxWorldDistance_m) c->fail("position is more than 1000 km from the world's origin");
    ++forms;
  }
  if (forms != 1) node.fail("give exactly one of ecef_m, lla_deg_m, world_enu_m");
  return position;
}

PositionSetting::Kind parse_frame(const Node& node) {
  const std::string frame = node.as_choice({"ecef", "lla", "world_enu"});
  if (frame == "ecef") return PositionSetting::Kind::kEcef;
  if (frame == "lla") return PositionSetting::Kind::kLla;
  return PositionSetting::Kind::kWorldEnu;
}

ReceiverSettings parse_receiver(const Node& node, const std::filesystem::path& base, const std::string& default_name) {
  node.expect_keys({"name", "position", "trajectory", "antenna_height_m", "antenna_offset_en_m", "elevation_mask_deg",
                    "profile", "antenna", "signals", "receiver_type", "antenna_type", "antex", "rtk"});
  ReceiverSettings r;
  r.name = default_name;
  if (auto c = node.child("name")) {
    r.name = c->as_string();
    // The name becomes part of file names (obs_NAME.rnx): no folders, no hidden files.
    const bool safe = !r.name.empty() && r.name.size() <= 64 && r.name.front() != '.' &&
                      std::all_of(r.name.begin(), r.name.end(), [](unsigned char ch) {
                        return std::isalnum(ch) || ch == '_' || ch == '-' || ch == '.';
                      });
    if (!safe) c->fail("receiver name '" + r.name + "': expected 1-64 letters, digits, '_', '-' or '.' (it names output files)");
  }
  if (auto c = node.child("position")) r.position = parse_position(*c);
  if (auto c = node.child("trajectory")) {
    c->expect_keys({"file", "frame", "time_scale"});
    TrajectorySetting t;
    t.file = existing_file(c->required("file"), base);
    if (auto f = c->child("frame")) t.frame = parse_frame(*f);
    if (auto s = c->child("time_scale")) {
      auto scale = parse_time_scale(s->as_string());
      if (!scale) s->fail(scale.error().message);
      t.time_scale = *scale;
    }
    r.trajectory = t;
  }
  if (!r.position && !r.trajectory) node.fail("give receiver.position or receiver.trajectory");
  if (r.position && r.trajectory) node.fail("give either receiver.position or receiver.trajectory, not both");
  if (auto c = node.child("antenna_height_m")) r.antenna_height_m = c->as_double_in(-100.0, 1000.0);
  if (auto c = node.child("antenna_offset_en_m")) {
    auto items = c->elements();
    if (items.size() != 2) c->fail("expected [east_m, north_m]");
    r.antenna_offset_en_m = {items[0].as_double(), items[1].as_double()};
  }
  if (auto c = node.child("elevation_mask_deg")) r.elevation_mask_deg = c->as_double_in(-10.0, 90.0);
  if (auto c = node.child("profile")) r.profile = c->as_string();
  if (auto c = node.child("antenna")) {
    r.antenna = c->as_string();
    if (r.antenna.empty()) c->fail("expected an antenna profile's name, path or IGS name");
  }
  const Node signals = node.required("signals");
  for (const Node& s : signals.elements()) {
    auto signal = Signal::parse(s.as_string());
    if (!signal) s.fail(signal.error().message);
    if (std::find(r.signals.begin(), r.signals.end(), *signal) != r.signals.end()) {
      s.fail("signal " + signal->to_string() + " listed twice");
    }
    r.signals.push_back(*signal);
  }
  if (r.signals.empty()) signals.fail("list at least one signal");
  if (auto c = node.child("receiver_type")) r.receiver_type = c->as_string();
  if (auto c = node.child("antenna_type")) r.antenna_type = c->as_string();
  if (auto c = node.child("antex")) r.antex = existing_file(*c, base);
  if (auto c = node.child("rtk")) {
    c->expect_keys({"base", "latency_s", "interval_s", "outages_s", "moving_base"});
    RtkSettings rtk;
    rtk.base = c->required("base").as_string();
    if (auto v = c->child("latency_s")) rtk.latency_s = v->as_double_in(0.0, 60.0);
    if (auto v = c->child("moving_base")) rtk.moving_base = v->as_bool();
    if (auto v = c->child("interval_s")) rtk.interval_s = v->as_double_in(0.0, 3600.0);
    if (auto v = c->child("outages_s")) {
      for (const auto& interval : v->elements()) {
        const auto bounds = interval.elements();
        if (bounds.size() != 2) interval.fail("expected [from_s, to_s], seconds after the start");
        const double from_s = bounds[0].as_double_in(0.0, 1e9), to_s = bounds[1].as_double_in(0.0, 1e9);
        if (!(to_s > from_s)) interval.fail("an outage must end after it begins");
        rtk.outages_s.emplace_back(from_s, to_s);
      }
    }
    r.rtk = rtk;
  }
  return r;
}

std::string parse_kind(const Node& node) { return node.as_choice({"building", "tree", "ground", "other"}); }

MaterialClass parse_class(const Node& node) {
  auto parsed = world::parse_material_class(node.as_string());
  if (!parsed) node.fail(parsed.error().message);
  return *parsed;
}

MeshSetting parse_mesh(const Node& node, const std::filesystem::path& base) {
  node.expect_keys({"file", "name", "position_m", "rpy_deg", "scale", "up_axis", "kind", "material"});
  MeshSetting m;
  m.file = existing_file(node.required("file"), base);
  m.name = m.file.filename().string();
  if (auto c = node.child("name")) {
    m.name = c->as_string();
    if (m.name.empty() || m.name.find('/') != std::string::npos) c->fail("expected a name without '/'");
  }
  if (auto c = node.child("position_m")) m.position_m = c->as_vector3();
  if (auto c = node.child("rpy_deg")) m.rpy_deg = c->as_vector3();
  if (auto c = node.child("scale")) {
    m.scale = c->as_double();
    if (!(m.scale > 0.0)) c->fail("expected a scale above 0");
  }
  if (auto c = node.child("up_axis")) m.up_axis = c->as_choice({"auto", "y", "z"});
  if (auto c = node.child("kind")) m.kind = parse_kind(*c);
  if (auto c = node.child("material")) {
    m.material = parse_class(*c);
    if (m.material == MaterialClass::kVegetation) c->fail("give vegetation through world.materials or kind: tree");
  }
  return m;
}

MaterialRuleSetting parse_material_rule(const Node& node) {
  node.expect_keys({"match", "class", "attenuation_db_per_m", "kind"});
  MaterialRuleSetting rule;
  rule.match = node.required("match").as_string();
  if (rule.match.empty()) node.required("match").fail("expected a name pattern such as \"glass*\"");
  rule.material_class = parse_class(node.required("class"));
  if (auto c = node.child("attenuation_db_per_m")) {
    if (rule.material_class != MaterialClass::kVegetation) c->fail("only vegetation has an attenuation (class: vegetation)");
    rule.attenuation_db_per_m = c->as_double_in(0.0, 1000.0);
  }
  if (auto c = node.child("kind")) rule.kind = parse_kind(*c);
  return rule;
}

void parse_world(const Node& world, const std::filesystem::path& base, WorldSettings& w) {
  world.expect_keys({"sdf", "model_paths", "osm", "footprints", "footprint_height_field", "cityjson",
                     "cityjson_height_offset_m", "citygml", "citygml_height_offset_m", "dem", "dem_height_offset_m", "meshes", "materials", "moving",
                     "vegetation_attenuation_db_per_m", "vegetation_hull_tolerance_m", "surroundings_height_m",
                     "latitude_deg", "longitude_deg", "elevation_m", "heading_deg"});
  if (auto c = world.child("sdf")) w.sdf = existing_file(*c, base);
  if (auto c = world.child("model_paths")) {
    for (const Node& p : c->as_list_or_single()) w.model_paths.push_back(resolve(base, p.as_string()));
  }
  if (auto c = world.child("osm")) w.osm = existing_file(*c, base);
  if (auto c = world.child("footprints")) w.footprints = existing_file(*c, base);
  if (auto c = world.child("cityjson")) w.cityjson = existing_file(*c, base);
  if (auto c = world.child("cityjson_height_offset_m")) {
    if (!w.cityjson) c->fail("needs world.cityjson");
    w.cityjson_height_offset_m = c->as_double_in(-500.0, 10000.0);
  }
  if (auto c = world.child("citygml")) w.citygml = existing_file(*c, base);
  if (auto c = world.child("citygml_height_offset_m")) {
    if (!w.citygml) c->fail("needs world.citygml");
    w.citygml_height_offset_m = c->as_double_in(-500.0, 10000.0);
  }
  if (auto c = world.child("dem")) w.dem = existing_file(*c, base);
  if (auto c = world.child("dem_height_offset_m")) {
    if (!w.dem) c->fail("needs world.dem");
    w.dem_height_offset_m = c->as_double_in(-500.0, 10000.0);
  }
  if (auto c = world.child("footprint_height_field")) {
    if (!w.footprints) c->fail("needs world.footprints");
    w.footprint_height_field = c->as_string();
  }
  if (auto c = world.child("meshes")) {
    for (const Node& m : c->elements()) {
      w.meshes.push_back(parse_mesh(m, base));
      for (size_t i = 0; i + 1 < w.meshes.size(); ++i) {
        if (w.meshes[i].name == w.meshes.back().name) m.fail("two meshes named '" + w.meshes[i].name + "': give each a name");
      }
    }
  }
  if (auto c = world.child("materials")) {
    for (const Node& m : c->elements()) w.materials.push_back(parse_material_rule(m));
  }
  if (auto c = world.child("vegetation_attenuation_db_per_m")) w.vegetation_attenuation_db_per_m = c->as_double_in(0.0, 1000.0);
  if (auto c = world.child("vegetation_hull_tolerance_m")) w.vegetation_hull_tolerance_m = c->as_double_in(0.0, 10.0);
  if (auto c = world.child("surroundings_height_m")) w.surroundings_height_m = c->as_double_in(0.0, 1000.0);
  if (auto c = world.child("latitude_deg")) w.latitude_deg = c->as_double_in(-90.0, 90.0);
  if (auto c = world.child("longitude_deg")) w.longitude_deg = c->as_double_in(-360.0, 360.0);
  if (auto c = world.child("elevation_m")) w.elevation_m = c->as_double_in(-500.0, 10000.0);
  if (auto c = world.child("heading_deg")) w.heading_deg = c->as_double_in(-360.0, 360.0);
  if (w.latitude_deg.has_value() != w.longitude_deg.has_value()) {
    world.fail("give both world.latitude_deg and world.longitude_deg, or neither");
  }
  if (!w.meshes.empty() && !w.sdf && !w.osm && !w.footprints && !w.cityjson && !w.citygml && !w.dem && !w.latitude_deg) {
    world.required("meshes").fail("meshes are placed in the world frame: give world.latitude_deg and world.longitude_deg "
                                  "(and elevation_m, heading_deg), or a world.sdf / world.osm that has an origin");
  }
  if (auto c = world.child("moving")) {
    if (!w.any()) c->fail("moving models need a world (world.sdf, world.osm or world.meshes)");
    for (const Node& m : c->elements()) {
      m.expect_keys({"model", "trajectory", "time_scale"});
      MovingModelSetting moving;
      moving.model = m.required("model").as_string();
      moving.trajectory = existing_file(m.required("trajectory"), base);
      if (auto t = m.child("time_scale")) {
        auto scale = parse_time_scale(t->as_string());
        if (!scale) t->fail(scale.error().message);
        moving.time_scale = *scale;
      }
      for (const auto& other : w.moving) {
        if (other.model == moving.model) m.required("model").fail("model '" + moving.model + "' is listed twice");
      }
      w.moving.push_back(std::move(moving));
    }
  }
}

Scenario parse_root(const Node& root, const std::filesystem::path& base) {
  root.expect_keys({"name", "time", "receiver", "receivers", "ephemeris", "models", "world", "output", "seed"});
  Scenario s;
  if (auto c = root.child("name")) s.name = c->as_string();

  const Node time = root.required("time");
  time.expect_keys({"start", "scale", "duration_s", "interval_s"});
  if (auto c = time.child("scale")) {
    auto scale = parse_time_scale(c->as_string());
    if (!scale) c->fail(scale.error().message);
    s.time.scale = *scale;
  }
  {
    const Node start = time.required("start");
    auto t = GnssTime::parse_iso8601(start.as_string(), s.time.scale);
    if (!t) start.fail(t.error().message);
    s.time.start = *t;
  }
  if (auto c = time.child("duration_s")) s.time.duration_s = c->as_double_in(0.0, 366.0 * 86400.0);
  if (auto c = time.child("interval_s")) s.time.interval_s = c->as_double_in(1e-3, 86400.0);

  // One or the other (docs/scenario.md): with both, the receivers' places in the file and in the
  // list would no longer match (found by the scenario fuzzer).
  if (root.child("receiver") && root.child("receivers")) {
    root.fail("give 'receiver' (one receiver) or 'receivers' (a list), not both");
  }
  if (auto c = root.child("receiver")) s.receivers.push_back(parse_receiver(*c, base, s.name.substr(0, 4)));
  if (auto c = root.child("receivers")) {
    int index = 0;
    for (const Node& r : c->elements()) s.receivers.push_back(parse_receiver(r, base, "RX" + std::to_string(++index)));
  }
  if (s.receivers.empty()) root.fail("missing required key 'receiver' (or 'receivers')");
  for (size_t i = 0; i < s.receivers.size(); ++i) {
    const auto& r = s.receivers[i];
    if (!r.rtk) continue;
    const auto base_receiver = std::find_if(s.receivers.begin(), s.receivers.end(),
                                   [&](const ReceiverSettings& other) { return other.name == r.rtk->base; });
    const Node where = root.child("receivers") ? root.required("receivers").elements()[i].required("rtk").required("base")
                                               : root.required("receiver").required("rtk").required("base");
    if (base_receiver == s.receivers.end()) where.fail("rtk base '" + r.rtk->base + "' is not a receiver of this scenario");
    if (base_receiver->name == r.name) where.fail("a receiver cannot be its own rtk base");
    if (base_receiver->rtk) where.fail("rtk base '" + r.rtk->base + "' has an rtk base itself (chains are not supported)");
  }
  if (auto c = root.child("receivers")) {
    // Each receiver's outputs are named after it (obs_NAME.rnx): two of one name would overwrite.
    const auto elements = c->elements();
    for (size_t i = 0; i < s.receivers.size(); ++i) {
      for (size_t k = 0; k < i; ++k) {
        if (s.receivers[i].name == s.receivers[k].name) {
          elements[std::min(i, elements.size() - 1)].fail("receiver name '" + s.receivers[i].name +
                                                           "' is also receiver " + std::to_string(k + 1) +
                                                           "'s: names must be unique (they name the output files)");
        }
      }
    }
  }

  const Node ephemeris = root.required("ephemeris");
  ephemeris.expect_keys({"navigation", "precise_orbits", "precise_clocks", "nominal"});
  if (auto c = ephemeris.child("navigation")) {
    for (const Node& f : c->as_list_or_single()) s.ephemeris.navigation.push_back(existing_file(f, base));
  }
  if (auto c = ephemeris.child("precise_orbits")) {
    for (const Node& f : c->as_list_or_single()) s.ephemeris.precise_orbits.push_back(existing_file(f, base));
  }
  if (auto c = ephemeris.child("precise_clocks")) {
    for (const Node& f : c->as_list_or_single()) s.ephemeris.precise_clocks.push_back(existing_file(f, base));
  }
  if (auto c = ephemeris.child("nominal")) s.ephemeris.nominal = c->as_bool();
  if (s.ephemeris.navigation.empty() && !s.ephemeris.nominal) {
    ephemeris.fail("give ephemeris.navigation files or set ephemeris.nominal: true");
  }
  if (!s.ephemeris.navigation.empty() && s.ephemeris.nominal) {
    ephemeris.fail("ephemeris.nominal cannot be combined with navigation files");
  }
  if (!s.ephemeris.precise_clocks.empty() && s.ephemeris.precise_orbits.empty()) {
    ephemeris.fail("ephemeris.precise_clocks needs ephemeris.precise_orbits");
  }

  if (auto models = root.child("models")) {
    models->expect_keys({"ionosphere", "ionex_file", "troposphere", "receiver_clock", "noise", "multipath",
                         "multipath_radius_m", "multipath_order", "multipath_order2_radius_m", "diffraction", "scattering_coefficient",
                         "scattering_lobe_exponent", "scattering_radius_m", "static_sky_cell_deg", "moving_cell_m", "ionosphere_residual_ppm",
                         "ionosphere_residual_length_km", "troposphere_residual_ppm", "troposphere_residual_length_km",
                         "foliage_fading", "foliage_diffuse_db", "foliage_wind_spread_hz"});
    if (auto c = models->child("ionosphere")) s.models.ionosphere = c->as_choice({"none", "klobuchar", "ionex"});
    if (auto c = models->child("ionex_file")) s.models.ionex_file = existing_file(*c, base);
    if (s.models.ionosphere == "ionex" && !s.models.ionex_file) {
      models->fail("models.ionosphere is ionex: give the map in models.ionex_file");
    }
    if (auto c = models->child("troposphere")) s.models.troposphere = c->as_choice({"none", "saastamoinen", "unb3m"});
    if (auto c = models->child("receiver_clock")) {
      s.models.receiver_clock = c->as_choice({"ideal", "profile", "tcxo", "ocxo"});
    }
    if (auto c = models->child("noise")) s.models.noise = c->as_bool();
    if (auto c = models->child("multipath")) s.models.multipath = c->as_bool();
    if (auto c = models->child("multipath_radius_m")) s.models.multipath_radius_m = c->as_double_in(1.0, 5000.0);
    if (auto c = models->child("multipath_order")) {
      const double order = c->as_double_in(0.0, 2.0);
      if (order != std::floor(order)) c->fail("must be 0, 1 or 2");
      s.models.multipath_order = static_cast<int>(order);
    }
    if (auto c = models->child("multipath_order2_radius_m")) {
      s.models.multipath_order2_radius_m = c->as_double_in(1.0, 5000.0);
    }
    if (auto c = models->child("diffraction")) s.models.diffraction = c->as_bool();
    if (auto c = models->child("scattering_coefficient")) s.models.scattering_coefficient = c->as_double_in(0.0, 1.0);
    if (auto c = models->child("scattering_lobe_exponent")) s.models.scattering_lobe_exponent = c->as_int_in(0, 20);
    if (auto c = models->child("scattering_radius_m")) s.models.scattering_radius_m = c->as_double_in(1.0, 1000.0);
    if (auto c = models->child("static_sky_cell_deg")) {
      s.models.static_sky_cell_deg = c->as_double_in(0.0, 1.0);
      if (s.models.static_sky_cell_deg > 0.0 && s.models.static_sky_cell_deg < 1e-3) c->fail("must be 0 or 0.001 to 1");
    }
    if (auto c = models->child("moving_cell_m")) {
      s.models.moving_cell_m = c->as_double_in(0.0, 20.0);
      if (s.models.moving_cell_m > 0.0 && s.models.moving_cell_m < 0.1) c->fail("must be 0 or 0.1 to 20");
    }
    if (auto c = models->child("ionosphere_residual_ppm")) s.models.ionosphere_residual_ppm = c->as_double_in(0.0, 50.0);
    if (auto c = models->child("ionosphere_residual_length_km")) {
      s.models.ionosphere_residual_length_km = c->as_double_in(10.0, 5000.0);
    }
    if (auto c = models->child("troposphere_residual_ppm")) s.models.troposphere_residual_ppm = c->as_double_in(0.0, 10.0);
    if (auto c = models->child("troposphere_residual_length_km")) {
      s.models.troposphere_residual_length_km = c->as_double_in(1.0, 1000.0);
    }
    if (auto c = models->child("foliage_fading")) s.models.foliage_fading = c->as_bool();
    if (auto c = models->child("foliage_diffuse_db")) s.models.foliage_diffuse_db = c->as_double_in(-40.0, -3.0);
    if (auto c = models->child("foliage_wind_spread_hz")) s.models.foliage_wind_spread_hz = c->as_double_in(0.0, 20.0);
  }

  if (auto world = root.child("world")) parse_world(*world, base, s.world);
  for (const auto& r : s.receivers) {
    const bool needs_world = (r.position && r.position->kind == PositionSetting::Kind::kWorldEnu) ||
                             (r.trajectory && r.trajectory->frame == PositionSetting::Kind::kWorldEnu);
    if (needs_world && !s.world.sdf && !s.world.osm && !s.world.footprints && !s.world.cityjson && !s.world.citygml && !s.world.dem &&
        !(s.world.latitude_deg && s.world.longitude_deg)) {
      root.fail("receiver '" + r.name +
                "' uses world_enu_m coordinates: give world.sdf, world.osm, world.footprints or "
                "world.latitude_deg/longitude_deg");
    }
  }

  if (auto output = root.child("output")) {
    output->expect_keys({"rinex_version", "fix", "nmea", "rtcm3", "mcap", "mcap_compression", "truth_format", "iq"});
    if (auto c = output->child("rinex_version")) s.output.rinex_version = c->as_choice({"3.04", "4.00"});
    if (auto c = output->child("fix")) s.output.fix = c->as_bool();
    if (auto c = output->child("nmea")) s.output.nmea = c->as_bool();
    if (auto c = output->child("rtcm3")) s.output.rtcm3 = c->as_bool();
    if (auto c = output->child("mcap")) s.output.mcap = c->as_bool();
    if (auto c = output->child("mcap_compression")) s.output.mcap_compression = c->as_choice({"zstd", "lz4", "none"});
    if (auto c = output->child("truth_format")) s.output.truth_format = c->as_choice({"csv.zst", "csv"});
    if (auto iq = output->child("iq")) {
      iq->expect_keys({"sample_rate_hz", "format", "bands"});
      IqSettings settings;
      // L1 C/A's main lobe is 2.046 MHz wide: complex samples need at least that rate.
      if (auto c = iq->child("sample_rate_hz")) settings.sample_rate_hz = c->as_double_in(2.046e6, 100e6);
      if (auto c = iq->child("format")) settings.format = c->as_choice({"sc8", "sc16", "gr_complex"});
      if (auto c = iq->child("bands")) {
        settings.bands.clear();
        for (const auto& band : c->as_list_or_single()) {
          const std::string name = band.as_string();
          if (find_iq_band(name) == nullptr) {
            std::string names;
            for (const IqBand& b : iq_bands()) names += std::string(names.empty() ? "" : ", ") + b.name;
            band.fail("unknown value '" + name + "' (expected one of: " + names + ")");
          }
          if (std::find(settings.bands.begin(), settings.bands.end(), name) == settings.bands.end()) {
            settings.bands.push_back(name);
          }
        }
      }
      for (const std::string& band : settings.bands) {
        const IqBand& spec = *find_iq_band(band);
        if (settings.sample_rate_hz < spec.min_sample_rate_hz) {
          iq->fail(fmt::format("sample_rate_hz {:.6g}: band {} needs at least {:.4g} complex samples/s", settings.sample_rate_hz,
                               band, spec.min_sample_rate_hz));
        }
        const bool tracks = !s.receivers.empty() &&
                            std::any_of(s.receivers.front().signals.begin(), s.receivers.front().signals.end(),
                                        [&](const Signal& sig) { return sig.to_string() == spec.signal; });
        if (!tracks) {
          iq->fail("band " + band + " (" + spec.description + "): the first receiver does not list signal " + spec.signal +
                   " in receiver.signals");
        }
      }
      s.output.iq = settings;
    }
  }
  if (auto c = root.child("seed")) {
    const double seed = c->as_double_in(0.0, 1.8e19);
    if (seed != std::floor(seed)) c->fail("expected a whole number");
    s.seed = static_cast<std::uint64_t>(seed);
  }
  return s;
}

}  // namespace

namespace {

// Sets `a.b.c=value` in the YAML tree (value parsed as YAML), creating missing mappings, and
// appends what it set to `set_values`.
Status apply_override(YAML::Node& root, const ScenarioOverride& given, std::vector<YamlOverride>& set_values) {
  const std::string& assignment = given.assignment;
  const auto equals = assignment.find('=');
  if (equals == std::string::npos || equals == 0) {
    return make_error(ErrorCode::kInvalidArgument, "--set '" + assignment + "': expected KEY.PATH=VALUE");
  }
  const std::string path = assignment.substr(0, equals);
  YAML::Node value;
  try {
    value = YAML::Load(assignment.substr(equals + 1));
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kInvalidArgument, "--set " + path + ": the value is not valid YAML: " + e.msg);
  }
  std::vector<std::string> keys;
  for (size_t start = 0;;) {
    const auto dot = path.find('.', start);
    keys.push_back(path.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
    if (keys.back().empty()) return make_error(ErrorCode::kInvalidArgument, "--set " + path + ": empty key in the path");
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  YAML::Node node;
  node.reset(root);
  std::string walked;  // the key path of `node`
  // A key of a list is an index from 0: receivers.1.rtk.latency_s.
  const auto list_index = [&](const std::string& key) -> std::optional<size_t> {
    if (!node.IsSequence()) return std::nullopt;
    if (key.empty() || key.size() > 6 || !std::all_of(key.begin(), key.end(), [](unsigned char c) { return std::isdigit(c); })) {
      return std::nullopt;
    }
    const size_t index = std::stoul(key);
    if (index >= node.size()) return std::nullopt;
    return index;
  };
  std::string field_path;  // the path as the parser names it, an index of a list in brackets
  for (size_t i = 0; i < keys.size(); ++i) {
    if (node.IsSequence()) {
      if (!list_index(keys[i])) {
        return make_error(ErrorCode::kInvalidArgument, "--set " + path + ": '" + walked + "' is a list of " +
                                                           std::to_string(node.size()) + ": '" + keys[i] +
                                                           "' is not an index from 0 to " + std::to_string(node.size() - 1));
      }
    } else if (node.IsDefined() && !node.IsMap() && !node.IsNull()) {
      return make_error(ErrorCode::kInvalidArgument,
                        "--set " + path + ": " + (walked.empty() ? "the document" : "'" + walked + "'") + " is not a mapping");
    }
    if (node.IsSequence()) {
      field_path.append(1, '[').append(std::to_string(*list_index(keys[i]))).append(1, ']');
    } else {
      field_path.append(field_path.empty() ? "" : ".").append(keys[i]);
    }
    if (i + 1 == keys.size()) break;
    walked += (walked.empty() ? "" : ".") + keys[i];
    YAML::Node child = node.IsSequence() ? node[*list_index(keys[i])] : node[keys[i]];
    node.reset(child);
  }
  if (node.IsSequence()) {
    node[*list_index(keys.back())] = value;
  } else {
    node[keys.back()] = value;
  }
  set_values.push_back({field_path, given.option});
  return Ok{};
}

}  // namespace

std::vector<ScenarioOverride> overrides_given_with_set(const std::vector<std::string>& assignments) {
  std::vector<ScenarioOverride> out;
  out.reserve(assignments.size());
  for (const std::string& assignment : assignments) out.push_back({assignment, "--set " + assignment});
  return out;
}

Result<Scenario> parse_scenario(const std::string& text, const std::string& name, const std::filesystem::path& base_dir,
                                const std::vector<std::string>& overrides) {
  return parse_scenario_with_options(text, name, base_dir, overrides_given_with_set(overrides));
}

Result<Scenario> parse_scenario_with_options(const std::string& text, const std::string& name,
                                             const std::filesystem::path& base_dir,
                                             const std::vector<ScenarioOverride>& overrides) {
  auto document = load_yaml_document(text, name);
  if (!document) return document.error();
  YAML::Node root = std::move(*document);
  std::vector<YamlOverride> set_values;
  for (const ScenarioOverride& given : overrides) {
    if (auto st = apply_override(root, given, set_values); !st) return st.error().with_context(name);
  }
  try {
    Scenario s = parse_root(Node(root, "", &name, "scenario", &set_values), base_dir);
    return s;
  } catch (const YamlFieldError& e) {
    return make_error(ErrorCode::kParse, e.message);
  } catch (const YAML::Exception& e) {
    return make_error(ErrorCode::kParse, name + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
}

Result<size_t> find_receiver(const Scenario& scenario, std::string_view name) {
  std::string names;
  for (size_t i = 0; i < scenario.receivers.size(); ++i) {
    if (scenario.receivers[i].name == name) return i;
    names += (i > 0 ? ", " : "") + scenario.receivers[i].name;
  }
  return make_error(ErrorCode::kInvalidArgument,
                    "receiver '" + std::string(name) + "': no such receiver in " + scenario.name + " (it has " + names + ")");
}

Result<Scenario> load_scenario(const std::filesystem::path& path, const std::vector<std::string>& overrides) {
  return load_scenario_with_options(path, overrides_given_with_set(overrides));
}

Result<Scenario> load_scenario_with_options(const std::filesystem::path& path, const std::vector<ScenarioOverride>& overrides) {
  auto text = read_text_file(path);
  if (!text) return text.error();
  auto scenario = parse_scenario_with_options(*text, path.string(), path.parent_path(), overrides);
  if (scenario) scenario->source = path;
  return scenario;
}

std::string scenario_to_json(const Scenario& s) {
  using nlohmann::json;
  auto kind_name = [](PositionSetting::Kind k) {
    switch (k) {
      case PositionSetting::Kind::kEcef: return "ecef_m";
      case PositionSetting::Kind::kLla: return "lla_deg_m";
      case PositionSetting::Kind::kWorldEnu: return "world_enu_m";
    }
    return "?";
  };
  auto paths = [](const std::vector<std::filesystem::path>& v) {
    json a = json::array();
    for (const auto& p : v) a.push_back(p.string());
    return a;
  };
  json j;
  j["name"] = s.name;
  j["time"] = {{"start", s.time.start.to_iso8601(s.time.scale, 3)},
               {"scale", std::string(to_string(s.time.scale))},
               {"duration_s", s.time.duration_s},
               {"interval_s", s.time.interval_s}};
  j["receivers"] = json::array();
  for (const auto& r : s.receivers) {
    json jr;
    jr["name"] = r.name;
    if (r.position) jr["position"][kind_name(r.position->kind)] = {r.position->value.x(), r.position->value.y(), r.position->value.z()};
    if (r.trajectory) {
      jr["trajectory"] = {{"file", r.trajectory->file.string()},
                          {"frame", kind_name(r.trajectory->frame)},
                          {"time_scale", std::string(to_string(r.trajectory->time_scale))}};
    }
    jr["antenna_height_m"] = r.antenna_height_m;
    jr["antenna_offset_en_m"] = {r.antenna_offset_en_m.x(), r.antenna_offset_en_m.y()};
    jr["elevation_mask_deg"] = r.elevation_mask_deg;
    jr["profile"] = r.profile;
    if (!r.antenna.empty()) jr["antenna"] = r.antenna;
    jr["signals"] = json::array();
    for (const auto& sig : r.signals) jr["signals"].push_back(sig.to_string());
    jr["receiver_type"] = r.receiver_type;
    jr["antenna_type"] = r.antenna_type;
    if (r.antex) jr["antex"] = r.antex->string();
    if (r.rtk) {
      jr["rtk"] = {{"base", r.rtk->base}, {"latency_s", r.rtk->latency_s}, {"interval_s", r.rtk->interval_s},
                   {"outages_s", r.rtk->outages_s}, {"moving_base", r.rtk->moving_base}};
    }
    j["receivers"].push_back(jr);
  }
  j["ephemeris"] = {{"navigation", paths(s.ephemeris.navigation)},
                    {"precise_orbits", paths(s.ephemeris.precise_orbits)},
                    {"precise_clocks", paths(s.ephemeris.precise_clocks)},
                    {"nominal", s.ephemeris.nominal}};
  j["models"] = {{"ionosphere", s.models.ionosphere},
                 {"ionex_file", s.models.ionex_file ? s.models.ionex_file->string() : ""},
                 {"troposphere", s.models.troposphere},
                 {"receiver_clock", s.models.receiver_clock},
                 {"noise", s.models.noise},
                 {"multipath", s.models.multipath},
                 {"multipath_radius_m", s.models.multipath_radius_m},
                 {"multipath_order", s.models.multipath_order},
                 {"multipath_order2_radius_m", s.models.multipath_order2_radius_m},
                 {"diffraction", s.models.diffraction},
                 {"scattering_coefficient", s.models.scattering_coefficient},
                 {"scattering_lobe_exponent", s.models.scattering_lobe_exponent},
                 {"scattering_radius_m", s.models.scattering_radius_m},
                 {"static_sky_cell_deg", s.models.static_sky_cell_deg},
                 {"moving_cell_m", s.models.moving_cell_m},
                 {"ionosphere_residual_ppm", s.models.ionosphere_residual_ppm},
                 {"ionosphere_residual_length_km", s.models.ionosphere_residual_length_km},
                 {"troposphere_residual_ppm", s.models.troposphere_residual_ppm},
                 {"troposphere_residual_length_km", s.models.troposphere_residual_length_km},
                 {"foliage_fading", s.models.foliage_fading},
                 {"foliage_diffuse_db", s.models.foliage_diffuse_db},
                 {"foliage_wind_spread_hz", s.models.foliage_wind_spread_hz}};
  json w;
  if (s.world.sdf) w["sdf"] = s.world.sdf->string();
  w["model_paths"] = paths(s.world.model_paths);
  if (s.world.latitude_deg) w["latitude_deg"] = *s.world.latitude_deg;
  if (s.world.longitude_deg) w["longitude_deg"] = *s.world.longitude_deg;
  if (s.world.elevation_m) w["elevation_m"] = *s.world.elevation_m;
  if (s.world.heading_deg) w["heading_deg"] = *s.world.heading_deg;
  if (s.world.osm) w["osm"] = s.world.osm->string();
  if (s.world.footprints) w["footprints"] = s.world.footprints->string();
  if (!s.world.footprint_height_field.empty()) w["footprint_height_field"] = s.world.footprint_height_field;
  if (s.world.cityjson) w["cityjson"] = s.world.cityjson->string();
  if (s.world.cityjson_height_offset_m) w["cityjson_height_offset_m"] = *s.world.cityjson_height_offset_m;
  if (s.world.citygml) w["citygml"] = s.world.citygml->string();
  if (s.world.citygml_height_offset_m) w["citygml_height_offset_m"] = *s.world.citygml_height_offset_m;
  if (s.world.dem) w["dem"] = s.world.dem->string();
  if (s.world.dem_height_offset_m) w["dem_height_offset_m"] = *s.world.dem_height_offset_m;
  if (s.world.vegetation_attenuation_db_per_m) w["vegetation_attenuation_db_per_m"] = *s.world.vegetation_attenuation_db_per_m;
  if (s.world.vegetation_hull_tolerance_m) w["vegetation_hull_tolerance_m"] = *s.world.vegetation_hull_tolerance_m;
  if (s.world.surroundings_height_m) w["surroundings_height_m"] = *s.world.surroundings_height_m;
  w["meshes"] = json::array();
  for (const auto& m : s.world.meshes) {
    w["meshes"].push_back({{"file", m.file.string()},
                           {"name", m.name},
                           {"position_m", {m.position_m.x(), m.position_m.y(), m.position_m.z()}},
                           {"rpy_deg", {m.rpy_deg.x(), m.rpy_deg.y(), m.rpy_deg.z()}},
                           {"scale", m.scale},
                           {"up_axis", m.up_axis},
                           {"kind", m.kind},
                           {"material", std::string(world::material_class_name(m.material))}});
  }
  w["materials"] = json::array();
  for (const auto& r : s.world.materials) {
    json rule = {{"match", r.match}, {"class", std::string(world::material_class_name(r.material_class))}};
    if (r.attenuation_db_per_m) rule["attenuation_db_per_m"] = *r.attenuation_db_per_m;
    if (r.kind) rule["kind"] = *r.kind;
    w["materials"].push_back(rule);
  }
  w["moving"] = json::array();
  for (const auto& m : s.world.moving) {
    w["moving"].push_back({{"model", m.model},
                           {"trajectory", m.trajectory.string()},
                           {"time_scale", std::string(to_string(m.time_scale))}});
  }
  j["world"] = w;
  j["output"] = {{"rinex_version", s.output.rinex_version},
                 {"fix", s.output.fix},
                 {"nmea", s.output.nmea},
                 {"rtcm3", s.output.rtcm3},
                 {"mcap", s.output.mcap},
                 {"mcap_compression", s.output.mcap_compression},
                 {"truth_format", s.output.truth_format}};
  if (s.output.iq) {
    j["output"]["iq"] = {{"sample_rate_hz", s.output.iq->sample_rate_hz},
                         {"format", s.output.iq->format},
                         {"bands", s.output.iq->bands}};
  }
  j["seed"] = s.seed;
  return j.dump(2);
}

}  // namespace skytrace::sim

// What the world does to a signal: the receiver layer asks, the world layer answers. Defined in
// core so that receiver code (and its tests, with a stub world) never depends on the 3D scene.
#pragma once

#include <Eigen/Core>

#include <cmath>
#include <complex>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace skytrace {

// Electrical class of an opaque surface (for reflections, multipath work) or vegetation.
enum class MaterialClass : std::uint8_t {
  kConcrete, kBrick, kGlass, kMetal, kWood, kGround, kVegetation, kUnknown,
};

struct Material {
  MaterialClass material_class = MaterialClass::kConcrete;
  // Specific attenuation of vegetation along the path (dB per metre); 0 for opaque surfaces.
  double attenuation_db_per_m = 0.0;
  [[nodiscard]] bool is_vegetation() const { return material_class == MaterialClass::kVegetation; }
};

// The fate of one ray from a point towards a direction (to infinity: a satellite).
struct RayOutcome {
  bool blocked = false;
  // When blocked: the first opaque hit.
  double blocking_distance_m = 0.0;
  // World object name (model/link/collision, building id): a view of the name the answering scene
  // holds, valid while that scene lives (copy it to keep it longer). No allocation per ray.
  std::string_view blocking_object;
  MaterialClass blocking_material = MaterialClass::kUnknown;
  Eigen::Vector3d blocking_point_m = Eigen::Vector3d::Zero();  // world frame
  Eigen::Vector3d blocking_normal = Eigen::Vector3d::Zero();   // unit, world frame
  // Vegetation crossed before the first opaque hit (or to infinity): total path length and the
  // attenuation it causes.
  double vegetation_path_m = 0.0;
  double vegetation_attenuation_db = 0.0;
};

// kScattered: diffuse scattering off one rough facade (the incoherent sum of its lit patches that
// the receiver sees), world/propagation.hpp.
enum class PathType : std::uint8_t { kDirect, kReflected, kDiffracted, kScattered };

// One way a satellite's signal reaches the receiver (multipath work, world/propagation.hpp).
struct SignalPath {
  PathType type = PathType::kDirect;
  // Path length minus the direct geometric range (m); >= 0.
  double excess_delay_m = 0.0;
  // Complex field amplitude relative to the unobstructed direct signal (unit RHCP), split into its
  // right- and left-hand circular components at PathSearchSettings::frequency_hz: reflection
  // coefficients, diffraction and vegetation losses, but not the phase of the excess path (the
  // receiver adds -2 pi excess_delay_m / wavelength per signal) nor the receiving antenna's gain.
  std::complex<double> rhcp_amplitude{1.0, 0.0};
  std::complex<double> lhcp_amplitude{0.0, 0.0};
  // Unit vector (world frame) from the receiver towards where the path arrives from.
  Eigen::Vector3d arrival_direction = Eigen::Vector3d::UnitZ();
  // Reflection or diffraction point nearest the receiver (world frame); a second-order reflection
  // also has the one nearest the satellite.
  Eigen::Vector3d point_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d second_point_m = Eigen::Vector3d::Zero();
  int reflections = 0;  // odd: RHCP became mostly LHCP
  MaterialClass material = MaterialClass::kUnknown;
  std::string object;                   // reflecting or diffracting object (last one before the receiver)
  double diffraction_v = 0.0;           // Fresnel-Kirchhoff parameter (diffracted paths, direct with an edge loss)
  double diffraction_loss_db = 0.0;     // ITU-R P.526 knife-edge loss J(v)
  double vegetation_attenuation_db = 0.0;
  // Gradients of excess_delay_m with respect to the receiver position and to the unit direction
  // towards the satellite (world frame): the rate of the excess delay is
  // grad_origin . v_receiver + grad_direction . d(direction)/dt.
  Eigen::Vector3d delay_gradient_origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d delay_gradient_direction = Eigen::Vector3d::Zero();

  [[nodiscard]] double power_linear() const { return std::norm(rhcp_amplitude) + std::norm(lhcp_amplitude); }
  [[nodiscard]] double relative_power_db() const { return 10.0 * std::log10(power_linear()); }
};

struct PathSearchSettings {
  // Reflecting facets whose closest point is within this distance of the receiver.
  double radius_m = 150.0;
  // 0: none, 1: single bounce, 2: also double bounces and (with diffraction) a diffraction combined
  // with one reflection, either way round.
  int max_reflection_order = 1;
  // Double bounces only between facets within this distance (0: radius_m), whose cost grows as the
  // square of the facets within it; a diffraction then a reflection only off them.
  double second_order_radius_m = 0.0;
  bool diffraction = true;       // knife-edge diffraction over building edges
  // Diffraction is for satellites just below an edge: the knife-edge model holds for small angles
  // into the shadow (25 dB: about 14 deg behind an edge 30 m away at L1).
  double max_diffraction_loss_db = 25.0;
  // Carrier frequency for the reflection coefficients and the diffraction parameter.
  double frequency_hz = 1575.42e6;
  // Paths weaker than this (relative to the unobstructed direct signal) are dropped.
  double min_relative_power_db = -35.0;
  // Facets smaller than this reflect no coherent specular signal (smaller than a Fresnel zone,
  // about sqrt(wavelength * distance) ~ 2 m across at 20 m).
  double min_facet_area_m2 = 1.0;
  // Diffuse scattering off facades (effective-roughness model, Lambertian): the scattering
  // coefficient S (0: none); specular reflections keep sqrt(1 - S^2) of their amplitude. Computed for
  // satellites whose direct ray is blocked, from facade patches of about scattering_patch_m across
  // within scattering_radius_m of the receiver.
  double scattering_coefficient = 0.0;
  // 0: Lambertian (cos theta_s); n >= 1: the directive single-lobe model, ((1 + cos psi) / 2)^n
  // around the specular direction, normalised to the same scattered power.
  int scattering_lobe_exponent = 0;
  double scattering_radius_m = 100.0;
  double scattering_patch_m = 2.0;
  // For an antenna that stays at one point (the simulator sets it for receivers at a fixed
  // position, models.static_sky_cell_deg): > 0 searches each direction at the centre of its sky
  // cell of about this size, keeps each cell's paths for the point, and carries every path's excess
  // delay to the direction by its gradient, so that a satellite is searched again only when it
  // enters a new cell. The answer depends on the cell alone, never on what was asked before.
  // 0: every direction is searched as given; cells below 0.001 deg are taken as 0.001 deg.
  double static_sky_cell_deg = 0.0;
  // For an antenna that moves (the simulator sets it for trajectories and live poses,
  // models.moving_cell_m): > 0 searches the direct paths, the single reflections and the knife
  // edges at the antenna as given, and the second-order paths (double bounces, a diffraction with a
  // reflection) and the diffuse scattering, which cost three quarters of a moving search, once per
  // cube of this size (m) that the antenna enters and per sky cell of kMovingSkyCell_deg, at their
  // centres; those paths' excess delays are carried to the antenna and the direction by their
  // gradients. The answer depends on the cells alone. 0: every path searched as given.
  double moving_cell_m = 0.0;
  // The sky cells of a moving antenna's second-order and scattered paths (deg): a cube of a few
  // metres at reflectors 10-30 m away already moves their geometry by several degrees.
  static constexpr double kMovingSkyCell_deg = 2.0;

  [[nodiscard]] bool operator==(const PathSearchSettings&) const = default;
};

// Every path of one satellite: the direct ray's outcome (blocked or not, vegetation) and the
// paths that reach the receiver (the direct path first when it is not blocked).
struct PathSet {
  RayOutcome direct;
  std::vector<SignalPath> paths;
};

// Batched line-of-sight queries in the world frame (local ENU metres of the world origin).
class PathQuery {
 public:
  virtual ~PathQuery() = default;
  // One outcome per direction (unit vectors, world frame) from `origin_m`.
  [[nodiscard]] virtual std::vector<RayOutcome> trace(const Eigen::Vector3d& origin_m,
                                                      const std::vector<Eigen::Vector3d>& directions) const = 0;

  // The line-of-sight question alone, all a receiver without multipath asks: blocked, with
  // blocking_object and blocking_material naming an opaque object on the line (with several, any
  // one of them; distance, point and normal are not filled and blocked rays report no
  // vegetation), or free, with the vegetation crossed. Scenes that answer it faster than trace()
  // override it; this default is trace().
  [[nodiscard]] virtual std::vector<RayOutcome> trace_line_of_sight(const Eigen::Vector3d& origin_m,
                                                                    const std::vector<Eigen::Vector3d>& directions) const {
    return trace(origin_m, directions);
  }
  // The line-of-sight question of one direction from many origins (whether each of many points is
  // lit by a satellite): one outcome per origin, as trace_line_of_sight from that origin alone
  // gives it. Scenes that answer it faster override it; this default asks origin by origin.
  [[nodiscard]] virtual std::vector<RayOutcome> trace_line_of_sight_from(const std::vector<Eigen::Vector3d>& origins_m,
                                                                         const Eigen::Vector3d& direction) const {
    std::vector<RayOutcome> out;
    out.reserve(origins_m.size());
    const std::vector<Eigen::Vector3d> one{direction};
    for (const Eigen::Vector3d& origin_m : origins_m) out.push_back(trace_line_of_sight(origin_m, one).front());
    return out;
  }

  // Every path per direction. This default knows only the direct ray; world::PropagationScene
  // adds reflections and diffraction.
  [[nodiscard]] virtual std::vector<PathSet> paths(const Eigen::Vector3d& origin_m,
                                                   const std::vector<Eigen::Vector3d>& directions,
                                                   const PathSearchSettings& /*settings*/) const {
    std::vector<PathSet> out;
    auto outcomes = trace(origin_m, directions);
    out.reserve(outcomes.size());
    for (std::size_t i = 0; i < outcomes.size(); ++i) {
      PathSet set;
      set.direct = std::move(outcomes[i]);
      if (!set.direct.blocked) {
        SignalPath direct;
        direct.rhcp_amplitude = std::pow(10.0, -set.direct.vegetation_attenuation_db / 20.0);
        direct.arrival_direction = directions[i];
        direct.vegetation_attenuation_db = set.direct.vegetation_attenuation_db;
        set.paths.push_back(std::move(direct));
      }
      out.push_back(std::move(set));
    }
    return out;
  }
};

}  // namespace skytrace

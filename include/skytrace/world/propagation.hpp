// Signal paths through the 3D world for multipath work: the direct ray, specular reflections off
// planar facets (image method, first and optionally second order), knife-edge diffraction over
// building edges (ITU-R P.526) and diffuse scattering off rough facades (effective roughness,
// Degli-Esposti et al. 2007), each leg checked against the scene for obstruction and vegetation.
// The electrical side: complex permittivities of the material classes (ITU-R P.2040-1 Table 3,
// ground from ITU-R P.527), Fresnel coefficients for both linear polarisations combined into
// co- and cross-polar circular coefficients. docs/multipath.md explains the models and limits.
#pragma once

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <cstddef>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "skytrace/core/error.hpp"
#include "skytrace/core/path_query.hpp"
#include "skytrace/world/world_model.hpp"

namespace skytrace::world {

// Relative permittivity (real part) and conductivity of a material class at a frequency:
// eps' = a f^b, sigma = c f^d with f in GHz (ITU-R P.2040-1 Table 3; "medium dry ground" for
// kGround; concrete for kUnknown; metal as a near-perfect conductor).
struct ElectricalProperties {
  double relative_permittivity = 1.0;
  double conductivity_s_per_m = 0.0;
};
[[nodiscard]] ElectricalProperties electrical_properties(MaterialClass material, double frequency_hz);

// Complex relative permittivity eps' - j 17.98 sigma / f_GHz (ITU-R P.2040-1 eq. 9b).
[[nodiscard]] std::complex<double> complex_permittivity(MaterialClass material, double frequency_hz);

// Reflection coefficients of a plane wave from air on a half-space of complex permittivity `eta`
// at an incidence angle theta from the normal (ITU-R P.2040-1 eqs. 31, 32):
//   TE (perpendicular) = (cos t - sqrt(eta - sin^2 t)) / (cos t + sqrt(eta - sin^2 t))
//   TM (parallel)      = (eta cos t - sqrt(eta - sin^2 t)) / (eta cos t + sqrt(eta - sin^2 t))
// With this sign convention TM = -TE at normal incidence; the circular coefficients are
// co = (TE + TM) / 2 (RHCP stays RHCP) and cross = (TE - TM) / 2 (RHCP turns LHCP): a perfect
// conductor gives co = 0, |cross| = 1; grazing incidence gives co = -1, cross = 0.
struct FresnelCoefficients {
  std::complex<double> te, tm, co, cross;
};
[[nodiscard]] FresnelCoefficients fresnel_coefficients(std::complex<double> eta, double cos_incidence);

// ITU-R P.526 single knife-edge loss (dB): J(v) = 6.9 + 20 log10(sqrt((v - 0.1)^2 + 1) + v - 0.1)
// for v > -0.78, 0 below.
[[nodiscard]] double knife_edge_loss_db(double v);

// The centre of the sky cell (PathSearchSettings::static_sky_cell_deg) that holds the unit
// direction (world frame, z up): where the paths of every direction of the cell are searched.
[[nodiscard]] Eigen::Vector3d sky_cell_centre(const Eigen::Vector3d& direction, double cell_deg);

// The centre of the cube (PathSearchSettings::moving_cell_m, world frame) that holds the point:
// where a moving antenna's second-order and scattered paths are searched.
[[nodiscard]] Eigen::Vector3d moving_cell_centre(const Eigen::Vector3d& point_m, double cell_m);

// A planar reflector: coplanar triangles of one static object merged.
struct Facet {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // unit; the plane is normal . x = offset_m
  double offset_m = 0.0;
  Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();  // a point of the plane, origin of (axis_u, axis_v)
  Eigen::Vector3d axis_u = Eigen::Vector3d::UnitX(), axis_v = Eigen::Vector3d::UnitY();
  std::vector<Eigen::Vector2d> triangles_uv;  // 3 per triangle, in the plane's coordinates
  Eigen::Vector2d min_uv = Eigen::Vector2d::Zero(), max_uv = Eigen::Vector2d::Zero();
  Eigen::Vector3d min_m = Eigen::Vector3d::Zero(), max_m = Eigen::Vector3d::Zero();  // 3D bounds
  Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();  // bounding sphere of the corners
  double radius_m = 0.0;
  double area_m2 = 0.0;
  MaterialClass material = MaterialClass::kConcrete;
  std::size_t object = 0;  // index into PropagationScene::object_names()

  // Per triangle its box in (u, v), a hair wider than what contains() accepts, so that most
  // triangles of a facet of many are passed over by four comparisons (set_triangle_bounds()).
  std::vector<std::array<double, 4>> triangle_bounds_uv;  // min u, min v, max u, max v

  // Whether a point of the plane lies in one of the facet's triangles (boundary included).
  [[nodiscard]] bool contains(const Eigen::Vector3d& point_m) const;
  // Fills triangle_bounds_uv from triangles_uv (contains() works without them, only slower).
  void set_triangle_bounds();
};

// A convex edge of a static building-like object (not ground, not vegetation) where diffraction
// happens: between two faces meeting at an outward angle, or the boundary of an open surface.
struct DiffractionEdge {
  Eigen::Vector3d start_m = Eigen::Vector3d::Zero(), end_m = Eigen::Vector3d::Zero();
  // Unit outward direction away from the object (bisector of the faces' normals): the offset
  // for rays leaving the edge.
  Eigen::Vector3d outward = Eigen::Vector3d::UnitZ();
  // The normals of the two faces that meet at the edge (an open surface's border: its face's
  // normal and the opposite, as a sheet has both sides). A satellite lights exactly one of them
  // when the edge lies on the object's outline seen from it.
  Eigen::Vector3d face_normal_a = Eigen::Vector3d::UnitZ(), face_normal_b = -Eigen::Vector3d::UnitZ();
  Eigen::Vector3d midpoint_m = Eigen::Vector3d::Zero();
  double half_length_m = 0.0;
  // Unit direction from start to end, and the length (m).
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();
  double length_m = 0.0;
  std::size_t object = 0;
  MaterialClass material = MaterialClass::kConcrete;
};

// An angle with its cosine and sine: the sky-cell screens compare cosines rather than take an
// inverse sine or cosine per sphere and edge.
struct ConeReach {
  explicit ConeReach(double angle_rad) : rad(angle_rad), cos(std::cos(angle_rad)), sin(std::sin(angle_rad)) {}
  double rad = 0.0, cos = 1.0, sin = 0.0;
};

// A PathQuery that answers trace() with the given scene and paths() with reflections and
// diffraction from the static objects of the world model (movable objects block but do not
// reflect). paths() is const and thread-safe.
// Diffraction edges are searched on the objects that matter: the blocking object of a hidden
// satellite, and for a satellite in view the objects hit by 4 probe rays 3.5 deg around its
// direction (an edge must pass within ~1.4 m of the ray 30 m away to cost the direct signal anything).
class PropagationScene final : public PathQuery {
 public:
  // `scene` must answer for the same world (it does the ray casting).
  [[nodiscard]] static Result<std::unique_ptr<PropagationScene>> build(const WorldModel& world,
                                                                       std::shared_ptr<const PathQuery> scene);

  [[nodiscard]] std::vector<RayOutcome> trace(const Eigen::Vector3d& origin_m,
                                              const std::vector<Eigen::Vector3d>& directions) const override;
  [[nodiscard]] std::vector<RayOutcome> trace_line_of_sight(const Eigen::Vector3d& origin_m,
                                                            const std::vector<Eigen::Vector3d>& directions) const override;
  [[nodiscard]] std::vector<RayOutcome> trace_line_of_sight_from(const std::vector<Eigen::Vector3d>& origins_m,
                                                                 const Eigen::Vector3d& direction) const override;
  [[nodiscard]] std::vector<PathSet> paths(const Eigen::Vector3d& origin_m, const std::vector<Eigen::Vector3d>& directions,
                                           const PathSearchSettings& settings) const override;

  [[nodiscard]] const std::vector<Facet>& facets() const { return facets_; }
  [[nodiscard]] const std::vector<DiffractionEdge>& edges() const { return edges_; }
  [[nodiscard]] const std::vector<std::string>& object_names() const { return object_names_; }

 private:
  PropagationScene() = default;
  // What a search finds and keeps.
  struct SearchScope {
    // Only the direct paths, single reflections and knife edges: no second-order or scattered path
    // (the specular reflections still keep only the share that the settings' scattering leaves).
    bool near_only = false;
    // Indexes of an antenna point met twice (a static antenna's): a moving antenna's cube centres
    // are searched once per sky cell and would build them for nothing.
    bool point_indexes = true;
  };
  // paths() for the directions as given (settings.static_sky_cell_deg and moving_cell_m ignored).
  [[nodiscard]] std::vector<PathSet> search_paths(const Eigen::Vector3d& origin_m, const std::vector<Eigen::Vector3d>& directions,
                                                  const PathSearchSettings& settings, SearchScope scope) const;
  // paths() with settings.static_sky_cell_deg > 0: each direction's paths from its sky cell's.
  [[nodiscard]] std::vector<PathSet> paths_by_sky_cell(const Eigen::Vector3d& origin_m,
                                                       const std::vector<Eigen::Vector3d>& directions,
                                                       const PathSearchSettings& settings, SearchScope scope) const;
  // paths() with settings.moving_cell_m > 0: the near paths at the antenna, the others from its cube's.
  [[nodiscard]] std::vector<PathSet> paths_by_moving_cell(const Eigen::Vector3d& origin_m,
                                                          const std::vector<Eigen::Vector3d>& directions,
                                                          const PathSearchSettings& settings) const;
  // A facet near the receiver, seen from it: the normal turned towards it, its height above the
  // plane, the material's permittivity.
  // A patch of a facet for diffuse scattering: its centre and area.
  struct FacetPatch {
    Eigen::Vector3d point_m = Eigen::Vector3d::Zero();
    double area_m2 = 0.0;
  };
  struct NearFacet {
    std::size_t index = 0;
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
    double height_m = 0.0;
    std::complex<double> eta;
    const std::vector<FacetPatch>* patches = nullptr;  // when scattering: the facet's patches
  };
  struct Candidates {
    Eigen::Vector3d origin_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    double radius_m = 0.0, min_area_m2 = 0.0, frequency_hz = 0.0;
    double scattering_radius_m = 0.0, scattering_patch_m = 0.0;  // 0: no patches made
    std::vector<NearFacet> facets;
    // Per facet, those within scattering reach (none: beyond it); shared with the candidate sets
    // kept before, as a facet's patches depend on it and the patch size alone.
    std::vector<std::shared_ptr<const std::vector<FacetPatch>>> patches;
  };
  // Facets near a point (a uniform grid in x, y): those within the radius plus a margin, so that the
  // last answer serves an antenna moving less than the margin. Normal and height as seen from the
  // cached point; paths() turns them to the antenna's actual position. With scattering, also the
  // patches of the facets within its radius plus the margin (they do not depend on the antenna).
  std::shared_ptr<const Candidates> candidates(const Eigen::Vector3d& origin_m, const PathSearchSettings& settings) const;
  // Diffuse scattering (settings.scattering_coefficient > 0): for each satellite whose direct ray is
  // blocked, one path per facade from its patches lit by the satellite and seen by the receiver.
  void add_scattered_paths(const Eigen::Vector3d& origin_m, const std::vector<Eigen::Vector3d>& directions,
                           const PathSearchSettings& settings, const Candidates& candidates,
                           const std::vector<NearFacet>& near_facets, std::vector<PathSet>& out) const;
  // What an antenna met at the same point twice sees of the scattering patches (within the radius,
  // facing it, not hidden), kept so that it traces them once.
  struct PatchSight {
    Eigen::Vector3d origin_m = Eigen::Vector3d::Zero();
    const Candidates* candidates = nullptr;
    double radius_m = 0.0;
    // Per near facet k, its patches in view (indices into its patches) and the vegetation the ray
    // to each crosses, from in_view_first[k] to in_view_first[k + 1]: the search passes over the
    // others, most of a city's, without a look.
    std::vector<std::size_t> in_view_first;
    std::vector<std::uint32_t> in_view;
    std::vector<double> in_view_vegetation_db;
  };
  std::shared_ptr<const PatchSight> patch_sight(const Eigen::Vector3d& origin_m, const Candidates& candidates,
                                                const std::vector<NearFacet>& near_facets, double radius_m) const;

  // Double bounces (satellite -> B -> A -> receiver) for one antenna position: a pair of facets
  // that can face each other whatever the satellite, and the index of the pairs by sky direction
  // kept for an antenna that stays where it was (docs/performance.md).
  struct FacetPair;
  struct DoubleBounceIndex;
  // The pairs of second-order facet a (indices into `facets`) with every facet b that may pass a
  // satellite's signal on to it; plane_a and image_of: each facet's plane constant and the antenna's image in it.
  void append_facet_pairs(std::size_t a, const std::vector<NearFacet>& facets, const std::vector<double>& plane_a,
                          const std::vector<Eigen::Vector3d>& image_of, std::vector<FacetPair>& out) const;
  // The pair of facets a and b as append_facet_pairs forms it; false when b cannot pass a signal on to a.
  bool make_facet_pair(std::size_t a, std::size_t b, const std::vector<NearFacet>& facets, const std::vector<double>& plane_a,
                       const std::vector<Eigen::Vector3d>& image_of, FacetPair& pair) const;
  // A pair's two cones narrowed to the facets' bounding rectangles where that is tighter than
  // their spheres (image_a: the antenna's image in facet a).
  void narrow_cones(FacetPair& pair, const Eigen::Vector3d& image_a, const std::vector<NearFacet>& facets) const;
  // The index for an antenna found at the same point in an earlier call (built on the second
  // call there), else none.
  std::shared_ptr<const DoubleBounceIndex> double_bounce_index(const Eigen::Vector3d& origin_m,
                                                               const std::vector<NearFacet>& facets,
                                                               const std::vector<double>& plane_a,
                                                               const std::vector<Eigen::Vector3d>& image_of) const;

  // Knife-edge diffraction over the blocking object, and diffraction then reflection (over one of
  // its edges, then off a second-order facet), for an antenna that stays where it was: per sky cell
  // and object, the edges and the facet-edge pairs that may serve a satellite in the cell, each
  // with the band of directions it can serve, found once (docs/performance.md).
  struct FacetEdge {
    std::uint32_t facet = 0;  // index into the second-order facets
    std::uint32_t edge = 0;   // index into object_edges_[object]
    // The edge's unit direction, and the band of satellite directions s (as s . axis) whose
    // stationary point on the edge, seen from the receiver's image in the facet, projects into
    // the facet's bounding rectangle: no other direction can use the pair.
    Eigen::Vector3d axis = Eigen::Vector3d::Zero();
    double cos_min = 0.0, cos_max = 0.0;
  };
  // The entries of one list of the index below, and their bands in single precision, a little
  // wide, to screen them all against a direction at once before the exact test.
  struct FacetEdgeList {
    std::vector<FacetEdge> entries;
    std::vector<float> axis_x, axis_y, axis_z, cos_low, cos_high;
  };
  struct ReflectedEdgeIndex;
  // First-order reflections of an antenna that stays at one point: per sky cell, the facets whose
  // reflection point may lie on them for a direction of the cell (docs/performance.md).
  struct ReflectorIndex;
  // The index for an antenna found at the same point in an earlier call, else none.
  std::shared_ptr<const ReflectorIndex> reflector_index(const Eigen::Vector3d& origin_m,
                                                        const std::vector<NearFacet>& facets) const;
  // The pair of facet nf (the receiver's image in its plane normal . x = plane) and the edge, with
  // its band; none when no direction within cell_reach of cell_axis is in the band.
  static std::optional<FacetEdge> facet_edge_band(const NearFacet& nf, const Facet& f, const Eigen::Vector3d& image,
                                                  double plane, const DiffractionEdge& edge,
                                                  const Eigen::Vector3d& cell_axis, const ConeReach& cell_reach);
  // The edge's direction and band for knife-edge diffraction from `origin` (Keller's point within
  // radius_m), `facet` unused; none when no direction within cell_reach of cell_axis is in it.
  static std::optional<FacetEdge> edge_band(const DiffractionEdge& edge, const Eigen::Vector3d& origin, double radius_m,
                                            const Eigen::Vector3d& cell_axis, const ConeReach& cell_reach);
  // The band of s . axis for Keller points between u0 and u1 along an edge whose start lies `along`
  // the axis from the origin and rho from its line; none when it misses the cell.
  static std::optional<FacetEdge> band_of(const Eigen::Vector3d& axis, double along, double rho, double u0, double u1,
                                          const Eigen::Vector3d& cell_axis, const ConeReach& cell_reach);
  using FacetEdgeSearch = std::function<std::vector<FacetEdge>(const Eigen::Vector3d& cell_axis, const ConeReach& cell_reach)>;
  // The index for an antenna found at the same point in an earlier call, else none.
  std::shared_ptr<const ReflectedEdgeIndex> reflected_edge_index(const Eigen::Vector3d& origin_m,
                                                                 const std::vector<NearFacet>& facets,
                                                                 double excess_max_m, double radius_m) const;
  // The pairs (knife_edges: the edges alone) for satellite direction s and the object, `search`
  // finding them for its cell when the index has none yet (a superset of what any direction in the
  // cell can use).
  static std::shared_ptr<const FacetEdgeList> facet_edge_pairs(const ReflectedEdgeIndex& index, bool knife_edges,
                                                               std::size_t object, const Eigen::Vector3d& s,
                                                               const FacetEdgeSearch& search);

  std::shared_ptr<const PathQuery> scene_;
  std::vector<Facet> facets_;
  std::vector<DiffractionEdge> edges_;
  std::vector<std::string> object_names_;
  // Grid of facet and edge indices by cell (x, y).
  double cell_m_ = 20.0;
  Eigen::Vector2d grid_min_ = Eigen::Vector2d::Zero();
  int grid_nx_ = 0, grid_ny_ = 0;
  std::vector<std::vector<std::size_t>> facet_cells_;
  // Edge indices per object, in spatial order, and clusters of them with a bounding sphere, so
  // that a ray's search skips the clusters far from it.
  struct EdgeCluster {
    Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();
    double radius_m = 0.0;
    std::size_t begin = 0, end = 0;  // range in object_edges_[object]
  };
  std::vector<std::vector<std::size_t>> object_edges_;
  std::vector<std::vector<EdgeCluster>> object_clusters_;
  // Per object, a sphere around its edge clusters, and one around each group of
  // kClustersPerGroup neighbouring clusters (they are in Morton order): a search tests an object,
  // then a group, then a cluster, then an edge (a city mesh holds thousands of clusters).
  static constexpr std::size_t kClustersPerGroup = 16;
  struct Sphere {
    Eigen::Vector3d centre_m = Eigen::Vector3d::Zero();
    double radius_m = 0.0;
  };
  std::vector<Sphere> object_spheres_;
  std::vector<std::vector<Sphere>> group_spheres_;
  // Per object, its edges in object_edges_ order as arrays (start, unit direction, length), for a
  // first test of many Keller points at once.
  struct EdgeArrays {
    std::vector<double> sx, sy, sz, ax, ay, az, length;
  };
  std::vector<EdgeArrays> object_edge_arrays_;
  // Per object, its edge clusters' spheres as arrays (centre, radius), to test many at once.
  struct SphereArrays {
    std::vector<double> cx, cy, cz, radius;
  };
  std::vector<SphereArrays> object_cluster_arrays_;
  std::unordered_map<std::string, std::size_t> object_index_;
  // Kept per antenna point: one per band or settings in use (a GPS and a GLONASS signal search
  // with different permittivities).
  static constexpr std::size_t kCachedCandidateSets = 4;
  // The last few results of a computation per antenna point, replaced oldest first; and the points met once, for results worth keeping only for an antenna
  // that comes back to the very same point (a static one). Guarded by cache_mutex_.
  template <typename T>
  struct RecentResults {
    std::array<std::shared_ptr<const T>, kCachedCandidateSets> kept;
    std::size_t next = 0;
    std::array<std::optional<Eigen::Vector3d>, kCachedCandidateSets> met;
    std::size_t next_met = 0;

    template <typename Match>
    [[nodiscard]] std::shared_ptr<const T> find(Match&& match) const {
      for (const auto& result : kept) {
        if (result && match(*result)) return result;
      }
      return nullptr;
    }
    void keep(std::shared_ptr<const T> result) {
      kept[next] = std::move(result);
      next = (next + 1) % kept.size();
    }
    // Whether the point was met before; remembers it if not.
    bool met_before(const Eigen::Vector3d& point_m) {
      for (const auto& m : met) {
        if (m && *m == point_m) return true;
      }
      met[next_met] = point_m;
      next_met = (next_met + 1) % met.size();
      return false;
    }
  };
  mutable std::mutex cache_mutex_;
  mutable RecentResults<Candidates> candidate_sets_;
  mutable RecentResults<DoubleBounceIndex> double_bounce_indexes_;
  mutable RecentResults<PatchSight> patch_sights_;
  mutable RecentResults<ReflectedEdgeIndex> reflected_edge_indexes_;
  mutable RecentResults<ReflectorIndex> reflector_indexes_;
  // The paths searched at sky-cell centres, per antenna point and settings (paths_by_sky_cell).
  struct SkyCellPaths;
  mutable std::mutex sky_cell_mutex_;
  mutable std::array<std::shared_ptr<SkyCellPaths>, kCachedCandidateSets> sky_cell_paths_;
  mutable std::size_t next_sky_cell_paths_ = 0;
};

}  // namespace skytrace::world

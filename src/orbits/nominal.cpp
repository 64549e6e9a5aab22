#include "skytrace/orbits/nominal.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "skytrace/core/constants.hpp"
#include "skytrace/core/random.hpp"
#include "skytrace/orbits/broadcast.hpp"

namespace skytrace::orbits {
namespace {

namespace k = constants;
constexpr double kPi = std::numbers::pi;
constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

// Angle in [-pi, pi), as broadcast angles are.
double wrap_pi(double angle_rad) {
  double a = std::fmod(angle_rad + kPi, kTwoPi);
  if (a < 0.0) a += kTwoPi;
  return a - kPi;
}

struct SystemConstants {
  double gm_m3ps2;
  double earth_rotation_radps;
};

// The GM and Earth rotation rate each system's ICD prescribes for its broadcast orbit, so that the
// records evaluate to the design orbit with the receiver's own algorithm.
SystemConstants system_constants(GnssSystem system) {
  switch (system) {
    case GnssSystem::kGalileo:
      return {k::kGmGalileo_m3ps2, k::kEarthRotationRateGalileo_radps};
    case GnssSystem::kBeiDou:
      return {k::kGmBeiDou_m3ps2, k::kEarthRotationRateBeiDou_radps};
    case GnssSystem::kGlonass:
      return {k::kGmGlonass_m3ps2, k::kEarthRotationRateGlonass_radps};
    default:
      return {k::kGmGps_m3ps2, k::kEarthRotationRateGps_radps};
  }
}

// Semi-major axis whose Keplerian mean motion equals the Earth's rotation rate (geosynchronous).
double synchronous_axis_m(const SystemConstants& c) {
  return std::cbrt(c.gm_m3ps2 / (c.earth_rotation_radps * c.earth_rotation_radps));
}

NominalOrbit make_orbit(GnssSystem system, int number, NominalOrbitType type, std::string slot,
                        double a_m, double e, double i_deg, double omega_deg, const GnssTime& epoch,
                        double node_lon_deg, double mean_anomaly_deg) {
  const SystemConstants c = system_constants(system);
  NominalOrbit o;
  o.satellite = SatelliteId{system, static_cast<std::uint8_t>(number)};
  o.type = type;
  o.slot = std::move(slot);
  o.semi_major_axis_m = a_m;
  o.eccentricity = e;
  o.inclination_rad = i_deg * kDeg;
  o.argument_of_perigee_rad = omega_deg * kDeg;
  o.reference_epoch = epoch;
  o.node_longitude_rad = wrap_pi(node_lon_deg * kDeg);
  o.mean_anomaly_rad = wrap_pi(mean_anomaly_deg * kDeg);
  o.gm_m3ps2 = c.gm_m3ps2;
  o.earth_rotation_radps = c.earth_rotation_radps;
  return o;
}

// Inertial node rate that makes a ground track repeat after `revolutions` orbits in `days` turns
// of the Earth relative to the node: n T = 2 pi revolutions, (omega_e - node_rate) T = 2 pi days.
double repeat_node_rate(const NominalOrbit& o, double revolutions, double days) {
  return o.earth_rotation_radps - o.mean_motion_rad_per_s() * days / revolutions;
}

// --- GPS: SPS PS baseline 24-slot table (RAAN, argument of latitude in degrees at the epoch).
struct GpsSlot {
  const char* name;
  double raan_deg;
  double argument_of_latitude_deg;
};
constexpr std::array<GpsSlot, 24> kGpsSlots = {{
    {"A1", 272.847, 268.126}, {"A2", 272.847, 161.786}, {"A3", 272.847, 11.676},
    {"A4", 272.847, 41.806},  {"B1", 332.847, 80.956},  {"B2", 332.847, 173.336},
    {"B3", 332.847, 309.976}, {"B4", 332.847, 204.376}, {"C1", 32.847, 111.876},
    {"C2", 32.847, 11.796},   {"C3", 32.847, 339.666},  {"C4", 32.847, 241.556},
    {"D1", 92.847, 135.226},  {"D2", 92.847, 265.446},  {"D3", 92.847, 35.156},
    {"D4", 92.847, 167.356},  {"E1", 152.847, 197.046}, {"E2", 152.847, 302.596},
    {"E3", 152.847, 66.066},  {"E4", 152.847, 333.686}, {"F1", 212.847, 238.886},
    {"F2", 212.847, 345.226}, {"F3", 212.847, 105.206}, {"F4", 212.847, 135.346},
}};
// Greenwich hour angle at the defined epoch: 18 h 36 min 14.4 s.
constexpr double kGpsEpochGha_deg = (18.0 + 36.0 / 60.0 + 14.4 / 3600.0) * 15.0;

void add_gps(std::vector<NominalOrbit>& out) {
  const GnssTime epoch =
      GnssTime::from_calendar(CalendarTime{1993, 7, 1, 0, 0, 0.0}, TimeScale::kUtc);
  int prn = 1;
  for (const GpsSlot& s : kGpsSlots) {
    // Earth-fixed node longitude = inertial RAAN - Greenwich hour angle; e = 0, so M = u.
    NominalOrbit o =
        make_orbit(GnssSystem::kGps, prn++, NominalOrbitType::kMeo, s.name, 26559.7e3, 0.0, 55.0,
                   0.0, epoch, s.raan_deg - kGpsEpochGha_deg, s.argument_of_latitude_deg);
    o.node_rate_rad_per_s = repeat_node_rate(o, 2.0, 1.0);
    out.push_back(std::move(o));
  }
}

// Walker T/P/F = 24/3/1: planes 120 deg apart in node, 8 slots 45 deg apart, +15 deg per plane.
void add_walker(std::vector<NominalOrbit>& out, GnssSystem system, const std::vector<int>& numbers,
                double a_m, double i_deg, const GnssTime& epoch, double revolutions, double days) {
  for (int plane = 0; plane < 3; ++plane) {
    for (int slot = 0; slot < 8; ++slot) {
      const int index = plane * 8 + slot;
      const std::string name = "plane " + std::string(1, static_cast<char>('A' + plane)) +
                               " slot " + std::to_string(slot + 1);
      NominalOrbit o =
          make_orbit(system, numbers[static_cast<size_t>(index)], NominalOrbitType::kMeo, name, a_m,
                     0.0, i_deg, 0.0, epoch, 120.0 * plane, 45.0 * slot + 15.0 * plane);
      o.node_rate_rad_per_s = revolutions > 0.0 ? repeat_node_rate(o, revolutions, days) : 0.0;
      out.push_back(std::move(o));
    }
  }
}

std::string longitude_label(const char* kind, double longitude_deg) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%s %.2fE", kind, longitude_deg);
  return buffer;
}

NominalOrbit geo(GnssSystem system, int number, double longitude_deg, const GnssTime& epoch) {
  // Equatorial circular synchronous orbit: longitude = node longitude + argument of latitude.
  return make_orbit(system, number, NominalOrbitType::kGeo, longitude_label("GEO", longitude_deg),
                    synchronous_axis_m(system_constants(system)), 0.0, 0.0, 0.0, epoch,
                    longitude_deg, 0.0);
}

// A circular inclined synchronous orbit whose figure-8 crosses the equator at `crossing_deg`, at
// mean anomaly `phase_deg` at the epoch. The crossing longitude is node longitude + argument of
// latitude (both change at the Earth rate), so node longitude = crossing - phase.
NominalOrbit igso(GnssSystem system, int number, double crossing_deg, double i_deg,
                  double phase_deg, const GnssTime& epoch) {
  return make_orbit(system, number, NominalOrbitType::kIgso, longitude_label("IGSO", crossing_deg),
                    synchronous_axis_m(system_constants(system)), 0.0, i_deg, 0.0, epoch,
                    crossing_deg - phase_deg, phase_deg);
}

void add_galileo(std::vector<NominalOrbit>& out) {
  std::vector<int> numbers(24);
  for (int i = 0; i < 24; ++i) numbers[static_cast<size_t>(i)] = i + 1;
  add_walker(out, GnssSystem::kGalileo, numbers, 29600e3, 56.0,
             GnssTime::from_week_tow(TimeScale::kGst, 0, 0.0), 17.0, 10.0);
}

void add_beidou(std::vector<NominalOrbit>& out) {
  const GnssTime epoch = GnssTime::from_week_tow(TimeScale::kBdt, 0, 0.0);
  std::vector<int> meo;
  for (int prn = 19; prn <= 30; ++prn) meo.push_back(prn);
  for (int prn = 32; prn <= 37; ++prn) meo.push_back(prn);
  for (int prn = 41; prn <= 46; ++prn) meo.push_back(prn);
  add_walker(out, GnssSystem::kBeiDou, meo, 27906e3, 55.0, epoch, 13.0, 7.0);
  // IGSO C38-C40 on one ground track, 8 h apart: each later one is the previous one 8 h late.
  for (int k = 0; k < 3; ++k)
    out.push_back(igso(GnssSystem::kBeiDou, 38 + k, 118.0, 55.0, -120.0 * k, epoch));
  out.push_back(geo(GnssSystem::kBeiDou, 59, 140.0, epoch));
  out.push_back(geo(GnssSystem::kBeiDou, 60, 80.0, epoch));
  out.push_back(geo(GnssSystem::kBeiDou, 61, 110.5, epoch));
  std::sort(out.begin(), out.end(),
            [](const NominalOrbit& a, const NominalOrbit& b) { return a.satellite < b.satellite; });
}

// Frequency channel k per slot 1..24.
constexpr std::array<int, 24> kGlonassChannels = {1,  -4, 5, 6,  1, -4, 5, 6, -2, -7, 0, -1,
                                                  -2, -7, 0, -1, 4, -3, 3, 2, 4,  -3, 3, 2};

void add_glonass(std::vector<NominalOrbit>& out) {
  const GnssTime epoch =
      GnssTime::from_calendar(CalendarTime{2000, 1, 1, 0, 0, 0.0}, TimeScale::kUtc);
  for (int plane = 0; plane < 3; ++plane) {
    for (int slot = 0; slot < 8; ++slot) {
      const int number = plane * 8 + slot + 1;
      // Slot numbers grow against the motion: slot j + 1 trails slot j by 45 deg.
      NominalOrbit o =
          make_orbit(GnssSystem::kGlonass, number, NominalOrbitType::kMeo,
                     "plane " + std::to_string(plane + 1) + " slot " + std::to_string(number),
                     25510e3, 0.0, 64.8, 0.0, epoch, 120.0 * plane, 15.0 * plane - 45.0 * slot);
      o.glonass_channel = kGlonassChannels[static_cast<size_t>(number - 1)];
      out.push_back(std::move(o));
    }
  }
}

void add_qzss(std::vector<NominalOrbit>& out) {
  const GnssTime epoch;  // GPS epoch
  const double a_m = synchronous_axis_m(system_constants(GnssSystem::kQzss));
  // J01 at apogee (M = 180 deg, u = 90 deg) over 135 E at the epoch: longitude = node + 90 deg.
  // J02 and J03 follow the same ground track 8 and 16 h later.
  for (int k = 0; k < 3; ++k) {
    out.push_back(make_orbit(GnssSystem::kQzss, 1 + k, NominalOrbitType::kQzo, "QZO 135.00E", a_m,
                             0.075, 41.0, 270.0, epoch, 45.0 + 120.0 * k, 180.0 - 120.0 * k));
  }
  out.push_back(geo(GnssSystem::kQzss, 7, 127.0, epoch));
}

void add_navic(std::vector<NominalOrbit>& out) {
  const GnssTime epoch;  // GPS epoch (IRNWT is aligned with GPST)
  out.push_back(igso(GnssSystem::kNavic, 1, 55.0, 29.0, 0.0, epoch));
  out.push_back(igso(GnssSystem::kNavic, 2, 55.0, 29.0, -90.0, epoch));
  out.push_back(geo(GnssSystem::kNavic, 3, 83.0, epoch));
  out.push_back(igso(GnssSystem::kNavic, 4, 111.75, 29.0, 0.0, epoch));
  out.push_back(igso(GnssSystem::kNavic, 5, 111.75, 29.0, -90.0, epoch));
  out.push_back(geo(GnssSystem::kNavic, 6, 32.5, epoch));
  out.push_back(geo(GnssSystem::kNavic, 7, 131.5, epoch));
}

// Mean anomaly and Earth-fixed node longitude of a design orbit at t.
struct Phase {
  double mean_anomaly_rad;
  double node_longitude_rad;
};
Phase phase_at(const NominalOrbit& o, const GnssTime& t) {
  const double dt_s = t - o.reference_epoch;
  return {wrap_pi(o.mean_anomaly_rad + o.mean_motion_rad_per_s() * dt_s),
          wrap_pi(o.node_longitude_rad + (o.node_rate_rad_per_s - o.earth_rotation_radps) * dt_s)};
}

// --- Records.

// Klobuchar coefficients broadcast by GPS on 2004-01-01 (RTKLIB's ionmodel default set).
KlobucharCoefficients typical_klobuchar() {
  KlobucharCoefficients k;
  k.alpha = {0.1118e-07, -0.7451e-08, -0.5961e-07, 0.1192e-06};
  k.beta = {0.1167e+06, -0.2294e+06, -0.1311e+06, 0.1049e+07};
  return k;
}

double symmetric(RandomStream& rng, double half_width) {
  return (2.0 * rng.uniform() - 1.0) * half_width;
}
double quantize(double value, double lsb) { return std::round(value / lsb) * lsb; }

struct ClockModel {
  double bias_at_anchor_s;
  double drift_s_per_s;
};

ClockModel clock_model(std::uint64_t seed, const SatelliteId& sat) {
  RandomStream rng(
      stream_key(seed, {hash_name("nominal-clock"), static_cast<std::uint64_t>(sat.system),
                        static_cast<std::uint64_t>(sat.number)}));
  ClockModel c;
  c.bias_at_anchor_s = symmetric(rng, 3e-4);
  if (sat.system == GnssSystem::kGlonass) {
    c.drift_s_per_s = std::round(symmetric(rng, 3.0)) * 0x1.0p-40;  // gamma_n LSB 2^-40
  } else {
    c.drift_s_per_s = symmetric(rng, 5e-12);
  }
  return c;
}

GroupDelays group_delays(std::uint64_t seed, const SatelliteId& sat) {
  RandomStream rng(
      stream_key(seed, {hash_name("nominal-group-delay"), static_cast<std::uint64_t>(sat.system),
                        static_cast<std::uint64_t>(sat.number)}));
  GroupDelays gd;
  switch (sat.system) {
    case GnssSystem::kGalileo:
      // BGD(E1,E5a) and BGD(E1,E5b) of one satellite differ by well under a nanosecond.
      gd.bgd_e1e5a_s = quantize(symmetric(rng, 5e-9), 0x1.0p-32);
      gd.bgd_e1e5b_s = quantize(gd.bgd_e1e5a_s + symmetric(rng, 5e-10), 0x1.0p-32);
      break;
    case GnssSystem::kBeiDou:
      gd.tgd1_s = quantize(symmetric(rng, 1e-8), 1e-10);
      gd.tgd2_s = quantize(symmetric(rng, 1e-8), 1e-10);
      break;
    default:
      gd.tgd_s = quantize(symmetric(rng, 1e-8), 0x1.0p-31);
      break;
  }
  return gd;
}

// Reference times t = k * spacing (+ offset) of GPST whole seconds covering [begin, end].
std::vector<GnssTime> record_times(const GnssTime& begin, const GnssTime& end,
                                   std::int64_t spacing_s, std::int64_t offset_s) {
  auto floor_div = [](std::int64_t a, std::int64_t b) {
    std::int64_t q = a / b;
    if ((a % b != 0) && (a < 0)) --q;
    return q;
  };
  const std::int64_t first = floor_div(begin.whole_seconds() - offset_s, spacing_s);
  const std::int64_t last =
      -floor_div(-(end.whole_seconds() + (end.fraction_s() > 0.0 ? 1 : 0) - offset_s), spacing_s);
  std::vector<GnssTime> times;
  for (std::int64_t i = first; i <= last; ++i)
    times.push_back(GnssTime::from_gpst_seconds(i * spacing_s + offset_s));
  return times;
}

NavMessage legacy_message(const NominalOrbit& o) {
  switch (o.satellite.system) {
    case GnssSystem::kBeiDou:
      return o.type == NominalOrbitType::kGeo ? NavMessage::kBeiDouD2 : NavMessage::kBeiDouD1;
    case GnssSystem::kQzss:
      return NavMessage::kQzssLnav;
    case GnssSystem::kNavic:
      return NavMessage::kNavicLnav;
    default:
      return NavMessage::kGpsLnav;
  }
}

// Orbit elements of a record at toe. Standard ICD algorithm: Omega_k = Omega0 + (Omega_dot -
// omega_e) tk - omega_e toe_sow, so Omega0 = node longitude at toe + omega_e toe_sow.
void set_orbit(KeplerEphemeris& e, const NominalOrbit& o, double toe_sow) {
  const Phase p = phase_at(o, e.toe);
  e.sqrt_a_sqrtm = std::sqrt(o.semi_major_axis_m);
  e.eccentricity = o.eccentricity;
  e.delta_n_rad_per_s = 0.0;
  if (o.satellite.system == GnssSystem::kBeiDou && o.type == NominalOrbitType::kGeo) {
    // BDS-SIS-ICD GEO: the elements describe the orbit in a frame tilted by +5 deg about x, with
    // no Earth rotation over tk in the node; [X Y Z] = R_Z(omega_e tk) R_X(-5 deg) [X_GK Y_GK
    // Z_GK]. An equatorial orbit at longitude L appears there with i = 5 deg, node at 180 deg and
    // argument of latitude L + 180 deg.
    const double longitude_rad = p.node_longitude_rad + p.mean_anomaly_rad;
    e.i0_rad = 5.0 * kDeg;
    e.omega_rad = 0.0;
    e.m0_rad = wrap_pi(longitude_rad + kPi);
    e.omega0_rad = wrap_pi(kPi + o.earth_rotation_radps * toe_sow);
    e.omega_dot_rad_per_s = 0.0;
    return;
  }
  e.i0_rad = o.inclination_rad;
  e.omega_rad = wrap_pi(o.argument_of_perigee_rad);
  e.m0_rad = p.mean_anomaly_rad;
  e.omega0_rad = wrap_pi(p.node_longitude_rad + o.earth_rotation_radps * toe_sow);
  e.omega_dot_rad_per_s = o.node_rate_rad_per_s;
}

void add_kepler_records(NavigationData& data, const NominalOrbit& o, const GnssTime& begin,
                        const GnssTime& end, const GnssTime& clock_anchor, std::uint64_t seed) {
  const GnssSystem system = o.satellite.system;
  const bool beidou = system == GnssSystem::kBeiDou;
  // BeiDou D1 records are hourly in BDT (BDT = GPST - 14 s); the others every 2 h.
  const std::int64_t spacing_s = beidou ? 3600 : 7200;
  const std::int64_t offset_s = beidou ? 14 : 0;
  const ClockModel clock = clock_model(seed, o.satellite);
  const GroupDelays delays = group_delays(seed, o.satellite);
  const TimeScale week_scale = beidou ? TimeScale::kBdt : TimeScale::kGpst;

  // Galileo data sets are broadcast from their toe on, and receivers (RTKLIB, BroadcastEphemerides)
  // only use one whose toe has passed: the first toe must lie before `begin`.
  const bool galileo = system == GnssSystem::kGalileo;
  const GnssTime first_needed = galileo ? begin - 1.0 : begin;
  for (const GnssTime& toe : record_times(first_needed, end, spacing_s, offset_s)) {
    const WeekTow wt = toe.to_week_tow(week_scale);
    const std::int64_t issue = toe.whole_seconds() / spacing_s;

    KeplerEphemeris e;
    e.satellite = o.satellite;
    e.message = legacy_message(o);
    e.toe = toe;
    e.toc = toe;
    e.week = wt.week;
    e.toe_sow = wt.tow_s;
    e.af0_s = clock.bias_at_anchor_s + clock.drift_s_per_s * (toe - clock_anchor);
    e.af1_s_per_s = clock.drift_s_per_s;
    e.af2_s_per_s2 = 0.0;
    set_orbit(e, o, wt.tow_s);
    e.group_delays = delays;
    e.health = 0;
    // GPS-like records are broadcast from half a spacing before toe (from then on they are the
    // nearest in time); Galileo ones from toe.
    e.transmission_time_sow = galileo ? wt.tow_s : wt.tow_s - static_cast<double>(spacing_s) / 2.0;
    e.source = "nominal constellation";
    switch (system) {
      case GnssSystem::kGps:
        e.iodc = static_cast<int>(issue % 1024);
        e.iode = e.iodc % 256;
        e.accuracy_m = 2.0;
        e.fit_interval_h = 4.0;
        e.codes_on_l2 = 1;
        break;
      case GnssSystem::kQzss:
        e.iodc = static_cast<int>(issue % 1024);
        e.iode = e.iodc % 256;
        e.accuracy_m = 2.8;
        e.fit_interval_h = 2.0;
        e.codes_on_l2 = 2;
        e.l2p_data_flag = 1;
        break;
      case GnssSystem::kNavic:
        e.iode = e.iodc = static_cast<int>(issue % 256);
        e.accuracy_m = 2.0;
        break;
      case GnssSystem::kBeiDou:
        e.iode = e.iodc = static_cast<int>(issue % 24);  // 5-bit AODE/AODC
        e.accuracy_m = 2.0;
        break;
      default:
        break;
    }
    if (system == GnssSystem::kGalileo) {
      e.iode = e.iodc = static_cast<int>(issue % 1024);  // IODnav
      e.accuracy_m = 3.12;                               // SISA
      e.message = NavMessage::kGalileoInav;
      e.data_source = 517;  // I/NAV E1-B and E5b, clock for E5b/E1
      KeplerEphemeris fnav = e;
      fnav.message = NavMessage::kGalileoFnav;
      fnav.data_source = 258;               // F/NAV E5a, clock for E5a/E1
      fnav.group_delays.bgd_e1e5b_s = 0.0;  // F/NAV does not carry BGD(E1,E5b)
      data.kepler.push_back(std::move(e));
      data.kepler.push_back(std::move(fnav));
    } else {
      data.kepler.push_back(std::move(e));
    }
  }
}

// The design state adjusted for J2: integrated as receivers do, a state taken from the J2-free
// design would circle about 1.1 km above the design radius. The inertial speed is scaled until
// the mean radius over one revolution is the design's (two Newton steps: <r> moves by 2 a dv/v).
NominalState glonass_initial_state(const NominalOrbit& o, const GnssTime& t) {
  NominalState s = nominal_state(o, t);
  const Eigen::Vector3d spin(0.0, 0.0, o.earth_rotation_radps);
  const double revolution_s = kTwoPi / o.mean_motion_rad_per_s();
  constexpr double kStep_s = 60.0;
  for (int iteration = 0; iteration < 2; ++iteration) {
    GlonassEphemeris g;
    g.toe = t;
    g.position_m = s.position_m;
    g.velocity_mps = s.velocity_mps;
    double sum_m = 0.0;
    int samples = 0;
    for (double elapsed_s = 0.0; elapsed_s < revolution_s; elapsed_s += kStep_s) {
      sum_m += g.position_m.norm();
      ++samples;
      const SatelliteState next = evaluate_glonass(g, g.toe + kStep_s);
      g.toe = g.toe + kStep_s;
      g.position_m = next.position_m;
      g.velocity_mps = next.velocity_mps;
    }
    const double mean_radius_m = sum_m / samples;
    const double scale = 1.0 + (o.semi_major_axis_m - mean_radius_m) / (2.0 * o.semi_major_axis_m);
    const Eigen::Vector3d inertial_mps = s.velocity_mps + spin.cross(s.position_m);
    s.velocity_mps = inertial_mps * scale - spin.cross(s.position_m);
  }
  return s;
}

// GLONASS state vectors at t_b = hh:15 and hh:45 UTC (t_b is a multiple of 15 min of Moscow time).
void add_glonass_records(NavigationData& data, const NominalOrbit& o, const GnssTime& begin,
                         const GnssTime& end, const GnssTime& clock_anchor, std::uint64_t seed) {
  const ClockModel clock = clock_model(seed, o.satellite);
  // Walk UTC days from the one holding `begin - 30 min`, placing t_b on the UTC calendar so that
  // leap seconds do not shift the grid.
  CalendarTime day = (begin - 1800.0).to_calendar(TimeScale::kUtc);
  for (int guard = 0; guard < 400; ++guard) {
    bool past_end = false;
    for (int half_hour = 0; half_hour < 48; ++half_hour) {
      const int minutes = 15 + 30 * half_hour;
      const GnssTime tb = GnssTime::from_calendar(
          CalendarTime{day.year, day.month, day.day, minutes / 60, minutes % 60, 0.0},
          TimeScale::kUtc);
      if (tb - end > 1800.0) {
        past_end = true;
        break;
      }
      if (begin - tb > 1800.0) continue;
      // The first state is the design's; each later one is the previous record integrated as a
      // receiver integrates it (PZ-90 with J2). States taken from the J2-free design at every t_b
      // would disagree with their neighbours by ~15 m at the switch (the J2 drift of 15 min).
      const NominalState s = data.glonass.empty() || data.glonass.back().satellite != o.satellite
                                 ? glonass_initial_state(o, tb)
                                 : [&] {
                                     const SatelliteState p =
                                         evaluate_glonass(data.glonass.back(), tb);
                                     return NominalState{p.position_m, p.velocity_mps};
                                   }();
      GlonassEphemeris g;
      g.satellite = o.satellite;
      g.toe = tb;
      g.minus_tau_n_s = clock.bias_at_anchor_s + clock.drift_s_per_s * (tb - clock_anchor);
      g.gamma_n = clock.drift_s_per_s;
      // t_k: start of the frame carrying the data, 15 min before t_b, in seconds of the UTC day.
      const CalendarTime tk = (tb - 900.0).to_calendar(TimeScale::kUtc);
      g.message_frame_time_s = tk.hour * 3600.0 + tk.minute * 60.0 + std::floor(tk.second);
      g.position_m = s.position_m;
      g.velocity_mps = s.velocity_mps;
      g.frequency_channel = o.glonass_channel;
      g.source = "nominal constellation";
      data.glonass.push_back(std::move(g));
    }
    if (past_end) break;
    // Next UTC day: noon of the following day is safely inside it whatever the leap seconds.
    const GnssTime noon =
        GnssTime::from_calendar(CalendarTime{day.year, day.month, day.day, 12, 0, 0.0},
                                TimeScale::kUtc) +
        86400.0;
    day = noon.to_calendar(TimeScale::kUtc);
  }
}

}  // namespace

std::vector<GnssSystem> nominal_systems() {
  std::vector<GnssSystem> systems;
  for (const GnssSystem system : kAllSystems) {
    if (system != GnssSystem::kSbas) systems.push_back(system);
  }
  return systems;
}

double NominalOrbit::mean_motion_rad_per_s() const {
  return std::sqrt(gm_m3ps2 / (semi_major_axis_m * semi_major_axis_m * semi_major_axis_m));
}

std::vector<NominalOrbit> nominal_orbits(const std::vector<GnssSystem>& systems) {
  std::vector<NominalOrbit> out;
  for (const GnssSystem system : kAllSystems) {
    if (std::find(systems.begin(), systems.end(), system) == systems.end()) continue;
    std::vector<NominalOrbit> part;
    switch (system) {
      case GnssSystem::kGps:
        add_gps(part);
        break;
      case GnssSystem::kGlonass:
        add_glonass(part);
        break;
      case GnssSystem::kGalileo:
        add_galileo(part);
        break;
      case GnssSystem::kBeiDou:
        add_beidou(part);
        break;
      case GnssSystem::kQzss:
        add_qzss(part);
        break;
      case GnssSystem::kNavic:
        add_navic(part);
        break;
      case GnssSystem::kSbas:
        break;
    }
    for (auto& o : part) out.push_back(std::move(o));
  }
  return out;
}

NominalState nominal_state(const NominalOrbit& o, const GnssTime& t) {
  const Phase p = phase_at(o, t);
  const double e = o.eccentricity;
  const double a_m = o.semi_major_axis_m;
  const double n_radps = o.mean_motion_rad_per_s();
  double ecc_rad = p.mean_anomaly_rad;
  for (int i = 0; i < 30; ++i) {
    const double step =
        (ecc_rad - e * std::sin(ecc_rad) - p.mean_anomaly_rad) / (1.0 - e * std::cos(ecc_rad));
    ecc_rad -= step;
    if (std::fabs(step) < 1e-14) break;
  }
  const double one_minus_e_cos = 1.0 - e * std::cos(ecc_rad);
  const double sqrt_1_e2 = std::sqrt(1.0 - e * e);
  const double nu_rad = std::atan2(sqrt_1_e2 * std::sin(ecc_rad), std::cos(ecc_rad) - e);
  const double u_rad = o.argument_of_perigee_rad + nu_rad;
  const double r_m = a_m * one_minus_e_cos;
  const double ecc_rate = n_radps / one_minus_e_cos;
  const double r_rate_mps = a_m * e * std::sin(ecc_rad) * ecc_rate;
  const double u_rate = ecc_rate * sqrt_1_e2 / one_minus_e_cos;

  const Eigen::Vector3d p_plane(r_m * std::cos(u_rad), r_m * std::sin(u_rad), 0.0);
  const Eigen::Vector3d v_plane(r_rate_mps * std::cos(u_rad) - r_m * u_rate * std::sin(u_rad),
                                r_rate_mps * std::sin(u_rad) + r_m * u_rate * std::cos(u_rad), 0.0);
  // Orbital plane -> Earth-fixed: rotate by i about x, then by the node longitude about z.
  const Eigen::Matrix3d rotation =
      (Eigen::AngleAxisd(p.node_longitude_rad, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(o.inclination_rad, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  NominalState s;
  s.position_m = rotation * p_plane;
  // The frame turns with the node's Earth-fixed rate about z.
  const double node_rate = o.node_rate_rad_per_s - o.earth_rotation_radps;
  s.velocity_mps = rotation * v_plane + node_rate * Eigen::Vector3d::UnitZ().cross(s.position_m);
  return s;
}

Result<NavigationData> make_nominal_constellation(const GnssTime& start, double duration_s,
                                                  const NominalConstellationOptions& options) {
  if (!std::isfinite(duration_s) || duration_s < 0.0) {
    return make_error(
        ErrorCode::kInvalidArgument,
        "nominal constellation: duration must be a finite number of seconds >= 0, got " +
            std::to_string(duration_s));
  }
  if (!std::isfinite(options.margin_s) || options.margin_s < 0.0) {
    return make_error(
        ErrorCode::kInvalidArgument,
        "nominal constellation: margin must be a finite number of seconds >= 0, got " +
            std::to_string(options.margin_s));
  }
  if (duration_s + 2.0 * options.margin_s > 366.0 * 86400.0) {
    return make_error(ErrorCode::kInvalidArgument,
                      "nominal constellation: span of " + std::to_string(duration_s / 86400.0) +
                          " days is longer than the 366 days supported");
  }
  if (std::find(options.systems.begin(), options.systems.end(), GnssSystem::kSbas) !=
      options.systems.end()) {
    return make_error(ErrorCode::kUnsupported,
                      "nominal constellation: SBAS has no nominal constellation");
  }

  const GnssTime begin = start - options.margin_s;
  const GnssTime end = start + duration_s + options.margin_s;
  NavigationData data;
  for (const NominalOrbit& o : nominal_orbits(options.systems)) {
    if (o.satellite.system == GnssSystem::kGlonass) {
      add_glonass_records(data, o, begin, end, start, options.seed);
    } else {
      add_kepler_records(data, o, begin, end, start, options.seed);
    }
  }
  data.ionosphere.gps = typical_klobuchar();
  data.leap_seconds = gps_minus_utc_s(start);
  data.source_files.push_back("nominal constellation");
  return data;
}

}  // namespace skytrace::orbits

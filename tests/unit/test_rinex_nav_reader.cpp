// Unit tests of the RINEX navigation reader on small inline files (2.x GPS/GLONASS/GEO, 3.04 mixed,
// 4.00) and on malformed input. Expected values are the numbers written in the snippets, converted
// by hand (km -> m, calendar epochs -> GPST with the scale offsets: BDT = GPST - 14 s, UTC = GPST -
// 18 s in 2020, - 17 s in 2016).
#include <gtest/gtest.h>
#include <zlib.h>

#include <string>

#include "skytrace/orbits/rinex_nav.hpp"
#include "test_support.hpp"

namespace skytrace::orbits {
namespace {

// RINEX 3.04 mixed: one record per system and case. I05 gives its week counted from the NavIC
// epoch (1087 = GPS week 2111); G07 has toe (Saturday 23:59:44) in the week before toc (Sunday
// 00:00) but writes the week of toc; R07 and R09 carry the 3.05 fourth line (R09 with unknowns).
constexpr const char* kMixed304 = R"(     3.04           N: GNSS NAV DATA    M: MIXED            RINEX VERSION / TYPE
skytrace-test       unit test           20200626 000000 UTC PGM / RUN BY / DATE
GPSA   4.6566E-09  1.4901E-08 -5.9605E-08 -1.1921E-07       IONOSPHERIC CORR
GPSB   8.1920E+04  9.8304E+04 -6.5536E+04 -5.2429E+05       IONOSPHERIC CORR
GAL    2.8250E+01  7.8125E-03  1.0071E-02  0.0000E+00       IONOSPHERIC CORR
BDSA   1.0245E-08  2.2352E-08 -5.9605E-08 -1.1921E-07 A 07  IONOSPHERIC CORR
BDSB   9.0112E+04  4.9152E+04 -6.5536E+04 -3.9322E+05 A 07  IONOSPHERIC CORR
BDSA   2.0000E-08  0.0000E+00  0.0000E+00  0.0000E+00 X 08  IONOSPHERIC CORR
GPUT  9.3132257462E-10 2.664535259E-15 589824 2111          TIME SYSTEM CORR
BDUT  1.0244548321E-08-2.042810365E-14  14400  755          TIME SYSTEM CORR
    18    18  2185     7GPS                                 LEAP SECONDS
                                                            END OF HEADER
G05 2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00
     5.800000000000E+01-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01
    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03
     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07
     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09
    -5.714523747137E-11 1.000000000000E+00 2.111000000000E+03 0.000000000000E+00
     2.000000000000E+00 0.000000000000E+00 5.122274160385E-09 5.800000000000E+01
     3.561060000000E+05 4.000000000000E+00
E11 2020 06 25 04 00 00-8.846927667037E-04-7.972289495228E-12 0.000000000000E+00
     6.100000000000E+01-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01
    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03
     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07
     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09
    -5.714523747137E-11 5.170000000000E+02 2.111000000000E+03
     3.120000000000E+00 0.000000000000E+00-1.862645149231E-09-2.095475792885E-09
     3.564540000000E+05
E11 2020 06 25 04 00 00-8.846933487803E-04-7.972289495228E-12 0.000000000000E+00
     6.100000000000E+01-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01
    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03
     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07
     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09
    -5.714523747137E-11 2.580000000000E+02 2.111000000000E+03
     3.120000000000E+00 0.000000000000E+00-1.862645149231E-09 0.000000000000E+00
     3.564400000000E+05
C07 2020 06 25 04 00 00-5.154609680176E-04-6.708145150469E-11 0.000000000000E+00
     1.000000000000E+00-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01
    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03
     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07
     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09
    -5.714523747137E-11                    7.550000000000E+02
     2.000000000000E+00 0.000000000000E+00-9.300000000000E-09 1.000000000000E-10
     3.600276000000E+05 3.000000000000E+00
C03 2020 06 25 04 00 00 2.531307982281E-04 7.027267656667E-12 0.000000000000E+00
     1.000000000000E+00-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01
    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03
     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07
     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09
    -5.714523747137E-11                    7.550000000000E+02
     2.000000000000E+00 0.000000000000E+00-9.200000000000E-09-2.000000000000E-10
     3.600000000000E+05 0.000000000000E+00
J02 2020 06 25 04 00 00-2.819551154971E-04 5.684341886081E-12 0.000000000000E+00
     2.010000000000E+02-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01
    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03
     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07
     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09
    -5.714523747137E-11 2.000000000000E+00 2.111000000000E+03 1.000000000000E+00
     2.800000000000E+00 0.000000000000E+00-5.587935447693E-09 9.690000000000E+02
     3.560000000000E+05 0.000000000000E+00
I05 2020 06 25 04 00 00 1.000000000000E-04 0.000000000000E+00 0.000000000000E+00
     1.200000000000E+01-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01
    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03
     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07
     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09
    -5.714523747137E-11                    1.087000000000E+03
     4.850000000000E+00 0.000000000000E+00-1.000000000000E-09
     3.550000000000E+05
G07 2020 06 28 00 00 00 1.000000000000E-05 0.000000000000E+00 0.000000000000E+00
     1.200000000000E+01 1.000000000000E+00 4.000000000000E-09 5.000000000000E-01
     1.000000000000E-06 1.000000000000E-02 1.000000000000E-06 5.153600000000E+03
     6.047840000000E+05 1.000000000000E-07 2.500000000000E+00 1.000000000000E-07
     9.600000000000E-01 2.000000000000E+02 5.000000000000E-01-8.000000000000E-09
     1.000000000000E-10 1.000000000000E+00 2.112000000000E+03 0.000000000000E+00
     2.000000000000E+00 0.000000000000E+00 1.000000000000E-09 1.200000000000E+01
     5.976000000000E+05 4.000000000000E+00
R05 2020 06 25 00 15 00 6.355904042721E-05 0.000000000000E+00 3.455700000000E+05
     1.090894238281E+04 1.407806396484E+00-1.862645149231E-09 0.000000000000E+00
    -2.885726074219E+03 2.795855522156E+00 0.000000000000E+00 1.000000000000E+00
     2.288353955078E+04-3.169984817505E-01-2.793967723846E-09 0.000000000000E+00
R07 2020 06 25 00 15 00-1.000000000000E-04 1.000000000000E-12 3.455700000000E+05
    -1.158823828125E+04-5.671300888062E-01 0.000000000000E+00 0.000000000000E+00
    -1.108993261719E+04-2.651433944702E+00 9.313225746155E-10-5.000000000000E+00
     1.986426855469E+04-1.820190429688E+00-2.793967723846E-09 3.000000000000E+00
     1.830000000000E+02-2.793967723846E-09 3.000000000000E+00 0.000000000000E+00
R09 2020 06 25 00 15 00 2.000000000000E-05 0.000000000000E+00 3.455700000000E+05
     1.000000000000E+03 1.000000000000E-01 0.000000000000E+00 1.000000000000E+00
     2.000000000000E+03 2.000000000000E-01 0.000000000000E+00 6.000000000000E+00
     3.000000000000E+03 3.000000000000E-01 0.000000000000E+00 2.000000000000E+00
                         .999999999999E+09 1.500000000000E+01
S27 2020 06 25 00 00 16 1.000000000000E-08-2.000000000000E-12 3.456300000000E+05
     3.594460000000E+04 0.000000000000E+00 0.000000000000E+00 6.300000000000E+01
     2.204414000000E+04 0.000000000000E+00 0.000000000000E+00 3.276700000000E+04
     0.000000000000E+00 0.000000000000E+00 0.000000000000E+00 9.200000000000E+01
)";

constexpr const char* kGps211 = R"(     2.11           N: GPS NAV DATA                         RINEX VERSION / TYPE
    0.9313D-08  0.1490D-07 -0.5960D-07 -0.1192D-06          ION ALPHA
    0.8806D+05  0.4915D+05 -0.1311D+06 -0.3277D+06          ION BETA
   -0.279396772385D-08-0.266453525910D-14   503808     2155 DELTA-UTC: A0,A1,T,W
    18                                                      LEAP SECONDS
                                                            END OF HEADER
 6 21  4 28 17 59 44.0 0.109337270260D-04 0.329691829393D-11 0.000000000000D+00
    0.310000000000D+02-0.968750000000D+02 0.369765402213D-08 0.256518534901D+00
   -0.510737299919D-05 0.225707876962D-02 0.122226774692D-04 0.515375527000D+04
    0.323984000000D+06 0.167638063431D-07-0.294507412083D+01-0.298023223877D-07
    0.983895632254D+00 0.158375000000D+03-0.983603167134D+00-0.758853037846D-08
   -0.732173355102D-10 0.100000000000D+01 0.215500000000D+04 0.000000000000D+00
    0.200000000000D+01 0.000000000000D+00 0.419095158577D-08 0.310000000000D+02
    0.322932000000D+06 0.400000000000D+01 0.000000000000D+00 0.000000000000D+00
13 99  8 21 23 59 44.0 0.100000000000D-04 0.000000000000D+00 0.000000000000D+00
    0.700000000000D+01 0.100000000000D+01 0.400000000000D-08 0.500000000000D+00
    0.100000000000D-05 0.100000000000D-01 0.100000000000D-05 0.515360000000D+04
    0.604784000000D+06 0.100000000000D-06 0.250000000000D+01 0.100000000000D-06
    0.960000000000D+00 0.200000000000D+03 0.500000000000D+00-0.800000000000D-08
    0.100000000000D-09 0.100000000000D+01 0.102300000000D+04 0.000000000000D+00
    0.400000000000D+01 0.000000000000D+00 0.100000000000D-08 0.700000000000D+01
    0.597600000000D+06 0.000000000000D+00 0.000000000000D+00 0.000000000000D+00
)";

constexpr const char* kGlonass201 = R"(     2.01           GLONASS NAV DATA                        RINEX VERSION / TYPE
  2016     6     6    0.232830643654D-08                    CORR TO SYSTEM TIME
    17                                                      LEAP SECONDS
                                                            END OF HEADER
 1 16  6  6  0 15  0.0-0.142809003591D-03 0.000000000000D+00 0.300000000000D+02
   -0.655342626953D+04-0.518354415894D+00-0.931322574616D-09 0.000000000000D+00
    0.226091289062D+05 0.124916648865D+01-0.279396772385D-08 0.100000000000D+01
    0.985101660156D+04-0.321309471130D+01 0.000000000000D+00 0.000000000000D+00
)";

constexpr const char* kGeo211 = R"(     2.11           H: GEO NAV MSG DATA                     RINEX VERSION / TYPE
                                                            END OF HEADER
20 20  6 25  0  0 16.0 0.000000000000D+00 0.000000000000D+00 0.345630000000D+06
    0.359446000000D+05 0.000000000000D+00 0.000000000000D+00 0.630000000000D+02
    0.220441400000D+05 0.000000000000D+00 0.000000000000D+00 0.327670000000D+05
    0.000000000000D+00 0.000000000000D+00 0.000000000000D+00 0.920000000000D+02
)";

constexpr const char* kRinex400 = R"(     4.00           N: GNSS NAV DATA    M: MIXED            RINEX VERSION / TYPE
    18                                                      LEAP SECONDS
                                                            END OF HEADER
> EPH G05 LNAV
G05 2022 06 08 12 00 00 1.479960046709E-04-1.068656274583E-11 0.000000000000E+00
     2.290000000000E+02 2.109375000000E+01 4.035525238682E-09-9.071644364572E-01
     1.057982444763E-06 2.373437280767E-03 9.329989552498E-06 5.153735490799E+03
     3.024000000000E+05 1.862645149231E-08 2.375215272061E+00-1.117587089539E-07
     9.717472108861E-01 2.079687500000E+02 3.011898553893E+00-7.870684988479E-09
     1.000000000000E-10 1.000000000000E+00 2.213000000000E+03 0.000000000000E+00
     2.000000000000E+00 0.000000000000E+00 5.000000000000E-09 2.290000000000E+02
     2.952180000000E+05 4.000000000000E+00
> EPH G05 CNAV
G05 2022 06 08 12 00 00 1.479960046709E-04-1.068656274583E-11 0.000000000000E+00
     1.500000000000E-02 2.109375000000E+01 4.035525238682E-09-9.071644364572E-01
     1.057982444763E-06 2.373437280767E-03 9.329989552498E-06 5.153735490799E+03
     3.024000000000E+05 1.862645149231E-08 2.375215272061E+00-1.117587089539E-07
     9.717472108861E-01 2.079687500000E+02 3.011898553893E+00-7.870684988479E-09
     1.000000000000E-10-2.000000000000E-14 1.000000000000E+00 2.000000000000E+00
    -8.000000000000E+00 0.000000000000E+00 5.000000000000E-09 3.000000000000E+00
     1.000000000000E-09-2.000000000000E-09 3.000000000000E-09-4.000000000000E-09
     2.952180000000E+05 2.213000000000E+03
> EPH J03 CNV2
J03 2022 06 08 12 00 00 1.000000000000E-04 0.000000000000E+00 0.000000000000E+00
     0.000000000000E+00 1.000000000000E+00 4.000000000000E-09 5.000000000000E-01
     1.000000000000E-06 7.500000000000E-02 1.000000000000E-06 6.493600000000E+03
     3.024000000000E+05 1.000000000000E-07 2.500000000000E+00 1.000000000000E-07
     7.000000000000E-01 2.000000000000E+02-1.500000000000E+00-3.000000000000E-09
     1.000000000000E-10 0.000000000000E+00 0.000000000000E+00 0.000000000000E+00
     0.000000000000E+00 0.000000000000E+00-3.000000000000E-09 0.000000000000E+00
     1.000000000000E-10 2.000000000000E-10 3.000000000000E-10 4.000000000000E-10
     5.000000000000E-10 6.000000000000E-10
     2.952000000000E+05 2.213000000000E+03
> EPH E12 FNAV
E12 2022 06 08 09 40 00-4.921101499349E-04-7.375433597190E-12 0.000000000000E+00
     1.060000000000E+02 7.753125000000E+01 3.374069114950E-09-2.122972858410E+00
     3.518536686897E-06 6.983533967286E-05 5.226582288742E-06 5.440594810486E+03
     2.940000000000E+05-8.754432201385E-08 1.536449345111E-01-3.539025783539E-08
     9.738260452722E-01 2.342187500000E+02-9.944743556886E-01-5.739881946265E-09
     6.035965707914E-11 2.580000000000E+02 2.213000000000E+03
     3.120000000000E+00 0.000000000000E+00 6.984919309616E-10 0.000000000000E+00
     2.947400000000E+05
> EPH C25 CNV1
C25 2022 06 08 12 00 00 2.000000000000E-04 1.000000000000E-12 0.000000000000E+00
     5.000000000000E-01 1.000000000000E+01 4.000000000000E-09 1.000000000000E+00
     1.000000000000E-06 1.000000000000E-03 2.000000000000E-06 5.282600000000E+03
     3.024000000000E+05 1.000000000000E-08 1.700000000000E+00 2.000000000000E-08
     9.600000000000E-01 1.900000000000E+02 1.470000000000E+00-6.800000000000E-09
     3.000000000000E-10 1.000000000000E-14 3.000000000000E+00 3.021000000000E+05
     0.000000000000E+00 1.000000000000E+00 2.000000000000E+00 3.000000000000E+00
     1.000000000000E-09                    2.000000000000E-09 3.000000000000E-09
     0.000000000000E+00 0.000000000000E+00 0.000000000000E+00 1.200000000000E+01
     3.024180000000E+05                                       3.400000000000E+01
> EPH R03 FDMA
R03 2022 06 08 09 45 00 5.807634443045E-05 9.094947017729E-13 2.934000000000E+05
    -1.158823828125E+04-5.671300888062E-01 0.000000000000E+00 0.000000000000E+00
    -1.108993261719E+04-2.651433944702E+00 9.313225746155E-10 5.000000000000E+00
     1.986426855469E+04-1.820190429688E+00-2.793967723846E-09 0.000000000000E+00
     1.830000000000E+02-2.793967723846E-09 3.000000000000E+00 0.000000000000E+00
> EPH S48 SBAS
S48 2022 06 08 09 59 12 0.000000000000E+00 0.000000000000E+00 2.951920000000E+05
     3.047423624000E+04-4.518750000000E-04 0.000000000000E+00 3.100000000000E+01
    -2.913785960000E+04 7.918750000000E-04 0.000000000000E+00 2.000000000000E+00
    -3.222000000000E+00-9.600000000000E-04 0.000000000000E+00 0.000000000000E+00
> EPH R04 L1OC
    this record type is not read
    and is skipped whole
> ION G29 LNAV
    2022 06 08 09 59 48 1.024454832077E-08 2.235174179077E-08-5.960464477539E-08
    -1.192092895508E-07 9.625600000000E+04 1.310720000000E+05-6.553600000000E+04
    -5.898240000000E+05 0.000000000000E+00
> ION E01 IFNV
    2022 06 08 09 59 57 7.850000000000E+01 5.390625000000E-01 2.713012695312E-02
     0.000000000000E+00
> ION C08 CNVX
    2022 06 08 09 59 50 1.0 2.0 3.0
    4.0
    5.0
> STO G26 LNAV
    2022 06 10 19 56 48 GPUT                                  UTC(USNO)
     2.952840000000E+05 9.313225746155E-10 2.664535259100E-15 0.000000000000E+00
> EOP G01 LNAV
    2022 06 08 00 00 00 1.0 2.0 3.0
    4.0
    5.0
)";

GnssTime gpst(int y, int mo, int d, int h, int mi, double s) {
  return GnssTime::from_calendar(CalendarTime{y, mo, d, h, mi, s}, TimeScale::kGpst);
}

NavigationData parse_ok(const std::string& name, const std::string& text) {
  auto nav = parse_rinex_nav(name, text);
  if (!nav) ADD_FAILURE() << nav.error().message;
  return nav ? *nav : NavigationData{};
}

const KeplerEphemeris* find(const NavigationData& nav, const char* sat, NavMessage message) {
  for (const auto& e : nav.kepler) {
    if (e.satellite.to_string() == sat && e.message == message) return &e;
  }
  return nullptr;
}

TEST(RinexNavReader, Rinex3HeaderValues) {
  const auto nav = parse_ok("mixed.rnx", kMixed304);
  ASSERT_TRUE(nav.ionosphere.gps);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->alpha[0], 4.6566e-09);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->beta[3], -5.2429e+05);
  ASSERT_TRUE(nav.ionosphere.galileo);
  EXPECT_DOUBLE_EQ(nav.ionosphere.galileo->ai0_sfu, 28.25);
  EXPECT_DOUBLE_EQ(nav.ionosphere.galileo->ai2_sfu_per_deg2, 1.0071e-02);
  // BDSA/BDSB with time marks: the first set is kept (not the 'X 08' one).
  ASSERT_TRUE(nav.ionosphere.beidou);
  EXPECT_DOUBLE_EQ(nav.ionosphere.beidou->alpha[0], 1.0245e-08);
  EXPECT_DOUBLE_EQ(nav.ionosphere.beidou->beta[0], 9.0112e+04);
  EXPECT_FALSE(nav.ionosphere.qzss);
  ASSERT_EQ(nav.time_corrections.size(), 2u);
  EXPECT_EQ(nav.time_corrections[0].type, "GPUT");
  EXPECT_DOUBLE_EQ(nav.time_corrections[0].a0_s, 9.3132257462e-10);
  EXPECT_EQ(nav.time_corrections[0].reference_time, gpst(2020, 6, 27, 19, 50, 24));  // week 2111, 589824 s
  EXPECT_EQ(nav.time_corrections[0].source, "mixed.rnx:9");
  // BDUT: BDT week 755 (= GPS week 2111), 14400 s BDT = 04:00:14 GPST on Sunday 2020-06-21.
  EXPECT_EQ(nav.time_corrections[1].type, "BDUT");
  EXPECT_EQ(nav.time_corrections[1].reference_time, gpst(2020, 6, 21, 4, 0, 14));
  EXPECT_EQ(nav.leap_seconds, 18);
  ASSERT_EQ(nav.source_files.size(), 1u);
  EXPECT_EQ(nav.source_files[0], "mixed.rnx");
}

TEST(RinexNavReader, Rinex3GpsRecord) {
  const auto nav = parse_ok("mixed.rnx", kMixed304);
  EXPECT_EQ(nav.kepler.size(), 8u);
  const auto* g = find(nav, "G05", NavMessage::kGpsLnav);
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(g->toc, gpst(2020, 6, 25, 4, 0, 0));
  EXPECT_EQ(g->toe, g->toc);  // week 2111, 360000 s = Thursday 04:00
  EXPECT_EQ(g->week, 2111);
  EXPECT_DOUBLE_EQ(g->toe_sow, 360000.0);
  EXPECT_DOUBLE_EQ(g->af0_s, 1.604342833161e-05);
  EXPECT_DOUBLE_EQ(g->af1_s_per_s, 7.048583938740e-12);
  EXPECT_DOUBLE_EQ(g->crs_m, -39.6875);
  EXPECT_DOUBLE_EQ(g->delta_n_rad_per_s, 4.304822170265e-09);
  EXPECT_DOUBLE_EQ(g->m0_rad, 0.6342094507864);
  EXPECT_DOUBLE_EQ(g->eccentricity, 1.000394229777e-02);
  EXPECT_DOUBLE_EQ(g->sqrt_a_sqrtm, 5153.707128525);
  EXPECT_DOUBLE_EQ(g->cic_rad, -1.508742570877e-07);
  EXPECT_DOUBLE_EQ(g->omega0_rad, 2.572838528869);
  EXPECT_DOUBLE_EQ(g->i0_rad, 0.9806518601091);
  EXPECT_DOUBLE_EQ(g->crc_m, 353.96875);
  EXPECT_DOUBLE_EQ(g->omega_rad, 0.7941703015008);
  EXPECT_DOUBLE_EQ(g->omega_dot_rad_per_s, -8.384634967987e-09);
  EXPECT_DOUBLE_EQ(g->idot_rad_per_s, -5.714523747137e-11);
  EXPECT_EQ(g->iode, 58);
  EXPECT_EQ(g->iodc, 58);
  EXPECT_EQ(g->codes_on_l2, 1);
  EXPECT_EQ(g->l2p_data_flag, 0);
  EXPECT_DOUBLE_EQ(g->accuracy_m, 2.0);
  EXPECT_EQ(g->health, 0);
  EXPECT_DOUBLE_EQ(g->group_delays.tgd_s, 5.122274160385e-09);
  EXPECT_DOUBLE_EQ(g->transmission_time_sow, 356106.0);
  EXPECT_DOUBLE_EQ(g->fit_interval_h, 4.0);
  EXPECT_EQ(g->source, "mixed.rnx:13");
}

TEST(RinexNavReader, GalileoInavAndFnavFromDataSourceBits) {
  const auto nav = parse_ok("mixed.rnx", kMixed304);
  const auto* inav = find(nav, "E11", NavMessage::kGalileoInav);
  const auto* fnav = find(nav, "E11", NavMessage::kGalileoFnav);
  ASSERT_NE(inav, nullptr);
  ASSERT_NE(fnav, nullptr);
  EXPECT_EQ(inav->data_source, 517u);  // bits 0, 2, 9
  EXPECT_EQ(fnav->data_source, 258u);  // bits 1, 8
  EXPECT_DOUBLE_EQ(inav->group_delays.bgd_e1e5a_s, -1.862645149231e-09);
  EXPECT_DOUBLE_EQ(inav->group_delays.bgd_e1e5b_s, -2.095475792885e-09);
  EXPECT_DOUBLE_EQ(fnav->group_delays.bgd_e1e5b_s, 0.0);
  EXPECT_DOUBLE_EQ(inav->accuracy_m, 3.12);
  EXPECT_EQ(inav->iode, 61);
  EXPECT_EQ(inav->iodc, 61);
  // GST is aligned to GPST; the GAL week field is the GPS week.
  EXPECT_EQ(inav->toc, gpst(2020, 6, 25, 4, 0, 0));
  EXPECT_EQ(inav->toe, inav->toc);
  EXPECT_EQ(inav->source, "mixed.rnx:21");
  EXPECT_EQ(fnav->source, "mixed.rnx:29");
}

TEST(RinexNavReader, BeiDouEpochIsBdtAndGeoSatellitesAreD2) {
  const auto nav = parse_ok("mixed.rnx", kMixed304);
  const auto* c07 = find(nav, "C07", NavMessage::kBeiDouD1);
  const auto* c03 = find(nav, "C03", NavMessage::kBeiDouD2);
  ASSERT_NE(c07, nullptr);
  ASSERT_NE(c03, nullptr);
  // The same calendar numbers read as BDT are 14 s later on the GPST timeline.
  EXPECT_DOUBLE_EQ(c07->toc - gpst(2020, 6, 25, 4, 0, 0), 14.0);
  EXPECT_EQ(c07->week, 755);
  EXPECT_EQ(c07->toe, c07->toc);  // BDT week 755, 360000 s
  EXPECT_EQ(c07->iode, 1);        // AODE
  EXPECT_EQ(c07->iodc, 3);        // AODC
  EXPECT_DOUBLE_EQ(c07->group_delays.tgd1_s, -9.3e-09);
  EXPECT_DOUBLE_EQ(c07->group_delays.tgd2_s, 1.0e-10);
  EXPECT_DOUBLE_EQ(c07->transmission_time_sow, 360027.6);
}

TEST(RinexNavReader, QzssFitFlagAndNavicWeek) {
  const auto nav = parse_ok("mixed.rnx", kMixed304);
  const auto* j = find(nav, "J02", NavMessage::kQzssLnav);
  ASSERT_NE(j, nullptr);
  EXPECT_DOUBLE_EQ(j->fit_interval_h, 2.0);  // flag 0: two hours
  EXPECT_EQ(j->codes_on_l2, 2);
  EXPECT_EQ(j->l2p_data_flag, 1);
  EXPECT_EQ(j->iodc, 969);
  EXPECT_EQ(j->satellite.prn(), 194);
  const auto* i = find(nav, "I05", NavMessage::kNavicLnav);
  ASSERT_NE(i, nullptr);
  EXPECT_EQ(i->week, 1087);  // as written
  EXPECT_EQ(i->toe, i->toc);  // resolved to GPS week 2111 by the nearest-to-toc rule
  EXPECT_DOUBLE_EQ(i->accuracy_m, 4.85);
  EXPECT_DOUBLE_EQ(i->group_delays.tgd_s, -1.0e-09);
}

TEST(RinexNavReader, ToeNearWeekBoundaryIsTheInstanceNearestToc) {
  const auto nav = parse_ok("mixed.rnx", kMixed304);
  const auto* g = find(nav, "G07", NavMessage::kGpsLnav);
  ASSERT_NE(g, nullptr);
  EXPECT_EQ(g->toc, gpst(2020, 6, 28, 0, 0, 0));
  EXPECT_EQ(g->week, 2112);
  EXPECT_DOUBLE_EQ(g->toe - g->toc, -16.0);  // not +604784 s
}

TEST(RinexNavReader, GlonassUtcEpochKilometresAndFourthLine) {
  const auto nav = parse_ok("mixed.rnx", kMixed304);
  ASSERT_EQ(nav.glonass.size(), 3u);
  const auto& r05 = nav.glonass[0];
  EXPECT_EQ(r05.satellite.to_string(), "R05");
  // 00:15:00 UTC is 00:15:18 GPST in 2020.
  EXPECT_DOUBLE_EQ(r05.toe - gpst(2020, 6, 25, 0, 15, 0), 18.0);
  EXPECT_DOUBLE_EQ(r05.minus_tau_n_s, 6.355904042721e-05);
  EXPECT_NEAR(r05.position_m.x(), 10908942.38281, 1e-6);
  EXPECT_NEAR(r05.position_m.y(), -2885726.074219, 1e-6);
  EXPECT_NEAR(r05.position_m.z(), 22883539.55078, 1e-6);
  EXPECT_NEAR(r05.velocity_mps.x(), 1407.806396484, 1e-9);
  EXPECT_NEAR(r05.acceleration_mps2.z(), -2.793967723846e-06, 1e-18);
  EXPECT_DOUBLE_EQ(r05.message_frame_time_s, 86370.0);  // 345570 s of the week -> of the day
  EXPECT_EQ(r05.frequency_channel, 1);
  EXPECT_EQ(r05.health, 0);
  EXPECT_FALSE(r05.delta_tau_n_s);
  EXPECT_EQ(r05.source, "mixed.rnx:77");

  const auto& r07 = nav.glonass[1];
  EXPECT_EQ(r07.frequency_channel, -5);
  EXPECT_DOUBLE_EQ(r07.age_days, 3.0);
  ASSERT_TRUE(r07.delta_tau_n_s);
  EXPECT_DOUBLE_EQ(*r07.delta_tau_n_s, -2.793967723846e-09);
  EXPECT_EQ(r07.status_flags, 183);
  EXPECT_EQ(r07.urai, 3);
  EXPECT_EQ(r07.health_flags, 0);

  const auto& r09 = nav.glonass[2];  // fourth line: blank, .999999999999E+09, 15, blank
  EXPECT_FALSE(r09.delta_tau_n_s);
  EXPECT_EQ(r09.urai, 15);
  EXPECT_EQ(r09.health, 1);
  EXPECT_EQ(r09.frequency_channel, 6);
  EXPECT_DOUBLE_EQ(r09.age_days, 2.0);
}

TEST(RinexNavReader, SbasRecordInKilometresOnGpst) {
  const auto nav = parse_ok("mixed.rnx", kMixed304);
  ASSERT_EQ(nav.sbas.size(), 1u);
  const auto& s = nav.sbas[0];
  EXPECT_EQ(s.satellite.to_string(), "S27");
  EXPECT_EQ(s.satellite.prn(), 127);
  EXPECT_EQ(s.toe, gpst(2020, 6, 25, 0, 0, 16));
  EXPECT_DOUBLE_EQ(s.agf0_s, 1.0e-08);
  EXPECT_DOUBLE_EQ(s.agf1_s_per_s, -2.0e-12);
  EXPECT_DOUBLE_EQ(s.transmission_time_sow, 345630.0);
  EXPECT_NEAR(s.position_m.x(), 35944600.0, 1e-6);
  EXPECT_NEAR(s.position_m.y(), 22044140.0, 1e-6);
  EXPECT_EQ(s.health, 63);
  EXPECT_DOUBLE_EQ(s.accuracy_m, 32767.0);
  EXPECT_EQ(s.iodn, 92);
}

TEST(RinexNavReader, Rinex2Gps) {
  const auto nav = parse_ok("brdc.21n", kGps211);
  ASSERT_EQ(nav.kepler.size(), 2u);
  const auto& g06 = nav.kepler[0];
  EXPECT_EQ(g06.satellite.to_string(), "G06");
  EXPECT_EQ(g06.message, NavMessage::kGpsLnav);
  EXPECT_EQ(g06.toc, gpst(2021, 4, 28, 17, 59, 44));
  EXPECT_EQ(g06.toe, g06.toc);  // week 2155, 323984 s
  EXPECT_DOUBLE_EQ(g06.af0_s, 0.109337270260e-04);  // D exponents
  EXPECT_DOUBLE_EQ(g06.sqrt_a_sqrtm, 5153.75527);
  EXPECT_DOUBLE_EQ(g06.omega0_rad, -2.94507412083);
  EXPECT_EQ(g06.iode, 31);
  EXPECT_DOUBLE_EQ(g06.group_delays.tgd_s, 0.419095158577e-08);
  EXPECT_EQ(g06.source, "brdc.21n:7");
  // Two-digit year 99 -> 1999; toe in GPS week 1023.
  const auto& g13 = nav.kepler[1];
  EXPECT_EQ(g13.toc, gpst(1999, 8, 21, 23, 59, 44));
  EXPECT_EQ(g13.toe, g13.toc);
  EXPECT_DOUBLE_EQ(g13.accuracy_m, 4.0);
  ASSERT_TRUE(nav.ionosphere.gps);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->alpha[0], 0.9313e-08);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->beta[3], -0.3277e+06);
  ASSERT_EQ(nav.time_corrections.size(), 1u);
  EXPECT_EQ(nav.time_corrections[0].type, "GPUT");
  EXPECT_DOUBLE_EQ(nav.time_corrections[0].a0_s, -0.279396772385e-08);
  EXPECT_DOUBLE_EQ(nav.time_corrections[0].a1_s_per_s, -0.266453525910e-14);
  EXPECT_EQ(nav.time_corrections[0].reference_time, gpst(2021, 4, 30, 19, 56, 48));  // week 2155, 503808 s
  EXPECT_EQ(nav.leap_seconds, 18);
}

TEST(RinexNavReader, Rinex2GlonassUtcEpochAndKilometres) {
  const auto nav = parse_ok("brdc.16g", kGlonass201);
  ASSERT_EQ(nav.glonass.size(), 1u);
  const auto& r = nav.glonass[0];
  EXPECT_EQ(r.satellite.to_string(), "R01");
  EXPECT_DOUBLE_EQ(r.toe - gpst(2016, 6, 6, 0, 15, 0), 17.0);  // UTC + 17 s in 2016
  EXPECT_DOUBLE_EQ(r.minus_tau_n_s, -0.142809003591e-03);
  EXPECT_DOUBLE_EQ(r.message_frame_time_s, 30.0);
  EXPECT_NEAR(r.position_m.x(), -6553426.26953, 1e-6);
  EXPECT_NEAR(r.velocity_mps.y(), 1249.16648865, 1e-9);
  EXPECT_NEAR(r.acceleration_mps2.y(), -0.279396772385e-05, 1e-18);
  EXPECT_EQ(r.frequency_channel, 1);
  EXPECT_FALSE(r.delta_tau_n_s);
  ASSERT_EQ(nav.time_corrections.size(), 1u);
  EXPECT_EQ(nav.time_corrections[0].type, "GLUT");
  EXPECT_DOUBLE_EQ(nav.time_corrections[0].a0_s, 0.232830643654e-08);
  EXPECT_DOUBLE_EQ(nav.time_corrections[0].reference_time - gpst(2016, 6, 6, 0, 0, 0), 17.0);
  EXPECT_EQ(nav.leap_seconds, 17);
}

TEST(RinexNavReader, GlonassEpochWrittenInGpstIsSnappedToTheUtcGrid) {
  // A 2016 brdc writer put "12 15 17.0" (GPST) in the UTC epoch field: t_b is 12:15:00 UTC.
  std::string text(kGlonass201);
  const std::string written = " 1 16  6  6  0 15  0.0";
  text.replace(text.find(written), written.size(), " 1 16  6  6  0 15 17.0");
  const auto nav = parse_ok("brdc.16g", text);
  ASSERT_EQ(nav.glonass.size(), 1u);
  EXPECT_DOUBLE_EQ(nav.glonass[0].toe - gpst(2016, 6, 6, 0, 15, 0), 17.0);
  // Far off the grid (7 min 30 s) the epoch is kept as written.
  text.replace(text.find(" 0 15 17.0"), 10, " 0 07 30.0");
  const auto odd = parse_ok("brdc.16g", text);
  ASSERT_EQ(odd.glonass.size(), 1u);
  EXPECT_DOUBLE_EQ(odd.glonass[0].toe - gpst(2016, 6, 6, 0, 7, 30), 17.0);
}

TEST(RinexNavReader, Rinex2GeoFile) {
  const auto nav = parse_ok("geo.20h", kGeo211);
  ASSERT_EQ(nav.sbas.size(), 1u);
  EXPECT_EQ(nav.sbas[0].satellite.prn(), 120);
  EXPECT_EQ(nav.sbas[0].toe, gpst(2020, 6, 25, 0, 0, 16));
  EXPECT_NEAR(nav.sbas[0].position_m.x(), 35944600.0, 1e-6);
  EXPECT_EQ(nav.sbas[0].iodn, 92);
}

TEST(RinexNavReader, Rinex4Records) {
  const auto nav = parse_ok("v4.rnx", kRinex400);
  EXPECT_EQ(nav.kepler.size(), 5u);  // R04 L1OC, ION CNVX and EOP skipped
  EXPECT_EQ(nav.glonass.size(), 1u);
  EXPECT_EQ(nav.sbas.size(), 1u);
  EXPECT_EQ(nav.leap_seconds, 18);

  const auto* lnav = find(nav, "G05", NavMessage::kGpsLnav);
  ASSERT_NE(lnav, nullptr);
  EXPECT_EQ(lnav->source, "v4.rnx:4");
  EXPECT_EQ(lnav->toe, gpst(2022, 6, 8, 12, 0, 0));

  const auto* cnav = find(nav, "G05", NavMessage::kGpsCnav);
  ASSERT_NE(cnav, nullptr);
  EXPECT_DOUBLE_EQ(cnav->a_dot_m_per_s, 1.5e-2);
  EXPECT_DOUBLE_EQ(cnav->delta_n_dot_rad_per_s2, -2.0e-14);
  EXPECT_DOUBLE_EQ(cnav->sqrt_a_sqrtm, 5153.735490799);
  EXPECT_DOUBLE_EQ(cnav->group_delays.tgd_s, 5.0e-09);
  EXPECT_DOUBLE_EQ(cnav->group_delays.isc_l1ca_s, 1.0e-09);
  EXPECT_DOUBLE_EQ(cnav->group_delays.isc_l2c_s, -2.0e-09);
  EXPECT_DOUBLE_EQ(cnav->group_delays.isc_l5i5_s, 3.0e-09);
  EXPECT_DOUBLE_EQ(cnav->group_delays.isc_l5q5_s, -4.0e-09);
  EXPECT_DOUBLE_EQ(cnav->accuracy_m, 0.125);  // URAI_ED -8: 2^(1 - 8/2) m
  EXPECT_EQ(cnav->week, 2213);
  EXPECT_EQ(cnav->toe, cnav->toc);
  EXPECT_DOUBLE_EQ(cnav->transmission_time_sow, 295218.0);

  const auto* cnv2 = find(nav, "J03", NavMessage::kQzssCnav2);
  ASSERT_NE(cnv2, nullptr);
  EXPECT_DOUBLE_EQ(cnv2->group_delays.isc_l5q5_s, 4.0e-10);
  EXPECT_DOUBLE_EQ(cnv2->group_delays.isc_l1cd_s, 5.0e-10);
  EXPECT_DOUBLE_EQ(cnv2->group_delays.isc_l1cp_s, 6.0e-10);
  EXPECT_DOUBLE_EQ(cnv2->transmission_time_sow, 295200.0);

  const auto* fnav = find(nav, "E12", NavMessage::kGalileoFnav);
  ASSERT_NE(fnav, nullptr);
  EXPECT_EQ(fnav->data_source, 258u);
  EXPECT_EQ(fnav->toe, gpst(2022, 6, 8, 9, 40, 0));

  const auto* b1c = find(nav, "C25", NavMessage::kBeiDouCnav1);
  ASSERT_NE(b1c, nullptr);
  EXPECT_DOUBLE_EQ(b1c->toc - gpst(2022, 6, 8, 12, 0, 0), 14.0);
  EXPECT_EQ(b1c->toe, b1c->toc);  // no week field: the BDT week of toc
  EXPECT_EQ(b1c->week, 857);
  EXPECT_DOUBLE_EQ(b1c->a_dot_m_per_s, 0.5);
  EXPECT_DOUBLE_EQ(b1c->group_delays.isc_b1cd_s, 1.0e-09);
  EXPECT_DOUBLE_EQ(b1c->group_delays.tgd_b1cp_s, 2.0e-09);
  EXPECT_DOUBLE_EQ(b1c->group_delays.tgd_b2ap_s, 3.0e-09);
  EXPECT_EQ(b1c->iodc, 12);
  EXPECT_EQ(b1c->iode, 34);
  EXPECT_DOUBLE_EQ(b1c->transmission_time_sow, 302418.0);

  const auto& r = nav.glonass[0];
  EXPECT_DOUBLE_EQ(r.toe - gpst(2022, 6, 8, 9, 45, 0), 18.0);
  EXPECT_EQ(r.frequency_channel, 5);
  ASSERT_TRUE(r.delta_tau_n_s);
  EXPECT_DOUBLE_EQ(*r.delta_tau_n_s, -2.793967723846e-09);
  EXPECT_EQ(r.urai, 3);
  EXPECT_EQ(r.status_flags, 183);
  EXPECT_DOUBLE_EQ(r.message_frame_time_s, 34200.0);

  const auto& s = nav.sbas[0];
  EXPECT_NEAR(s.position_m.z(), -3222.0, 1e-9);
  EXPECT_NEAR(s.velocity_mps.x(), -0.451875, 1e-12);
  EXPECT_EQ(s.health, 31);
  EXPECT_DOUBLE_EQ(s.accuracy_m, 2.0);

  ASSERT_TRUE(nav.ionosphere.gps);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->alpha[0], 1.024454832077e-08);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->alpha[3], -1.192092895508e-07);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->beta[0], 9.6256e+04);
  EXPECT_DOUBLE_EQ(nav.ionosphere.gps->beta[3], -5.89824e+05);
  ASSERT_TRUE(nav.ionosphere.galileo);
  EXPECT_DOUBLE_EQ(nav.ionosphere.galileo->ai0_sfu, 78.5);
  EXPECT_FALSE(nav.ionosphere.beidou);  // BDGIM (CNVX) is not read

  ASSERT_EQ(nav.time_corrections.size(), 1u);
  EXPECT_EQ(nav.time_corrections[0].type, "GPUT");
  EXPECT_DOUBLE_EQ(nav.time_corrections[0].a0_s, 9.313225746155e-10);
  EXPECT_DOUBLE_EQ(nav.time_corrections[0].a1_s_per_s, 2.664535259100e-15);
  EXPECT_EQ(nav.time_corrections[0].reference_time, gpst(2022, 6, 10, 19, 56, 48));
  EXPECT_EQ(nav.time_corrections[0].source, "v4.rnx:79");
}

// ------------------------------------------------------------------------------------- bad input

// A minimal RINEX 3.04 GPS file: line 1 version, line 2 end of header, lines 3-10 one record.
const std::string kMinimalHeader =
    "     3.04           N: GNSS NAV DATA    G: GPS              RINEX VERSION / TYPE\n"
    "                                                            END OF HEADER\n";
const std::string kG05 =
    "G05 2020 06 25 04 00 00 1.604342833161E-05 7.048583938740E-12 0.000000000000E+00\n"
    "     5.800000000000E+01-3.968750000000E+01 4.304822170265E-09 6.342094507864E-01\n"
    "    -2.177432179451E-06 1.000394229777E-02 1.937150955200E-06 5.153707128525E+03\n"
    "     3.600000000000E+05-1.508742570877E-07 2.572838528869E+00 1.359730958939E-07\n"
    "     9.806518601091E-01 3.539687500000E+02 7.941703015008E-01-8.384634967987E-09\n"
    "    -5.714523747137E-11 1.000000000000E+00 2.111000000000E+03 0.000000000000E+00\n"
    "     2.000000000000E+00 0.000000000000E+00 5.122274160385E-09 5.800000000000E+01\n"
    "     3.561060000000E+05 4.000000000000E+00\n";

std::string first_lines(const std::string& text, int count) {
  size_t pos = 0;
  for (int i = 0; i < count; ++i) pos = text.find('\n', pos) + 1;
  return text.substr(0, pos);
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const size_t pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

Error parse_error(const std::string& text, const std::string& name = "t.rnx") {
  auto nav = parse_rinex_nav(name, text);
  EXPECT_FALSE(nav.ok());
  return nav ? Error{} : nav.error();
}

TEST(RinexNavReaderErrors, MinimalFileParses) {
  const auto nav = parse_ok("t.rnx", kMinimalHeader + kG05);
  EXPECT_EQ(nav.kepler.size(), 1u);
}

TEST(RinexNavReaderErrors, TruncatedRecordAtEndOfFile) {
  const Error e = parse_error(kMinimalHeader + first_lines(kG05, 5));
  EXPECT_EQ(e.code, ErrorCode::kParse);
  EXPECT_EQ(e.message, "t.rnx:3: record of G05 ends after 5 of 8 lines");
}

TEST(RinexNavReaderErrors, TruncatedRecordFollowedByAnother) {
  const std::string g06 = replaced(kG05, "G05", "G06");
  const Error e = parse_error(kMinimalHeader + first_lines(kG05, 7) + g06);
  EXPECT_EQ(e.message, "t.rnx:3: record of G05 ends after 7 of 8 lines");
}

TEST(RinexNavReaderErrors, MalformedNumberNamesTheField) {
  const Error e = parse_error(kMinimalHeader + replaced(kG05, "5.153707128525E+03", "5.15370x128525E+03"));
  EXPECT_EQ(e.code, ErrorCode::kParse);
  EXPECT_EQ(e.message, "t.rnx:5: field 'sqrt(A)': not a number '5.15370x128525E+03'");
}

TEST(RinexNavReaderErrors, BlankRequiredFieldIsNotZero) {
  const Error e = parse_error(kMinimalHeader + replaced(kG05, "-3.968750000000E+01", "                   "));
  EXPECT_EQ(e.message, "t.rnx:4: field 'Crs': missing (blank)");
}

TEST(RinexNavReaderErrors, UnknownSystemLetter) {
  const Error e = parse_error(kMinimalHeader + replaced(kG05, "G05", "X05"));
  EXPECT_EQ(e.code, ErrorCode::kParse);
  EXPECT_EQ(e.message, "t.rnx:3: unknown satellite system letter 'X'");
}

TEST(RinexNavReaderErrors, SatelliteNumberOutOfRange) {
  const Error e = parse_error(kMinimalHeader + replaced(kG05, "G05", "G45"));
  EXPECT_EQ(e.message.rfind("t.rnx:3: field 'satellite':", 0), 0u) << e.message;
}

TEST(RinexNavReaderErrors, EpochOutOfRange) {
  const Error e = parse_error(kMinimalHeader + replaced(kG05, "2020 06 25", "2020 13 25"));
  EXPECT_EQ(e.message, "t.rnx:3: field 'epoch month': 13 out of range");
}

TEST(RinexNavReaderErrors, ObservationFileIsNotANavigationFile) {
  const Error e = parse_error(
      "     3.04           OBSERVATION DATA    M: MIXED            RINEX VERSION / TYPE\n"
      "                                                            END OF HEADER\n");
  EXPECT_EQ(e.code, ErrorCode::kParse);
  EXPECT_EQ(e.message, "t.rnx:1: not a RINEX navigation file (file type 'O' in RINEX VERSION / TYPE)");
}

TEST(RinexNavReaderErrors, NotRinexAtAll) {
  const Error e = parse_error("hello world\n");
  EXPECT_EQ(e.message, "t.rnx:1: not a RINEX file: the first line lacks 'RINEX VERSION / TYPE'");
  EXPECT_EQ(parse_error("").message.rfind("t.rnx:1: not a RINEX file", 0), 0u);
}

TEST(RinexNavReaderErrors, MissingEndOfHeader) {
  const Error e = parse_error(
      "     3.04           N: GNSS NAV DATA    G: GPS              RINEX VERSION / TYPE\n"
      "    18                                                      LEAP SECONDS\n");
  EXPECT_EQ(e.message, "t.rnx:2: header has no 'END OF HEADER' line");
}

TEST(RinexNavReaderErrors, UnsupportedVersion) {
  const Error e = parse_error(
      "     1.00           N: GPS NAV DATA                         RINEX VERSION / TYPE\n"
      "                                                            END OF HEADER\n");
  EXPECT_EQ(e.code, ErrorCode::kUnsupported);
  EXPECT_EQ(e.message.rfind("t.rnx:1: unsupported RINEX version 1.00", 0), 0u) << e.message;
}

TEST(RinexNavReaderErrors, GalileoWithoutMessageBits) {
  std::string e11 = replaced(kG05, "G05", "E11");
  e11 = replaced(e11, "-5.714523747137E-11 1.000000000000E+00", "-5.714523747137E-11 1.600000000000E+01");
  const Error e = parse_error(kMinimalHeader + e11);
  EXPECT_EQ(e.message, "t.rnx:8: field 'data sources': 16 sets neither I/NAV nor F/NAV bits");
}

TEST(RinexNavReaderErrors, GalileoE5bOnlyIsInavAndContradictoryBitsFail) {
  std::string e11 = replaced(kG05, "G05", "E11");
  const std::string source_field = "-5.714523747137E-11 1.000000000000E+00";
  // 516 = bit 2 (I/NAV E5b-I) + bit 9 (clock for E5b): I/NAV without the E1-B bit.
  auto nav = parse_ok("t.rnx", kMinimalHeader + replaced(e11, source_field, "-5.714523747137E-11 5.160000000000E+02"));
  ASSERT_EQ(nav.kepler.size(), 1u);
  EXPECT_EQ(nav.kepler[0].message, NavMessage::kGalileoInav);
  // 257 = I/NAV E1-B with the E5a (F/NAV) clock bit.
  const Error e = parse_error(kMinimalHeader + replaced(e11, source_field, "-5.714523747137E-11 2.570000000000E+02"));
  EXPECT_EQ(e.message, "t.rnx:8: field 'data sources': 257 sets both I/NAV and F/NAV bits");
}

TEST(RinexNavReaderErrors, Rinex4TruncatedAndMismatchedRecords) {
  const std::string header =
      "     4.00           N: GNSS NAV DATA    M: MIXED            RINEX VERSION / TYPE\n"
      "                                                            END OF HEADER\n";
  Error e = parse_error(header + "> EPH G05 LNAV\n" + first_lines(kG05, 6) + "> EPH G06 LNAV\n" +
                        replaced(kG05, "G05", "G06"));
  EXPECT_EQ(e.message, "t.rnx:3: record of G05 ends after 6 of 8 lines");
  e = parse_error(header + "> EPH G06 LNAV\n" + kG05);
  EXPECT_EQ(e.message, "t.rnx:4: satellite G05 differs from G06 named on the record start");
  e = parse_error(header + kG05);
  EXPECT_EQ(e.message.rfind("t.rnx:3: expected a record start '>'", 0), 0u) << e.message;
  e = parse_error(header + "> EPH X05 LNAV\n" + kG05);
  EXPECT_EQ(e.message, "t.rnx:3: unknown satellite system letter 'X'");
}

TEST(RinexNavReaderErrors, ExtraBroadcastOrbitLine) {
  const std::string extra = "     1.000000000000E+00\n";
  Error e = parse_error(kMinimalHeader + kG05 + extra);
  EXPECT_EQ(e.message, "t.rnx:11: broadcast-orbit line outside a record");
  const std::string header4 =
      "     4.00           N: GNSS NAV DATA    M: MIXED            RINEX VERSION / TYPE\n"
      "                                                            END OF HEADER\n";
  e = parse_error(header4 + "> EPH G05 LNAV\n" + kG05 + extra);
  EXPECT_EQ(e.message, "t.rnx:12: record of G05 has 9 lines, expected 8");
}

TEST(RinexNavReaderErrors, Rinex2TruncatedGlonassRecord) {
  const std::string text(kGlonass201);
  const Error e = parse_error(first_lines(text, 6), "brdc.16g");
  EXPECT_EQ(e.message, "brdc.16g:5: record of R01 ends after 2 of 4 lines");
}

TEST(RinexNavReaderErrors, TrailingBlankLinesAndCrlfAreFine) {
  auto nav = parse_ok("t.rnx", kMinimalHeader + kG05 + "\n\n    \n");
  EXPECT_EQ(nav.kepler.size(), 1u);
  std::string crlf;
  for (const char c : kMinimalHeader + kG05) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  nav = parse_ok("t.rnx", crlf);
  ASSERT_EQ(nav.kepler.size(), 1u);
  EXPECT_DOUBLE_EQ(nav.kepler[0].fit_interval_h, 4.0);
}

TEST(RinexNavReaderFiles, GzipFileAndMissingFile) {
  const auto dir = test::make_temp_dir("rinex_nav_reader_gzip");
  const auto path = dir / "brdc.21n.gz";
  gzFile out = gzopen(path.c_str(), "wb");
  ASSERT_NE(out, nullptr);
  const std::string text(kGps211);
  ASSERT_EQ(gzwrite(out, text.data(), static_cast<unsigned>(text.size())), static_cast<int>(text.size()));
  ASSERT_EQ(gzclose(out), Z_OK);
  auto nav = read_rinex_nav(path);
  ASSERT_TRUE(nav.ok()) << nav.error().message;
  EXPECT_EQ(nav->kepler.size(), 2u);
  ASSERT_EQ(nav->source_files.size(), 1u);
  EXPECT_EQ(nav->source_files[0], path.string());
  EXPECT_EQ(nav->kepler[0].source, "brdc.21n.gz:7");

  auto missing = read_rinex_nav(dir / "absent.rnx");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code, ErrorCode::kIo);
}

}  // namespace
}  // namespace skytrace::orbits

#include "skytrace/core/satellite_catalog.hpp"

#include <algorithm>
#include <array>
#include <limits>

namespace skytrace {
namespace {

using B = SatelliteBlock;

// One PRN (GLONASS: slot) assignment. Times are those of the IGS metadata SINEX file:
// year * 1000 + day of year, and second of day; `until` is inclusive (the SINEX "Valid_To").
struct Row {
  GnssSystem system;
  std::uint8_t number;
  std::uint16_t svn;
  SatelliteBlock block;
  std::int64_t from_key;
  std::int64_t until_key;
};

constexpr int kOpen = 0;
constexpr std::int64_t kOpenKey = std::numeric_limits<std::int64_t>::max();

constexpr std::int64_t make_key(int year_doy, int second_of_day) {
  return static_cast<std::int64_t>(year_doy) * 100000 + second_of_day;
}

constexpr Row row(GnssSystem system, int number, int svn, B block, int from_year_doy, int until_year_doy,
                  int from_second = 0, int until_second = 86399) {
  return Row{system,
             static_cast<std::uint8_t>(number),
             static_cast<std::uint16_t>(svn),
             block,
             make_key(from_year_doy, from_second),
             until_year_doy == kOpen ? kOpenKey : make_key(until_year_doy, until_second)};
}

// Per-system shorthands so that the table reads like the SINEX rows it comes from.
constexpr Row G(int prn, int svn, B block, int from, int until, int from_s = 0, int until_s = 86399) {
  return row(GnssSystem::kGps, prn, svn, block, from, until, from_s, until_s);
}
constexpr Row R(int slot, int svn, B block, int from, int until, int from_s = 0, int until_s = 86399) {
  return row(GnssSystem::kGlonass, slot, svn, block, from, until, from_s, until_s);
}
constexpr Row E(int prn, int svn, B block, int from, int until) {
  return row(GnssSystem::kGalileo, prn, svn, block, from, until);
}
constexpr Row C(int prn, int svn, B block, int from, int until, int from_s = 0, int until_s = 86399) {
  return row(GnssSystem::kBeiDou, prn, svn, block, from, until, from_s, until_s);
}
constexpr Row J(int number, int svn, B block, int from, int until) {
  return row(GnssSystem::kQzss, number, svn, block, from, until);
}
constexpr Row S(int number, B block, int from, int until) {
  return row(GnssSystem::kSbas, number, 0, block, from, until);
}

constexpr B IIA = B::kGpsIIA, IIRA = B::kGpsIIRA, IIRB = B::kGpsIIRB, IIRM = B::kGpsIIRM, IIF = B::kGpsIIF,
            III = B::kGpsIIIA;
constexpr B GM = B::kGlonassM, GMP = B::kGlonassMPlus, GK1 = B::kGlonassK1, GK2 = B::kGlonassK2;
constexpr B IOV = B::kGalileoIov, FOC = B::kGalileoFoc;
constexpr B C2G = B::kBds2Geo, C2I = B::kBds2Igso, C2M = B::kBds2Meo, C3G = B::kBds3Geo, C3I = B::kBds3Igso,
            C3M = B::kBds3Meo, C3SI = B::kBds3SIgso, C3SM = B::kBds3SMeo;

// Sources (docs/satellites.md): [IGS] IGS satellite metadata SINEX as tabulated by PRIDE-PPPAR
// table/sat_parameters (generated 2024-02-07), rows ending before 2010 left out; [IGS24] 2024
// GPS PRN 01 rows of the same SINEX quoted by canvodpy's tests; [CT] CelesTrak GPS element sets
// (names carry the PRN) of 2024-11-25, 2025-11-14, 2026-04-06 and 2026-07-15; [QZ] qzss.go.jp
// notice of 2022-03-14; [EG] EGNOS service notice 015 (via Spirent FAQ18382). Open rows are open
// in the newest source.
constexpr auto kRows = std::to_array<Row>({
    // ---- GPS [IGS]
    G(1, 49, IIRM, 2009083, 2011126), G(1, 35, IIA, 2011153, 2011193),
    G(1, 63, IIF, 2011197, 2024103, 0, 0),                                   // end [IGS24]
    G(1, 49, IIRM, 2024113, 2024352, 0, 0), G(1, 80, III, 2024352, kOpen),   // [IGS24], [CT]
    G(2, 61, IIRB, 2004311, kOpen),
    G(3, 33, IIA, 1996088, 2014230), G(3, 35, IIA, 2014248, 2014293), G(3, 69, IIF, 2014302, kOpen),
    G(4, 34, IIA, 1993299, 2015313), G(4, 49, IIRM, 2016033, 2016257), G(4, 32, IIA, 2016259, 2016340),
    G(4, 34, IIA, 2016344, 2017003), G(4, 49, IIRM, 2017006, 2017132), G(4, 38, IIA, 2017139, 2017195),
    G(4, 36, IIA, 2017201, 2017332), G(4, 49, IIRM, 2017335, 2018271), G(4, 36, IIA, 2018283, 2019002),
    G(4, 74, III, 2019009, 2019193), G(4, 36, IIA, 2019194, 2019281), G(4, 74, III, 2019294, kOpen),
    G(5, 50, IIRM, 2009229, kOpen),
    G(6, 36, IIA, 1994069, 2014062), G(6, 49, IIRM, 2014093, 2014125), G(6, 67, IIF, 2014137, kOpen),
    G(7, 48, IIRM, 2008075, kOpen),
    G(8, 38, IIA, 1997310, 2015103), G(8, 49, IIRM, 2015120, 2015182), G(8, 72, IIF, 2015196, kOpen),
    G(9, 39, IIA, 1993177, 2014202), G(9, 68, IIF, 2014214, kOpen),
    G(10, 40, IIA, 1996198, 2015215), G(10, 36, IIA, 2015259, 2015299), G(10, 73, IIF, 2015304, kOpen),
    G(11, 46, IIRA, 1999280, 2021099), G(11, 78, III, 2021168, kOpen),
    G(12, 58, IIRM, 2006321, kOpen),
    // PRN 13, 20, 21 went to new GPS III satellites after [IGS]; the handover dates are unknown,
    // so the old row ends on the last date a source shows it, the new row starts on the first
    // ([CT]: PRN 21 SVN 45 on 2024-11-25; PRN 21 GPS III SV08 and PRN 20 SVN 51 on 2025-11-14;
    // PRN 13 SVN 43 on 2026-04-06; PRN 13 SV10 and PRN 20 SV09 on 2026-07-15). SVNs of SV08..SV10
    // are not in the sources: 0.
    G(13, 43, IIRA, 1997204, 2026096), G(13, 0, III, 2026196, kOpen),
    G(14, 41, IIRA, 2000315, 2020209), G(14, 77, III, 2020310, kOpen),
    G(15, 55, IIRM, 2007290, kOpen),
    G(16, 56, IIRA, 2003029, kOpen),
    G(17, 53, IIRM, 2005269, kOpen),
    G(18, 54, IIRA, 2001030, 2018023), G(18, 34, IIA, 2018024, 2020069), G(18, 75, III, 2020073, kOpen),
    G(19, 59, IIRB, 2004080, kOpen),
    G(20, 51, IIRA, 2000132, 2025318), G(20, 0, III, 2026196, kOpen),
    G(21, 45, IIRA, 2003090, 2024330), G(21, 0, III, 2025318, kOpen),
    G(22, 47, IIRB, 2003355, 2022018), G(22, 41, IIRA, 2022020, 2023219), G(22, 44, IIRA, 2023222, kOpen),
    G(23, 60, IIRB, 2004175, 2020161), G(23, 76, III, 2020196, kOpen),
    G(24, 24, IIA, 1991185, 2011273), G(24, 49, IIRM, 2012033, 2012074), G(24, 32, IIA, 2012075, 2012116),
    G(24, 37, IIA, 2012117, 2012151), G(24, 49, IIRM, 2012222, 2012235), G(24, 65, IIF, 2012278, kOpen),
    G(25, 25, IIA, 1992054, 2010039), G(25, 35, IIA, 2010040, 2010147), G(25, 62, IIF, 2010148, kOpen),
    G(26, 26, IIA, 1992189, 2015005), G(26, 32, IIA, 2015036, 2015055), G(26, 27, IIA, 2015058, 2015075),
    G(26, 71, IIF, 2015084, kOpen),
    G(27, 27, IIA, 1992253, 2012291), G(27, 49, IIRM, 2012292, 2013129), G(27, 66, IIF, 2013135, kOpen),
    G(28, 44, IIRA, 2000198, 2022298), G(28, 49, IIRM, 2022299, 2022306), G(28, 79, III, 2023031, kOpen),
    G(29, 57, IIRM, 2007354, kOpen),
    G(30, 30, IIA, 1996256, 2011216), G(30, 35, IIA, 2011217, 2013126), G(30, 49, IIRM, 2013130, 2013233),
    G(30, 32, IIA, 2013234, 2013259), G(30, 37, IIA, 2013262, 2013280), G(30, 27, IIA, 2013337, 2013351),
    G(30, 49, IIRM, 2013353, 2014041), G(30, 64, IIF, 2014052, kOpen),
    G(31, 52, IIRM, 2006268, kOpen),
    G(32, 23, IIA, 2006336, 2016025), G(32, 70, IIF, 2016036, kOpen),

    // ---- GLONASS slots [IGS]; consecutive rows that differ only in frequency channel are merged.
    // M+ = serials 755..761 (IGS R855..R861), the GLONASS-M satellites with an L3 CDMA payload.
    R(1, 730, GM, 2009348, kOpen),
    R(2, 728, GM, 2008360, 2013181), R(2, 747, GM, 2013182, kOpen),
    R(3, 727, GM, 2008360, 2010273), R(3, 722, GM, 2010274, 2010349), R(3, 727, GM, 2010350, 2011069),
    R(3, 715, GM, 2011070, 2011285), R(3, 801, GK1, 2011286, 2011334), R(3, 744, GM, 2011335, kOpen),
    R(4, 733, GM, 2009348, 2010273), R(4, 727, GM, 2010274, 2010349), R(4, 801, GK1, 2011057, 2011284, 0, 0),
    R(4, 742, GM, 2011286, 2019237), R(4, 859, GMP, 2019361, kOpen),
    R(5, 734, GM, 2009348, 2018224, 0, 0), R(5, 856, GMP, 2018234, kOpen),
    R(6, 701, GM, 2009257, 2010117), R(6, 714, GM, 2010118, 2010273), R(6, 733, GM, 2010274, kOpen),
    R(7, 712, GM, 2007037, 2011348, 86399), R(7, 745, GM, 2011349, kOpen),
    R(8, 729, GM, 2008360, 2012257, 0, 0), R(8, 743, GM, 2012261, 2012291), R(8, 712, GM, 2012292, 2012356),
    R(8, 743, GM, 2012357, 2013005), R(8, 801, GK1, 2013006, 2013053), R(8, 743, GM, 2013054, kOpen),
    R(9, 722, GM, 2007359, 2010273), R(9, 736, GM, 2010274, 2016046), R(9, 802, GK1, 2016047, kOpen),
    R(10, 717, GM, 2009070, 2019214, 86399, 0), R(10, 723, GM, 2019273, kOpen),
    R(11, 723, GM, 2007359, 2016175), R(11, 853, GM, 2016176, 2020335), R(11, 805, GK1, 2020336, 2022077),
    R(11, 805, GK1, 2022087, 2022240), R(11, 805, GK1, 2022242, kOpen),
    R(12, 737, GM, 2010245, 2016327, 0, 0), R(12, 723, GM, 2016350, 2019170, 0, 37799),
    R(12, 858, GMP, 2019170, kOpen, 37800),
    R(13, 721, GM, 2007359, kOpen),
    R(14, 715, GM, 2009070, 2010349, 86399), R(14, 722, GM, 2010350, 2011285), R(14, 715, GM, 2011286, 2017189),
    R(14, 801, GK1, 2017264, 2017278), R(14, 852, GM, 2017283, kOpen),
    R(15, 716, GM, 2006359, 2018327), R(15, 857, GMP, 2018328, kOpen),
    R(16, 736, GM, 2010245, 2010273), R(16, 738, GM, 2010274, 2016045), R(16, 736, GM, 2016069, 2021347),
    R(16, 861, GMP, 2022354, kOpen),
    R(17, 718, GM, 2009070, 2010349, 86399), R(17, 714, GM, 2010350, 2011353), R(17, 746, GM, 2011354, 2015102),
    R(17, 714, GM, 2015103, 2016026), R(17, 802, GK1, 2016027, 2016046), R(17, 714, GM, 2016047, 2016054),
    R(17, 851, GM, 2016055, kOpen),
    R(18, 724, GM, 2008269, 2014042), R(18, 714, GM, 2014049, 2014100), R(18, 854, GM, 2014101, kOpen),
    R(19, 720, GM, 2007299, kOpen),
    R(20, 719, GM, 2007299, kOpen),
    R(21, 725, GM, 2009070, 2014213, 86399), R(21, 855, GMP, 2014214, kOpen),
    R(22, 726, GM, 2008269, 2010059), R(22, 731, GM, 2010060, 2020176), R(22, 735, GM, 2020226, 2022155),
    R(22, 806, GK1, 2022281, 2022356), R(22, 806, GK1, 2022361, kOpen),
    R(23, 714, GM, 2006059, 2010077), R(23, 732, GM, 2010078, kOpen),
    R(24, 713, GM, 2005359, 2010059), R(24, 735, GM, 2010060, 2020101, 0, 17999),
    R(24, 860, GMP, 2020101, kOpen, 18000),
    R(25, 805, GK1, 2020317, 2020335), R(25, 805, GK1, 2022219, 2022236), R(25, 805, GK1, 2022238, 2022280),
    R(25, 807, GK1, 2022310, 2023250), R(25, 807, GK1, 2023257, kOpen),
    R(26, 801, GK1, 2012075, 2013005), R(26, 801, GK1, 2013054, 2017263), R(26, 801, GK1, 2017279, 2021337),
    R(26, 801, GK1, 2022279, 2022281), R(26, 801, GK1, 2022310, 2023002), R(26, 803, GK2, 2023252, 2023256),
    R(26, 803, GK2, 2023258, 2023313), R(26, 803, GK2, 2023316, 2023363), R(26, 803, GK2, 2024005, kOpen),
    R(27, 802, GK1, 2014334, 2016026), R(27, 716, GM, 2019215, 2021337),

    // ---- Galileo [IGS] (GIOVE-A/B, E51/E52, ended 2012 and are left out)
    E(1, 210, FOC, 2016145, kOpen), E(2, 211, FOC, 2016145, kOpen), E(3, 212, FOC, 2016322, kOpen),
    E(4, 213, FOC, 2016322, kOpen), E(5, 214, FOC, 2016322, kOpen), E(7, 207, FOC, 2016322, kOpen),
    E(8, 208, FOC, 2015351, kOpen), E(9, 209, FOC, 2015351, kOpen), E(10, 224, FOC, 2021339, kOpen),
    E(11, 101, IOV, 2011294, kOpen), E(12, 102, IOV, 2011294, kOpen), E(13, 220, FOC, 2018206, kOpen),
    E(14, 202, FOC, 2014234, kOpen), E(15, 221, FOC, 2018206, kOpen), E(18, 201, FOC, 2014234, kOpen),
    E(19, 103, IOV, 2012286, kOpen), E(20, 104, IOV, 2012286, kOpen), E(21, 215, FOC, 2017346, kOpen),
    E(22, 204, FOC, 2015086, kOpen), E(24, 205, FOC, 2015254, kOpen), E(25, 216, FOC, 2017346, kOpen),
    E(26, 203, FOC, 2015086, kOpen), E(27, 217, FOC, 2017346, kOpen), E(30, 206, FOC, 2015254, kOpen),
    E(31, 218, FOC, 2017346, kOpen), E(33, 222, FOC, 2018206, kOpen), E(34, 223, FOC, 2021339, kOpen),
    E(36, 219, FOC, 2018206, kOpen),

    // ---- BeiDou [IGS]
    C(1, 3, C2G, 2010016, 2020091, 0, 13499), C(1, 20, C2G, 2020091, kOpen, 13500),
    C(2, 16, C2G, 2012299, kOpen),
    C(3, 4, C2G, 2010153, 2018271), C(3, 18, C2G, 2018272, kOpen, 7320),
    C(4, 6, C2G, 2010304, kOpen),
    C(5, 11, C2G, 2012055, kOpen),
    C(6, 5, C2I, 2010212, kOpen), C(7, 7, C2I, 2010351, kOpen), C(8, 8, C2I, 2011099, kOpen),
    C(9, 9, C2I, 2011207, kOpen), C(10, 10, C2I, 2011335, kOpen),
    C(11, 12, C2M, 2012120, kOpen), C(12, 13, C2M, 2012120, kOpen),
    C(13, 14, C2M, 2012262, 2014294), C(13, 17, C2I, 2016285, kOpen, 27000),
    C(14, 15, C2M, 2012262, kOpen),
    C(15, 17, C2I, 2016089, 2016285, 0, 18000),
    C(16, 101, C3SI, 2018114, 2018191, 36060, 28800), C(16, 19, C2I, 2018197, kOpen),
    C(17, 18, C2G, 2016164, 2018272, 0, 7319),
    C(18, 104, C3SI, 2018158, 2019114, 36300, 7200), C(18, 20, C2G, 2019143, 2020091, 0, 13499),
    C(19, 201, C3M, 2017309, 2018163), C(19, 102, C3SM, 2018165, 2018314, 31620), C(19, 201, C3M, 2018319, kOpen),
    C(20, 202, C3M, 2017309, kOpen), C(21, 206, C3M, 2018043, kOpen), C(22, 205, C3M, 2018043, kOpen),
    C(23, 209, C3M, 2018210, kOpen), C(24, 210, C3M, 2018210, kOpen), C(25, 212, C3M, 2018236, kOpen),
    C(26, 211, C3M, 2018236, kOpen), C(27, 203, C3M, 2018011, kOpen),
    C(28, 204, C3M, 2018011, 2018162, 0, 43199), C(28, 103, C3SM, 2018162, 2018354, 43200, 50400),
    C(28, 204, C3M, 2018354, kOpen, 54000),
    C(29, 207, C3M, 2018088, kOpen),
    C(30, 1, C2M, 2007103, 2012181), C(30, 208, C3M, 2018088, kOpen),
    C(31, 101, C3SI, 2015089, 2018114, 0, 36000), C(31, 101, C3SI, 2018191, kOpen, 28860),
    C(32, 104, C3SI, 2015272, 2018158, 0, 36299), C(32, 213, C3M, 2018262, kOpen),
    C(33, 102, C3SM, 2015211, 2018165, 0, 31619), C(33, 214, C3M, 2018262, kOpen),
    C(34, 103, C3SM, 2015211, 2018162, 0, 34380), C(34, 216, C3M, 2018288, kOpen),
    C(35, 215, C3M, 2018288, kOpen), C(36, 218, C3M, 2018322, kOpen), C(37, 219, C3M, 2018322, kOpen),
    C(38, 220, C3I, 2019110, kOpen), C(39, 221, C3I, 2019175, kOpen), C(40, 224, C3I, 2019308, kOpen),
    C(41, 227, C3M, 2019350, kOpen), C(42, 228, C3M, 2019350, kOpen), C(43, 226, C3M, 2019327, kOpen),
    C(44, 225, C3M, 2019327, kOpen), C(45, 223, C3M, 2019280, kOpen), C(46, 222, C3M, 2019280, kOpen),
    C(47, 201, C3M, 2018200, 2018318), C(48, 204, C3M, 2018200, 2018354, 0, 50400),
    C(56, 104, C3SI, 2019115, kOpen), C(57, 102, C3SM, 2018316, kOpen), C(58, 103, C3SM, 2018354, kOpen, 54000),
    C(59, 217, C3G, 2018305, kOpen), C(60, 229, C3G, 2020069, kOpen), C(61, 230, C3G, 2020175, kOpen),
    C(62, 231, C3G, 2023137, kOpen),

    // ---- QZSS [IGS]; QZS-1 stopped transmitting when QZS-1R took over on 2022-03-24 [QZ]
    J(1, 1, B::kQzs1, 2010254, 2022082), J(2, 2, B::kQzs2Igso, 2017152, kOpen),
    J(3, 4, B::kQzs2Igso, 2017282, kOpen), J(4, 5, B::kQzs2A, 2021321, kOpen),
    J(7, 3, B::kQzs2Geo, 2017231, kOpen),

    // ---- SBAS: the two EGNOS GEOs with an L5 payload seen in the reference data [EG]
    S(23, B::kSbasGeo, 2017079, kOpen),  // PRN 123, ASTRA-5B, operational from 2017-03-20
    S(36, B::kSbasGeo, 2017080, kOpen),  // PRN 136, SES-5, EGNOS test platform from 2017-03-21
});

// The GPST calendar date of `t` as a SINEX-style key (the table's ~1 s resolution is ample).
std::int64_t key_of(const GnssTime& t) {
  const CalendarTime cal = t.to_calendar(TimeScale::kGpst);
  const int second_of_day = cal.hour * 3600 + cal.minute * 60 + static_cast<int>(cal.second);
  return make_key(cal.year * 1000 + t.day_of_year(TimeScale::kGpst), second_of_day);
}

GnssTime time_of(std::int64_t key) {
  const auto year_doy = static_cast<int>(key / 100000);
  const auto second_of_day = static_cast<double>(key % 100000);
  const GnssTime new_year = GnssTime::from_calendar(CalendarTime{year_doy / 1000, 1, 1, 0, 0, 0.0}, TimeScale::kGpst);
  return new_year + ((year_doy % 1000) - 1) * 86400.0 + second_of_day;
}

SatelliteInfo to_info(const Row& r) {
  SatelliteInfo info;
  info.id = SatelliteId{r.system, r.number};
  info.svn = r.svn;
  info.block_id = r.block;
  info.block = std::string(block_name(r.block));
  info.valid_from = time_of(r.from_key);
  info.open_ended = r.until_key == kOpenKey;
  // Open rows end "in the far future": 2100-01-01.
  info.valid_until = info.open_ended ? time_of(make_key(2100001, 0)) : time_of(r.until_key) + 1.0;
  return info;
}

const Row* find_row(const SatelliteId& id, std::int64_t key) {
  for (const Row& r : kRows) {
    if (r.system == id.system && r.number == id.number && r.from_key <= key && key <= r.until_key) return &r;
  }
  return nullptr;
}

using A = SignalAvailability;

constexpr A yes_if(bool condition) { return condition ? A::kYes : A::kNo; }

// GPS (IS-GPS-200/705/800): C/A and P(Y) on every block; M code and L2C from IIR-M; L5 from IIF;
// L1C from III. P with AS off (1P/2P) is only seen in tests; L2 C/A (2C) is not broadcast in
// normal operations.
A gps_availability(B block, int svn, char band, char attribute) {
  const bool known = block != B::kUnknown;
  const bool modernized = block == B::kGpsIIRM || block == B::kGpsIIF || block == B::kGpsIIIA;
  const bool l5_block = block == B::kGpsIIF || block == B::kGpsIIIA;
  switch (band) {
    case '1':
      switch (attribute) {
        case 'C': case 'W': case 'Y': case 'N': return A::kYes;
        case 'P': return A::kUncertain;
        case 'M': return known ? yes_if(modernized) : A::kUncertain;
        case 'S': case 'L': case 'X': return known ? yes_if(block == B::kGpsIIIA) : A::kUncertain;
        default: return A::kNo;
      }
    case '2':
      switch (attribute) {
        case 'W': case 'Y': case 'N': case 'D': return A::kYes;
        case 'P': return A::kUncertain;
        case 'C': return A::kNo;
        case 'M': case 'S': case 'L': case 'X': return known ? yes_if(modernized) : A::kUncertain;
        default: return A::kNo;
      }
    case '5':
      // SVN 49 (IIR-M) carries an L5 demonstration payload, not an operational L5 signal.
      if (block == B::kGpsIIRM && svn == 49) return A::kUncertain;
      return known ? yes_if(l5_block) : A::kUncertain;
    default: return A::kNo;
  }
}

// GLONASS satellites whose L3OC (3I/3Q/3X) broadcast public sources show over their whole row of
// the table (docs/satellites.md): SVN 801, GLONASS-K1 No. 11L, L3 on from 2011-04-07 (IAC news
// "L3 CDMA Signal of Glonass-K"); 802, K1 No. 12L (R09), tracked in the 2020 reference files;
// 805, K1 No. 15L (R11), and 855, the first GLONASS-M+ (R21), tracked by KMS300DNK on 2022-06-08
// and (855) NYA100NOR on 2024-05-03. Other K1/K2/M+ payloads are switched on and off or never seen
// (858 in 2020 but not 2022; 806, 856, 859, 860, 861 not seen): uncertain.
constexpr std::array<int, 4> kL3ocSvns = {801, 802, 805, 855};

// GLONASS (ICD 5.1 and the CDMA ICDs): FDMA G1 C/A, G1/G2 P on every satellite and G2 C/A from
// GLONASS-M; the CDMA signals exist on K1, K2 and M+ payloads but are switched on and off (see
// docs/satellites.md), hence uncertain except L3OC on the satellites of kL3ocSvns.
A glonass_availability(B block, int svn, char band, char attribute) {
  switch (band) {
    case '1': return (attribute == 'C' || attribute == 'P') ? A::kYes : A::kNo;
    case '2':
      if (attribute == 'P') return A::kYes;
      if (attribute == 'C') return block == B::kUnknown ? A::kUncertain : A::kYes;
      return A::kNo;
    case '3':
      if (block == B::kGlonassM) return A::kNo;
      if ((attribute == 'I' || attribute == 'Q' || attribute == 'X') &&
          std::find(kL3ocSvns.begin(), kL3ocSvns.end(), svn) != kL3ocSvns.end()) {
        return A::kYes;
      }
      return A::kUncertain;
    case '4': case '6':
      return (block == B::kGlonassK1 || block == B::kGlonassK2 || block == B::kUnknown) ? A::kUncertain : A::kNo;
    default: return A::kNo;
  }
}

// Galileo: every IOV and FOC satellite broadcasts E1, E5a, E5b, E5 AltBOC and E6 (incl. PRS).
// Exception: E20 (GSAT0104) lost E5 and E6 in a power anomaly on 2014-05-27; only E1 came back.
A galileo_availability(const SatelliteId& id, int svn, char band, std::int64_t key) {
  if (id.number == 20 && svn == 104 && key >= make_key(2014147, 0)) {
    return band == '1' ? A::kUncertain : A::kNo;
  }
  return A::kYes;
}

// BeiDou (BDS SIS ICDs B1I 3.0, B3I 1.0, B1C 1.0, B2a 1.0, B2b 1.0, PPP-B2b 1.0): BDS-2 broadcasts
// B1I, B2I, B3I. BDS-3 MEO/IGSO broadcast B1I, B3I, B1C, B2a and B2b (no B2I); BDS-3 GEOs B1I,
// B3I and PPP-B2b on the B2b I component (B1C and B2a "shall not be transmitted by GEO").
A beidou_availability(B block, int prn, char band, char attribute) {
  if (block == B::kUnknown) {
    if (prn <= 18) block = B::kBds2Meo;
    else if (prn >= 59) block = B::kBds3Geo;
    else block = B::kBds3Meo;
  }
  if (block == B::kBds3SIgso || block == B::kBds3SMeo) return A::kUncertain;  // demonstration satellites
  const bool bds2 = block == B::kBds2Geo || block == B::kBds2Igso || block == B::kBds2Meo;
  const bool bds3_geo = block == B::kBds3Geo;
  const bool b1i_or_b3i = (band == '2' || band == '6') && (attribute == 'I' || attribute == 'Q' || attribute == 'X');
  if (b1i_or_b3i) return A::kYes;
  if (band == '7' && (attribute == 'I' || attribute == 'Q' || attribute == 'X')) return yes_if(bds2);
  if (bds2) return A::kNo;
  // Authorized-service signals (B1A, B3A, codeless B1) are not documented per block.
  if ((band == '1' && (attribute == 'A' || attribute == 'N')) || (band == '6' && attribute == 'A')) {
    return A::kUncertain;
  }
  if (bds3_geo) {
    if (band == '7' && attribute == 'D') return A::kYes;
    if (band == '7' && attribute == 'Z') return A::kUncertain;
    return A::kNo;
  }
  return A::kYes;  // BDS-3 MEO/IGSO: B1C (1D/1P/1X), B2a (5D/5P/5X), B2b (7D/7P/7Z), B2a+b (8D/8P/8X)
}

// QZSS (IS-QZSS-PNT, IS-QZSS-L6; QZS-1R notice [QZ]): every satellite broadcasts L1 C/A, L1C,
// L2C, L5, L1S (L1-SAIF on QZS-1) and L6; L5S is a demonstration signal of the QZS-2 series and
// QZS-1R; L6E was introduced with the QZS-2 series; L1C/B is reserved for QZS-5 onwards.
A qzss_availability(B block, char band, char attribute) {
  if (block == B::kUnknown) {
    const bool l1c = band == '1' && (attribute == 'S' || attribute == 'L' || attribute == 'X');
    return (l1c || band == '5') && attribute != 'D' && attribute != 'P' && attribute != 'Z' ? A::kYes
                                                                                         : A::kUncertain;
  }
  const bool qzs1 = block == B::kQzs1;
  switch (band) {
    case '1':
      if (attribute == 'E' || attribute == 'B') return A::kNo;
      return A::kYes;  // 1C, 1S, 1L, 1X, 1Z
    case '2': return A::kYes;
    case '5':
      if (attribute == 'D' || attribute == 'P' || attribute == 'Z') return qzs1 ? A::kNo : A::kUncertain;
      return A::kYes;
    case '6':
      if (attribute == 'E' || attribute == 'Z') return qzs1 ? A::kNo : A::kYes;
      if (attribute == 'L') return A::kUncertain;
      return A::kYes;  // 6S, 6X
    default: return A::kNo;
  }
}

// NavIC (IRNSS SPS ICD): L5 and S (SPS and RS) on every satellite; L1 SPS only from NVS-01, which
// the table does not track.
A navic_availability(char band) {
  if (band == '5' || band == '9') return A::kYes;
  return A::kUncertain;
}

// SBAS (RTCA DO-229, DFMC): L1 C/A on every GEO; L5 only on GEOs with an L5 payload and, in
// 2010-2026, as test broadcasts that come and go.
A sbas_availability(char band) { return band == '1' ? A::kYes : A::kUncertain; }

}  // namespace

std::string_view block_name(SatelliteBlock block) {
  switch (block) {
    case B::kUnknown: return "unknown";
    case B::kGpsIIA: return "GPS-IIA";
    case B::kGpsIIRA: return "GPS-IIR-A";
    case B::kGpsIIRB: return "GPS-IIR-B";
    case B::kGpsIIRM: return "GPS-IIR-M";
    case B::kGpsIIF: return "GPS-IIF";
    case B::kGpsIIIA: return "GPS-IIIA";
    case B::kGlonassM: return "GLO-M";
    case B::kGlonassMPlus: return "GLO-M+";
    case B::kGlonassK1: return "GLO-K1";
    case B::kGlonassK2: return "GLO-K2";
    case B::kGalileoIov: return "GAL-1";
    case B::kGalileoFoc: return "GAL-2";
    case B::kBds2Geo: return "BDS-2G";
    case B::kBds2Igso: return "BDS-2I";
    case B::kBds2Meo: return "BDS-2M";
    case B::kBds3Geo: return "BDS-3G";
    case B::kBds3Igso: return "BDS-3I";
    case B::kBds3Meo: return "BDS-3M";
    case B::kBds3SIgso: return "BDS-3SI";
    case B::kBds3SMeo: return "BDS-3SM";
    case B::kQzs1: return "QZS-1";
    case B::kQzs2Igso: return "QZS-2I";
    case B::kQzs2Geo: return "QZS-2G";
    case B::kQzs2A: return "QZS-2A";
    case B::kSbasGeo: return "SBAS-GEO";
  }
  return "unknown";
}

std::optional<SatelliteInfo> satellite_info(const SatelliteId& id, const GnssTime& t) {
  const Row* r = find_row(id, key_of(t));
  if (r == nullptr) return std::nullopt;
  return to_info(*r);
}

std::vector<SatelliteInfo> catalogued_satellites(GnssSystem system, const GnssTime& t) {
  const std::int64_t key = key_of(t);
  std::vector<SatelliteInfo> out;
  for (int number = 1; number <= max_satellite_number(system); ++number) {
    if (const Row* r = find_row(SatelliteId{system, static_cast<std::uint8_t>(number)}, key)) {
      out.push_back(to_info(*r));
    }
  }
  return out;
}

SignalAvailability signal_availability(const SatelliteId& id, const Signal& signal, const GnssTime& t) {
  if (signal.system != id.system || find_signal_info(signal) == nullptr) return A::kNo;
  const std::int64_t key = key_of(t);
  const Row* r = find_row(id, key);
  const B block = r != nullptr ? r->block : B::kUnknown;
  const int svn = r != nullptr ? r->svn : 0;
  switch (id.system) {
    case GnssSystem::kGps: return gps_availability(block, svn, signal.band, signal.attribute);
    case GnssSystem::kGlonass: return glonass_availability(block, svn, signal.band, signal.attribute);
    case GnssSystem::kGalileo: return galileo_availability(id, svn, signal.band, key);
    case GnssSystem::kBeiDou: return beidou_availability(block, id.number, signal.band, signal.attribute);
    case GnssSystem::kQzss: return qzss_availability(block, signal.band, signal.attribute);
    case GnssSystem::kNavic: return navic_availability(signal.band);
    case GnssSystem::kSbas: return sbas_availability(signal.band);
  }
  return A::kNo;
}

bool transmits(const SatelliteId& id, const Signal& signal, const GnssTime& t) {
  return signal_availability(id, signal, t) == SignalAvailability::kYes;
}

}  // namespace skytrace

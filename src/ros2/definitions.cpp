// Definitions of the message types as their packages declare them (fields, constants, defaults;
// comments left out), and their assembly into rosbag2's "ros2msg" schema text.
#include <algorithm>
#include <map>
#include <set>
#include <sstream>

#include "skytrace/ros2/messages.hpp"

namespace skytrace::ros2 {
namespace {

// gnss_comm's field names in lower case, as ROS 2 requires (messages.hpp).
// Jazzy's text where Humble's differs only in constants and defaults (NavSatStatus, Marker): the
// fields and their wire form are the same in both.
const std::map<std::string, std::string, std::less<>>& definitions() {
  static const std::map<std::string, std::string, std::less<>> table = {
    {"builtin_interfaces/msg/Duration", R"msg(int32 sec
uint32 nanosec
)msg"},
    {"builtin_interfaces/msg/Time", R"msg(int32 sec
uint32 nanosec
)msg"},
    {"geometry_msgs/msg/Point", R"msg(float64 x
float64 y
float64 z
)msg"},
    {"geometry_msgs/msg/Pose", R"msg(Point position
Quaternion orientation
)msg"},
    {"geometry_msgs/msg/PoseStamped", R"msg(std_msgs/Header header
Pose pose
)msg"},
    {"geometry_msgs/msg/PoseWithCovariance", R"msg(Pose pose
float64[36] covariance
)msg"},
    {"geometry_msgs/msg/Quaternion", R"msg(float64 x 0
float64 y 0
float64 z 0
float64 w 1
)msg"},
    {"geometry_msgs/msg/Transform", R"msg(Vector3 translation
Quaternion rotation
)msg"},
    {"geometry_msgs/msg/TransformStamped", R"msg(std_msgs/Header header
string child_frame_id
Transform transform
)msg"},
    {"geometry_msgs/msg/Twist", R"msg(Vector3  linear
Vector3  angular
)msg"},
    {"geometry_msgs/msg/TwistWithCovariance", R"msg(Twist twist
float64[36] covariance
)msg"},
    {"geometry_msgs/msg/TwistWithCovarianceStamped", R"msg(std_msgs/Header header
TwistWithCovariance twist
)msg"},
    {"geometry_msgs/msg/Vector3", R"msg(float64 x
float64 y
float64 z
)msg"},
    {"gnss_comm/msg/GnssEphemMsg", R"msg(uint32 sat
GnssTimeMsg ttr
GnssTimeMsg toe
GnssTimeMsg toc
float64 toe_tow
uint32 week
uint32 iode
uint32 iodc
uint32 health
uint32 code
float64 ura
float64 a
float64 e
float64 i0
float64 omg
float64 omg0
float64 m0
float64 delta_n
float64 omg_dot
float64 i_dot
float64 cuc
float64 cus
float64 crc
float64 crs
float64 cic
float64 cis
float64 af0
float64 af1
float64 af2
float64 tgd0
float64 tgd1
float64 a_dot
float64 n_dot
)msg"},
    {"gnss_comm/msg/GnssGloEphemMsg", R"msg(uint32 sat
GnssTimeMsg ttr
GnssTimeMsg toe
int32  freqo
uint32 iode
uint32 health
uint32 age
float64 ura
float64 pos_x
float64 pos_y
float64 pos_z
float64 vel_x
float64 vel_y
float64 vel_z
float64 acc_x
float64 acc_y
float64 acc_z
float64 tau_n
float64 gamma
float64 delta_tau_n
)msg"},
    {"gnss_comm/msg/GnssMeasMsg", R"msg(GnssObsMsg[] meas
)msg"},
    {"gnss_comm/msg/GnssObsMsg", R"msg(GnssTimeMsg time
uint32 sat
float64[] freqs
float64[] cn0
uint8[] lli
uint8[] code
float64[] psr
float64[] psr_std
float64[] cp
float64[] cp_std
float64[] dopp
float64[] dopp_std
uint8[]   status
)msg"},
    {"gnss_comm/msg/GnssTimeMsg", R"msg(uint32 week
float64 tow
)msg"},
    {"nav_msgs/msg/Odometry", R"msg(std_msgs/Header header
string child_frame_id
geometry_msgs/PoseWithCovariance pose
geometry_msgs/TwistWithCovariance twist
)msg"},
    {"nmea_msgs/msg/Sentence", R"msg(std_msgs/Header header
string sentence
)msg"},
    {"rmw_dds_common/msg/Gid", R"msg(char[16] data
)msg"},
    {"rmw_dds_common/msg/NodeEntitiesInfo", R"msg(string<=256 node_namespace
string<=256 node_name
Gid[] reader_gid_seq
Gid[] writer_gid_seq
)msg"},
    {"rmw_dds_common/msg/ParticipantEntitiesInfo", R"msg(Gid gid
NodeEntitiesInfo[] node_entities_info_seq
)msg"},
    {"rosgraph_msgs/msg/Clock", R"msg(builtin_interfaces/Time clock
)msg"},
    {"rtcm_msgs/msg/Message", R"msg(std_msgs/Header header
uint8[] message
)msg"},
    {"sensor_msgs/msg/CompressedImage", R"msg(std_msgs/Header header
string format
uint8[] data
)msg"},
    {"sensor_msgs/msg/NavSatFix", R"msg(std_msgs/Header header
NavSatStatus status
float64 latitude
float64 longitude
float64 altitude
float64[9] position_covariance
uint8 COVARIANCE_TYPE_UNKNOWN = 0
uint8 COVARIANCE_TYPE_APPROXIMATED = 1
uint8 COVARIANCE_TYPE_DIAGONAL_KNOWN = 2
uint8 COVARIANCE_TYPE_KNOWN = 3
uint8 position_covariance_type
)msg"},
    {"sensor_msgs/msg/NavSatStatus", R"msg(int8 STATUS_UNKNOWN = -2
int8 STATUS_NO_FIX =  -1
int8 STATUS_FIX =      0
int8 STATUS_SBAS_FIX = 1
int8 STATUS_GBAS_FIX = 2
int8 status -2
uint16 SERVICE_UNKNOWN = 0
uint16 SERVICE_GPS =     1
uint16 SERVICE_GLONASS = 2
uint16 SERVICE_COMPASS = 4
uint16 SERVICE_GALILEO = 8
uint16 service
)msg"},
    {"sensor_msgs/msg/TimeReference", R"msg(std_msgs/Header header
builtin_interfaces/Time time_ref
string source
)msg"},
    {"skytrace_msgs/msg/Observation", R"msg(string satellite
string system
uint16 prn
int8 glonass_channel
string signal
float64 carrier_frequency_hz
float64 pseudorange_m
float64 carrier_phase_cycles
float64 doppler_hz
float64 cn0_dbhz
bool loss_of_lock
bool half_cycle_unresolved
float64 lock_time_s
float64 azimuth_deg
float64 elevation_deg
bool los
bool nlos
bool vegetation
bool blocked
float64 vegetation_path_m
float64 vegetation_attenuation_db
)msg"},
    {"skytrace_msgs/msg/Observations", R"msg(std_msgs/Header header
uint32 gps_week
float64 gps_tow_s
bool restarted
bool pose_stale
Observation[] observations
)msg"},
    {"skytrace_msgs/msg/SatelliteSky", R"msg(uint8 TRACKED=0
uint8 BELOW_MASK=1
uint8 NO_EPHEMERIS=2
uint8 NO_SIGNAL=3
uint8 BLOCKED=4
uint8 ATTENUATED=5
string satellite
string system
uint16 prn
float64 azimuth_deg
float64 elevation_deg
uint8 status
bool used_in_fix
float64 cn0_dbhz
float64 vegetation_path_m
float64 vegetation_attenuation_db
string detail
)msg"},
    {"skytrace_msgs/msg/Sky", R"msg(std_msgs/Header header
uint32 gps_week
float64 gps_tow_s
SatelliteSky[] satellites
)msg"},
    {"std_msgs/msg/ColorRGBA", R"msg(float32 r
float32 g
float32 b
float32 a
)msg"},
    {"std_msgs/msg/Header", R"msg(builtin_interfaces/Time stamp
string frame_id
)msg"},
    {"tf2_msgs/msg/TFMessage", R"msg(geometry_msgs/TransformStamped[] transforms
)msg"},
    {"visualization_msgs/msg/Marker", R"msg(int32 ARROW=0
int32 CUBE=1
int32 SPHERE=2
int32 CYLINDER=3
int32 LINE_STRIP=4
int32 LINE_LIST=5
int32 CUBE_LIST=6
int32 SPHERE_LIST=7
int32 POINTS=8
int32 TEXT_VIEW_FACING=9
int32 MESH_RESOURCE=10
int32 TRIANGLE_LIST=11
int32 ARROW_STRIP=12
int32 ADD=0
int32 MODIFY=0
int32 DELETE=2
int32 DELETEALL=3
std_msgs/Header header
string ns
int32 id
int32 type
int32 action
geometry_msgs/Pose pose
geometry_msgs/Vector3 scale
std_msgs/ColorRGBA color
builtin_interfaces/Duration lifetime
bool frame_locked
geometry_msgs/Point[] points
std_msgs/ColorRGBA[] colors
string texture_resource
sensor_msgs/CompressedImage texture
UVCoordinate[] uv_coordinates
string text
string mesh_resource
MeshFile mesh_file
bool mesh_use_embedded_materials
)msg"},
    {"visualization_msgs/msg/MarkerArray", R"msg(Marker[] markers
)msg"},
    {"visualization_msgs/msg/MeshFile", R"msg(string filename
uint8[] data
)msg"},
    {"visualization_msgs/msg/UVCoordinate", R"msg(float32 u
float32 v
)msg"},
  };
  return table;
}

bool is_primitive(std::string_view type) {
  static const std::set<std::string, std::less<>> primitives = {
      "bool",  "byte",   "char",   "float32", "float64", "int8",   "uint8",  "int16",
      "uint16", "int32", "uint32", "int64",   "uint64",  "string", "wstring"};
  return primitives.contains(type);
}

// The full name of a field's type in a definition of package `package`: "Header" inside
// std_msgs -> "std_msgs/msg/Header", "std_msgs/Header" -> "std_msgs/msg/Header".
std::string resolve(std::string_view type, std::string_view package) {
  const size_t slash = type.find('/');
  if (slash == std::string_view::npos) return std::string(package) + "/msg/" + std::string(type);
  if (type.find("/msg/") != std::string_view::npos) return std::string(type);
  return std::string(type.substr(0, slash)) + "/msg/" + std::string(type.substr(slash + 1));
}

// The types a definition's fields use, in order of first use.
std::vector<std::string> field_types(std::string_view ros_type, const std::string& text) {
  const std::string package(ros_type.substr(0, ros_type.find('/')));
  std::vector<std::string> used;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string type, name;
    if (!(words >> type >> name)) continue;
    type = type.substr(0, type.find('['));
    type = type.substr(0, type.find('<'));
    if (is_primitive(type)) continue;  // constants are always of primitive types
    used.push_back(resolve(type, package));
  }
  return used;
}

}  // namespace

std::string message_definition(std::string_view ros_type) {
  const auto& table = definitions();
  const auto root = table.find(ros_type);
  if (root == table.end()) return {};
  std::string text = root->second;
  // Depth-first, each dependency once.
  std::set<std::string, std::less<>> done{std::string(ros_type)};
  std::vector<std::string> pending = field_types(ros_type, root->second);
  std::reverse(pending.begin(), pending.end());
  while (!pending.empty()) {
    const std::string type = pending.back();
    pending.pop_back();
    if (!done.insert(type).second) continue;
    const auto found = table.find(type);
    if (found == table.end()) continue;
    // rosbag2 names a dependency as its fields do, "pkg/Name" (Foxglove's parser matches the
    // names exactly: "pkg/msg/Name" would leave "std_msgs/Header" unresolved).
    std::string name = type;
    if (const size_t msg = name.find("/msg/"); msg != std::string::npos) name.erase(msg, 4);
    text += std::string(80, '=') + "\nMSG: " + name + "\n" + found->second;
    auto more = field_types(type, found->second);
    pending.insert(pending.end(), more.rbegin(), more.rend());
  }
  return text;
}

}  // namespace skytrace::ros2

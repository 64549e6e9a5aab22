#include "ros2_wire.hpp"

#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fastcdr/exceptions/Exception.h>

#include <stdexcept>

namespace skytrace::test::ros2_wire {
namespace {

using eprosima::fastcdr::Cdr;
using eprosima::fastcdr::FastBuffer;

// A Fast CDR reader over a whole sample (encapsulation header first).
class Reader {
 public:
  explicit Reader(const Bytes& cdr)
      : size_(cdr.size()),
        buffer_(const_cast<char*>(reinterpret_cast<const char*>(cdr.data())), cdr.size()),
        cdr_(buffer_, Cdr::DEFAULT_ENDIAN, Cdr::DDS_CDR) {
    cdr_.read_encapsulation();
  }
  template <typename T>
  T get() {
    T value{};
    cdr_ >> value;
    return value;
  }
  template <typename T, size_t N>
  void array(std::array<T, N>& out) {
    cdr_.deserializeArray(out.data(), N);
  }
  Bytes raw(size_t n) {
    Bytes out(n);
    if (n > 0) cdr_.deserializeArray(out.data(), n);
    return out;
  }
  // A sequence's element count, refused when it cannot fit in what is left.
  size_t count() {
    const auto n = get<std::uint32_t>();
    if (n > size_ - cdr_.getSerializedDataLength()) throw std::runtime_error("sequence count beyond the message");
    return n;
  }
  Time time() {
    Time t;
    t.sec = get<std::int32_t>();
    t.nanosec = get<std::uint32_t>();
    return t;
  }
  Header header() {
    Header h;
    h.stamp = time();
    h.frame_id = get<std::string>();
    return h;
  }
  Vector3 vector3() { return Vector3{get<double>(), get<double>(), get<double>()}; }
  Quaternion quaternion() {
    Quaternion q;
    q.x = get<double>();
    q.y = get<double>();
    q.z = get<double>();
    q.w = get<double>();
    return q;
  }
  size_t left_over() const { return size_ - cdr_.getSerializedDataLength(); }

 private:
  size_t size_;
  FastBuffer buffer_;
  Cdr cdr_;
};

template <typename F>
auto decode(const Bytes& cdr, size_t& left_over, F body) {
  try {
    Reader r(cdr);
    auto message = body(r);
    left_over = r.left_over();
    return message;
  } catch (const eprosima::fastcdr::exception::Exception& e) {
    throw std::runtime_error(std::string("Fast CDR: ") + e.what());
  }
}

// A Fast CDR writer into a buffer that grows.
class Writer {
 public:
  Writer() : storage_(64 * 1024), buffer_(storage_.data(), storage_.size()), cdr_(buffer_, Cdr::DEFAULT_ENDIAN, Cdr::DDS_CDR) {
    cdr_.serialize_encapsulation();
  }
  template <typename T>
  Writer& operator<<(const T& value) {
    cdr_ << value;
    return *this;
  }
  void time(const Time& t) { cdr_ << t.sec << t.nanosec; }
  void header(const Header& h) {
    time(h.stamp);
    cdr_ << h.frame_id;
  }
  void vector3(const Vector3& v) { cdr_ << v.x << v.y << v.z; }
  void quaternion(const Quaternion& q) { cdr_ << q.x << q.y << q.z << q.w; }
  void zeros(size_t n) {
    for (size_t i = 0; i < n; ++i) cdr_ << 0.0;
  }
  Bytes take() {
    const auto* begin = reinterpret_cast<const std::uint8_t*>(storage_.data());
    return Bytes(begin, begin + cdr_.getSerializedDataLength());
  }

 private:
  std::vector<char> storage_;
  FastBuffer buffer_;
  Cdr cdr_;
};

}  // namespace

NavSatFix decode_navsat_fix(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    NavSatFix m;
    m.header = r.header();
    m.status = r.get<std::int8_t>();
    m.service = r.get<std::uint16_t>();
    m.latitude = r.get<double>();
    m.longitude = r.get<double>();
    m.altitude = r.get<double>();
    r.array(m.position_covariance);
    m.position_covariance_type = r.get<std::uint8_t>();
    return m;
  });
}

TwistWithCovarianceStamped decode_twist(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    TwistWithCovarianceStamped m;
    m.header = r.header();
    m.linear = r.vector3();
    m.angular = r.vector3();
    r.array(m.covariance);
    return m;
  });
}

TimeReference decode_time_reference(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    TimeReference m;
    m.header = r.header();
    m.time_ref = r.time();
    m.source = r.get<std::string>();
    return m;
  });
}

Sentence decode_sentence(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    Sentence m;
    m.header = r.header();
    m.sentence = r.get<std::string>();
    return m;
  });
}

RtcmMessage decode_rtcm(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    RtcmMessage m;
    m.header = r.header();
    m.message = r.raw(r.count());
    return m;
  });
}

GnssMeas decode_gnss_meas(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    GnssMeas m;
    const size_t n = r.count();
    for (size_t i = 0; i < n; ++i) {
      GnssObs o;
      o.week = r.get<std::uint32_t>();
      o.tow = r.get<double>();
      o.sat = r.get<std::uint32_t>();
      o.freqs = r.get<std::vector<double>>();
      o.cn0 = r.get<std::vector<double>>();
      o.lli = r.raw(r.count());
      o.code = r.raw(r.count());
      o.psr = r.get<std::vector<double>>();
      o.psr_std = r.get<std::vector<double>>();
      o.cp = r.get<std::vector<double>>();
      o.cp_std = r.get<std::vector<double>>();
      o.dopp = r.get<std::vector<double>>();
      o.dopp_std = r.get<std::vector<double>>();
      o.status = r.raw(r.count());
      m.meas.push_back(std::move(o));
    }
    return m;
  });
}

GnssEphem decode_gnss_ephem(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    GnssEphem m;
    m.sat = r.get<std::uint32_t>();
    r.get<std::uint32_t>();  // ttr
    r.get<double>();
    m.toe_week = r.get<std::uint32_t>();
    m.toe_tow = r.get<double>();
    r.get<std::uint32_t>();  // toc
    r.get<double>();
    m.toe_tow_field = r.get<double>();
    m.week = r.get<std::uint32_t>();
    m.iode = r.get<std::uint32_t>();
    r.get<std::uint32_t>();  // iodc
    m.health = r.get<std::uint32_t>();
    r.get<std::uint32_t>();  // code
    r.get<double>();         // ura
    m.A = r.get<double>();
    m.e = r.get<double>();
    for (int i = 0; i < 13; ++i) r.get<double>();  // i0, omg, OMG0, M0, delta_n, OMG_dot, i_dot, cuc .. cis
    m.af0 = r.get<double>();
    for (int i = 0; i < 6; ++i) r.get<double>();  // af1, af2, tgd0, tgd1, A_dot, n_dot
    return m;
  });
}

GnssGloEphem decode_gnss_glo_ephem(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    GnssGloEphem m;
    m.sat = r.get<std::uint32_t>();
    r.get<std::uint32_t>();  // ttr
    r.get<double>();
    m.toe_week = r.get<std::uint32_t>();
    m.toe_tow = r.get<double>();
    m.freqo = r.get<std::int32_t>();
    for (int i = 0; i < 3; ++i) r.get<std::uint32_t>();  // iode, health, age
    r.get<double>();                                      // ura
    m.pos_x = r.get<double>();
    m.pos_y = r.get<double>();
    m.pos_z = r.get<double>();
    for (int i = 0; i < 6; ++i) r.get<double>();  // velocity, acceleration
    m.tau_n = r.get<double>();
    r.get<double>();  // gamma
    r.get<double>();  // delta_tau_n
    return m;
  });
}

Observations decode_observations(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    Observations m;
    m.header = r.header();
    m.gps_week = r.get<std::uint32_t>();
    m.gps_tow_s = r.get<double>();
    m.restarted = r.get<bool>();
    m.pose_stale = r.get<bool>();
    const size_t n = r.count();
    for (size_t i = 0; i < n; ++i) {
      Observation o;
      o.satellite = r.get<std::string>();
      o.system = r.get<std::string>();
      o.prn = r.get<std::uint16_t>();
      r.get<std::int8_t>();  // glonass_channel
      o.signal = r.get<std::string>();
      r.get<double>();  // carrier_frequency_hz
      o.pseudorange_m = r.get<double>();
      r.get<double>();  // carrier_phase_cycles
      r.get<double>();  // doppler_hz
      o.cn0_dbhz = r.get<double>();
      r.get<bool>();  // loss_of_lock
      r.get<bool>();  // half_cycle_unresolved
      r.get<double>();  // lock_time_s
      r.get<double>();  // azimuth_deg
      o.elevation_deg = r.get<double>();
      o.los = r.get<bool>();
      r.get<bool>();  // nlos
      r.get<bool>();  // vegetation
      r.get<bool>();  // blocked
      r.get<double>();  // vegetation_path_m
      r.get<double>();  // vegetation_attenuation_db
      m.observations.push_back(std::move(o));
    }
    return m;
  });
}

Sky decode_sky(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    Sky m;
    m.header = r.header();
    r.get<std::uint32_t>();  // gps_week
    r.get<double>();         // gps_tow_s
    const size_t n = r.count();
    for (size_t i = 0; i < n; ++i) {
      SatelliteSky s;
      s.satellite = r.get<std::string>();
      r.get<std::string>();     // system
      r.get<std::uint16_t>();   // prn
      r.get<double>();          // azimuth_deg
      s.elevation_deg = r.get<double>();
      s.status = r.get<std::uint8_t>();
      s.used_in_fix = r.get<bool>();
      r.get<double>();  // cn0_dbhz
      r.get<double>();  // vegetation_path_m
      r.get<double>();  // vegetation_attenuation_db
      r.get<std::string>();  // detail
      m.satellites.push_back(std::move(s));
    }
    return m;
  });
}

MarkerArray decode_marker_array(const Bytes& cdr, size_t& left_over) {
  return decode(cdr, left_over, [](Reader& r) {
    MarkerArray m;
    const size_t n = r.count();
    for (size_t i = 0; i < n; ++i) {
      Marker k;
      k.header = r.header();
      k.ns = r.get<std::string>();
      r.get<std::int32_t>();  // id
      k.type = r.get<std::int32_t>();
      k.action = r.get<std::int32_t>();
      r.vector3();  // pose.position
      r.quaternion();
      r.vector3();  // scale
      for (int c = 0; c < 4; ++c) r.get<float>();  // color
      r.time();                                     // lifetime (Duration: int32, uint32)
      r.get<bool>();                                // frame_locked
      k.points = r.count();
      for (size_t p = 0; p < k.points; ++p) r.vector3();
      k.colors = r.count();
      for (size_t c = 0; c < 4 * k.colors; ++c) r.get<float>();
      r.get<std::string>();  // texture_resource
      r.header();            // texture: sensor_msgs/CompressedImage
      r.get<std::string>();
      r.raw(r.count());
      const size_t uv = r.count();  // uv_coordinates
      for (size_t c = 0; c < 2 * uv; ++c) r.get<float>();
      r.get<std::string>();  // text
      r.get<std::string>();  // mesh_resource
      r.get<std::string>();  // mesh_file.filename
      r.raw(r.count());      // mesh_file.data
      r.get<bool>();         // mesh_use_embedded_materials
      m.markers.push_back(std::move(k));
    }
    return m;
  });
}

ParticipantEntities decode_participant_entities(const Bytes& cdr, size_t gid_size, size_t& left_over) {
  return decode(cdr, left_over, [gid_size](Reader& r) {
    ParticipantEntities m;
    m.gid = r.raw(gid_size);
    const size_t nodes = r.count();
    for (size_t i = 0; i < nodes; ++i) {
      NodeEntities n;
      n.node_namespace = r.get<std::string>();
      n.node_name = r.get<std::string>();
      const size_t readers = r.count();
      for (size_t k = 0; k < readers; ++k) n.reader_gids.push_back(r.raw(gid_size));
      const size_t writers = r.count();
      for (size_t k = 0; k < writers; ++k) n.writer_gids.push_back(r.raw(gid_size));
      m.nodes.push_back(std::move(n));
    }
    return m;
  });
}

Bytes encode_clock(const Time& clock) {
  Writer w;
  w.time(clock);
  return w.take();
}

Bytes encode_tf(const std::vector<Transform>& transforms) {
  Writer w;
  w << static_cast<std::uint32_t>(transforms.size());
  for (const auto& t : transforms) {
    w.header(t.header);
    w << t.child_frame_id;
    w.vector3(t.translation);
    w.quaternion(t.rotation);
  }
  return w.take();
}

Bytes encode_pose_stamped(const Header& header, const Vector3& position, const Quaternion& orientation) {
  Writer w;
  w.header(header);
  w.vector3(position);
  w.quaternion(orientation);
  return w.take();
}

Bytes encode_odometry(const Header& header, const std::string& child_frame_id, const Vector3& position,
                      const Quaternion& orientation, const Vector3& linear_velocity) {
  Writer w;
  w.header(header);
  w << child_frame_id;
  w.vector3(position);
  w.quaternion(orientation);
  w.zeros(36);  // pose covariance
  w.vector3(linear_velocity);
  w.vector3(Vector3{});
  w.zeros(36);  // twist covariance
  return w.take();
}

std::uint32_t crc24q(const std::uint8_t* data, size_t size) {
  std::uint32_t crc = 0;
  for (size_t i = 0; i < size; ++i) {
    crc ^= static_cast<std::uint32_t>(data[i]) << 16;
    for (int bit = 0; bit < 8; ++bit) {
      crc <<= 1;
      if (crc & 0x1000000U) crc ^= 0x1864CFBU;
    }
  }
  return crc & 0xFFFFFFU;
}

}  // namespace skytrace::test::ros2_wire

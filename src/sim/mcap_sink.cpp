// output.mcap: the ROS 2 topics of every receiver in a rosbag2 folder `bag/` (one MCAP file),
// stamped with the UTC of each epoch as a driver on a GNSS-synchronised clock would stamp them.
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <thread>

#include "skytrace/io/rosbag2.hpp"
#include "skytrace/receiver/profile.hpp"
#include "skytrace/sim/ros2_topics.hpp"
#include "skytrace/sim/sinks.hpp"
#include "skytrace/sim/streams.hpp"

namespace skytrace::sim {
namespace {

io::QosProfileKind bag_qos(Ros2Qos qos) {
  switch (qos) {
    case Ros2Qos::kSensorData: return io::QosProfileKind::kSensorData;
    case Ros2Qos::kDefault: return io::QosProfileKind::kDefault;
    case Ros2Qos::kLatched: return io::QosProfileKind::kTransientLocal;
  }
  return io::QosProfileKind::kDefault;
}

// The messages of an epoch are built on the caller's thread (the builders keep state from epoch to
// epoch) and serialized and written by the sink's own thread, so that the run's writer thread
// carries little more than it does without the bag. At most kQueuedEpochs wait.
class McapSink final : public EpochSink {
 public:
  ~McapSink() override { stop(); }

  Status add(const SinkEpoch& e) override {
    Receiver& rx = receivers_[e.receiver_index];
    const ros2::Time stamp = unix_utc_time(e.observations->true_time);
    Item item;
    {
      std::lock_guard lock(mutex_);
      if (error_) return *error_;
      if (!spare_.empty()) {
        item.messages = std::move(spare_.back());  // keeps the storage of an earlier epoch
        spare_.pop_back();
      }
    }
    item.receiver = e.receiver_index;
    item.stamp_ns = static_cast<std::uint64_t>(stamp.nanoseconds());
    if (auto st = rx.builder->build_into(item.messages, *e.observations, e.fix, stamp); !st) return st;
    if (!threaded_) {
      Status written = write(item);
      spare_.push_back(std::move(item.messages));
      return written;
    }
    if (!writer_.joinable()) writer_ = std::thread([this] { write_loop(); });
    std::unique_lock lock(mutex_);
    changed_.wait(lock, [&] { return queue_.size() < kQueuedEpochs || error_; });
    if (error_) return *error_;
    queue_.push_back(std::move(item));
    changed_.notify_all();
    return Ok{};
  }

  Status finish() override {
    stop();
    if (error_) return *error_;
    return bag_->close();
  }

 private:
  static constexpr size_t kQueuedEpochs = 16;
  struct Item {
    size_t receiver = 0;
    std::uint64_t stamp_ns = 0;
    Ros2Epoch messages;
  };

  void stop() {
    if (!writer_.joinable()) return;
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    changed_.notify_all();
    writer_.join();
  }

  void write_loop() {
    std::unique_lock lock(mutex_);
    for (;;) {
      changed_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
      if (queue_.empty()) return;
      Item item = std::move(queue_.front());
      queue_.pop_front();
      lock.unlock();
      Status written = write(item);
      lock.lock();
      if (!written.ok() && !error_) error_ = written.error();
      spare_.push_back(std::move(item.messages));
      changed_.notify_all();
    }
  }

  Status write(const Item& item) {
    const auto& topic_ids = receivers_[item.receiver].topic_ids;
    return visit_messages(item.messages, [&](std::string_view topic, const auto& message) -> Status {
      const auto id = topic_ids.find(topic);
      if (id == topic_ids.end()) return Ok{};  // a topic this bag leaves out
      ros2::serialize_into(message, buffer_);
      return bag_->write(id->second, item.stamp_ns, buffer_);
    });
  }

 public:
  static Result<std::unique_ptr<EpochSink>> make(const RunContext& c) {
    auto sink = std::make_unique<McapSink>();
    io::Rosbag2Options options;
    options.mcap.compression = c.scenario->output.mcap_compression == "none" ? "" : c.scenario->output.mcap_compression;
    options.file_stem = "bag";  // not the staging folder's name
    options.mcap.worker_thread = c.threads >= 2;
    sink->threaded_ = c.threads >= 2;
    auto bag = io::Rosbag2Writer::open(c.staging_dir / "bag", options);
    if (!bag) return bag.error();
    sink->bag_ = std::move(*bag);
    const auto world = world_origin(*c.scenario, c.resources->world);
    for (const SinkReceiver& rx : c.receivers) {
      auto profile = receiver::load_profile(rx.settings->profile, c.scenario->source.parent_path());
      if (!profile) return profile.error();
      const LocalFrame frame = world ? *world : LocalFrame{ecef_to_geodetic(rx.marker_m), 0.0};
      Receiver& out = sink->receivers_.emplace_back();
      // The bag carries what the run outputs: the RTCM and NMEA topics when output.rtcm3 and
      // output.nmea ask for those streams.
      Ros2TopicSettings settings;
      settings.rtcm = c.scenario->output.rtcm3;
      settings.nmea = c.scenario->output.nmea;
      out.builder = std::make_unique<Ros2EpochBuilder>(*c.resources->ephemerides, std::move(*profile), frame,
                                                       rtcm_station(rx.marker_m, *rx.settings), settings);
      // One receiver: /skytrace/fix as the live node's default name; several: /skytrace/NAME/fix.
      const std::string ns = c.receivers.size() == 1 ? "/skytrace/" : "/skytrace/" + rx.settings->name + "/";
      for (const Ros2Topic& topic : ros2_receiver_topics()) {
        if ((topic.name == "rtcm" && !settings.rtcm) || (topic.name == "nmea" && !settings.nmea)) continue;
        const std::string type(topic.type);
        auto id = sink->bag_->add_topic(ns + std::string(topic.name), type, ros2::message_definition(type),
                                        bag_qos(topic.qos));
        if (!id) return id.error();
        out.topic_ids.emplace(std::string(topic.name), *id);
      }
    }
    return std::unique_ptr<EpochSink>(std::move(sink));
  }

 private:
  struct Receiver {
    std::unique_ptr<Ros2EpochBuilder> builder;
    std::map<std::string, std::uint16_t, std::less<>> topic_ids;
  };
  std::unique_ptr<io::Rosbag2Writer> bag_;
  std::vector<std::uint8_t> buffer_;  // CDR of one message (the writer thread's)
  std::thread writer_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<Item> queue_;
  std::vector<Ros2Epoch> spare_;  // written epochs' messages, for reuse
  std::optional<Error> error_;
  bool stopping_ = false;
  bool threaded_ = true;  // serialises and writes on a thread of its own
  std::vector<Receiver> receivers_;
};

}  // namespace

Result<std::unique_ptr<EpochSink>> make_mcap_sink(const RunContext& context) { return McapSink::make(context); }

}  // namespace skytrace::sim

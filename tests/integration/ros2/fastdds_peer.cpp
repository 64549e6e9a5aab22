#include "fastdds_peer.hpp"

#include <fastdds/dds/core/policy/QosPolicies.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <fastdds/rtps/builtin/data/ParticipantProxyData.h>
#include <fastdds/rtps/builtin/data/ReaderProxyData.h>
#include <fastdds/rtps/builtin/data/WriterProxyData.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

#include <algorithm>
#include <cstring>
#include <set>

namespace skytrace::test::ros2_peer {
namespace {

namespace dds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

// A DDS type of a given name whose samples are the CDR bytes themselves (encapsulation included):
// the peer never needs the type's structure to send or receive it.
class RawType final : public dds::TopicDataType {
 public:
  explicit RawType(const std::string& name) {
    setName(name.c_str());
    m_typeSize = 4 * 1024 * 1024;  // an upper bound; payloads are allocated at their own size
    m_isGetKeyDefined = false;
    auto_fill_type_object(false);
    auto_fill_type_information(false);
  }
  bool serialize(void* data, rtps::SerializedPayload_t* payload) override {
    const auto& bytes = *static_cast<const Bytes*>(data);
    if (bytes.size() > payload->max_size) return false;
    std::memcpy(payload->data, bytes.data(), bytes.size());
    payload->length = static_cast<uint32_t>(bytes.size());
    payload->encapsulation = bytes.size() > 1 && bytes[1] == 0x00 ? CDR_BE : CDR_LE;
    return true;
  }
  bool deserialize(rtps::SerializedPayload_t* payload, void* data) override {
    auto& bytes = *static_cast<Bytes*>(data);
    bytes.assign(payload->data, payload->data + payload->length);
    return true;
  }
  std::function<uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data] { return static_cast<uint32_t>(static_cast<const Bytes*>(data)->size()); };
  }
  void* createData() override { return new Bytes(); }
  void deleteData(void* data) override { delete static_cast<Bytes*>(data); }
  bool getKey(void*, rtps::InstanceHandle_t*, bool) override { return false; }
};

Guid to_guid(const rtps::GUID_t& g) {
  Guid out{};
  std::memcpy(out.data(), g.guidPrefix.value, 12);
  std::memcpy(out.data() + 12, g.entityId.value, 4);
  return out;
}

class FastSubscription final : public Subscription, public dds::DataReaderListener {
 public:
  std::vector<Bytes> samples() const override {
    const std::lock_guard lock(mutex_);
    return samples_;
  }
  bool wait_for(size_t count, std::chrono::milliseconds timeout) const override {
    std::unique_lock lock(mutex_);
    return changed_.wait_for(lock, timeout, [&] { return samples_.size() >= count; });
  }
  size_t incompatible_qos_count() const override {
    const std::lock_guard lock(mutex_);
    return incompatible_;
  }
  void on_data_available(dds::DataReader* reader) override {
    Bytes bytes;
    dds::SampleInfo info;
    while (reader->take_next_sample(&bytes, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;
      const std::lock_guard lock(mutex_);
      samples_.push_back(bytes);
      changed_.notify_all();
    }
  }
  void on_requested_incompatible_qos(dds::DataReader*, const dds::RequestedIncompatibleQosStatus&) override {
    const std::lock_guard lock(mutex_);
    ++incompatible_;
  }
  dds::DataReader* reader = nullptr;

 private:
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  std::vector<Bytes> samples_;
  size_t incompatible_ = 0;
};

class FastPublication final : public Publication {
 public:
  bool write(const Bytes& cdr) override {
    Bytes copy = cdr;
    return writer->write(&copy);
  }
  int matched() const override {
    dds::PublicationMatchedStatus status;
    writer->get_publication_matched_status(status);
    return status.current_count;
  }
  dds::DataWriter* writer = nullptr;
};

class FastPeer final : public Peer, public dds::DomainParticipantListener {
 public:
  ~FastPeer() override {
    if (participant_ != nullptr) {
      participant_->set_listener(nullptr);
      participant_->delete_contained_entities();
      dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
    }
  }

  bool open(int domain_id) {
    dds::DomainParticipantQos qos;
    qos.name("skytrace_test_peer");
    // rmw_fastrtps's localhost-only setup: UDPv4 on the loopback interface, no shared memory.
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList.emplace_back("127.0.0.1");
    // Cyclone takes the first free participant index; reach up to the node's limit (32).
    udp->maxInitialPeersRange = 32;
    qos.transport().user_transports.push_back(udp);
    qos.transport().use_builtin_transports = false;
    rtps::Locator_t localhost;
    eprosima::fastrtps::rtps::IPLocator::setIPv4(localhost, "127.0.0.1");
    localhost.port = 0;  // every participant index's discovery port
    qos.wire_protocol().builtin.initialPeersList.push_back(localhost);
    participant_ = dds::DomainParticipantFactory::get_instance()->create_participant(
        static_cast<dds::DomainId_t>(domain_id), qos, this, dds::StatusMask::none());
    if (participant_ == nullptr) return false;
    publisher_ = participant_->create_publisher(dds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(dds::SUBSCRIBER_QOS_DEFAULT);
    return publisher_ != nullptr && subscriber_ != nullptr;
  }

  Subscription& subscribe(const std::string& topic, const std::string& type, const Qos& qos) override {
    dds::Topic* t = topic_of(topic, type);
    dds::DataReaderQos rq = dds::DATAREADER_QOS_DEFAULT;
    rq.reliability().kind = qos.reliable ? dds::RELIABLE_RELIABILITY_QOS : dds::BEST_EFFORT_RELIABILITY_QOS;
    rq.durability().kind = qos.transient_local ? dds::TRANSIENT_LOCAL_DURABILITY_QOS : dds::VOLATILE_DURABILITY_QOS;
    rq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    rq.history().depth = qos.depth;
    rq.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    rq.data_sharing().off();
    auto subscription = std::make_unique<FastSubscription>();
    subscription->reader = subscriber_->create_datareader(t, rq, subscription.get(), dds::StatusMask::all());
    subscriptions_.push_back(std::move(subscription));
    return *subscriptions_.back();
  }

  Publication& advertise(const std::string& topic, const std::string& type, const Qos& qos) override {
    dds::Topic* t = topic_of(topic, type);
    dds::DataWriterQos wq = dds::DATAWRITER_QOS_DEFAULT;
    wq.reliability().kind = qos.reliable ? dds::RELIABLE_RELIABILITY_QOS : dds::BEST_EFFORT_RELIABILITY_QOS;
    wq.durability().kind = qos.transient_local ? dds::TRANSIENT_LOCAL_DURABILITY_QOS : dds::VOLATILE_DURABILITY_QOS;
    wq.history().kind = dds::KEEP_LAST_HISTORY_QOS;
    wq.history().depth = qos.depth;
    wq.endpoint().history_memory_policy = rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    wq.data_sharing().off();
    auto publication = std::make_unique<FastPublication>();
    publication->writer = publisher_->create_datawriter(t, wq);
    publications_.push_back(std::move(publication));
    return *publications_.back();
  }

  std::vector<RemoteEndpoint> remote_writers() const override {
    const std::lock_guard lock(mutex_);
    return writers_;
  }
  std::vector<RemoteEndpoint> remote_readers() const override {
    const std::lock_guard lock(mutex_);
    return readers_;
  }
  std::vector<Guid> remote_participants() const override {
    const std::lock_guard lock(mutex_);
    return participants_;
  }

  void on_participant_discovery(dds::DomainParticipant*, rtps::ParticipantDiscoveryInfo&& info) override {
    if (info.status != rtps::ParticipantDiscoveryInfo::DISCOVERED_PARTICIPANT) return;
    const std::lock_guard lock(mutex_);
    participants_.push_back(to_guid(info.info.m_guid));
  }
  void on_publisher_discovery(dds::DomainParticipant*, rtps::WriterDiscoveryInfo&& info) override {
    if (info.status != rtps::WriterDiscoveryInfo::DISCOVERED_WRITER) return;
    RemoteEndpoint e{info.info.topicName().to_string(), info.info.typeName().to_string(), to_guid(info.info.guid()),
                     info.info.m_qos.m_reliability.kind == dds::RELIABLE_RELIABILITY_QOS,
                     info.info.m_qos.m_durability.kind == dds::TRANSIENT_LOCAL_DURABILITY_QOS};
    const std::lock_guard lock(mutex_);
    writers_.push_back(std::move(e));
  }
  void on_subscriber_discovery(dds::DomainParticipant*, rtps::ReaderDiscoveryInfo&& info) override {
    if (info.status != rtps::ReaderDiscoveryInfo::DISCOVERED_READER) return;
    RemoteEndpoint e{info.info.topicName().to_string(), info.info.typeName().to_string(), to_guid(info.info.guid()),
                     info.info.m_qos.m_reliability.kind == dds::RELIABLE_RELIABILITY_QOS,
                     info.info.m_qos.m_durability.kind == dds::TRANSIENT_LOCAL_DURABILITY_QOS};
    const std::lock_guard lock(mutex_);
    readers_.push_back(std::move(e));
  }

 private:
  dds::Topic* topic_of(const std::string& name, const std::string& type) {
    if (!types_.count(type)) {
      dds::TypeSupport support(new RawType(type));
      support.register_type(participant_);
      types_.insert(type);
    }
    if (auto it = topics_.find(name); it != topics_.end()) return it->second;
    dds::Topic* topic = participant_->create_topic(name, type, dds::TOPIC_QOS_DEFAULT);
    topics_[name] = topic;
    return topic;
  }

  dds::DomainParticipant* participant_ = nullptr;
  dds::Publisher* publisher_ = nullptr;
  dds::Subscriber* subscriber_ = nullptr;
  std::set<std::string> types_;
  std::map<std::string, dds::Topic*> topics_;
  std::vector<std::unique_ptr<FastSubscription>> subscriptions_;
  std::vector<std::unique_ptr<FastPublication>> publications_;
  mutable std::mutex mutex_;
  std::vector<RemoteEndpoint> writers_, readers_;
  std::vector<Guid> participants_;
};

}  // namespace

std::unique_ptr<Peer> Peer::create(int domain_id) {
  auto peer = std::make_unique<FastPeer>();
  if (!peer->open(domain_id)) return nullptr;
  return peer;
}

}  // namespace skytrace::test::ros2_peer

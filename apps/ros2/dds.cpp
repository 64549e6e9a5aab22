// Cyclone DDS 0.10 behind dds.hpp. Samples travel as opaque CDR blobs: a keyless sertype whose
// serdata holds the bytes as they go on the wire (encapsulation header included), written with
// dds_writecdr and taken with dds_takecdr, so that Cyclone never needs a type description. ROS 2
// types have no keys, so every key operation is trivial.
#include "dds.hpp"

#include <dds/dds.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsi/ddsi_sertype.h>
#include <dds/ddsi/q_radmin.h>
#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <new>

namespace skytrace::ros2_node {
namespace {

// ---- Opaque CDR samples ------------------------------------------------------------------------

struct BlobSertype : ddsi_sertype {};

struct BlobSerdata : ddsi_serdata {
  std::vector<std::uint8_t> bytes;  // encapsulation header and data, zero-padded to 4 bytes
  BlobSerdata(const ddsi_sertype* of_type, ddsi_serdata_kind of_kind) : ddsi_serdata{} {
    ddsi_serdata_init(this, of_type, of_kind);
  }
  void resize(size_t size) {
    // DDSI copies whole 4-byte words: the padding must be there and be zeros.
    bytes.assign((size + 3) & ~size_t{3}, 0);
  }
};

BlobSerdata* blob(ddsi_serdata* d) { return static_cast<BlobSerdata*>(d); }
const BlobSerdata* blob(const ddsi_serdata* d) { return static_cast<const BlobSerdata*>(d); }

bool serdata_eqkey(const ddsi_serdata*, const ddsi_serdata*) { return true; }

uint32_t serdata_size(const ddsi_serdata* d) { return static_cast<uint32_t>(blob(d)->bytes.size()); }

void serdata_free(ddsi_serdata* d) { delete blob(d); }

ddsi_serdata* serdata_from_ser(const ddsi_sertype* type, ddsi_serdata_kind kind, const nn_rdata* fragment, size_t size) {
  auto* d = new (std::nothrow) BlobSerdata(type, kind);
  if (d == nullptr) return nullptr;
  d->resize(size);
  // Fragments are in order and may overlap: copy what each adds beyond the bytes already there.
  size_t filled = 0;
  for (; fragment != nullptr; fragment = fragment->nextfrag) {
    if (fragment->maxp1 <= filled) continue;
    const unsigned char* payload = NN_RMSG_PAYLOADOFF(fragment->rmsg, NN_RDATA_PAYLOAD_OFF(fragment));
    const size_t end = std::min<size_t>(fragment->maxp1, size);
    if (end > filled) std::memcpy(d->bytes.data() + filled, payload + (filled - fragment->min), end - filled);
    filled = std::max(filled, end);
  }
  return d;
}

ddsi_serdata* serdata_from_ser_iov(const ddsi_sertype* type, ddsi_serdata_kind kind, ddsrt_msg_iovlen_t count,
                                   const ddsrt_iovec_t* iov, size_t size) {
  auto* d = new (std::nothrow) BlobSerdata(type, kind);
  if (d == nullptr) return nullptr;
  d->resize(size);
  size_t filled = 0;
  for (ddsrt_msg_iovlen_t i = 0; i < count && filled < size; ++i) {
    const size_t n = std::min<size_t>(iov[i].iov_len, size - filled);
    std::memcpy(d->bytes.data() + filled, iov[i].iov_base, n);
    filled += n;
  }
  return d;
}

ddsi_serdata* serdata_from_keyhash(const ddsi_sertype* type, const ddsi_keyhash*) {
  return new (std::nothrow) BlobSerdata(type, SDK_KEY);
}

// The typed write path (dds_write) is not used: samples arrive serialised through dds_writecdr.
ddsi_serdata* serdata_from_sample(const ddsi_sertype*, ddsi_serdata_kind, const void*) { return nullptr; }

void serdata_to_ser(const ddsi_serdata* d, size_t offset, size_t size, void* out) {
  std::memcpy(out, blob(d)->bytes.data() + offset, size);
}

ddsi_serdata* serdata_to_ser_ref(const ddsi_serdata* d, size_t offset, size_t size, ddsrt_iovec_t* ref) {
  ref->iov_base = const_cast<std::uint8_t*>(blob(d)->bytes.data()) + offset;
  ref->iov_len = static_cast<ddsrt_iov_len_t>(size);
  return ddsi_serdata_ref(d);
}

void serdata_to_ser_unref(ddsi_serdata* d, const ddsrt_iovec_t*) { ddsi_serdata_unref(d); }

// The typed read path (dds_take) is not used either.
bool serdata_to_sample(const ddsi_serdata*, void*, void**, void*) { return false; }

ddsi_serdata* serdata_to_untyped(const ddsi_serdata* d) {
  auto* key = new (std::nothrow) BlobSerdata(d->type, SDK_KEY);
  if (key != nullptr) key->type = nullptr;
  return key;
}

bool serdata_untyped_to_sample(const ddsi_sertype*, const ddsi_serdata*, void*, void**, void*) { return true; }

size_t serdata_print(const ddsi_sertype*, const ddsi_serdata* d, char* buffer, size_t size) {
  return static_cast<size_t>(std::snprintf(buffer, size, "CDR(%zu bytes)", blob(d)->bytes.size()));
}

void serdata_get_keyhash(const ddsi_serdata*, ddsi_keyhash* out, bool) { std::memset(out, 0, sizeof(*out)); }

const ddsi_serdata_ops kSerdataOps = [] {
  ddsi_serdata_ops ops{};
  ops.eqkey = serdata_eqkey;
  ops.get_size = serdata_size;
  ops.from_ser = serdata_from_ser;
  ops.from_ser_iov = serdata_from_ser_iov;
  ops.from_keyhash = serdata_from_keyhash;
  ops.from_sample = serdata_from_sample;
  ops.to_ser = serdata_to_ser;
  ops.to_ser_ref = serdata_to_ser_ref;
  ops.to_ser_unref = serdata_to_ser_unref;
  ops.to_sample = serdata_to_sample;
  ops.to_untyped = serdata_to_untyped;
  ops.untyped_to_sample = serdata_untyped_to_sample;
  ops.free = serdata_free;
  ops.print = serdata_print;
  ops.get_keyhash = serdata_get_keyhash;
  return ops;  // shared-memory (iceoryx) operations left out: the node does not enable it
}();

void sertype_free(ddsi_sertype* type) {
  ddsi_sertype_fini(type);
  delete static_cast<BlobSertype*>(type);
}
void sertype_zero_samples(const ddsi_sertype*, void*, size_t) {}
void sertype_realloc_samples(void** ptrs, const ddsi_sertype*, void*, size_t, size_t count) {
  // Loans and typed reads are not used; never reached.
  std::fill(ptrs, ptrs + count, nullptr);
}
void sertype_free_samples(const ddsi_sertype*, void**, size_t, dds_free_op_t) {}
// Two blob sertypes of one type name describe the same samples.
bool sertype_equal(const ddsi_sertype*, const ddsi_sertype*) { return true; }
uint32_t sertype_hash(const ddsi_sertype*) { return 0x5eed0cdbU; }

const ddsi_sertype_ops kSertypeOps = [] {
  ddsi_sertype_ops ops{};
  ops.version = ddsi_sertype_v0;
  ops.free = sertype_free;
  ops.zero_samples = sertype_zero_samples;
  ops.realloc_samples = sertype_realloc_samples;
  ops.free_samples = sertype_free_samples;
  ops.equal = sertype_equal;
  ops.hash = sertype_hash;
  return ops;  // no type information: ROS 2 peers match on the type name
}();

ddsi_sertype* make_sertype(const std::string& type_name) {
  auto* type = new BlobSertype{};
  ddsi_sertype_init_flags(type, type_name.c_str(), &kSertypeOps, &kSerdataOps, DDSI_SERTYPE_FLAG_TOPICKIND_NO_KEY);
  type->allowed_data_representation = DDS_DATA_REPRESENTATION_FLAG_XCDR1;
  return type;
}

// ---- QoS and entities ----------------------------------------------------------------------------

std::string_view policy_name(uint32_t id) {
  switch (id) {
    case DDS_DURABILITY_QOS_POLICY_ID: return "DURABILITY";
    case DDS_DEADLINE_QOS_POLICY_ID: return "DEADLINE";
    case DDS_LIVELINESS_QOS_POLICY_ID: return "LIVELINESS";
    case DDS_RELIABILITY_QOS_POLICY_ID: return "RELIABILITY";
    case DDS_HISTORY_QOS_POLICY_ID: return "HISTORY";
    case DDS_LIFESPAN_QOS_POLICY_ID: return "LIFESPAN";
    case DDS_OWNERSHIP_QOS_POLICY_ID: return "OWNERSHIP";
    case DDS_PRESENTATION_QOS_POLICY_ID: return "PRESENTATION";
    case DDS_DESTINATIONORDER_QOS_POLICY_ID: return "DESTINATION_ORDER";
    case DDS_DATA_REPRESENTATION_QOS_POLICY_ID: return "DATA_REPRESENTATION";
    case DDS_TYPE_CONSISTENCY_ENFORCEMENT_QOS_POLICY_ID: return "TYPE_CONSISTENCY";
    default: return "unknown policy";
  }
}

struct QosDeleter {
  void operator()(dds_qos_t* qos) const { dds_delete_qos(qos); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

// As rmw_cyclonedds sets a reader's or writer's QoS for a ROS profile.
QosPtr endpoint_qos(const QosProfile& profile, bool ignore_local) {
  QosPtr qos(dds_create_qos());
  dds_qset_writer_data_lifecycle(qos.get(), false);  // no dispose when a writer goes
  if (profile.history == QosProfile::History::kKeepAll) {
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_ALL, DDS_LENGTH_UNLIMITED);
  } else {
    dds_qset_history(qos.get(), DDS_HISTORY_KEEP_LAST, std::max(1, profile.depth));
  }
  if (profile.reliability == QosProfile::Reliability::kReliable) {
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_RELIABLE, DDS_INFINITY);
  } else {
    dds_qset_reliability(qos.get(), DDS_RELIABILITY_BEST_EFFORT, 0);
  }
  if (profile.durability == QosProfile::Durability::kTransientLocal) {
    dds_qset_durability(qos.get(), DDS_DURABILITY_TRANSIENT_LOCAL);
    // Cyclone keeps the late joiners' history per the durability service: the same as the history.
    dds_history_kind_t kind = DDS_HISTORY_KEEP_LAST;
    int32_t depth = 1;
    dds_qget_history(qos.get(), &kind, &depth);
    dds_qset_durability_service(qos.get(), 0, kind, depth, DDS_LENGTH_UNLIMITED, DDS_LENGTH_UNLIMITED,
                                DDS_LENGTH_UNLIMITED);
  } else {
    dds_qset_durability(qos.get(), DDS_DURABILITY_VOLATILE);
  }
  dds_qset_liveliness(qos.get(), DDS_LIVELINESS_AUTOMATIC, DDS_INFINITY);
  if (ignore_local) dds_qset_ignorelocal(qos.get(), DDS_IGNORELOCAL_PARTICIPANT);
  return qos;
}

Guid entity_guid(dds_entity_t entity) {
  dds_guid_t guid{};
  Guid out{};
  if (dds_get_guid(entity, &guid) == DDS_RETCODE_OK) std::memcpy(out.data(), guid.v, out.size());
  return out;
}

Error dds_error(const std::string& what, dds_return_t code) {
  return Error{ErrorCode::kNetwork, fmt::format("{}: {}", what, dds_strretcode(code))};
}

// Listener context: which endpoint, and where warnings go. Outlives the entity (owned by it).
struct ListenerContext {
  std::string topic;
  DdsWarning warning;
};

void on_requested_incompatible_qos(dds_entity_t, const dds_requested_incompatible_qos_status_t status, void* arg) {
  const auto* context = static_cast<const ListenerContext*>(arg);
  if (context->warning) {
    context->warning(fmt::format("subscription '{}': a publisher offers incompatible QoS ({}), {} so far; no data from it",
                                 context->topic, policy_name(status.last_policy_id), status.total_count));
  }
}

void on_offered_incompatible_qos(dds_entity_t, const dds_offered_incompatible_qos_status_t status, void* arg) {
  const auto* context = static_cast<const ListenerContext*>(arg);
  if (context->warning) {
    context->warning(fmt::format("publisher '{}': a subscription requests incompatible QoS ({}), {} so far; it gets no data",
                                 context->topic, policy_name(status.last_policy_id), status.total_count));
  }
}

class CycloneWriter final : public DdsWriter {
 public:
  CycloneWriter(dds_entity_t writer, const ddsi_sertype* type, std::unique_ptr<ListenerContext> context)
      : writer_(writer), type_(type), context_(std::move(context)) {}
  ~CycloneWriter() override { dds_delete(writer_); }
  Status write(std::span<const std::uint8_t> cdr) override {
    if (cdr.size() < 4) return Error{ErrorCode::kInvalidArgument, "a CDR sample needs its 4-byte encapsulation header"};
    ddsrt_iovec_t iov{};
    iov.iov_base = const_cast<std::uint8_t*>(cdr.data());
    iov.iov_len = static_cast<ddsrt_iov_len_t>(cdr.size());
    ddsi_serdata* sample = ddsi_serdata_from_ser_iov(type_, SDK_DATA, 1, &iov, cdr.size());
    if (sample == nullptr) return Error{ErrorCode::kOutput, "out of memory for a sample"};
    // dds_writecdr takes the reference.
    if (const dds_return_t rc = dds_writecdr(writer_, sample); rc < 0) return dds_error("dds_writecdr " + context_->topic, rc);
    return Ok{};
  }
  Guid guid() const override { return entity_guid(writer_); }
  int matched_readers() const override {
    dds_publication_matched_status_t status{};
    return dds_get_publication_matched_status(writer_, &status) == DDS_RETCODE_OK ? static_cast<int>(status.current_count) : 0;
  }

 private:
  dds_entity_t writer_;
  const ddsi_sertype* type_;  // owned by the topic
  std::unique_ptr<ListenerContext> context_;
};

class CycloneReader final : public DdsReader {
 public:
  CycloneReader(dds_entity_t reader, std::unique_ptr<ListenerContext> context)
      : reader_(reader), context_(std::move(context)) {}
  ~CycloneReader() override { dds_delete(reader_); }
  std::vector<std::vector<std::uint8_t>> take(size_t max_samples) override {
    std::vector<std::vector<std::uint8_t>> out;
    constexpr uint32_t kBatch = 16;
    ddsi_serdata* samples[kBatch];
    dds_sample_info_t infos[kBatch];
    while (out.size() < max_samples) {
      const dds_return_t n = dds_takecdr(reader_, samples, kBatch, infos, DDS_ANY_STATE);
      if (n <= 0) break;
      for (dds_return_t i = 0; i < n; ++i) {
        if (infos[i].valid_data) {
          const uint32_t size = ddsi_serdata_size(samples[i]);
          std::vector<std::uint8_t> bytes(size);
          ddsi_serdata_to_ser(samples[i], 0, size, bytes.data());
          out.push_back(std::move(bytes));
        }
        ddsi_serdata_unref(samples[i]);
      }
      if (n < static_cast<dds_return_t>(kBatch)) break;
    }
    return out;
  }
  Guid guid() const override { return entity_guid(reader_); }
  int matched_writers() const override {
    dds_subscription_matched_status_t status{};
    return dds_get_subscription_matched_status(reader_, &status) == DDS_RETCODE_OK ? static_cast<int>(status.current_count) : 0;
  }
  [[nodiscard]] dds_entity_t entity() const { return reader_; }

 private:
  dds_entity_t reader_;
  std::unique_ptr<ListenerContext> context_;
};

class CycloneParticipant final : public DdsParticipant {
 public:
  CycloneParticipant(dds_entity_t domain, dds_entity_t participant, dds_entity_t waitset, DdsWarning warning)
      : domain_(domain), participant_(participant), waitset_(waitset), warning_(std::move(warning)) {}
  ~CycloneParticipant() override {
    // Deleting the participant deletes its readers, writers, topics and the waitset; the
    // endpoints' destructors then find theirs gone, which dds_delete tolerates.
    dds_delete(participant_);
    if (domain_ > 0) dds_delete(domain_);
  }

  Result<std::unique_ptr<DdsWriter>> create_writer(const std::string& topic, const std::string& type,
                                                   const QosProfile& qos) override {
    auto t = find_or_create_topic(topic, type);
    if (!t) return t.error();
    auto context = std::make_unique<ListenerContext>(ListenerContext{topic, warning_});
    dds_listener_t* listener = dds_create_listener(context.get());
    dds_lset_offered_incompatible_qos(listener, on_offered_incompatible_qos);
    const QosPtr q = endpoint_qos(qos, false);
    const dds_entity_t writer = dds_create_writer(participant_, t->entity, q.get(), listener);
    dds_delete_listener(listener);
    if (writer < 0) return dds_error("creating the writer of " + topic, writer);
    return std::unique_ptr<DdsWriter>(std::make_unique<CycloneWriter>(writer, t->type, std::move(context)));
  }

  Result<std::unique_ptr<DdsReader>> create_reader(const std::string& topic, const std::string& type,
                                                   const QosProfile& qos, bool ignore_local) override {
    auto t = find_or_create_topic(topic, type);
    if (!t) return t.error();
    auto context = std::make_unique<ListenerContext>(ListenerContext{topic, warning_});
    dds_listener_t* listener = dds_create_listener(context.get());
    dds_lset_requested_incompatible_qos(listener, on_requested_incompatible_qos);
    const QosPtr q = endpoint_qos(qos, ignore_local);
    const dds_entity_t reader = dds_create_reader(participant_, t->entity, q.get(), listener);
    dds_delete_listener(listener);
    if (reader < 0) return dds_error("creating the reader of " + topic, reader);
    const dds_entity_t condition = dds_create_readcondition(reader, DDS_ANY_STATE);
    if (condition >= 0) dds_waitset_attach(waitset_, condition, reader);
    return std::unique_ptr<DdsReader>(std::make_unique<CycloneReader>(reader, std::move(context)));
  }

  Guid guid() const override { return entity_guid(participant_); }

  void wait_for_data(double timeout_s) override {
    dds_waitset_wait(waitset_, nullptr, 0, static_cast<dds_duration_t>(std::max(0.0, timeout_s) * 1e9));
  }

 private:
  struct Topic {
    dds_entity_t entity = 0;
    const ddsi_sertype* type = nullptr;
  };
  Result<Topic> find_or_create_topic(const std::string& name, const std::string& type_name) {
    for (const auto& [n, t] : topics_) {
      if (n == name) return t;
    }
    ddsi_sertype* type = make_sertype(type_name);
    // On success Cyclone owns the sertype and may replace it with an equal one it already has.
    const dds_entity_t topic = dds_create_topic_sertype(participant_, name.c_str(), &type, nullptr, nullptr, nullptr);
    if (topic < 0) {
      sertype_free(type);
      return dds_error(fmt::format("creating topic {} of type {}", name, type_name), topic);
    }
    Topic t{topic, type};
    topics_.emplace_back(name, t);
    return t;
  }

  dds_entity_t domain_;
  dds_entity_t participant_;
  dds_entity_t waitset_;
  DdsWarning warning_;
  std::vector<std::pair<std::string, Topic>> topics_;
};

std::string environment(const char* name) {
  const char* value = std::getenv(name);
  return value == nullptr ? std::string() : std::string(value);
}

}  // namespace

Result<std::unique_ptr<DdsParticipant>> DdsParticipant::create(const DiscoveryOptions& options, DdsWarning warning) {
  const auto domain_id = static_cast<dds_domainid_t>(options.domain_id);
  std::string config = cyclone_config(options);
  dds_entity_t domain = 0;
  if (!config.empty()) {
    // Cyclone reads CYCLONEDDS_URI only for domains it creates itself: append it, as rmw does.
    if (const std::string uri = environment("CYCLONEDDS_URI"); !uri.empty()) config += "," + uri;
    domain = dds_create_domain(domain_id, config.c_str());
    if (domain < 0) return dds_error(fmt::format("creating DDS domain {} (CYCLONEDDS_URI?)", options.domain_id), domain);
  }
  QosPtr qos(dds_create_qos());
  const std::string user_data = "enclave=" + options.enclave + ";";
  dds_qset_userdata(qos.get(), user_data.data(), user_data.size());
  const dds_entity_t participant = dds_create_participant(domain_id, qos.get(), nullptr);
  if (participant < 0) {
    if (domain > 0) dds_delete(domain);
    return dds_error(fmt::format("creating a DDS participant in domain {}", options.domain_id), participant);
  }
  const dds_entity_t waitset = dds_create_waitset(participant);
  if (waitset < 0) {
    dds_delete(participant);
    if (domain > 0) dds_delete(domain);
    return dds_error("creating a DDS waitset", waitset);
  }
  return std::unique_ptr<DdsParticipant>(std::make_unique<CycloneParticipant>(domain, participant, waitset, std::move(warning)));
}

}  // namespace skytrace::ros2_node

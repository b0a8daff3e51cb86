#pragma once
// A DDS type support that moves serialized payloads as they are, without decoding them.
//
// RawPubSubType wraps the generated PubSubType of a topic (so the type name, the maximum size
// and the key match the live writers and readers exactly) but its samples are RawSample: the
// serialized payload bytes, encapsulation header included (XCDR1, as written on the wire). A
// recorder takes what the writers sent byte for byte; a player writes those bytes back. Neither
// depends on the QoS the session used nor on the IDL the recording was made with, as long as
// the type name is the same.
#include <fastdds/rtps/common/InstanceHandle.h>
#include <fastdds/rtps/common/SerializedPayload.h>
#include <fastdds/dds/topic/TopicDataType.hpp>

#include <cstdint>
#include <cstring>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

namespace teleop::record {

/// One serialized sample: the CDR encapsulation header (4 bytes) followed by the body.
struct RawSample {
  std::vector<std::uint8_t> bytes;
};

class RawPubSubType : public eprosima::fastdds::dds::TopicDataType {
 public:
  /// Takes ownership of the topic's generated type support.
  explicit RawPubSubType(eprosima::fastdds::dds::TopicDataType* typed) : typed_(typed) {
    setName(typed_->getName());
    m_typeSize = typed_->m_typeSize;
    m_isGetKeyDefined = typed_->m_isGetKeyDefined;
    auto_fill_type_object(false);
    auto_fill_type_information(false);
  }

  bool serialize(void* data, eprosima::fastrtps::rtps::SerializedPayload_t* payload) override {
    const auto* s = static_cast<const RawSample*>(data);
    const auto n = static_cast<std::uint32_t>(s->bytes.size());
    if (n < 4) return false;
    if (payload->max_size < n) payload->reserve(n);
    std::memcpy(payload->data, s->bytes.data(), n);
    payload->length = n;
    // encapsulation identifier: 0x0000 CDR big endian, 0x0001 CDR little endian
    payload->encapsulation = s->bytes[1] == 0 ? CDR_BE : CDR_LE;
    return true;
  }

  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    auto* s = static_cast<RawSample*>(data);
    s->bytes.assign(payload->data, payload->data + payload->length);
    return true;
  }

  std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override {
    return [data]() {
      return static_cast<std::uint32_t>(static_cast<RawSample*>(data)->bytes.size());
    };
  }

  void* createData() override { return new RawSample(); }
  void deleteData(void* data) override { delete static_cast<RawSample*>(data); }

  /// Keyed topics (mesh frames and topology): decodes the sample with the generated type to
  /// compute its key. Used by writers only (a player), never on a reader's path.
  bool getKey(void* data, eprosima::fastrtps::rtps::InstanceHandle_t* ihandle,
              bool force_md5 = false) override {
    if (!m_isGetKeyDefined) return false;
    const auto* s = static_cast<const RawSample*>(data);
    std::lock_guard<std::mutex> lock(key_mutex_);
    if (!key_scratch_) key_scratch_ = typed_->createData();
    eprosima::fastrtps::rtps::SerializedPayload_t p(static_cast<std::uint32_t>(s->bytes.size()));
    std::memcpy(p.data, s->bytes.data(), s->bytes.size());
    p.length = static_cast<std::uint32_t>(s->bytes.size());
    p.encapsulation = s->bytes.size() > 1 && s->bytes[1] == 0 ? CDR_BE : CDR_LE;
    if (!typed_->deserialize(&p, key_scratch_)) return false;
    return typed_->getKey(key_scratch_, ihandle, force_md5);
  }

  ~RawPubSubType() override {
    if (key_scratch_) typed_->deleteData(key_scratch_);
  }

  /// The wrapped generated type (decodes a RawSample for display or checks).
  eprosima::fastdds::dds::TopicDataType& typed() { return *typed_; }

 private:
  std::unique_ptr<eprosima::fastdds::dds::TopicDataType> typed_;
  std::mutex key_mutex_;
  void* key_scratch_ = nullptr;
};

}  // namespace teleop::record

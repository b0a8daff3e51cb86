#pragma once
// Deserialization that a malformed sample cannot turn into a crash.
//
// The code fastddsgen generates for a type (e.g. teleop::MasterCommandPubSubType::deserialize)
// catches only fastcdr's NotEnoughMemoryException. A payload with an unknown encapsulation, or a
// boolean byte that is neither 0 nor 1, throws BadParamException out of deserialize(), and Fast
// DDS 2.9 calls deserialize() inside DataReader::take_next_sample() on the reader's own thread:
// one such sample from any participant on the domain ended the reading process through
// std::terminate (found by tests/fuzz/fuzz_command.cpp). Fast DDS also ignores deserialize()'s
// result and hands the half-filled sample on as valid.
//
// CheckedType<PubSub> is PubSub whose deserialize() never throws: on a malformed payload it
// returns false and counts it in malformed_samples() of the calling thread, which the Reader
// (common/dds/endpoint.hpp) compares around take_next_sample() to drop that sample.
#include <fastcdr/exceptions/Exception.h>
#include <fastdds/rtps/common/SerializedPayload.h>
#include <cstdint>
#include <exception>

namespace teleop::dds {

/// Samples this thread could not deserialize so far.
inline std::uint64_t& malformed_samples() {
  thread_local std::uint64_t count = 0;
  return count;
}

/// PubSub (a fastddsgen TopicDataType) whose deserialize() does not throw.
template <class PubSub>
class CheckedType : public PubSub {
 public:
  using type = typename PubSub::type;

  bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
    bool ok = false;
    try {
      ok = PubSub::deserialize(payload, data);
    } catch (const eprosima::fastcdr::exception::Exception&) {
      ok = false;
    } catch (const std::exception&) {  // e.g. std::bad_alloc for an absurd sequence length
      ok = false;
    }
    if (!ok) ++malformed_samples();
    return ok;
  }
};

/// Deserializes `payload` into `out` with CheckedType's rules: false for a malformed payload.
template <class PubSub>
bool deserialize_checked(eprosima::fastrtps::rtps::SerializedPayload_t& payload,
                         typename PubSub::type& out) {
  CheckedType<PubSub> t;
  return t.deserialize(&payload, &out);
}

}  // namespace teleop::dds

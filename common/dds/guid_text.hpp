#pragma once
// A participant's GUID prefix as text: how programs name the server they watch or are bound to
// (all writers of one participant share the prefix; SampleInfo::sample_identity carries it).
#include <cstdio>
#include <fastdds/rtps/common/GuidPrefix_t.hpp>
#include <string>

namespace teleop::dds {

/// "0f01a2b3.c4d5e6f7.00000001": a GUID prefix as 24 hex digits in three groups.
inline std::string guid_prefix_text(const eprosima::fastrtps::rtps::GuidPrefix_t& p) {
  char buf[32];
  const auto* v = p.value;
  std::snprintf(buf, sizeof buf, "%02x%02x%02x%02x.%02x%02x%02x%02x.%02x%02x%02x%02x", v[0], v[1],
                v[2], v[3], v[4], v[5], v[6], v[7], v[8], v[9], v[10], v[11]);
  return buf;
}

}  // namespace teleop::dds

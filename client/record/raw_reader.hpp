#pragma once
// A DataReader of serialized payloads (raw_type.hpp) on a known topic (topic_table.hpp), with
// the QoS class of the topic's live writers: what the recorder and the bridge read with. It only
// subscribes, so it never slows a writer (stream topics are best effort).
#include "client/record/topic_table.hpp"
#include "common/dds/participant.hpp"

namespace eprosima::fastdds::dds {
class DataReader;
}

namespace teleop::record {

/// Creates the reader (samples are RawSample). Stream and latest topics keep `stream_depth`
/// samples so that a reader thread that takes in batches loses none. @throws dds::DdsError.
eprosima::fastdds::dds::DataReader* create_raw_reader(dds::Participant& participant,
                                                      const TopicEntry& entry, int stream_depth);

}  // namespace teleop::record

#include "client/record/raw_reader.hpp"

#include <fastdds/dds/core/status/StatusMask.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>

#include "client/record/raw_type.hpp"

namespace teleop::record {

namespace fdds = eprosima::fastdds::dds;

fdds::DataReader* create_raw_reader(dds::Participant& participant, const TopicEntry& entry,
                                    int stream_depth) {
  auto* topic =
      participant.topic(entry.name, fdds::TypeSupport(new RawPubSubType(entry.make_type())));
  fdds::DataReaderQos q = dds::reader_qos(participant.subscriber(), entry.qos);
  if (entry.qos == dds::TopicQos::kStream || entry.qos == dds::TopicQos::kLatest) {
    // a deeper reader history absorbs bursts while the reading thread is descheduled (writers
    // are best effort, so this never slows them)
    q.history().depth = stream_depth;
  }
  auto* reader = participant.subscriber()->create_datareader(topic, q);
  if (!reader) throw dds::DdsError("cannot create a raw DataReader on " + entry.name);
  reader->get_statuscondition().set_enabled_statuses(fdds::StatusMask::data_available());
  return reader;
}

}  // namespace teleop::record

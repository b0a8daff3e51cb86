// libFuzzer target: an MCAP recording from arbitrary bytes, read as teleop_play reads one
// (common/record/mcap_reader.hpp): open (footer, summary, or recovery by a scan of the data
// section), count the messages, check the data section's CRC, and read every message in
// log-time order. Properties checked:
//   - any bytes end in a result or a config::ConfigError / RecordingError, never a crash, an
//     out-of-bounds read (AddressSanitizer) or a hang;
//   - the messages come in non-decreasing log time, each inside the file's [start, end] and on
//     a channel the file defines.
#include <cstddef>
#include <cstdint>

#include "common/config/config.hpp"
#include "common/record/mcap_reader.hpp"
#include "common/record/recording.hpp"

namespace {
void check(bool ok) {
  if (!ok) __builtin_trap();
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    teleop::record::mcap::Reader r(data, size, "fuzz.mcap");
    std::uint64_t counted = 0;
    for (const auto& [id, n] : r.channel_counts()) counted += n;
    (void)r.verify_data_crc();
    r.scan(0, 0, {});
    teleop::record::mcap::MessageView m;
    std::uint64_t prev = 0, n = 0;
    while (r.next(m)) {
      check(m.log_time_ns >= prev);
      check(m.log_time_ns >= r.start_ns() && m.log_time_ns <= r.end_ns());
      check(r.channels().count(m.channel_id) == 1);
      check(m.size <= size);
      prev = m.log_time_ns;
      ++n;
    }
    // a recovered file counts what it read; a summary's counts may say anything
    if (r.health().recovered) check(n == counted);
  } catch (const teleop::config::ConfigError&) {
  } catch (const teleop::record::RecordingError&) {
  }
  return 0;
}

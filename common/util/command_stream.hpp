#pragma once
// A command stream: the master's commands of a session as the server received them, for an
// off-line re-simulation (server/node/resim.hpp). One CSV file, written by `teleop_play
// --export-commands` from a recording and read by `teleop_experiment resim`:
//
//   receive_ns,source_ns,writer,payload
//   1732390000123456789,1732390000123400000,0f01...(32 hex digits),0001000000...(hex CDR)
//
// receive_ns: when the sample arrived (the recorder's clock) [ns]; source_ns: when the master
// wrote it [ns]; writer: the writer's GUID (a new writer is a new master session); payload: the
// serialized MasterCommand with its encapsulation header, byte for byte as it was on the wire,
// so a re-simulation sees exactly the recorded commands (no decimal round trip).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace teleop {

struct StreamedCommand {
  std::int64_t receive_ns = 0;
  std::int64_t source_ns = 0;
  std::string writer;                 ///< 32 hex digits
  std::vector<std::uint8_t> payload;  ///< CDR with encapsulation header
};

/// Lower-case hex of `bytes`.
std::string to_hex(const std::uint8_t* bytes, std::size_t n);

/// Writes the stream (header + rows). @throws std::runtime_error when the file cannot be written.
void write_command_stream(const std::string& path, const std::vector<StreamedCommand>& rows);

/// Longest row read_command_stream() accepts [bytes] (a MasterCommand row is ~500).
constexpr std::size_t kMaxStreamLineBytes = std::size_t{1} << 16;
/// Largest stream read_command_stream() accepts [bytes]: about two hours of commands at 1 kHz.
constexpr std::uintmax_t kMaxStreamFileBytes = std::uintmax_t{4} << 30;

/// Reads a stream written by write_command_stream. Rows must be in non-decreasing receive
/// order. @throws config::ConfigError naming the file, line and column of the first bad field;
/// for a file that is not a regular file (a FIFO, /dev/zero), one larger than
/// kMaxStreamFileBytes, or a line longer than kMaxStreamLineBytes.
std::vector<StreamedCommand> read_command_stream(const std::string& path);

}  // namespace teleop

#pragma once
// Output files that never fail silently: every write error names the file and the reason.
#include <ostream>
#include <string>
#include <vector>

namespace teleop {

/// Writes `text` to `path` (created or replaced).
/// @throws std::runtime_error "<path>: cannot write: <reason>" when the file cannot be opened,
/// written (a full disk, /dev/full) or closed.
void write_text_file(const std::string& path, const std::string& text);

/// Makes the folder that will hold the output file `path` of `flag` (its parents, as
/// `mkdir -p`), before any work starts. Refuses a path that is a folder, an existing file that
/// cannot be written, or a new file whose folder cannot be made or written. "-" (stdout) and a
/// path without a folder part need nothing.
/// @throws config::ConfigError "<flag> '<path>': cannot create the folder '<dir>': <reason>".
void prepare_output_file(const std::string& flag, const std::string& path);
/// The same for an output folder (`teleop_experiment --out DIR`): made with its parents, refused
/// when it is a file or cannot be written. @throws config::ConfigError naming flag and folder.
void prepare_output_dir(const std::string& flag, const std::string& dir);

/// Flushes `out` and throws std::runtime_error "<path>: write error: <reason>" unless every
/// write to it succeeded.
void check_written(std::ostream& out, const std::string& path);

/// Files whose buffered writes failed where nothing could throw (a CsvWriter destroyed without
/// close()); the tools' shared main reports them and exits non-zero.
std::vector<std::string> failed_writes();
/// Adds `message` (naming the file) to failed_writes().
void note_failed_write(const std::string& message);

}  // namespace teleop

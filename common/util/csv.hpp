#pragma once
// Minimal CSV writer for experiment and benchmark data (numbers and plain words only).
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

namespace teleop {

class CsvWriter {
 public:
  /// Opens `path` for writing and writes the header. @throws std::runtime_error on failure.
  CsvWriter(const std::string& path, const std::vector<std::string>& columns);
  /// A writer not close()d checks its writes here; a failure cannot throw from a destructor, so
  /// it is printed and noted in failed_writes() (common/util/files.hpp).
  ~CsvWriter();
  CsvWriter(const CsvWriter&) = delete;
  CsvWriter& operator=(const CsvWriter&) = delete;
  /// Writes one row of numbers; the count must match the header.
  void row(std::initializer_list<double> values);
  void row(const std::vector<double>& values);
  /// Writes one row of `count` numbers without allocating (stack buffer, buffered stream):
  /// for rows written from real-time loops.
  void row(const double* values, std::size_t count);
  /// Writes one row of pre-formatted fields.
  void row_text(const std::vector<std::string>& fields);
  void flush() { out_.flush(); }
  /// Flushes and closes the file. @throws std::runtime_error naming the file when any write
  /// failed (a full disk, /dev/full).
  void close();
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ofstream out_;
  std::size_t columns_;
};

/// Formats a double with enough digits to round-trip (%.17g style, shortest form).
std::string format_number(double v);

}  // namespace teleop

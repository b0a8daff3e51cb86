#include "common/util/csv.hpp"

#include <charconv>
#include <iostream>
#include <stdexcept>

#include "common/util/files.hpp"

namespace teleop {

std::string format_number(double v) {
  char buf[64];
  auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

CsvWriter::CsvWriter(const std::string& path, const std::vector<std::string>& columns)
    : path_(path), out_(path), columns_(columns.size()) {
  if (!out_) throw std::runtime_error("cannot open '" + path + "' for writing");
  row_text(columns);
}

CsvWriter::~CsvWriter() {
  if (!out_.is_open()) return;
  out_.flush();
  if (!out_) {
    const std::string message = path_ + ": write error (the file is incomplete)";
    std::cerr << "error: " << message << "\n";
    note_failed_write(message);
  }
}

void CsvWriter::close() {
  if (!out_.is_open()) return;
  check_written(out_, path_);
  out_.close();
  if (!out_) throw std::runtime_error(path_ + ": write error on close");
}

void CsvWriter::row(std::initializer_list<double> values) { row(std::vector<double>(values)); }

void CsvWriter::row(const std::vector<double>& values) {
  if (values.size() != columns_) {
    throw std::logic_error("CsvWriter: row of " + std::to_string(values.size()) + " values for " +
                           std::to_string(columns_) + " columns in " + path_);
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) out_ << ',';
    out_ << format_number(values[i]);
  }
  out_ << '\n';
}

void CsvWriter::row(const double* values, std::size_t count) {
  if (count != columns_) {
    throw std::logic_error("CsvWriter: row of " + std::to_string(count) + " values for " +
                           std::to_string(columns_) + " columns in " + path_);
  }
  char buf[32];
  for (std::size_t i = 0; i < count; ++i) {
    if (i) out_.put(',');
    const auto res = std::to_chars(buf, buf + sizeof(buf), values[i]);
    out_.write(buf, res.ptr - buf);
  }
  out_.put('\n');
}

void CsvWriter::row_text(const std::vector<std::string>& fields) {
  if (fields.size() != columns_) {
    throw std::logic_error("CsvWriter: row of " + std::to_string(fields.size()) + " fields for " +
                           std::to_string(columns_) + " columns in " + path_);
  }
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (i) out_ << ',';
    out_ << fields[i];
  }
  out_ << '\n';
}

}  // namespace teleop

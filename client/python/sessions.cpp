// In-process sessions and campaign runs for Python: a campaign (a file, or YAML/JSON text the
// package builds from keyword arguments) and a run id in, the run's row of the results table
// (as the header's names) and its traces (numpy arrays) out. The session runs without the GIL.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <charconv>
#include <cstdlib>
#include <string>
#include <vector>

#include "client/campaign/campaign.hpp"
#include "client/campaign/results.hpp"
#include "client/python/bindings.hpp"
#include "common/config/config.hpp"

namespace py = pybind11;

namespace teleop::python {

namespace {

/// The cells of a comma-separated line.
std::vector<std::string> split_cells(const std::string& line) {
  std::vector<std::string> cells(1);
  for (char ch : line) {
    if (ch == ',') {
      cells.emplace_back();
    } else {
      cells.back() += ch;
    }
  }
  return cells;
}

/// A cell as Python sees it: int for the integer columns, float for numbers ("nan", "inf"
/// included), str for the text columns and anything that is not a number.
py::object cell_value(const std::string& name, const std::string& text) {
  static const char* const kText[] = {"run_id", "sweep",      "model",  "scene",   "environment",
                                      "script", "trajectory", "scheme", "verdict", "reason"};
  for (const char* t : kText) {
    if (name == t) return py::str(text);
  }
  if (name == "verdict_code" || name == "theory_stable" || name == "safety_cut" || name == "seed") {
    long long v = 0;
    const auto r = std::from_chars(text.data(), text.data() + text.size(), v);
    if (r.ec == std::errc() && r.ptr == text.data() + text.size()) return py::int_(v);
  }
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size()) return py::str(text);
  return py::float_(v);
}

/// Header names and row cells as a dict (the names of the campaign results table).
py::dict row_dict(const std::string& header, const std::string& row) {
  const std::vector<std::string> names = split_cells(header), cells = split_cells(row);
  py::dict d;
  for (std::size_t i = 0; i < names.size() && i < cells.size(); ++i) {
    d[py::str(names[i])] = cell_value(names[i], cells[i]);
  }
  return d;
}

/// Runs run `index` of `c` with its traces; the result as a dict (summary, traces, row,
/// header, dropped).
py::dict run_index(const campaign::Campaign& c, long long index) {
  if (index < 0 || static_cast<std::size_t>(index) >= c.runs.size()) {
    throw py::value_error("index = " + std::to_string(index) + " is outside the campaign's " +
                          std::to_string(c.runs.size()) + " runs (allowed 0 to " +
                          std::to_string(static_cast<long long>(c.runs.size()) - 1) + ")");
  }
  campaign::RunTraces traces;
  std::string row;
  {
    py::gil_scoped_release release;
    row = campaign::run_one(c, c.runs[static_cast<std::size_t>(index)], &traces);
  }
  const std::string header = campaign::results_header(c);
  py::dict tr;
  for (std::size_t k = 0; k < campaign::RunTraces::kChannelCount; ++k) {
    tr[campaign::RunTraces::name(k)] =
        array_of(traces.data[k].data(), traces.size, campaign::RunTraces::width(k));
  }
  py::dict out;
  out["summary"] = row_dict(header, row);
  out["traces"] = tr;
  out["row"] = row;
  out["header"] = header;
  out["dropped"] = traces.dropped;
  return out;
}

/// Every run's parameters as dicts (the parameter columns of the results table).
py::list run_parameters(const campaign::Campaign& c) {
  const std::string header = campaign::results_header(c);
  py::list runs;
  for (const campaign::RunParams& p : c.runs) {
    runs.append(row_dict(header, campaign::parameter_cells(c, p)));
  }
  return runs;
}

}  // namespace

void bind_sessions(py::module_& m) {
  m.def(
      "run_campaign_file",
      [](const std::string& file, long long index) {
        return run_index(campaign::load_campaign(file), index);
      },
      py::arg("campaign_file"), py::arg("index"),
      "Runs run `index` of a campaign file: dict(summary, traces, row, header, dropped).");
  m.def(
      "run_campaign_text",
      [](const std::string& text, const std::string& file, long long index) {
        return run_index(campaign::parse_campaign(text, file), index);
      },
      py::arg("text"), py::arg("file"), py::arg("index") = 0,
      "The same from campaign text (YAML or JSON); `file` names it in messages and resolves "
      "relative paths.");
  m.def(
      "campaign_runs",
      [](const std::string& file) { return run_parameters(campaign::load_campaign(file)); },
      py::arg("campaign_file"), "The parameters of every run of a campaign file, in run order.");
  m.def(
      "campaign_text_runs",
      [](const std::string& text, const std::string& file) {
        return run_parameters(campaign::parse_campaign(text, file));
      },
      py::arg("text"), py::arg("file"), "The same from campaign text.");
  m.def("scheme_labels", &campaign::scheme_labels, "Every scheme a session accepts.");
}

}  // namespace teleop::python

// The topic table (common/dds/topics.hpp) against the wire's documentation: docs/topics.md's
// table lists exactly the table's topics, each with its IDL type and QoS class.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <memory>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "common/dds/topics.hpp"

namespace teleop::dds {
namespace {

struct Row {
  std::string type;
  std::string qos;
};

std::string qos_text(TopicQos q) {
  switch (q) {
    case TopicQos::kStream:
      return "kStream";
    case TopicQos::kLatched:
      return "kLatched";
    case TopicQos::kEventLog:
      return "kEventLog";
    case TopicQos::kReliableStream:
      return "kReliableStream";
    case TopicQos::kLatest:
      return "kLatest";
  }
  return "?";
}

/// The table's topics: name -> (IDL type without its module, QoS class).
std::map<std::string, Row> table_rows() {
  std::map<std::string, Row> out;
  topics::for_each([&out](const auto& t) {
    std::unique_ptr<PubSubOf<decltype(t)>> type(new PubSubOf<decltype(t)>());
    std::string name = type->getName();
    name = name.substr(name.rfind(':') + 1);
    EXPECT_TRUE(out.emplace(t.name, Row{name, qos_text(t.qos)}).second) << t.name << " twice";
  });
  return out;
}

/// docs/topics.md's topic table: each row's `teleop/...` names (first cell), the same number
/// of `Type` names (second cell) and the QoS class (`kX`, last cell).
std::map<std::string, Row> doc_rows(const std::string& path) {
  std::ifstream in(path);
  EXPECT_TRUE(in.good()) << path;
  std::map<std::string, Row> out;
  const std::regex quoted("`([^`]+)`");
  const std::regex qos_class("`(k[A-Z][A-Za-z]+)`");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("| `teleop/", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream ss(line.substr(1));
    for (std::string c; std::getline(ss, c, '|');) cells.push_back(c);
    if (cells.size() < 5) continue;  // another table naming topics (observer topics)
    std::vector<std::string> names, types;
    for (std::sregex_iterator it(cells[0].begin(), cells[0].end(), quoted), end; it != end; ++it)
      names.push_back((*it)[1]);
    for (std::sregex_iterator it(cells[1].begin(), cells[1].end(), quoted), end; it != end; ++it)
      types.push_back((*it)[1]);
    std::smatch q;
    const std::string last = cells.back();
    EXPECT_TRUE(std::regex_search(last, q, qos_class)) << line;
    EXPECT_GE(types.size(), names.size()) << line;
    for (std::size_t i = 0; i < names.size() && i < types.size(); ++i) {
      EXPECT_TRUE(out.emplace(names[i], Row{types[i], q.empty() ? "" : q[1].str()}).second)
          << names[i] << " twice in " << path;
    }
  }
  return out;
}

TEST(TopicTable, TheDocsTableIsTheTable) {
  const std::map<std::string, Row> table = table_rows();
  const std::map<std::string, Row> docs =
      doc_rows(std::string(TELEOP_SOURCE_DIR) + "/docs/topics.md");
  ASSERT_EQ(table.size(), 18u);
  for (const auto& [name, row] : table) {
    const auto it = docs.find(name);
    ASSERT_NE(it, docs.end()) << name << " is not in docs/topics.md's table";
    EXPECT_EQ(it->second.type, row.type) << name;
    EXPECT_EQ(it->second.qos, row.qos) << name;
  }
  for (const auto& [name, row] : docs) {
    EXPECT_EQ(table.count(name), 1u) << name << " is documented but not in the topic table";
  }
}

TEST(TopicTable, NamesAreTheWiresAndTheObserverCopiesShareTheirSourcesType) {
  std::set<std::string> names;
  topics::for_each([&names](const auto& t) {
    EXPECT_EQ(std::string(t.name).rfind("teleop/", 0), 0u) << t.name;
    EXPECT_TRUE(names.insert(t.name).second) << t.name;
  });
  EXPECT_EQ(names.size(), 18u);
  // the copies are the hot topics' types, at the observers' QoS class
  static_assert(std::is_same_v<PubSubOf<decltype(topics::kSlaveStateView)>,
                               PubSubOf<decltype(topics::kSlaveState)>>);
  static_assert(std::is_same_v<PubSubOf<decltype(topics::kMasterStateMonitor)>,
                               PubSubOf<decltype(topics::kMasterState)>>);
  static_assert(std::is_same_v<PubSubOf<decltype(topics::kMeshFrameMonitor)>,
                               PubSubOf<decltype(topics::kMeshFrame)>>);
  EXPECT_EQ(topics::kSlaveStateView.qos, TopicQos::kLatest);
  EXPECT_EQ(topics::kMeshFrameMonitor.qos, TopicQos::kLatest);
}

}  // namespace
}  // namespace teleop::dds

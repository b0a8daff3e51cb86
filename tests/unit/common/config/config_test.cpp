#include "common/config/config.hpp"

#include <gtest/gtest.h>

#include "tests/support/config_error.hpp"

#include <functional>

using teleop::config::ConfigError;
using teleop::config::Node;

namespace {

std::string error_of(const std::function<void()>& fn) { return teleop::test::config_error_of(fn); }

TEST(Config, NumberInRangeIsReturned) {
  const Node n = Node::parse("sphere: {radius_m: 0.25}", "scene.yaml");
  EXPECT_DOUBLE_EQ(n.at("sphere").number("radius_m", 0.01, 10.0), 0.25);
}

TEST(Config, OutOfRangeNamesFileFieldValueAndRange) {
  const Node n = Node::parse("sphere: {radius_m: -3}", "scene.yaml");
  const std::string msg = error_of([&] { n.at("sphere").number("radius_m", 0.01, 10.0); });
  EXPECT_NE(msg.find("scene.yaml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("sphere.radius_m"), std::string::npos) << msg;
  EXPECT_NE(msg.find("-3"), std::string::npos) << msg;
  EXPECT_NE(msg.find("[0.01, 10]"), std::string::npos) << msg;
}

TEST(Config, PositiveNumberRefusesZeroAndNamesTheOpenRange) {
  const Node n = Node::parse("a: {step_s: 0.001, zero: 0, big: 2e3, text: auto}", "s.yaml");
  const Node a = n.at("a");
  EXPECT_DOUBLE_EQ(a.positive_number("step_s", 1.0), 0.001);
  for (const char* key : {"zero", "big"}) {
    const std::string msg = error_of([&] { a.positive_number(key, 1e3); });
    EXPECT_NE(msg.find("s.yaml"), std::string::npos) << msg;
    EXPECT_NE(msg.find(std::string("a.") + key), std::string::npos) << msg;
    EXPECT_NE(msg.find("out of the allowed range (0, 1000]"), std::string::npos) << msg;
  }
  EXPECT_NE(error_of([&] { a.positive_number("text", 1.0); }).find("'auto' is not a number"),
            std::string::npos);
  EXPECT_TRUE(a.is_text("text", "auto"));
  EXPECT_FALSE(a.is_text("step_s", "auto"));
  EXPECT_FALSE(a.is_text("missing", "auto"));
}

TEST(Config, NotANumberIsRejected) {
  const Node n = Node::parse("k: stiff", "a.yaml");
  const std::string msg = error_of([&] { n.number("k", 0, 1e6); });
  EXPECT_NE(msg.find("'stiff' is not a number"), std::string::npos) << msg;
}

TEST(Config, NanIsRejected) {
  const Node n = Node::parse("k: .nan", "a.yaml");
  EXPECT_THROW(n.number("k", 0, 1e6), ConfigError);
}

TEST(Config, MissingRequiredFieldIsNamed) {
  const Node n = Node::parse("a: 1", "a.yaml");
  const std::string msg = error_of([&] { n.number("b", 0, 1); });
  EXPECT_NE(msg.find("'b'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("missing"), std::string::npos) << msg;
}

TEST(Config, ChoiceListsAllowedValues) {
  const Node n = Node::parse("integrator: rk4", "a.yaml");
  const std::string msg = error_of([&] {
    n.choice("integrator", {"explicit-euler", "symplectic-euler"});
  });
  EXPECT_NE(msg.find("rk4"), std::string::npos) << msg;
  EXPECT_NE(msg.find("symplectic-euler"), std::string::npos) << msg;
}

TEST(Config, UnknownKeysAreRejected) {
  const Node n = Node::parse("radus_m: 1", "a.yaml");
  const std::string msg = error_of([&] { n.reject_unknown_keys({"radius_m"}); });
  EXPECT_NE(msg.find("radus_m"), std::string::npos) << msg;
}

TEST(Config, NumbersListChecksLengthAndElements) {
  const Node n = Node::parse("g: [0, 0, -9.81]\nbad: [0, 1]", "a.yaml");
  EXPECT_EQ(n.numbers("g", 3, -100, 100)[2], -9.81);
  EXPECT_THROW(n.numbers("bad", 3, -100, 100), ConfigError);
}

TEST(Config, SyntaxErrorNamesFile) {
  const std::string msg = error_of([&] { Node::parse("a: [1, 2", "broken.yaml"); });
  EXPECT_NE(msg.find("broken.yaml"), std::string::npos) << msg;
}

TEST(Config, MissingFileIsReported) {
  const std::string msg = error_of([&] { Node::load_file("/nonexistent/x.yaml"); });
  EXPECT_NE(msg.find("/nonexistent/x.yaml"), std::string::npos) << msg;
}

TEST(Config, DurationsAndProbabilities) {
  using teleop::config::parse_duration_s;
  using teleop::config::parse_probability;
  EXPECT_DOUBLE_EQ(parse_duration_s("--delay", "50ms"), 0.05);
  EXPECT_DOUBLE_EQ(parse_duration_s("--delay", "2"), 2.0);
  EXPECT_DOUBLE_EQ(parse_duration_s("--delay", "150us"), 150e-6);
  EXPECT_THROW(parse_duration_s("--delay", "5 parsecs"), ConfigError);
  EXPECT_THROW(parse_duration_s("--delay", "-1ms"), ConfigError);
  EXPECT_DOUBLE_EQ(parse_probability("--loss", "1%"), 0.01);
  EXPECT_DOUBLE_EQ(parse_probability("--loss", "0.2"), 0.2);
  EXPECT_THROW(parse_probability("--loss", "120%"), ConfigError);
}

}  // namespace

namespace {

// What yaml-cpp lets pass is refused for every configuration file: duplicate keys at
// any level, null values, keys that are not names, several documents, self-referencing aliases.
TEST(ConfigChecks, DuplicateKeysAreRefusedAtAnyLevel) {
  std::string msg = error_of([] { Node::parse("a: 1\nb: 2\na: 3\n", "c.yaml"); });
  EXPECT_NE(msg.find("c.yaml: field 'a' is given twice (lines 1 and 3; value '1' and '3')"),
            std::string::npos)
      << msg;
  msg = error_of([] { Node::parse("x:\n  - {k: 1, k: 2}\n", "c.yaml"); });
  EXPECT_NE(msg.find("field 'x[0].k' is given twice"), std::string::npos) << msg;
}

TEST(ConfigChecks, NullValuesKeysThatAreNotNamesAndSeveralDocumentsAreRefused) {
  std::string msg = error_of([] { Node::parse("delay:\ncontroller: {}\n", "m.yaml"); });
  EXPECT_NE(msg.find("m.yaml: field 'delay' (line 1): value is empty (null)"), std::string::npos)
      << msg;
  msg = error_of([] { Node::parse("{a: 1}: 2\n", "m.yaml"); });
  EXPECT_NE(msg.find("not a plain name"), std::string::npos) << msg;
  // the explicit complex-key form is outside the subset the parser is given at all
  msg = error_of([] { Node::parse("? {a: 1}\n: 2\n", "m.yaml"); });
  EXPECT_NE(msg.find("m.yaml: line 1 (byte 0) is outside the YAML subset"), std::string::npos)
      << msg;
  msg = error_of([] { Node::parse("a: 1\n---\na: 2\n", "m.yaml"); });
  EXPECT_NE(msg.find("2 YAML documents"), std::string::npos) << msg;
}

TEST(ConfigChecks, SelfReferencingAliasEndsWithABoundedMessage) {
  // anchors and aliases are outside the subset: refused before yaml-cpp builds the cycle
  const std::string msg = error_of([] { Node::parse("k: &a [*a]\n", "a.yaml"); });
  EXPECT_NE(msg.find("a.yaml: line 1 (byte 3) is outside the YAML subset"), std::string::npos)
      << msg;
  EXPECT_NE(msg.find("anchor"), std::string::npos) << msg;
  EXPECT_LT(msg.size(), 400u) << msg;
}

TEST(ConfigChecks, ASectionThatIsNotAMappingIsRefused) {
  const Node n = Node::parse("physics: 5\n", "s.yaml");
  const std::string msg = error_of([&] { n.at("physics").reject_unknown_keys({"rate_hz"}); });
  EXPECT_NE(msg.find("field 'physics': value '5' must be a mapping of the fields {rate_hz}"),
            std::string::npos)
      << msg;
}

TEST(ConfigChecks, EmptyDocumentsAndDirectories) {
  EXPECT_TRUE(Node::parse("", "e.yaml").empty_document());
  EXPECT_TRUE(Node::parse("# only a comment\n", "e.yaml").empty_document());
  EXPECT_TRUE(Node::load_file("/dev/null").empty_document());
  const std::string msg = error_of([] { Node::load_file("/tmp"); });
  EXPECT_NE(msg.find("/tmp: is a directory"), std::string::npos) << msg;
}

}  // namespace

namespace {

std::string parse_error(const std::string& text) {
  try {
    Node::parse(text, "s.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, InvalidUtf8IsRefusedBeforeTheParserWithByteAndLine) {
  // the fuzzer's input that kept yaml-cpp 0.7 busy for more than 13 s
  const std::string hang("\x2c\xc7\xff\xff\xff\x62\x20\xff\x2a", 9);
  const std::string e = parse_error(hang);
  EXPECT_NE(e.find("s.yaml: byte 1 (line 1) is 0xc7, not valid UTF-8"), std::string::npos) << e;
  EXPECT_NE(parse_error("a: 1\nb: \xff\n").find("byte 8 (line 2) is 0xff"), std::string::npos);
  EXPECT_NE(parse_error(std::string("a: 1\n\0b: 2\n", 10)).find("byte 5"), std::string::npos);
  // valid UTF-8 (a BOM, accents, tabs in comments) still parses
  EXPECT_EQ(parse_error("\xef\xbb\xbfname: d\xc3\xa9\x66\x61ut  #\tcomment\n"), "");
}

TEST(Config, YamlTagsAreRefusedQuotedOrInnerBangsAreNot) {
  // the fuzzer's input that made yaml-cpp 0.7 allocate without end
  EXPECT_NE(parse_error("!visual_ra,e_hz").find("line 1 (byte 0) is outside the YAML subset"),
            std::string::npos);
  EXPECT_NE(parse_error("!visual_ra,e_hz").find("a YAML tag"), std::string::npos);
  EXPECT_NE(parse_error("a: 1\nb: !!str 5\n").find("line 2"), std::string::npos);
  EXPECT_EQ(parse_error("name: 'wow!'\nother: \"!x\"\nthird: a!b  # !comment\n"), "");
  // a ',' starting a token outside [ ] / { } (a fuzz input that hung yaml-cpp started ", a")
  EXPECT_NE(parse_error(", a sphere\nname: x\n").find("outside [ ] or { }"), std::string::npos);
  EXPECT_EQ(parse_error("v: [1, 2, 3]\nm: {a: 1, b: [4, 5]}\ns: a, b\n"), "");
}

}  // namespace

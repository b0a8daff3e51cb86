#include "common/util/json.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace teleop {
namespace {

std::string number_text(double v) { return json_compact(json_number(v)); }

TEST(JsonNumber, SixSignificantDigitsWholeNumbersAsIntegersNonFiniteAsNull) {
  EXPECT_EQ(number_text(0.1234567), "0.123457");
  EXPECT_EQ(number_text(0.1), "0.1");
  EXPECT_EQ(number_text(-2.5), "-2.5");
  EXPECT_EQ(number_text(1000.0), "1000");
  EXPECT_EQ(number_text(-1.0), "-1");
  EXPECT_EQ(number_text(1234567.0), "1234570");
  EXPECT_EQ(number_text(1.5e-5), "1.5e-05");
  EXPECT_EQ(number_text(0.00015), "0.00015");
  EXPECT_EQ(number_text(std::numeric_limits<double>::quiet_NaN()), "null");
  EXPECT_EQ(number_text(std::numeric_limits<double>::infinity()), "null");
  EXPECT_EQ(number_text(-std::numeric_limits<double>::infinity()), "null");
}

TEST(JsonLayout, LineAndDocumentKeepKeyOrder) {
  OrderedJson j;
  j["zeta"] = 1;
  j["alpha"] = OrderedJson::array({1, 2});
  j["mid"] = {{"p50", json_number(0.5)}, {"max", nullptr}};
  j["text"] = "ok";
  EXPECT_EQ(json_line(j), R"({"zeta": 1, "alpha": [1, 2], "mid": {"p50": 0.5, "max": null}, )"
                          R"("text": "ok"})");
  EXPECT_EQ(json_document(j),
            "{\n  \"zeta\": 1,\n  \"alpha\": [1, 2],\n"
            "  \"mid\": {\"p50\": 0.5, \"max\": null},\n  \"text\": \"ok\"\n}\n");
  EXPECT_EQ(json_compact(j),
            R"({"zeta":1,"alpha":[1,2],"mid":{"p50":0.5,"max":null},"text":"ok"})");
  EXPECT_EQ(json_line(OrderedJson::object()), "{}");
  EXPECT_EQ(json_line(OrderedJson::array()), "[]");
}

TEST(JsonText, EscapedByTheLibraryAndReadBackUnchanged) {
  const std::string text = std::string("a \"quoted\" \\ line\nbreak\ttab\x01 bell\x07") + "end";
  OrderedJson j;
  j["message"] = text;
  j[std::string("key \"with\" quotes")] = true;
  const std::string line = json_line(j);
  EXPECT_NE(line.find(R"(\n)"), std::string::npos) << line;
  EXPECT_NE(line.find(R"(\u0001)"), std::string::npos) << line;
  EXPECT_EQ(line.find('\x01'), std::string::npos) << "no raw control character";
  const OrderedJson back = OrderedJson::parse(line);
  EXPECT_EQ(back["message"].get<std::string>(), text);
  EXPECT_TRUE(back["key \"with\" quotes"].get<bool>());
  EXPECT_EQ(OrderedJson::parse(json_document(j)), back);
}

TEST(JsonText, BytesThatAreNotUtf8AreReplacedNotThrown) {
  OrderedJson j;
  j["name"] = std::string("bad \xff\xfe byte");
  std::string line;
  ASSERT_NO_THROW(line = json_line(j));
  const OrderedJson back = OrderedJson::parse(line);
  EXPECT_EQ(back["name"].get<std::string>(), "bad \xEF\xBF\xBD\xEF\xBF\xBD byte");
  ASSERT_NO_THROW(line = json_compact(j));
  EXPECT_TRUE(OrderedJson::accept(line));
}

}  // namespace
}  // namespace teleop

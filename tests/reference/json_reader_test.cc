// Tests for reference/core/json_reader.h: the checks parse() makes before a document is built
// (depth, duplicate keys, number range, syntax) and the range-checked readers, each asserting the
// message names the document and the field path (issue #18, "validation at the door").
#include "reference/core/json_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "reference/core/io.h"

namespace dentsim {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

std::string parse_error(const std::string& text) {
  try {
    JsonReader("doc.json").parse(text);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string nested(int levels, const std::string& inner) {
  std::string s;
  for (int i = 0; i < levels; ++i) s += "{\"a\": [";
  s += inner;
  for (int i = 0; i < levels; ++i) s += "]}";
  return s;
}

TEST(JsonReader, DeepNestingIsAnErrorNotACrash) {
  // 10^5 levels used to overflow the stack in the consumers of the tree (issue #18).
  std::string deep(100000, '[');
  deep += std::string(100000, ']');
  EXPECT_THAT(parse_error(deep),
              AllOf(HasSubstr("doc.json: "), HasSubstr("nested deeper than 64")));
  // The path names where the limit was hit: 32 objects each holding an array = 64 levels.
  EXPECT_THAT(parse_error(nested(33, "1")),
              AllOf(HasSubstr("a[0].a[0]"), HasSubstr("nested deeper than 64")));
  // Exactly at the limit is accepted.
  EXPECT_EQ(parse_error(nested(32, "1")), "(no error)");
}

TEST(JsonReader, DuplicateKeysAreErrorsWithTheirPath) {
  EXPECT_EQ(parse_error(R"({"tool": {"bur_radius_mm": 0.5, "bur_radius_mm": 5}})"),
            "doc.json: tool.bur_radius_mm: key given twice in one object (JSON would silently "
            "keep the last)");
  EXPECT_EQ(parse_error(R"({"a": 1, "a": 1})"),
            "doc.json: a: key given twice in one object (JSON would silently keep the last)");
  // The same key in two different objects is fine.
  EXPECT_EQ(parse_error(R"({"x": {"a": 1}, "y": {"a": 1}, "z": [{"a": 1}, {"a": 2}]})"),
            "(no error)");
}

TEST(JsonReader, NumbersBeyondADoubleNameTheField) {
  EXPECT_EQ(parse_error(R"({"method": {"k_vc_n_per_m": 1e400}})"),
            "doc.json: method.k_vc_n_per_m: number '1e400' is outside the range of a double "
            "(|x| < 1.8e308)");
  EXPECT_THAT(parse_error(R"({"hand": {"script": [{"t_s": 0}, {"t_s": -1e999}]}})"),
              HasSubstr("doc.json: hand.script[1].t_s: number '-1e999' is outside the range"));
  EXPECT_THAT(parse_error("[1, 2, 1e400]"), HasSubstr("doc.json: [2]: number '1e400'"));
}

TEST(JsonReader, SyntaxErrorsAreEscaped) {
  const std::string e = parse_error("{\"a\": \x1b[31m}");
  EXPECT_THAT(e, AllOf(HasSubstr("doc.json: not valid JSON (parse error at line 1"),
                       Not(HasSubstr("\x1b"))));
  EXPECT_THAT(parse_error("{\"a\": 1"), HasSubstr("not valid JSON"));
}

TEST(JsonReader, IntegersAreRangeCheckedWithoutWrapping) {
  const JsonReader r("doc.json");
  auto error_of = [&](const std::string& text, long lo, long hi) -> std::string {
    try {
      const auto doc = r.parse(text);
      return std::to_string(r.integer(doc, "tooth", "resolution", 0, lo, hi));
    } catch (const InputError& e) {
      return e.what();
    }
  };
  // 4294967424 = 2^32 + 128 used to become 128 through a cast to int.
  EXPECT_EQ(error_of(R"({"resolution": 4294967424})", 32, 512),
            "doc.json: tooth.resolution: expected an integer in [32, 512], got 4294967424");
  EXPECT_EQ(error_of(R"({"resolution": 18446744073709551615})", 32, 512),
            "doc.json: tooth.resolution: expected an integer in [32, 512], got "
            "18446744073709551615");
  EXPECT_EQ(error_of(R"({"resolution": 16})", 32, 512),
            "doc.json: tooth.resolution: expected an integer in [32, 512], got 16");
  EXPECT_EQ(error_of(R"({"resolution": -64})", 32, 512),
            "doc.json: tooth.resolution: expected an integer in [32, 512], got -64");
  EXPECT_EQ(error_of(R"({"resolution": 64.0})", 32, 512),
            "doc.json: tooth.resolution: expected an integer in [32, 512], got 64.0");
  EXPECT_EQ(error_of(R"({"resolution": 64})", 32, 512), "64");
  EXPECT_EQ(error_of(R"({"resolution": -3})", -5, 5), "-3");
  EXPECT_EQ(error_of(R"({})", 32, 512), "0");  // absent: the fallback
}

TEST(JsonReader, QuotedValuesAndKeysAreEscaped) {
  const JsonReader r("doc.json");
  const auto doc = r.parse("{\"tool\": {\"pre\\u001bset\": 1, \"x\": \"\\u001b[2J\"}}");
  try {
    r.only_keys(doc.at("tool"), "tool", {"x"});
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()),
                AllOf(HasSubstr("tool.pre\\x1bset: unknown field"), Not(HasSubstr("\x1b"))));
  }
  try {
    r.number(doc.at("tool"), "tool", "x");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_THAT(std::string(e.what()),
                AllOf(HasSubstr("tool.x: expected a number, got string"), Not(HasSubstr("\x1b"))));
  }
}

TEST(JsonReader, VectorNamesTheBadElement) {
  const JsonReader r("doc.json");
  const auto doc = r.parse(R"({"v": [1, "2", 3]})");
  try {
    r.vec3(doc, "tooth", "v");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "doc.json: tooth.v[1]: expected a finite number (an array of 3 numbers), got \"2\"");
  }
}

}  // namespace
}  // namespace dentsim

#include "visproxy/core/json_input.h"

#include <gtest/gtest.h>

#include <string>

#include "visproxy/core/errors.h"

namespace visproxy {
namespace {

using nlohmann::json;

// The message `check` throws, or "accepted".
template <typename Check>
std::string error_of(Check check) {
  try {
    check();
    return "accepted";
  } catch (const InvalidInputError& error) {
    EXPECT_EQ(error.file(), "in.json");
    return error.what();
  }
}

TEST(JsonPath, PlainKeysAreDottedOthersQuoted) {
  EXPECT_EQ(json_member_path("", "instances"), "instances");
  EXPECT_EQ(json_member_path(json_index_path("instances", 2), "transform"), "instances[2].transform");
  EXPECT_EQ(json_member_path("meshes", "bunny_2-low"), "meshes.bunny_2-low");
  EXPECT_EQ(json_member_path("meshes", "my mesh"), "meshes[\"my mesh\"]");
  EXPECT_EQ(json_member_path("meshes", "a.b"), "meshes[\"a.b\"]");
  EXPECT_EQ(json_member_path("meshes", ""), "meshes[\"\"]");
  EXPECT_EQ(json_member_path("meshes", "line\nbreak \"quoted\""), "meshes[\"line\\nbreak \\\"quoted\\\"\"]");
  EXPECT_EQ(json_quoted(std::string("bad \xff utf-8")), "\"bad \xef\xbf\xbd utf-8\"");
}

TEST(JsonInput, ParseErrorsNameTheLine) {
  const JsonInput input("in.json");
  EXPECT_EQ(error_of([&] { input.parse("{\n  \"a\": 1,\n  \"b\": ]\n}"); }), "in.json:3: not valid JSON");
  EXPECT_EQ(error_of([&] { input.parse(""); }), "in.json:1: not valid JSON");
  EXPECT_EQ(error_of([&] { input.parse("[1e999]"); }), "in.json: not valid JSON");
  EXPECT_EQ(input.parse("{\"a\": [1, 2]}"), json({{"a", {1, 2}}}));
}

TEST(JsonInput, ChecksNameThePathAndWhatIsExpected) {
  const JsonInput input("in.json");
  const json document = input.parse(R"({"n": -2.5, "i": 7, "s": "text", "b": true, "v": [1, 2, 3], "o": {}})");
  EXPECT_EQ(input.number(document["n"], "n"), -2.5);
  EXPECT_EQ(input.integer(document["i"], "i", 1, 7), 7u);
  EXPECT_EQ(input.count(document["i"], "i"), 7u);
  EXPECT_EQ(input.string(document["s"], "s"), "text");
  EXPECT_TRUE(input.boolean(document["b"], "b"));
  EXPECT_EQ(input.triple(document["v"], "v"), (std::array<double, 3>{1, 2, 3}));
  EXPECT_EQ(input.optional_member(document, "missing", ""), nullptr);

  EXPECT_EQ(error_of([&] { input.member(document, "missing", ""); }), "in.json: missing \"missing\"");
  EXPECT_EQ(error_of([&] { input.member(document["o"], "key", "o"); }), "in.json: o: missing \"key\"");
  EXPECT_EQ(error_of([&] { input.member(document["v"], "key", "v"); }), "in.json: v: expected an object");
  EXPECT_EQ(error_of([&] { input.number(document["s"], "s"); }), "in.json: s: expected a number");
  EXPECT_EQ(error_of([&] { input.positive_number(document["n"], "n"); }), "in.json: n: must be a positive number");
  EXPECT_EQ(error_of([&] { input.integer(document["i"], "i", 1, 6); }), "in.json: i: expected an integer from 1 to 6");
  EXPECT_EQ(error_of([&] { input.integer(document["n"], "n", 0, 9); }), "in.json: n: expected an integer from 0 to 9");
  EXPECT_EQ(error_of([&] { input.count(document["n"], "n"); }),
            "in.json: n: expected a count (a non-negative integer)");
  EXPECT_EQ(error_of([&] { input.triple(document["o"], "o"); }), "in.json: o: expected an array of 3 numbers");
  EXPECT_EQ(error_of([&] { input.string(document["b"], "b"); }), "in.json: b: must be a string");
  EXPECT_EQ(error_of([&] { input.boolean(document["i"], "i"); }), "in.json: i: must be true or false");
}

}  // namespace
}  // namespace visproxy

#include <gtest/gtest.h>

#include "pteryla/core/error.hpp"
#include "pteryla/core/json.hpp"

using namespace pteryla;

TEST(JsonReader, RejectsUnknownKeyWithPath) {
  Json j = Json::parse(R"({"a": 1, "sub": {"x": 2, "typo": 3}})");
  JsonReader r(j, "scene.json");
  EXPECT_EQ(r.number("a"), 1.0);
  JsonReader s = r.object("sub");
  EXPECT_EQ(s.number("x"), 2.0);
  try {
    s.finish();
    FAIL() << "unknown key accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), "scene.json");
    EXPECT_EQ(e.element(), "sub.typo");
  }
  EXPECT_NO_THROW(r.finish());
}

TEST(JsonReader, RangeAndTypeErrorsNameTheField) {
  Json j = Json::parse(R"({"rp": 1.5, "name": 3, "arr": [{"v": "x"}]})");
  JsonReader r(j, "f.json");
  try {
    r.number("rp", 0.0, 1.0);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "rp");
  }
  try {
    r.string("name");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "name");
  }
  auto arr = r.objects("arr");
  ASSERT_EQ(arr.size(), 1u);
  try {
    arr[0].number("v");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.element(), "arr[0].v");
  }
  try {
    r.number("missing");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos);
  }
}

TEST(JsonFile, MalformedJsonReportsLine) {
  const std::string path = std::string(PTERYLA_BUILD_DIR) + "/malformed_test.json";
  {
    FILE* f = fopen(path.c_str(), "w");
    fputs("{\n  \"a\": 1,\n  \"b\": ]\n}\n", f);
    fclose(f);
  }
  try {
    readJsonFile(path);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(readJsonFile(path + ".does-not-exist"), Error);
}

// Found by tests/fuzz (feather reader): a number too large for a double made nlohmann throw out_of_range,
// which escaped as an internal failure instead of a pteryla::Error naming the file.
TEST(JsonFile, NumberOverflowIsBadInput) {
  const std::string path = std::string(PTERYLA_BUILD_DIR) + "/overflow_test.json";
  {
    FILE* f = fopen(path.c_str(), "w");
    fputs("{\n  \"length\": 1e3081\n}\n", f);
    fclose(f);
  }
  try {
    readJsonFile(path);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(std::string(e.what()).find("number overflow"), std::string::npos) << e.what();
  }
}

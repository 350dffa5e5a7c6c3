#pragma once
// Strict JSON reading shared by every pteryla file format (scene, feather, tract lists).
// A JsonReader wraps one JSON object, remembers the file and key path, hands out typed fields and,
// on finish(), rejects any key nobody asked for ("unknown key 'densty' at tracts[1]").
// Numbers are checked for finiteness and ranges; every failure is a pteryla::Error naming the path.
#include <nlohmann/json.hpp>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <limits>
#include <set>
#include <string>
#include <vector>

namespace pteryla {

using Json = nlohmann::json;

// Parses a JSON file; throws Error(file) for a missing file or a syntax error (with line/column).
Json readJsonFile(const std::string& path);
// Writes pretty JSON; refuses nothing (overwrite policy is the caller's).
void writeJsonFile(const std::string& path, const Json& j);

class JsonReader {
 public:
  JsonReader(const Json& j, std::string file, std::string path = "");
  // A reader keeps a reference to its JSON: a temporary would be destroyed under it (found by ASan:
  // `JsonReader r(c ? Json::object() : j, ...)` read a dead object). Name the Json first.
  JsonReader(Json&& j, std::string file, std::string path = "") = delete;

  bool has(const std::string& key) const;
  const std::string& file() const { return file_; }
  const std::string& path() const { return path_; }
  std::string pathOf(const std::string& key) const;
  const Json& json() const { return j_; }

  // Required fields.
  double number(const std::string& key, double lo = -std::numeric_limits<double>::infinity(),
                double hi = std::numeric_limits<double>::infinity());
  int64_t integer(const std::string& key, int64_t lo = std::numeric_limits<int64_t>::min(),
                  int64_t hi = std::numeric_limits<int64_t>::max());
  std::string string(const std::string& key);
  // Optional fields with defaults (range still checked when present).
  double number(const std::string& key, double def, double lo, double hi);
  int64_t integer(const std::string& key, int64_t def, int64_t lo, int64_t hi);
  uint64_t seed(const std::string& key, uint64_t def);
  bool boolean(const std::string& key, bool def);
  std::string string(const std::string& key, const std::string& def);
  std::string oneOf(const std::string& key, const std::string& def, const std::vector<std::string>& allowed);
  glm::dvec2 vec2(const std::string& key);
  glm::dvec3 vec3(const std::string& key);
  glm::dvec3 vec3(const std::string& key, const glm::dvec3& def);
  std::vector<double> numbers(const std::string& key);

  // Sub-objects and arrays: the key is marked used; children carry their own path.
  JsonReader object(const std::string& key);
  std::vector<JsonReader> objects(const std::string& key);  // array of objects (missing -> empty)
  const Json& raw(const std::string& key);                  // marks used, no type check
  // Marks an optional key as known without reading it (so finish() accepts it).
  void allow(const std::string& key) { used_.insert(key); }

  // Throws for any key not consumed. Call after reading all fields.
  void finish() const;

  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

 private:
  const Json& get(const std::string& key);
  const Json& j_;
  std::string file_, path_;
  std::set<std::string> used_;
};

// Largest magnitude of any number read from a pteryla file (docs/limits.md): beyond it squares and
// products overflow inside the geometry.
constexpr double kMaxJsonMagnitude = 1e12;

// Helpers for numbers in arrays (element paths like "cvs[3][1]").
double jsonNumber(const Json& v, const std::string& file, const std::string& path);

}  // namespace pteryla

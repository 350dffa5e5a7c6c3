#include "pteryla/core/json.hpp"

#include <cmath>
#include <fstream>
#include <sstream>

#include "pteryla/core/atomic_file.hpp"
#include "pteryla/core/error.hpp"

namespace pteryla {

Json readJsonFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open file (does it exist?)", path);
  std::stringstream ss;
  ss << in.rdbuf();
  try {
    return Json::parse(ss.str());
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte is the offset; turn it into line:column for humans.
    const std::string s = ss.str();
    size_t line = 1, col = 1;
    for (size_t i = 0; i + 1 < e.byte && i < s.size(); ++i) {
      if (s[i] == '\n') {
        ++line;
        col = 1;
      } else {
        ++col;
      }
    }
    std::string msg = e.what();
    const auto p = msg.find("parse error");
    if (p != std::string::npos) msg = msg.substr(p);
    throw Error("malformed JSON at line " + std::to_string(line) + ", column " + std::to_string(col) + ": " + msg,
                path);
  } catch (const nlohmann::json::exception& e) {
    // The parser's other rejections, e.g. out_of_range 406 "number overflow parsing '1e999'" (found by
    // tests/fuzz): bad input like a syntax error, not an internal failure. They carry no offset.
    std::string msg = e.what();
    const auto p = msg.find("] ");
    if (p != std::string::npos) msg = msg.substr(p + 2);
    throw Error("malformed JSON: " + msg, path);
  }
}

void writeJsonFile(const std::string& path, const Json& j) { writeFileAtomic(path, j.dump(2) + "\n"); }

JsonReader::JsonReader(const Json& j, std::string file, std::string path)
    : j_(j), file_(std::move(file)), path_(std::move(path)) {
  if (!j_.is_object()) throw Error("expected a JSON object", file_, path_.empty() ? "(top level)" : path_);
}

std::string JsonReader::pathOf(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

void JsonReader::fail(const std::string& key, const std::string& what) const {
  throw Error(what, file_, key.empty() ? (path_.empty() ? "(top level)" : path_) : pathOf(key));
}

bool JsonReader::has(const std::string& key) const { return j_.contains(key) && !j_.at(key).is_null(); }

const Json& JsonReader::get(const std::string& key) {
  used_.insert(key);
  if (!j_.contains(key)) fail(key, "missing required field");
  return j_.at(key);
}

const Json& JsonReader::raw(const std::string& key) { return get(key); }

double jsonNumber(const Json& v, const std::string& file, const std::string& path) {
  if (!v.is_number()) throw Error("expected a number, got " + std::string(v.type_name()), file, path);
  const double d = v.get<double>();
  if (!std::isfinite(d)) throw Error("expected a finite number", file, path);
  // Squares and products of larger values overflow to infinity inside the geometry (1e154 squared).
  if (std::abs(d) > kMaxJsonMagnitude) {
    std::ostringstream os;
    os << "value " << d << " is too large (pteryla accepts numbers in [-" << kMaxJsonMagnitude << ", "
       << kMaxJsonMagnitude << "])";
    throw Error(os.str(), file, path);
  }
  return d;
}

double JsonReader::number(const std::string& key, double lo, double hi) {
  const double d = jsonNumber(get(key), file_, pathOf(key));
  if (d < lo || d > hi) {
    std::ostringstream os;
    os << "value " << d << " is out of range [" << lo << ", " << hi << "]";
    fail(key, os.str());
  }
  return d;
}

double JsonReader::number(const std::string& key, double def, double lo, double hi) {
  if (!j_.contains(key)) {
    used_.insert(key);
    return def;
  }
  return number(key, lo, hi);
}

int64_t JsonReader::integer(const std::string& key, int64_t lo, int64_t hi) {
  const Json& v = get(key);
  if (!v.is_number_integer()) fail(key, "expected an integer");
  const int64_t i = v.get<int64_t>();
  if (i < lo || i > hi)
    fail(key,
         "value " + std::to_string(i) + " is out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return i;
}

int64_t JsonReader::integer(const std::string& key, int64_t def, int64_t lo, int64_t hi) {
  if (!j_.contains(key)) {
    used_.insert(key);
    return def;
  }
  return integer(key, lo, hi);
}

uint64_t JsonReader::seed(const std::string& key, uint64_t def) {
  if (!j_.contains(key)) {
    used_.insert(key);
    return def;
  }
  const Json& v = get(key);
  if (v.is_number_unsigned()) return v.get<uint64_t>();
  if (v.is_number_integer() && v.get<int64_t>() >= 0) return static_cast<uint64_t>(v.get<int64_t>());
  fail(key, "expected a non-negative integer seed");
}

bool JsonReader::boolean(const std::string& key, bool def) {
  if (!j_.contains(key)) {
    used_.insert(key);
    return def;
  }
  const Json& v = get(key);
  if (!v.is_boolean()) fail(key, "expected true or false");
  return v.get<bool>();
}

std::string JsonReader::string(const std::string& key) {
  const Json& v = get(key);
  if (!v.is_string()) fail(key, "expected a string");
  return v.get<std::string>();
}

std::string JsonReader::string(const std::string& key, const std::string& def) {
  if (!j_.contains(key)) {
    used_.insert(key);
    return def;
  }
  return string(key);
}

std::string JsonReader::oneOf(const std::string& key, const std::string& def, const std::vector<std::string>& allowed) {
  const std::string s = string(key, def);
  for (const auto& a : allowed)
    if (a == s) return s;
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + ("'" + a + "'");
  fail(key, "'" + s + "' is not one of " + list);
}

std::vector<double> JsonReader::numbers(const std::string& key) {
  const Json& v = get(key);
  if (!v.is_array()) fail(key, "expected an array of numbers");
  std::vector<double> out;
  for (size_t i = 0; i < v.size(); ++i)
    out.push_back(jsonNumber(v[i], file_, pathOf(key) + "[" + std::to_string(i) + "]"));
  return out;
}

glm::dvec2 JsonReader::vec2(const std::string& key) {
  const auto n = numbers(key);
  if (n.size() != 2) fail(key, "expected 2 numbers [x, y], got " + std::to_string(n.size()));
  return {n[0], n[1]};
}

glm::dvec3 JsonReader::vec3(const std::string& key) {
  const auto n = numbers(key);
  if (n.size() != 3) fail(key, "expected 3 numbers [x, y, z], got " + std::to_string(n.size()));
  return {n[0], n[1], n[2]};
}

glm::dvec3 JsonReader::vec3(const std::string& key, const glm::dvec3& def) {
  if (!j_.contains(key)) {
    used_.insert(key);
    return def;
  }
  return vec3(key);
}

JsonReader JsonReader::object(const std::string& key) {
  const Json& v = get(key);
  if (!v.is_object()) fail(key, "expected an object");
  return JsonReader(v, file_, pathOf(key));
}

std::vector<JsonReader> JsonReader::objects(const std::string& key) {
  std::vector<JsonReader> out;
  if (!j_.contains(key)) {
    used_.insert(key);
    return out;
  }
  const Json& v = get(key);
  if (!v.is_array()) fail(key, "expected an array of objects");
  for (size_t i = 0; i < v.size(); ++i) out.emplace_back(v[i], file_, pathOf(key) + "[" + std::to_string(i) + "]");
  return out;
}

void JsonReader::finish() const {
  for (auto it = j_.begin(); it != j_.end(); ++it) {
    if (!used_.count(it.key())) {
      std::string known;
      for (const auto& k : used_) known += (known.empty() ? "" : ", ") + k;
      throw Error("unknown key '" + it.key() + "' (known keys here: " + known + ")", file_, pathOf(it.key()));
    }
  }
}

}  // namespace pteryla

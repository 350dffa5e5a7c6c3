#pragma once
// A strict reader for the subset of USD text (.usda) pteryla writes: layer metadata, `def` prims with
// metadata and children, attributes with defaults, metadata and timeSamples, relationships. Anything
// else, a malformed value, or an array element that does not match the declared type (3 numbers for
// point3f, integers for int, ...) throws std::runtime_error with the line number. Independent of the
// writer: written from the usda syntax, not from pteryla's code.
#include <cctype>
#include <cstdlib>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace usda {

struct Value {
  enum class Kind { Number, String, Token, Path, Tuple, Array } kind = Kind::Number;
  std::string text;          // number text, string contents, token, path
  std::vector<Value> items;  // tuple or array elements
  double number() const { return std::strtod(text.c_str(), nullptr); }
};

struct Attribute {
  std::string type;  // "point3f[]"
  bool uniform = false, custom = false;
  bool hasDefault = false;
  Value value;
  std::map<std::string, Value> meta;
  std::map<double, Value> samples;  // timeSamples
};

struct Prim {
  std::string type, name;
  std::map<std::string, Value> meta;
  std::map<std::string, Attribute> attrs;
  std::map<std::string, std::vector<std::string>> rels;
  std::vector<Prim> children;
  const Prim* child(const std::string& n) const {
    for (const Prim& c : children)
      if (c.name == n) return &c;
    return nullptr;
  }
  const Attribute& attr(const std::string& n) const {
    auto it = attrs.find(n);
    if (it == attrs.end()) throw std::runtime_error("prim " + name + " has no attribute " + n);
    return it->second;
  }
};

struct Layer {
  std::map<std::string, Value> meta;
  std::vector<Prim> prims;
};

class Reader {
 public:
  explicit Reader(const std::string& text) : s_(text) {}

  Layer read() {
    if (s_.compare(0, 10, "#usda 1.0\n") != 0) fail("expected '#usda 1.0'");
    p_ = 10;
    Layer layer;
    skip();
    if (peek('(')) layer.meta = metadata();
    while (skip(), p_ < s_.size()) layer.prims.push_back(prim());
    return layer;
  }

 private:
  const std::string& s_;
  size_t p_ = 0;

  [[noreturn]] void fail(const std::string& what) const {
    size_t line = 1;
    for (size_t i = 0; i < p_ && i < s_.size(); ++i) line += s_[i] == '\n';
    throw std::runtime_error("usda line " + std::to_string(line) + ": " + what);
  }
  void skip() {
    while (p_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[p_]))) ++p_;
  }
  bool peek(char c) {
    skip();
    return p_ < s_.size() && s_[p_] == c;
  }
  void expect(char c) {
    if (!peek(c)) fail(std::string("expected '") + c + "'");
    ++p_;
  }
  std::string word() {
    skip();
    const size_t b = p_;
    while (p_ < s_.size() &&
           (std::isalnum(static_cast<unsigned char>(s_[p_])) || s_[p_] == '_' || s_[p_] == ':' || s_[p_] == '.'))
      ++p_;
    if (b == p_) fail("expected a name");
    return s_.substr(b, p_ - b);
  }
  std::string quoted() {
    expect('"');
    std::string out;
    while (p_ < s_.size() && s_[p_] != '"') {
      if (s_[p_] == '\n') fail("newline in a string");
      if (s_[p_] == '\\') ++p_;
      out += s_[p_++];
    }
    if (p_ >= s_.size()) fail("unterminated string");
    ++p_;
    return out;
  }
  Value number() {
    skip();
    const size_t b = p_;
    if (s_[p_] == '-' || s_[p_] == '+') ++p_;
    while (p_ < s_.size() &&
           (std::isdigit(static_cast<unsigned char>(s_[p_])) || s_[p_] == '.' || s_[p_] == 'e' || s_[p_] == 'E' ||
            ((s_[p_] == '-' || s_[p_] == '+') && (s_[p_ - 1] == 'e' || s_[p_ - 1] == 'E'))))
      ++p_;
    Value v;
    v.text = s_.substr(b, p_ - b);
    char* end = nullptr;
    std::strtod(v.text.c_str(), &end);
    if (v.text.empty() || end != v.text.c_str() + v.text.size()) fail("bad number '" + v.text + "'");
    return v;
  }
  Value value() {
    skip();
    if (p_ >= s_.size()) fail("expected a value");
    const char c = s_[p_];
    Value v;
    if (c == '"') {
      v.kind = Value::Kind::String;
      v.text = quoted();
    } else if (c == '<') {
      v.kind = Value::Kind::Path;
      const size_t e = s_.find('>', p_);
      if (e == std::string::npos) fail("unterminated path");
      v.text = s_.substr(p_ + 1, e - p_ - 1);
      p_ = e + 1;
    } else if (c == '(' || c == '[') {
      v.kind = c == '(' ? Value::Kind::Tuple : Value::Kind::Array;
      const char close = c == '(' ? ')' : ']';
      ++p_;
      if (!peek(close)) {
        for (;;) {
          v.items.push_back(value());
          if (peek(',')) {
            ++p_;
            continue;
          }
          break;
        }
      }
      expect(close);
    } else if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.') {
      v = number();
    } else {
      v.kind = Value::Kind::Token;
      v.text = word();
    }
    return v;
  }
  std::map<std::string, Value> metadata() {
    expect('(');
    std::map<std::string, Value> m;
    while (!peek(')')) {
      const std::string k = word();
      expect('=');
      if (!m.emplace(k, value()).second) fail("metadata '" + k + "' given twice");
    }
    expect(')');
    return m;
  }
  static bool knownType(const std::string& t) {
    static const char* kinds[] = {"int[]",        "int64[]",   "float[]",  "point3f[]", "normal3f[]",
                                  "texCoord2f[]", "color3f[]", "float3[]", "quath[]",   "string[]",
                                  "token",        "bool",      "string"};
    for (const char* k : kinds)
      if (t == k) return true;
    return false;
  }
  // Element shape of a declared type: tuple arity (0 = scalar), integer-only.
  static void shape(const std::string& t, size_t& arity, bool& integer, bool& text) {
    arity = 0;
    integer = t == "int[]" || t == "int64[]" || t == "bool";
    text = t == "string[]" || t == "string" || t == "token";
    if (t == "point3f[]" || t == "normal3f[]" || t == "color3f[]" || t == "float3[]") arity = 3;
    if (t == "texCoord2f[]") arity = 2;
    if (t == "quath[]") arity = 4;
  }
  void checkValue(const std::string& type, const Value& v) {
    size_t arity;
    bool integer, text;
    shape(type, arity, integer, text);
    const bool isArray = type.size() > 2 && type.compare(type.size() - 2, 2, "[]") == 0;
    auto scalar = [&](const Value& e) {
      if (text) {
        if (e.kind != Value::Kind::String) fail(type + ": expected a string");
        return;
      }
      if (arity) {
        if (e.kind != Value::Kind::Tuple || e.items.size() != arity)
          fail(type + ": expected " + std::to_string(arity) + "-tuples");
        for (const Value& x : e.items)
          if (x.kind != Value::Kind::Number) fail(type + ": tuple of non-numbers");
        return;
      }
      if (e.kind != Value::Kind::Number) fail(type + ": expected a number");
      if (integer && e.text.find_first_of(".eE") != std::string::npos)
        fail(type + ": expected an integer, got " + e.text);
    };
    if (type == "token") {
      if (v.kind != Value::Kind::String) fail("token: expected a quoted token");
      return;
    }
    if (isArray) {
      if (v.kind != Value::Kind::Array) fail(type + ": expected an array");
      for (const Value& e : v.items) scalar(e);
    } else {
      scalar(v);
    }
  }
  Prim prim() {
    if (word() != "def") fail("expected 'def'");
    Prim p;
    p.type = word();
    p.name = quoted();
    if (peek('(')) p.meta = metadata();
    expect('{');
    while (!peek('}')) {
      const size_t save = p_;
      std::string w = word();
      if (w == "def") {
        p_ = save;
        p.children.push_back(prim());
        continue;
      }
      if (w == "rel") {
        const std::string name = word();
        expect('=');
        const Value v = value();
        if (v.kind != Value::Kind::Array) fail("rel: expected an array of paths");
        std::vector<std::string> targets;
        for (const Value& e : v.items) {
          if (e.kind != Value::Kind::Path) fail("rel: expected paths");
          targets.push_back(e.text);
        }
        p.rels[name] = targets;
        continue;
      }
      bool custom = false, uniform = false;
      if (w == "custom") {
        custom = true;
        w = word();
      }
      if (w == "uniform") {
        uniform = true;
        w = word();
      }
      std::string type = w;
      if (peek('[')) {
        ++p_;
        expect(']');
        type += "[]";
      }
      if (!knownType(type)) fail("unknown attribute type '" + type + "'");
      std::string name = word();
      const bool samples = name.size() > 12 && name.compare(name.size() - 12, 12, ".timeSamples") == 0;
      if (samples) name.resize(name.size() - 12);
      Attribute& a = p.attrs[name];
      if (!a.type.empty() && a.type != type) fail("attribute '" + name + "' declared with two types");
      a.type = type;
      a.custom = a.custom || custom;
      a.uniform = a.uniform || uniform;
      if (samples) {
        expect('=');
        expect('{');
        while (!peek('}')) {
          const Value code = number();
          expect(':');
          const Value v = value();
          checkValue(type, v);
          if (!a.samples.emplace(code.number(), v).second) fail("time sample given twice");
          expect(',');
        }
        expect('}');
        continue;
      }
      if (peek('=')) {
        ++p_;
        if (a.hasDefault) fail("attribute '" + name + "' has two defaults");
        a.value = value();
        checkValue(type, a.value);
        a.hasDefault = true;
      }
      if (peek('(')) {
        for (auto& kv : metadata()) a.meta[kv.first] = kv.second;
      }
    }
    expect('}');
    return p;
  }
};

inline Layer read(const std::string& text) { return Reader(text).read(); }

}  // namespace usda

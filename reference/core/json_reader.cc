#include "reference/core/json_reader.h"

#include <cmath>
#include <set>
#include <sstream>
#include <vector>

#include "reference/core/io.h"

namespace dentsim {

namespace {

std::string shown_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// The streaming check of parse(): depth, duplicate keys, number range and syntax, with the path
// of the value being read. Returning false stops the parser; `error` then says why.
class Checker : public nlohmann::json_sax<nlohmann::json> {
 public:
  std::string error;  // "<field>: <problem>" or "<problem>"

  bool null() override { return value(); }
  bool boolean(bool) override { return value(); }
  bool number_integer(number_integer_t) override { return value(); }
  bool number_unsigned(number_unsigned_t) override { return value(); }
  bool number_float(number_float_t, const string_t&) override { return value(); }
  bool string(string_t&) override { return value(); }
  bool binary(binary_t&) override { return value(); }
  bool start_object(std::size_t) override { return open(true); }
  bool start_array(std::size_t) override { return open(false); }
  bool end_object() override { return close(); }
  bool end_array() override { return close(); }
  bool key(string_t& k) override {
    Frame& f = stack_.back();
    if (!f.keys.insert(k).second) {
      return stop(path() + (path().empty() ? "" : ".") + printable(k),
                  "key given twice in one object (JSON would silently keep the last)");
    }
    f.key = k;
    return true;
  }
  bool parse_error(std::size_t, const std::string&,
                   const nlohmann::detail::exception& ex) override {
    if (ex.id == 406) {  // out_of_range.406: number overflow
      std::string what = ex.what();
      const auto q = what.find('\'');
      const std::string token = q == std::string::npos ? "" : what.substr(q);
      return stop(value_path(), "number " + printable(token) +
                                    " is outside the range of a double (|x| < 1.8e308)");
    }
    std::string what = ex.what();
    const auto b = what.find("] ");  // drop "[json.exception.parse_error.101] "
    if (b != std::string::npos) what = what.substr(b + 2);
    return stop("", "not valid JSON (" + printable(what, 200) + ")");
  }

 private:
  struct Frame {
    bool object = false;
    std::set<std::string> keys;
    std::string key;
    std::size_t count = 0;  // arrays: values seen so far
  };

  std::string segment(const Frame& f, bool current) const {
    std::string s(f.object ? "." : "[");
    s += f.object ? printable(f.key) : std::to_string(current ? f.count : f.count - 1);
    if (!f.object) s += ']';
    return s;
  }
  // Path of the innermost container's current member (frames are pushed after counting).
  std::string path() const {
    std::string p;
    for (std::size_t i = 0; i < stack_.size(); ++i) {
      if (i + 1 < stack_.size()) p += segment(stack_[i], false);
    }
    if (!p.empty() && p[0] == '.') p.erase(0, 1);
    return p;
  }
  // Path of the value about to be read (for errors raised by the lexer on a value).
  std::string value_path() const {
    std::string p;
    for (std::size_t i = 0; i < stack_.size(); ++i) {
      const bool last = i + 1 == stack_.size();
      if (stack_[i].object && last && stack_[i].key.empty()) break;
      p += segment(stack_[i], last);
    }
    if (!p.empty() && p[0] == '.') p.erase(0, 1);
    return p;
  }
  bool value() {
    if (!stack_.empty() && !stack_.back().object) ++stack_.back().count;
    return true;
  }
  bool open(bool object) {
    if (static_cast<int>(stack_.size()) >= kMaxJsonDepth) {
      return stop(value_path(), "nested deeper than " + std::to_string(kMaxJsonDepth) +
                                    " levels of objects and arrays");
    }
    value();
    stack_.push_back(Frame{object, {}, {}, 0});
    return true;
  }
  bool close() {
    stack_.pop_back();
    return true;
  }
  bool stop(const std::string& field, const std::string& what) {
    error = field.empty() ? what : field + ": " + what;
    return false;
  }

  std::vector<Frame> stack_;
};

}  // namespace

JsonReader::Json JsonReader::parse(const std::string& text) const {
  Checker check;
  if (!Json::sax_parse(text, &check)) throw InputError(origin_ + ": " + check.error);
  try {
    return Json::parse(text);
  } catch (const Json::exception& e) {  // not expected after the check; named all the same
    throw InputError(origin_ + ": not valid JSON (" + printable(e.what(), 200) + ")");
  }
}

void JsonReader::fail(const std::string& field, const std::string& what) const {
  // `what` may quote the file's text (an unknown method name, ...): control bytes never reach the
  // terminal (written \xNN; found by the scene fuzz target, tests/sim/scene_test.cc).
  std::string safe;
  safe.reserve(what.size());
  for (const char c : what) {
    const auto u = static_cast<unsigned char>(c);
    if (u < 0x20 || u == 0x7f) {
      static const char kHex[] = "0123456789abcdef";
      safe += "\\x";
      safe += kHex[u >> 4];
      safe += kHex[u & 15];
    } else {
      safe += c;
    }
  }
  throw InputError(origin_ + ": " + (field.empty() ? "" : field + ": ") + safe);
}

std::string JsonReader::join(const std::string& path, const std::string& key) {
  return path.empty() ? printable(key) : path + "." + printable(key);
}

std::string JsonReader::shown(const Json& j) {
  return printable(j.dump(-1, ' ', false, Json::error_handler_t::replace), 80);
}

void JsonReader::fail_element(const std::string& field, int i, const Json& j, int n) const {
  fail(field + "[" + std::to_string(i) + "]",
       "expected a finite number (an array of " + std::to_string(n) + " numbers), got " + shown(j));
}

void JsonReader::only_keys(const Json& obj, const std::string& path,
                           std::initializer_list<const char*> allowed) const {
  if (!obj.is_object()) fail(path, std::string("expected an object, got ") + obj.type_name());
  for (auto it = obj.begin(); it != obj.end(); ++it) {
    bool ok = false;
    for (const char* a : allowed) ok = ok || it.key() == a;
    if (!ok) {
      std::string list;
      for (const char* a : allowed) list += std::string(list.empty() ? "" : ", ") + a;
      fail(join(path, it.key()), "unknown field (expected one of: " + list + ")");
    }
  }
}

const JsonReader::Json& JsonReader::member(const Json& obj, const std::string& path,
                                           const std::string& key) const {
  if (!obj.is_object()) fail(path, std::string("expected an object, got ") + obj.type_name());
  if (!obj.contains(key)) fail(join(path, key), "missing (required)");
  return obj.at(key);
}

const JsonReader::Json& JsonReader::object(const Json& obj, const std::string& path,
                                           const std::string& key) const {
  const Json& j = member(obj, path, key);
  if (!j.is_object())
    fail(join(path, key), std::string("expected an object, got ") + j.type_name());
  return j;
}

double JsonReader::number(const Json& obj, const std::string& path, const std::string& key) const {
  const Json& j = member(obj, path, key);
  if (!j.is_number()) {
    fail(join(path, key), std::string("expected a number, got ") + j.type_name() + " " + shown(j));
  }
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(join(path, key), "must be finite");
  return v;
}

double JsonReader::number(const Json& obj, const std::string& path, const std::string& key,
                          double fallback) const {
  return obj.contains(key) ? number(obj, path, key) : fallback;
}

long JsonReader::integer(const Json& obj, const std::string& path, const std::string& key, long lo,
                         long hi) const {
  const Json& j = member(obj, path, key);
  std::string range("[");
  range += std::to_string(lo);
  range += ", ";
  range += std::to_string(hi);
  range += ']';
  if (!j.is_number_integer()) {
    fail(join(path, key), "expected an integer in " + range + ", got " + shown(j));
  }
  // Compare in the type the document holds: no wrap-around (4294967424 must not become 128).
  bool in_range = false;
  if (j.is_number_unsigned()) {
    const unsigned long u = j.get<unsigned long>();
    in_range = hi >= 0 && u <= static_cast<unsigned long>(hi) &&
               (lo <= 0 || u >= static_cast<unsigned long>(lo));
  } else {
    in_range = j.get<long>() >= lo && j.get<long>() <= hi;
  }
  if (!in_range) fail(join(path, key), "expected an integer in " + range + ", got " + shown(j));
  return j.is_number_unsigned() ? static_cast<long>(j.get<unsigned long>()) : j.get<long>();
}

long JsonReader::integer(const Json& obj, const std::string& path, const std::string& key,
                         long fallback, long lo, long hi) const {
  return obj.contains(key) ? integer(obj, path, key, lo, hi) : fallback;
}

bool JsonReader::boolean(const Json& obj, const std::string& path, const std::string& key) const {
  const Json& j = member(obj, path, key);
  if (!j.is_boolean()) fail(join(path, key), "expected true or false, got " + shown(j));
  return j.get<bool>();
}

bool JsonReader::boolean(const Json& obj, const std::string& path, const std::string& key,
                         bool fallback) const {
  return obj.contains(key) ? boolean(obj, path, key) : fallback;
}

std::string JsonReader::string(const Json& obj, const std::string& path,
                               const std::string& key) const {
  const Json& j = member(obj, path, key);
  if (!j.is_string()) fail(join(path, key), std::string("expected a string, got ") + j.type_name());
  return j.get<std::string>();
}

std::string JsonReader::string(const Json& obj, const std::string& path, const std::string& key,
                               const std::string& fallback) const {
  return obj.contains(key) ? string(obj, path, key) : fallback;
}

void JsonReader::positive(const std::string& field, double v) const {
  if (!(v > 0.0)) fail(field, "must be > 0 (got " + shown_number(v) + ")");
}

void JsonReader::non_negative(const std::string& field, double v) const {
  if (!(v >= 0.0)) fail(field, "must be >= 0 (got " + shown_number(v) + ")");
}

void JsonReader::at_most(const std::string& field, double v, double hi,
                         const std::string& why) const {
  if (!(v <= hi)) {
    fail(field,
         "must be at most " + shown_number(hi) + " (" + why + "; got " + shown_number(v) + ")");
  }
}

}  // namespace dentsim

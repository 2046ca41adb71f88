// Reading validated values out of a JSON document (scene files, device model files, ...), with
// errors that name the file, the field path and what was expected:
//   "scenes/x.json: tool.bur_radius_mm: must be > 0 (got -1)".
// Unknown keys are errors too (a typo must not silently fall back to a default).
//
// Before a document is built, parse() checks the text in one streaming (SAX) pass, so that these
// are errors naming the field path instead of crashes or silent surprises:
// - nesting deeper than kMaxJsonDepth levels (a deeply nested document would otherwise recurse
//   through every consumer of the tree);
// - a key given twice in one object (JSON would silently keep the last);
// - a number outside the range of a double (1e400);
// - invalid JSON (the message carries line, column and the escaped last token).
// Integers are range-checked (no silent wrap: 4294967424 is not 128), numbers must be finite,
// and text quoted from the document in a message is escaped (io.h printable()).
#pragma once

#include <Eigen/Core>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>

#include "reference/core/types.h"

namespace dentsim {

// Deepest nesting of objects and arrays accepted in a document (our formats need 4).
inline constexpr int kMaxJsonDepth = 64;

class JsonReader {
 public:
  using Json = nlohmann::json;

  // `origin` names the document in messages (a file path or "built-in scene 'drill'").
  explicit JsonReader(std::string origin) : origin_(std::move(origin)) {}
  const std::string& origin() const { return origin_; }

  // Checks (see above) and parses text; throws InputError "<origin>: [<field>: ]<problem>".
  Json parse(const std::string& text) const;

  [[noreturn]] void fail(const std::string& field, const std::string& what) const;

  // Throws if `obj` (at `path`) is not an object or has a key not in `allowed`.
  void only_keys(const Json& obj, const std::string& path,
                 std::initializer_list<const char*> allowed) const;

  // Required members (throw "missing (required)") and optional ones (return the default when
  // absent). Numbers must be finite.
  const Json& member(const Json& obj, const std::string& path, const std::string& key) const;
  const Json& object(const Json& obj, const std::string& path, const std::string& key) const;
  bool has(const Json& obj, const std::string& key) const { return obj.contains(key); }
  double number(const Json& obj, const std::string& path, const std::string& key) const;
  double number(const Json& obj, const std::string& path, const std::string& key,
                double fallback) const;
  // An integer in [lo, hi] (a JSON number without fraction or exponent).
  long integer(const Json& obj, const std::string& path, const std::string& key, long lo,
               long hi) const;
  long integer(const Json& obj, const std::string& path, const std::string& key, long fallback,
               long lo, long hi) const;
  bool boolean(const Json& obj, const std::string& path, const std::string& key) const;
  bool boolean(const Json& obj, const std::string& path, const std::string& key,
               bool fallback) const;
  std::string string(const Json& obj, const std::string& path, const std::string& key) const;
  std::string string(const Json& obj, const std::string& path, const std::string& key,
                     const std::string& fallback) const;
  // An array of N finite numbers; an element that is wrong is named "<field>[i]".
  template <int N>
  Eigen::Matrix<double, N, 1> vector(const Json& obj, const std::string& path,
                                     const std::string& key) const;
  Vec3 vec3(const Json& obj, const std::string& path, const std::string& key) const {
    return vector<3>(obj, path, key);
  }
  Vec3 vec3(const Json& obj, const std::string& path, const std::string& key,
            const Vec3& fallback) const {
    return obj.contains(key) ? vec3(obj, path, key) : fallback;
  }

  // Range checks on an already-read value (field = full path).
  void positive(const std::string& field, double v) const;      // v > 0
  void non_negative(const std::string& field, double v) const;  // v >= 0
  void at_most(const std::string& field, double v, double hi, const std::string& why) const;

  static std::string join(const std::string& path, const std::string& key);
  // A JSON value as it would appear in the file, escaped and cut for a message.
  static std::string shown(const Json& j);

 private:
  [[noreturn]] void fail_element(const std::string& field, int i, const Json& j, int n) const;
  std::string origin_;
};

template <int N>
Eigen::Matrix<double, N, 1> JsonReader::vector(const Json& obj, const std::string& path,
                                               const std::string& key) const {
  const Json& j = member(obj, path, key);
  if (!j.is_array() || j.size() != static_cast<std::size_t>(N)) {
    fail(join(path, key),
         "expected an array of " + std::to_string(N) + " numbers, got " + shown(j));
  }
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) {
    const Json& e = j[static_cast<std::size_t>(i)];
    if (!e.is_number() || !std::isfinite(e.get<double>())) fail_element(join(path, key), i, e, N);
    v(i) = e.get<double>();
  }
  return v;
}

}  // namespace dentsim

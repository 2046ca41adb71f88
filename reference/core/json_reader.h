// Reading validated values out of a JSON document (scene files, device model files, ...), with
// errors that name the file, the field path and what was expected:
//   "scenes/x.json: tool.bur_radius_mm: must be > 0 (got -1)".
// Unknown keys are errors too (a typo must not silently fall back to a default).
#pragma once

#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>

#include "reference/core/types.h"

namespace dentsim {

class JsonReader {
 public:
  using Json = nlohmann::json;

  // `origin` names the document in messages (a file path or "built-in scene 'drill'").
  explicit JsonReader(std::string origin) : origin_(std::move(origin)) {}
  const std::string& origin() const { return origin_; }

  // Parses text; throws InputError "<origin>: not valid JSON (...)".
  Json parse(const std::string& text) const;

  [[noreturn]] void fail(const std::string& field, const std::string& what) const;

  // Throws if `obj` (at `path`) has a key not in `allowed`.
  void only_keys(const Json& obj, const std::string& path,
                 std::initializer_list<const char*> allowed) const;

  // Required members (throw "missing (required)") and optional ones (return the default when
  // absent). Numbers must be finite.
  const Json& object(const Json& obj, const std::string& path, const std::string& key) const;
  bool has(const Json& obj, const std::string& key) const { return obj.contains(key); }
  double number(const Json& obj, const std::string& path, const std::string& key) const;
  double number(const Json& obj, const std::string& path, const std::string& key,
                double fallback) const;
  long integer(const Json& obj, const std::string& path, const std::string& key,
               long fallback) const;
  bool boolean(const Json& obj, const std::string& path, const std::string& key,
               bool fallback) const;
  std::string string(const Json& obj, const std::string& path, const std::string& key) const;
  std::string string(const Json& obj, const std::string& path, const std::string& key,
                     const std::string& fallback) const;
  Vec3 vec3(const Json& obj, const std::string& path, const std::string& key) const;
  Vec3 vec3(const Json& obj, const std::string& path, const std::string& key,
            const Vec3& fallback) const;

  // Range checks on an already-read value (field = full path).
  void positive(const std::string& field, double v) const;       // v > 0
  void non_negative(const std::string& field, double v) const;   // v >= 0

  static std::string join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

 private:
  const Json& member(const Json& obj, const std::string& path, const std::string& key) const;
  std::string origin_;
};

}  // namespace dentsim

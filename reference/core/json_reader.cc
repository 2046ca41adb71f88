#include "reference/core/json_reader.h"

#include <cmath>
#include <sstream>

#include "reference/core/io.h"

namespace dentsim {

namespace {
std::string shown(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
}  // namespace

JsonReader::Json JsonReader::parse(const std::string& text) const {
  try {
    return Json::parse(text);
  } catch (const Json::parse_error& e) {
    throw InputError(origin_ + ": not valid JSON (" + e.what() + ")");
  }
}

void JsonReader::fail(const std::string& field, const std::string& what) const {
  throw InputError(origin_ + ": " + (field.empty() ? "" : field + ": ") + what);
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
  if (!j.is_object()) fail(join(path, key), std::string("expected an object, got ") + j.type_name());
  return j;
}

double JsonReader::number(const Json& obj, const std::string& path, const std::string& key) const {
  const Json& j = member(obj, path, key);
  if (!j.is_number()) fail(join(path, key), std::string("expected a number, got ") + j.type_name());
  const double v = j.get<double>();
  if (!std::isfinite(v)) fail(join(path, key), "must be finite");
  return v;
}

double JsonReader::number(const Json& obj, const std::string& path, const std::string& key,
                          double fallback) const {
  return obj.contains(key) ? number(obj, path, key) : fallback;
}

long JsonReader::integer(const Json& obj, const std::string& path, const std::string& key,
                         long fallback) const {
  if (!obj.contains(key)) return fallback;
  const Json& j = obj.at(key);
  if (!j.is_number_integer()) {
    fail(join(path, key), std::string("expected an integer, got ") + j.dump());
  }
  return j.get<long>();
}

bool JsonReader::boolean(const Json& obj, const std::string& path, const std::string& key,
                         bool fallback) const {
  if (!obj.contains(key)) return fallback;
  const Json& j = obj.at(key);
  if (!j.is_boolean()) fail(join(path, key), std::string("expected true or false, got ") + j.dump());
  return j.get<bool>();
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

Vec3 JsonReader::vec3(const Json& obj, const std::string& path, const std::string& key) const {
  const Json& j = member(obj, path, key);
  if (!j.is_array() || j.size() != 3) {
    fail(join(path, key), "expected an array of 3 numbers, got " + j.dump());
  }
  Vec3 v;
  for (int i = 0; i < 3; ++i) {
    if (!j[i].is_number() || !std::isfinite(j[i].get<double>())) {
      fail(join(path, key), "expected an array of 3 finite numbers, got " + j.dump());
    }
    v(i) = j[i].get<double>();
  }
  return v;
}

Vec3 JsonReader::vec3(const Json& obj, const std::string& path, const std::string& key,
                      const Vec3& fallback) const {
  return obj.contains(key) ? vec3(obj, path, key) : fallback;
}

void JsonReader::positive(const std::string& field, double v) const {
  if (!(v > 0.0)) fail(field, "must be > 0 (got " + shown(v) + ")");
}

void JsonReader::non_negative(const std::string& field, double v) const {
  if (!(v >= 0.0)) fail(field, "must be >= 0 (got " + shown(v) + ")");
}

}  // namespace dentsim

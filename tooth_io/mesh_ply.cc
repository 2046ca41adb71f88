#include "tooth_io/mesh_ply.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <utility>
#include <vector>

#include "reference/core/io.h"

namespace dentsim {
namespace {

enum class Type { kInt8, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };

struct Property {
  std::string name;
  Type type = Type::kFloat32;
  bool list = false;
  Type count_type = Type::kUint8;
};

struct Element {
  std::string name;
  long count = 0;
  std::vector<Property> props;
  int header_line = 0;
};

int type_size(Type t) {
  switch (t) {
    case Type::kInt8:
    case Type::kUint8: return 1;
    case Type::kInt16:
    case Type::kUint16: return 2;
    case Type::kInt32:
    case Type::kUint32:
    case Type::kFloat32: return 4;
    case Type::kFloat64: return 8;
  }
  return 0;
}

bool parse_type(const std::string& s, Type* t) {
  static const std::pair<const char*, Type> names[] = {
      {"char", Type::kInt8},     {"int8", Type::kInt8},      {"uchar", Type::kUint8},
      {"uint8", Type::kUint8},   {"short", Type::kInt16},    {"int16", Type::kInt16},
      {"ushort", Type::kUint16}, {"uint16", Type::kUint16},  {"int", Type::kInt32},
      {"int32", Type::kInt32},   {"uint", Type::kUint32},    {"uint32", Type::kUint32},
      {"float", Type::kFloat32}, {"float32", Type::kFloat32}, {"double", Type::kFloat64},
      {"float64", Type::kFloat64}};
  for (const auto& [n, ty] : names) {
    if (s == n) {
      *t = ty;
      return true;
    }
  }
  return false;
}

bool is_integer(Type t) { return t != Type::kFloat32 && t != Type::kFloat64; }

// One binary scalar at p (size type_size(t)), byte order `big`.
double read_binary(const char* p, Type t, bool big) {
  unsigned char b[8];
  const int n = type_size(t);
  std::memcpy(b, p, n);
  if (big != (std::endian::native == std::endian::big)) {
    for (int i = 0; i < n / 2; ++i) std::swap(b[i], b[n - 1 - i]);
  }
  switch (t) {
    case Type::kInt8: { std::int8_t v; std::memcpy(&v, b, 1); return v; }
    case Type::kUint8: return b[0];
    case Type::kInt16: { std::int16_t v; std::memcpy(&v, b, 2); return v; }
    case Type::kUint16: { std::uint16_t v; std::memcpy(&v, b, 2); return v; }
    case Type::kInt32: { std::int32_t v; std::memcpy(&v, b, 4); return v; }
    case Type::kUint32: { std::uint32_t v; std::memcpy(&v, b, 4); return v; }
    case Type::kFloat32: { float v; std::memcpy(&v, b, 4); return v; }
    case Type::kFloat64: { double v; std::memcpy(&v, b, 8); return v; }
  }
  return 0;
}

// Reads the body value by value: ASCII (one element instance per line) or binary.
class Body {
 public:
  Body(const std::string& bytes, std::size_t pos, int line, bool ascii, bool big,
       const std::string& file)
      : bytes_(bytes), pos_(pos), line_(line), ascii_(ascii), big_(big), file_(file) {}

  // Starts instance `index` of element `e` (ASCII: reads its line).
  void begin(const Element& e, long index) {
    where_ = "PLY '" + file_ + "' " + e.name + " " + std::to_string(index);
    count_ = e.count;
    if (!ascii_) return;
    // Skip blank lines between instances.
    std::string text;
    do {
      if (pos_ >= bytes_.size()) {
        throw InputError(where_ + " of " + std::to_string(count_) +
                         ": the file ends; expected one line per " + e.name);
      }
      const std::size_t end = bytes_.find('\n', pos_);
      text = bytes_.substr(pos_, end == std::string::npos ? std::string::npos : end - pos_);
      pos_ = end == std::string::npos ? bytes_.size() : end + 1;
      ++line_;
    } while (text.find_first_not_of(" \t\r") == std::string::npos);
    where_ += " (line " + std::to_string(line_) + ")";
    in_.clear();
    in_.str(text);
  }

  double value(Type t, const std::string& prop) {
    if (ascii_) {
      std::string tok;
      if (!(in_ >> tok)) {
        throw InputError(where_ + ": the line ends before property '" + prop + "'");
      }
      char* end = nullptr;
      const double v = std::strtod(tok.c_str(), &end);
      if (end == tok.c_str() || *end != '\0') {
        throw InputError(where_ + ": property '" + prop + "': expected a number, found '" + tok +
                         "'");
      }
      if (is_integer(t) && v != std::floor(v)) {
        throw InputError(where_ + ": property '" + prop + "': expected an integer, found '" + tok +
                         "'");
      }
      return v;
    }
    const int n = type_size(t);
    if (pos_ + n > bytes_.size()) {
      throw InputError(where_ + " of " + std::to_string(count_) + ": the file ends in property '" +
                       prop + "'; expected " + std::to_string(n) + " more bytes");
    }
    const double v = read_binary(bytes_.data() + pos_, t, big_);
    pos_ += n;
    return v;
  }

  void end() {
    if (!ascii_) return;
    std::string extra;
    if (in_ >> extra) {
      throw InputError(where_ + ": unexpected '" + extra + "' after the last property");
    }
  }
  const std::string& where() const { return where_; }

 private:
  const std::string& bytes_;
  std::size_t pos_;
  int line_;
  bool ascii_, big_;
  std::string file_;
  std::string where_;
  long count_ = 0;
  std::istringstream in_;
};

}  // namespace

LoadedMesh parse_ply(const std::string& bytes, const std::string& name) {
  // ---- header ----
  std::size_t pos = 0;
  int line_no = 0;
  auto next_line = [&](std::string* line) {
    if (pos >= bytes.size()) return false;
    const std::size_t end = bytes.find('\n', pos);
    *line = bytes.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
    if (!line->empty() && line->back() == '\r') line->pop_back();
    pos = end == std::string::npos ? bytes.size() : end + 1;
    ++line_no;
    return true;
  };
  auto fail = [&](const std::string& msg) -> InputError {
    return InputError("PLY '" + name + "' line " + std::to_string(line_no) + ": " + msg);
  };
  std::string line;
  if (!next_line(&line) || line != "ply") throw fail("expected 'ply' as the first line");
  bool ascii = false, big = false, have_format = false;
  std::vector<Element> elements;
  bool ended = false;
  while (next_line(&line)) {
    std::istringstream in(line);
    std::string key;
    if (!(in >> key)) continue;
    if (key == "comment" || key == "obj_info") continue;
    if (key == "format") {
      std::string f, version;
      in >> f >> version;
      if (f == "ascii") {
        ascii = true;
      } else if (f == "binary_little_endian") {
        big = false;
      } else if (f == "binary_big_endian") {
        big = true;
      } else {
        throw fail("format '" + f + "'; expected ascii, binary_little_endian or binary_big_endian");
      }
      if (version != "1.0") throw fail("format version '" + version + "'; expected 1.0");
      have_format = true;
    } else if (key == "element") {
      Element e;
      std::string count;
      if (!(in >> e.name >> count)) throw fail("expected 'element NAME COUNT'");
      char* end = nullptr;
      e.count = std::strtol(count.c_str(), &end, 10);
      if (*end != '\0' || e.count < 0 || e.count > (1L << 31)) {
        throw fail("element '" + e.name + "' count '" + count + "'; expected 0..2^31");
      }
      e.header_line = line_no;
      elements.push_back(e);
    } else if (key == "property") {
      if (elements.empty()) throw fail("'property' before any 'element'");
      Property p;
      std::string t;
      in >> t;
      if (t == "list") {
        p.list = true;
        std::string ct, it;
        in >> ct >> it;
        if (!parse_type(ct, &p.count_type) || !is_integer(p.count_type)) {
          throw fail("list count type '" + ct + "'; expected an integer type");
        }
        if (!parse_type(it, &p.type)) throw fail("list item type '" + it + "' is not a PLY type");
      } else if (!parse_type(t, &p.type)) {
        throw fail("property type '" + t + "' is not a PLY type (char, uchar, short, ushort, "
                   "int, uint, float, double or their sized names)");
      }
      if (!(in >> p.name)) throw fail("property without a name");
      elements.back().props.push_back(p);
    } else if (key == "end_header") {
      ended = true;
      break;
    } else {
      throw fail("unknown header keyword '" + key + "'");
    }
  }
  if (!ended) throw fail("the file ends in the header; expected 'end_header'");
  if (!have_format) throw fail("no 'format' line in the header");

  // Which properties we use.
  const Element* vertex_el = nullptr;
  const Element* face_el = nullptr;
  int xi = -1, yi = -1, zi = -1, fi = -1;
  for (const Element& e : elements) {
    if (e.name == "vertex") {
      vertex_el = &e;
      for (std::size_t p = 0; p < e.props.size(); ++p) {
        if (e.props[p].list) continue;
        if (e.props[p].name == "x") xi = static_cast<int>(p);
        if (e.props[p].name == "y") yi = static_cast<int>(p);
        if (e.props[p].name == "z") zi = static_cast<int>(p);
      }
      if (xi < 0 || yi < 0 || zi < 0) {
        throw InputError("PLY '" + name + "' line " + std::to_string(e.header_line) +
                         ": element vertex lacks a scalar x, y or z property");
      }
    } else if (e.name == "face") {
      face_el = &e;
      for (std::size_t p = 0; p < e.props.size(); ++p) {
        if (e.props[p].list && (e.props[p].name == "vertex_indices" ||
                                e.props[p].name == "vertex_index")) {
          fi = static_cast<int>(p);
        }
      }
      if (fi < 0 || !is_integer(e.props[fi].type)) {
        throw InputError("PLY '" + name + "' line " + std::to_string(e.header_line) +
                         ": element face lacks an integer list property vertex_indices");
      }
    }
  }
  if (vertex_el == nullptr || face_el == nullptr) {
    throw InputError("PLY '" + name + "': the header declares no " +
                     std::string(vertex_el == nullptr ? "vertex" : "face") +
                     " element; expected a triangle mesh (element vertex, element face)");
  }

  // ---- body ----
  TriangleMesh mesh;
  mesh.groups.push_back("");
  Body body(bytes, pos, line_no, ascii, big, name);
  std::vector<int> poly;
  for (const Element& e : elements) {
    const bool is_vertex = &e == vertex_el, is_face = &e == face_el;
    for (long n = 0; n < e.count; ++n) {
      body.begin(e, n);
      Vec3 v = Vec3::Zero();
      for (std::size_t p = 0; p < e.props.size(); ++p) {
        const Property& pr = e.props[p];
        if (!pr.list) {
          const double x = body.value(pr.type, pr.name);
          if (is_vertex) {
            if (static_cast<int>(p) == xi) v.x() = x;
            if (static_cast<int>(p) == yi) v.y() = x;
            if (static_cast<int>(p) == zi) v.z() = x;
          }
          continue;
        }
        const double len = body.value(pr.count_type, pr.name + " count");
        if (len < 0 || len > 1e6) {
          throw InputError(body.where() + ": list '" + pr.name + "' has " + std::to_string(len) +
                           " items; expected 0..1000000");
        }
        poly.clear();
        for (int i = 0; i < static_cast<int>(len); ++i) {
          const double idx = body.value(pr.type, pr.name);
          if (!(is_face && static_cast<int>(p) == fi)) continue;
          if (idx < 0 || idx >= static_cast<double>(vertex_el->count)) {
            throw InputError(body.where() + ": vertex index " + std::to_string(long(idx)) +
                             " out of range 0.." + std::to_string(vertex_el->count - 1));
          }
          poly.push_back(static_cast<int>(idx));
        }
        if (is_face && static_cast<int>(p) == fi) {
          if (poly.size() < 3) {
            throw InputError(body.where() + ": a face with " + std::to_string(poly.size()) +
                             " vertices; expected at least 3");
          }
          for (std::size_t i = 1; i + 1 < poly.size(); ++i) {
            mesh.triangles.push_back({poly[0], poly[i], poly[i + 1]});
            mesh.triangle_group.push_back(0);
          }
        }
      }
      body.end();
      if (is_vertex) {
        if (!v.allFinite()) throw InputError(body.where() + ": a coordinate is not finite");
        mesh.vertices.push_back(v);
      }
    }
  }
  // Faces may come before vertices in the file; indices were checked against the declared count.
  LoadedMesh out;
  out.report = validate_and_repair(mesh, name);
  out.mesh = std::move(mesh);
  return out;
}

}  // namespace dentsim

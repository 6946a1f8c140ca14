// PLY import (Turk's polygon file format: ASCII, binary little and big
// endian): the vertex element's x, y, z and the faces' index lists; every
// other element and property is read past. Strict about structure, as the
// other readers (read_mesh.cc).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>

#include "mesh_formats.h"
#include "mesh_text.h"

namespace fabatlas::mesh::internal {
namespace {

// ---------------------------------------------------------------- PLY
enum class PlyType { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

bool ParsePlyType(const std::string& s, PlyType* t) {
  static const std::map<std::string, PlyType> kTypes = {
      {"char", PlyType::kInt8},      {"int8", PlyType::kInt8},       {"uchar", PlyType::kUInt8},
      {"uint8", PlyType::kUInt8},    {"short", PlyType::kInt16},     {"int16", PlyType::kInt16},
      {"ushort", PlyType::kUInt16},  {"uint16", PlyType::kUInt16},   {"int", PlyType::kInt32},
      {"int32", PlyType::kInt32},    {"uint", PlyType::kUInt32},     {"uint32", PlyType::kUInt32},
      {"float", PlyType::kFloat32},  {"float32", PlyType::kFloat32}, {"double", PlyType::kFloat64},
      {"float64", PlyType::kFloat64}};
  auto it = kTypes.find(s);
  if (it == kTypes.end()) return false;
  *t = it->second;
  return true;
}

int PlySize(PlyType t) {
  switch (t) {
    case PlyType::kInt8:
    case PlyType::kUInt8:
      return 1;
    case PlyType::kInt16:
    case PlyType::kUInt16:
      return 2;
    case PlyType::kInt32:
    case PlyType::kUInt32:
    case PlyType::kFloat32:
      return 4;
    case PlyType::kFloat64:
      return 8;
  }
  return 1;
}

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyType count_type = PlyType::kUInt8;
  PlyType type = PlyType::kFloat32;
};

struct PlyElement {
  std::string name;
  long long count = 0;
  std::vector<PlyProperty> properties;
};

// Reads scalars from the body of a PLY file, ASCII or binary.
class PlyBody {
 public:
  PlyBody(const std::filesystem::path& path, std::string_view body, int format)
      : path_(path), body_(body), format_(format) {}

  double Read(PlyType t) {
    if (format_ == 0) {
      while (pos_ < body_.size() && IsSpace(body_[pos_])) ++pos_;
      std::size_t end = pos_;
      while (end < body_.size() && !IsSpace(body_[end])) ++end;
      if (end == pos_) Fail(path_, "truncated PLY body");
      double v = 0;
      if (!ParseDouble(body_.substr(pos_, end - pos_), &v)) {
        Fail(path_,
             "unparsable PLY value '" + std::string(body_.substr(pos_, std::min<std::size_t>(end - pos_, 40))) + "'");
      }
      pos_ = end;
      return v;
    }
    const int n = PlySize(t);
    if (body_.size() - pos_ < static_cast<std::size_t>(n)) Fail(path_, "truncated PLY body");
    unsigned char b[8];
    std::memcpy(b, body_.data() + pos_, n);
    pos_ += n;
    const bool big = format_ == 2;
    if (big != (std::endian::native == std::endian::big)) std::reverse(b, b + n);
    switch (t) {
      case PlyType::kInt8: {
        std::int8_t v;
        std::memcpy(&v, b, 1);
        return v;
      }
      case PlyType::kUInt8: {
        std::uint8_t v;
        std::memcpy(&v, b, 1);
        return v;
      }
      case PlyType::kInt16: {
        std::int16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case PlyType::kUInt16: {
        std::uint16_t v;
        std::memcpy(&v, b, 2);
        return v;
      }
      case PlyType::kInt32: {
        std::int32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PlyType::kUInt32: {
        std::uint32_t v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PlyType::kFloat32: {
        float v;
        std::memcpy(&v, b, 4);
        return v;
      }
      case PlyType::kFloat64: {
        double v;
        std::memcpy(&v, b, 8);
        return v;
      }
    }
    return 0;
  }
  std::size_t remaining() const { return body_.size() - pos_; }

 private:
  const std::filesystem::path& path_;
  std::string_view body_;
  int format_;  // 0 ascii, 1 little endian, 2 big endian
  std::size_t pos_ = 0;
};

// A PLY header's format (0 ascii, 1 little endian, 2 big endian), its
// elements and where the body starts in the file's bytes.
struct PlyHeader {
  int format = -1;
  std::vector<PlyElement> elements;
  std::size_t body_start = 0;
};

// A 'property' header line's tokens (`where`: "line N: ").
PlyProperty ReadPlyProperty(const std::filesystem::path& path, const std::string& where,
                            const std::vector<std::string_view>& tok) {
  PlyProperty p;
  if (tok.size() == 5 && tok[1] == "list") {
    p.is_list = true;
    if (!ParsePlyType(std::string(tok[2]), &p.count_type) || !ParsePlyType(std::string(tok[3]), &p.type)) {
      Fail(path, where + "unknown PLY type");
    }
    p.name = std::string(tok[4]);
  } else if (tok.size() == 3) {
    if (!ParsePlyType(std::string(tok[1]), &p.type))
      Fail(path, where + "unknown PLY type '" + std::string(tok[1].substr(0, 40)) + "'");
    p.name = std::string(tok[2]);
  } else {
    Fail(path, where + "bad property line");
  }
  return p;
}

PlyHeader ReadPlyHeader(const std::filesystem::path& path, std::string_view data) {
  Lines lines(data);
  std::string_view line;
  if (!lines.Next(&line) || Tokens(line).empty() || Tokens(line)[0] != "ply") Fail(path, "missing 'ply' magic line");
  PlyHeader header;
  bool header_done = false;
  std::size_t consumed = line.size() + 1;
  while (lines.Next(&line)) {
    consumed += line.size() + 1;
    auto tok = Tokens(line);
    const std::string where = "line " + std::to_string(lines.number()) + ": ";
    if (tok.empty()) continue;
    if (tok[0] == "end_header") {
      header_done = true;
      header.body_start = std::min(consumed, data.size());
      break;
    } else if (tok[0] == "format") {
      if (tok.size() < 2) Fail(path, where + "bad format line");
      if (tok[1] == "ascii")
        header.format = 0;
      else if (tok[1] == "binary_little_endian")
        header.format = 1;
      else if (tok[1] == "binary_big_endian")
        header.format = 2;
      else
        Fail(path, where + "unknown PLY format '" + std::string(tok[1].substr(0, 40)) + "'");
    } else if (tok[0] == "element") {
      long long n = 0;
      if (tok.size() != 3 || !ParseInt(tok[2], &n) || n < 0) Fail(path, where + "expected 'element name count'");
      header.elements.push_back({std::string(tok[1]), n, {}});
    } else if (tok[0] == "property") {
      if (header.elements.empty()) Fail(path, where + "property before any element");
      header.elements.back().properties.push_back(ReadPlyProperty(path, where, tok));
    } else if (tok[0] == "comment" || tok[0] == "obj_info") {
    } else {
      Fail(path, where + "unexpected PLY header line");
    }
  }
  if (!header_done) Fail(path, "truncated PLY header (no end_header)");
  if (header.format < 0) Fail(path, "PLY header has no format line");
  return header;
}

// Face i's vertex index list (n >= 3 entries of type prop.type) from body,
// added to mesh as a polygon; `corners` is scratch.
void ReadPlyFace(const std::filesystem::path& path, const PlyProperty& prop, long long i, long long n,
                 long long vertex_count, PlyBody& body, std::vector<long long>& corners, TriangleMesh* mesh) {
  if (n < 3) Fail(path, "PLY face " + std::to_string(i) + " has fewer than 3 vertices");
  corners.clear();
  for (long long j = 0; j < n; ++j) {
    const double v = body.Read(prop.type);
    if (!(v >= 0 && v < static_cast<double>(vertex_count)) || v != std::floor(v)) {
      Fail(path, "PLY face " + std::to_string(i) + ": index " + std::to_string(v) + " out of range (" +
                     std::to_string(vertex_count) + " vertices)");
    }
    corners.push_back(static_cast<long long>(v));
  }
  AddPolygon(corners, mesh);
}

// Element e's items from body: a vertex element's x, y, z into
// mesh->vertices (setting *vertex_count), a face element's polygons into
// mesh->triangles; other elements and properties skipped.
void ReadPlyElement(const std::filesystem::path& path, const PlyElement& e, PlyBody& body, long long* vertex_count,
                    std::vector<long long>& corners, TriangleMesh* mesh) {
  const bool is_vertex = e.name == "vertex";
  const bool is_face = e.name == "face";
  // Each element needs at least one byte (binary) or character (ascii) per property.
  if (!e.properties.empty() && static_cast<unsigned long long>(e.count) > body.remaining()) {
    Fail(path, "truncated PLY: element '" + e.name + "' announces " + std::to_string(e.count) + " items");
  }
  int ix = -1, iy = -1, iz = -1, ilist = -1;
  for (std::size_t k = 0; k < e.properties.size(); ++k) {
    const auto& n = e.properties[k].name;
    if (n == "x") ix = static_cast<int>(k);
    if (n == "y") iy = static_cast<int>(k);
    if (n == "z") iz = static_cast<int>(k);
    if (e.properties[k].is_list && (n == "vertex_indices" || n == "vertex_index")) ilist = static_cast<int>(k);
  }
  if (is_vertex) {
    if (ix < 0 || iy < 0 || iz < 0) Fail(path, "PLY vertex element lacks x, y or z");
    *vertex_count = e.count;
    mesh->vertices.reserve(e.count);
  }
  if (is_face) {
    if (ilist < 0) Fail(path, "PLY face element lacks a vertex_indices list");
    if (*vertex_count < 0) Fail(path, "PLY face element before vertex element");
  }
  for (long long i = 0; i < e.count; ++i) {
    std::array<double, 3> p{};
    for (std::size_t k = 0; k < e.properties.size(); ++k) {
      const PlyProperty& prop = e.properties[k];
      if (prop.is_list) {
        const double cnt = body.Read(prop.count_type);
        if (!(cnt >= 0) || cnt > 1e6 || cnt != std::floor(cnt))
          Fail(path, "bad PLY list length in element '" + e.name + "'");
        const long long n = static_cast<long long>(cnt);
        if (is_face && static_cast<int>(k) == ilist) {
          ReadPlyFace(path, prop, i, n, *vertex_count, body, corners, mesh);
        } else {
          for (long long j = 0; j < n; ++j) body.Read(prop.type);
        }
      } else {
        const double v = body.Read(prop.type);
        if (is_vertex) {
          if (static_cast<int>(k) == ix) p[0] = v;
          if (static_cast<int>(k) == iy) p[1] = v;
          if (static_cast<int>(k) == iz) p[2] = v;
        }
      }
    }
    if (is_vertex) mesh->vertices.push_back(p);
  }
}

}  // namespace

TriangleMesh ReadPly(const std::filesystem::path& path, std::string_view data) {
  const PlyHeader header = ReadPlyHeader(path, data);
  TriangleMesh mesh;
  PlyBody body(path, data.substr(header.body_start), header.format);
  std::vector<long long> corners;
  long long vertex_count = -1;
  for (const PlyElement& e : header.elements) ReadPlyElement(path, e, body, &vertex_count, corners, &mesh);
  if (vertex_count < 0) Fail(path, "PLY has no vertex element");
  return mesh;
}

}  // namespace fabatlas::mesh::internal

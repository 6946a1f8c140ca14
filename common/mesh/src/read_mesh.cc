// Mesh import: hand-written readers for STL, OBJ, OFF and PLY. They are strict
// about structure (every failure is an InputError naming the file and the
// problem) and never index outside the buffer they parse.
#include "fabatlas/mesh/read_mesh.h"
#include "mesh_formats.h"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include "fabatlas/error.h"

namespace fabatlas::mesh {
namespace {

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& what) {
  throw InputError(path.string() + ": " + what);
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Splits a line into whitespace-separated tokens.
std::vector<std::string_view> Tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsSpace(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !IsSpace(line[j])) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

// Parses a whole token as a double (accepts nan/inf so they can be reported).
bool ParseDouble(std::string_view t, double* out) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), *out);
  return ec == std::errc() && p == t.data() + t.size();
}

bool ParseInt(std::string_view t, long long* out) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), *out);
  return ec == std::errc() && p == t.data() + t.size();
}

// Line iterator over the file contents with 1-based line numbers.
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {}
  bool Next(std::string_view* line) {
    if (pos_ >= text_.size()) return false;
    std::size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    *line = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++number_;
    return true;
  }
  int number() const { return number_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  int number_ = 0;
};

void AddPolygon(const std::vector<long long>& corners, TriangleMesh* mesh) {
  for (std::size_t k = 1; k + 1 < corners.size(); ++k) {
    mesh->triangles.push_back({static_cast<std::int32_t>(corners[0]), static_cast<std::int32_t>(corners[k]),
                               static_cast<std::int32_t>(corners[k + 1])});
  }
}

// Merges bit-identical vertices of a per-facet vertex list (STL).
// Non-finite coordinates are rejected first (NaN would break the ordering).
TriangleMesh IndexSoup(const std::filesystem::path& path, const std::vector<std::array<double, 3>>& corners) {
  for (std::size_t i = 0; i < corners.size(); ++i) {
    for (double c : corners[i]) {
      if (!std::isfinite(c)) {
        Fail(path, "facet " + std::to_string(i / 3) + " corner " + std::to_string(i % 3) + " has a " +
                       (std::isnan(c) ? "NaN" : "infinite") + " coordinate");
      }
    }
  }
  TriangleMesh mesh;
  std::map<std::array<double, 3>, std::int32_t> index;
  std::array<std::int32_t, 3> tri{};
  for (std::size_t i = 0; i < corners.size(); ++i) {
    auto [it, inserted] = index.emplace(corners[i], static_cast<std::int32_t>(mesh.vertices.size()));
    if (inserted) mesh.vertices.push_back(corners[i]);
    tri[i % 3] = it->second;
    if (i % 3 == 2) mesh.triangles.push_back(tri);
  }
  return mesh;
}

// ---------------------------------------------------------------- STL
TriangleMesh ReadBinaryStl(const std::filesystem::path& path, std::string_view data) {
  std::uint32_t n = 0;
  std::memcpy(&n, data.data() + 80, 4);  // little endian on every supported host
  std::vector<std::array<double, 3>> corners;
  corners.reserve(std::size_t{n} * 3);
  for (std::uint32_t t = 0; t < n; ++t) {
    const char* rec = data.data() + 84 + std::size_t{t} * 50;
    for (int c = 0; c < 3; ++c) {
      std::array<double, 3> p{};
      for (int a = 0; a < 3; ++a) {
        float f;
        std::memcpy(&f, rec + 12 + 12 * c + 4 * a, 4);
        p[a] = f;
      }
      corners.push_back(p);
    }
  }
  return IndexSoup(path, corners);
}

TriangleMesh ReadAsciiStl(const std::filesystem::path& path, std::string_view data) {
  std::vector<std::array<double, 3>> loop;
  std::vector<std::array<double, 3>> corners;
  Lines lines(data);
  std::string_view line;
  bool in_loop = false;
  while (lines.Next(&line)) {
    auto tok = Tokens(line);
    if (tok.empty()) continue;
    const std::string key = Lower(std::string(tok[0]));
    const std::string where = "line " + std::to_string(lines.number()) + ": ";
    if (key == "vertex") {
      if (!in_loop) Fail(path, where + "'vertex' outside 'outer loop'");
      std::array<double, 3> p{};
      if (tok.size() != 4 || !ParseDouble(tok[1], &p[0]) || !ParseDouble(tok[2], &p[1]) ||
          !ParseDouble(tok[3], &p[2])) {
        Fail(path, where + "expected 'vertex x y z'");
      }
      loop.push_back(p);
    } else if (key == "outer") {
      in_loop = true;
      loop.clear();
    } else if (key == "endloop") {
      if (!in_loop) Fail(path, where + "'endloop' without 'outer loop'");
      if (loop.size() < 3) Fail(path, where + "facet with fewer than 3 vertices");
      for (std::size_t k = 1; k + 1 < loop.size(); ++k) {
        corners.push_back(loop[0]);
        corners.push_back(loop[k]);
        corners.push_back(loop[k + 1]);
      }
      in_loop = false;
    } else if (key == "solid" || key == "facet" || key == "endfacet" || key == "endsolid") {
      // structure only
    } else {
      Fail(path, where + "unexpected '" + std::string(tok[0].substr(0, 40)) + "' in ASCII STL");
    }
  }
  if (in_loop) Fail(path, "truncated ASCII STL (unterminated facet)");
  return IndexSoup(path, corners);
}

TriangleMesh ReadStl(const std::filesystem::path& path, std::string_view data) {
  if (data.size() >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, data.data() + 80, 4);
    if (data.size() == 84 + std::uint64_t{n} * 50) return ReadBinaryStl(path, data);
  }
  std::string_view head = data.substr(0, std::min<std::size_t>(data.size(), 512));
  std::size_t start = 0;
  while (start < head.size() && IsSpace(head[start])) ++start;
  const bool ascii = Lower(std::string(head.substr(start, 5))) == "solid" && head.find('\0') == std::string_view::npos;
  if (ascii) return ReadAsciiStl(path, data);
  if (data.size() < 84) Fail(path, "truncated binary STL (" + std::to_string(data.size()) + " bytes, header needs 84)");
  std::uint32_t n = 0;
  std::memcpy(&n, data.data() + 80, 4);
  Fail(path, "truncated or corrupt binary STL: header announces " + std::to_string(n) + " triangles (" +
                 std::to_string(84 + std::uint64_t{n} * 50) + " bytes) but the file has " +
                 std::to_string(data.size()) + " bytes");
}

// ---------------------------------------------------------------- OBJ
TriangleMesh ReadObj(const std::filesystem::path& path, std::string_view data) {
  TriangleMesh mesh;
  Lines lines(data);
  std::string_view line;
  std::vector<long long> corners;
  while (lines.Next(&line)) {
    if (std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    auto tok = Tokens(line);
    if (tok.empty()) continue;
    const std::string where = "line " + std::to_string(lines.number()) + ": ";
    if (tok[0] == "v") {
      std::array<double, 3> p{};
      if (tok.size() < 4 || !ParseDouble(tok[1], &p[0]) || !ParseDouble(tok[2], &p[1]) || !ParseDouble(tok[3], &p[2])) {
        Fail(path, where + "expected 'v x y z'");
      }
      mesh.vertices.push_back(p);
    } else if (tok[0] == "f") {
      if (tok.size() < 4) Fail(path, where + "face with fewer than 3 vertices");
      corners.clear();
      for (std::size_t k = 1; k < tok.size(); ++k) {
        std::string_view idx = tok[k].substr(0, tok[k].find('/'));
        long long v = 0;
        if (!ParseInt(idx, &v) || v == 0)
          Fail(path, where + "bad face index '" + std::string(tok[k].substr(0, 40)) + "'");
        const long long n = static_cast<long long>(mesh.vertices.size());
        const long long zero_based = v > 0 ? v - 1 : n + v;
        if (zero_based < 0 || zero_based >= n) {
          Fail(path,
               where + "face index " + std::to_string(v) + " out of range (" + std::to_string(n) + " vertices so far)");
        }
        corners.push_back(zero_based);
      }
      AddPolygon(corners, &mesh);
    } else if (tok[0].size() > 32 || std::any_of(tok[0].begin(), tok[0].end(),
                                                 [](char c) { return !std::isprint(static_cast<unsigned char>(c)); })) {
      Fail(path, where + "not an OBJ record");
    }
    // vt, vn, vp, g, o, s, l, usemtl, mtllib, ...: not geometry we need.
  }
  return mesh;
}

// ---------------------------------------------------------------- OFF
TriangleMesh ReadOff(const std::filesystem::path& path, std::string_view data) {
  TriangleMesh mesh;
  Lines lines(data);
  std::string_view line;
  // Collect the meaningful lines (comments and blank lines removed) lazily.
  auto next_tokens = [&](std::vector<std::string_view>* tok) {
    while (lines.Next(&line)) {
      if (std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
      *tok = Tokens(line);
      if (!tok->empty()) return true;
    }
    return false;
  };
  std::vector<std::string_view> tok;
  if (!next_tokens(&tok)) Fail(path, "empty OFF file");
  std::string magic(tok[0]);
  if (magic.size() < 3 || magic.substr(magic.size() - 3) != "OFF" || magic.size() > 8) {
    Fail(path, "line " + std::to_string(lines.number()) + ": missing OFF header");
  }
  std::vector<std::string_view> counts(tok.begin() + 1, tok.end());
  if (counts.empty()) {
    if (!next_tokens(&tok)) Fail(path, "truncated OFF (no element counts)");
    counts = tok;
  }
  long long nv = 0, nf = 0;
  if (counts.size() < 2 || !ParseInt(counts[0], &nv) || !ParseInt(counts[1], &nf) || nv < 0 || nf < 0 ||
      nv > (1LL << 31) - 1 || nf > (1LL << 31) - 1) {
    Fail(path, "line " + std::to_string(lines.number()) + ": expected 'vertex_count face_count edge_count'");
  }
  if (static_cast<unsigned long long>(nv) > data.size() || static_cast<unsigned long long>(nf) > data.size()) {
    Fail(path, "truncated OFF: header announces " + std::to_string(nv) + " vertices and " + std::to_string(nf) +
                   " faces, more than the file can hold");
  }
  mesh.vertices.reserve(nv);
  for (long long i = 0; i < nv; ++i) {
    if (!next_tokens(&tok)) {
      Fail(path, "truncated OFF: " + std::to_string(i) + " of " + std::to_string(nv) + " vertices present");
    }
    std::array<double, 3> p{};
    if (tok.size() < 3 || !ParseDouble(tok[0], &p[0]) || !ParseDouble(tok[1], &p[1]) || !ParseDouble(tok[2], &p[2])) {
      Fail(path, "line " + std::to_string(lines.number()) + ": expected 'x y z'");
    }
    mesh.vertices.push_back(p);
  }
  std::vector<long long> corners;
  for (long long i = 0; i < nf; ++i) {
    if (!next_tokens(&tok)) {
      Fail(path, "truncated OFF: " + std::to_string(i) + " of " + std::to_string(nf) + " faces present");
    }
    const std::string where = "line " + std::to_string(lines.number()) + ": ";
    long long k = 0;
    if (!ParseInt(tok[0], &k) || k < 3 || k + 1 > static_cast<long long>(tok.size())) {
      Fail(path, where + "expected 'n i1 ... in' with n >= 3");
    }
    corners.clear();
    for (long long j = 1; j <= k; ++j) {
      long long v = 0;
      if (!ParseInt(tok[j], &v)) Fail(path, where + "bad face index '" + std::string(tok[j].substr(0, 40)) + "'");
      if (v < 0 || v >= nv) {
        Fail(path, where + "face index " + std::to_string(v) + " out of range (" + std::to_string(nv) + " vertices)");
      }
      corners.push_back(v);
    }
    AddPolygon(corners, &mesh);
  }
  return mesh;
}

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

}  // namespace

TriangleMesh ReadMesh(const std::filesystem::path& path) {
  const std::string ext = Lower(path.extension().string());
  if (ext != ".stl" && ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".3mf" && ext != ".amf") {
    Fail(path,
         "unknown mesh extension '" + path.extension().string() + "' (expected .stl, .obj, .off, .ply, .3mf or .amf)");
  }
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) Fail(path, "file does not exist");
  if (std::filesystem::is_directory(path, ec)) Fail(path, "is a directory, not a mesh file");
  std::ifstream in(path, std::ios::binary);
  if (!in) Fail(path, std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) Fail(path, "read error");
  const std::string data = buffer.str();
  if (data.empty()) Fail(path, "file is empty");

  TriangleMesh mesh;
  if (ext == ".stl")
    mesh = ReadStl(path, data);
  else if (ext == ".obj")
    mesh = ReadObj(path, data);
  else if (ext == ".off")
    mesh = ReadOff(path, data);
  else if (ext == ".3mf")
    mesh = internal::Read3mf(path, data);
  else if (ext == ".amf")
    mesh = internal::ReadAmf(path, data);
  else
    mesh = ReadPly(path, data);

  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (double c : mesh.vertices[i]) {
      if (!std::isfinite(c)) {
        Fail(path, "vertex " + std::to_string(i) + " has a " + (std::isnan(c) ? "NaN" : "infinite") + " coordinate");
      }
    }
  }
  if (mesh.triangles.empty()) Fail(path, "mesh has zero triangles");
  const auto n = static_cast<std::int64_t>(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (std::int32_t v : mesh.triangles[t]) {
      if (v < 0 || v >= n)
        Fail(path, "triangle " + std::to_string(t) + " has vertex index " + std::to_string(v) + " out of range");
    }
  }
  return mesh;
}

}  // namespace fabatlas::mesh

// Mesh import: hand-written readers for STL, OBJ and OFF (PLY in read_ply.cc). They are strict
// about structure (every failure is an InputError naming the file and the
// problem) and never index outside the buffer they parse.
#include "fabatlas/mesh/read_mesh.h"
#include "mesh_formats.h"
#include "mesh_text.h"

#include <algorithm>
#include <array>
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

using namespace internal;  // the text helpers (mesh_text.h)

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
    mesh = internal::ReadPly(path, data);

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

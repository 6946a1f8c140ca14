// Additive Manufacturing File format (ISO/ASTM 52915): <amf unit>, each
// <object>'s <mesh> of <vertices> (<vertex><coordinates><x><y><z>) and
// <volume>s of <triangle><v1><v2><v3> (indices into the object's vertices).
// Coordinates are taken as stored, whatever the unit attribute says, as
// OpenSCAD 2021.01 takes them. Materials, colours, curved triangles and
// constellations are not read.
#include <array>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "fabatlas/error.h"
#include "mesh_formats.h"

namespace fabatlas::mesh::internal {
namespace {

struct Amf {
  TriangleMesh mesh;
  std::size_t object_base = 0;  // the current object's first vertex in `mesh`
  std::array<double, 3> point{};
  std::array<long long, 3> corner{};
  std::string text;  // character data of the innermost element
  std::string problem;
};

void Start(void* data, const char* element, const char** attributes) {
  Amf& a = *static_cast<Amf*>(data);
  a.text.clear();
  const std::string_view name = LocalName(element);
  (void)attributes;
  if (name == "object") {
    a.object_base = a.mesh.vertices.size();
  }
}

void Characters(void* data, const char* s, int length) {
  Amf& a = *static_cast<Amf*>(data);
  if (a.text.size() < 256) a.text.append(s, static_cast<std::size_t>(length));
}

bool Parse(const std::string& text, double* out) {
  char* end = nullptr;
  *out = std::strtod(text.c_str(), &end);
  while (end && (*end == ' ' || *end == '\n' || *end == '\t' || *end == '\r')) ++end;
  return end != text.c_str() && *end == '\0' && std::isfinite(*out);
}

void End(void* data, const char* element) {
  Amf& a = *static_cast<Amf*>(data);
  if (!a.problem.empty()) return;
  const std::string_view name = LocalName(element);
  const std::string vertex_number = std::to_string(a.mesh.vertices.size() - a.object_base);
  if (name == "x" || name == "y" || name == "z") {
    if (!Parse(a.text, &a.point[name[0] - 'x']))
      a.problem = "vertex " + vertex_number + ": " + std::string(name) + " is not a finite number";
  } else if (name == "v1" || name == "v2" || name == "v3") {
    double v = 0;
    if (!Parse(a.text, &v) || v < 0 || v != std::floor(v)) a.problem = "a triangle corner that is not a vertex index";
    a.corner[name[1] - '1'] = static_cast<long long>(v);
  } else if (name == "vertex") {
    a.mesh.vertices.push_back(a.point);
    a.point = {};
  } else if (name == "triangle") {
    const std::size_t count = a.mesh.vertices.size() - a.object_base;
    for (long long c : a.corner)
      if (static_cast<std::size_t>(c) >= count) a.problem = "a triangle index " + std::to_string(c) + " out of range";
    a.mesh.triangles.push_back({static_cast<std::int32_t>(a.object_base + a.corner[0]),
                                static_cast<std::int32_t>(a.object_base + a.corner[1]),
                                static_cast<std::int32_t>(a.object_base + a.corner[2])});
  }
  a.text.clear();
}

}  // namespace

TriangleMesh ReadAmf(const std::filesystem::path& path, std::string_view data) {
  const std::string xml = IsZip(data) ? ZipEntry(path, data, "") : std::string(data);
  Amf a;
  ParseXml(path, "AMF", xml, &a, Start, End, Characters);
  if (!a.problem.empty()) throw InputError(path.string() + ": AMF: " + a.problem);
  return std::move(a.mesh);
}

}  // namespace fabatlas::mesh::internal

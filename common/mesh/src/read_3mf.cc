// 3MF core specification 1.2 (3MF Consortium): the package's model part
// (found through _rels/.rels), its objects (meshes and components) and build
// items, with their affine transforms ("m00 m01 m02 m10 ... m32", applied to
// row vectors). Coordinates are taken as stored, whatever the model's unit,
// as OpenSCAD 2021.01 takes them.
#include <array>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <sstream>
#include <vector>

#include "fabatlas/error.h"
#include "mesh_formats.h"

namespace fabatlas::mesh::internal {
namespace {

using Transform = std::array<double, 12>;
constexpr Transform kIdentity = {1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0};

struct Component {
  int object = 0;
  Transform transform = kIdentity;
};

struct Object {
  std::vector<std::array<double, 3>> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;
  std::vector<Component> components;
};

struct Model {
  std::map<int, Object> objects;
  std::vector<Component> items;
  std::string problem;
  int current = -1;
};

const char* Attribute(const char** attributes, std::string_view key) {
  for (int i = 0; attributes[i]; i += 2)
    if (LocalName(attributes[i]) == key) return attributes[i + 1];
  return nullptr;
}

bool Number(const char* text, double* out) {
  if (!text) return false;
  char* end = nullptr;
  *out = std::strtod(text, &end);
  return end != text && std::isfinite(*out);
}

bool ParseTransform(const char* text, Transform* t) {
  if (!text) return true;
  std::istringstream in(text);
  for (double& v : *t)
    if (!(in >> v) || !std::isfinite(v)) return false;
  return true;
}

Transform Compose(const Transform& inner, const Transform& outer) {  // p * inner * outer
  Transform r{};
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 3; ++col) {
      double v = row == 3 ? outer[9 + col] : 0;
      for (int k = 0; k < 3; ++k) v += inner[row * 3 + k] * outer[k * 3 + col];
      r[row * 3 + col] = v;
    }
  return r;
}

void Start(void* data, const char* element, const char** attributes) {
  Model& m = *static_cast<Model*>(data);
  if (!m.problem.empty()) return;
  const std::string_view name = LocalName(element);
  if (name == "object") {
    double id = 0;
    if (!Number(Attribute(attributes, "id"), &id)) m.problem = "an object without a numeric id";
    m.current = static_cast<int>(id);
    m.objects[m.current];
  } else if (name == "vertex" && m.current >= 0) {
    std::array<double, 3> p{};
    if (!Number(Attribute(attributes, "x"), &p[0]) || !Number(Attribute(attributes, "y"), &p[1]) ||
        !Number(Attribute(attributes, "z"), &p[2]))
      m.problem = "object " + std::to_string(m.current) + ": a vertex without finite x, y and z";
    m.objects[m.current].vertices.push_back(p);
  } else if (name == "triangle" && m.current >= 0) {
    double v[3] = {0, 0, 0};  // read below; a triangle without them is m.problem
    if (!Number(Attribute(attributes, "v1"), &v[0]) || !Number(Attribute(attributes, "v2"), &v[1]) ||
        !Number(Attribute(attributes, "v3"), &v[2]))
      m.problem = "object " + std::to_string(m.current) + ": a triangle without v1, v2 and v3";
    m.objects[m.current].triangles.push_back(
        {static_cast<std::int32_t>(v[0]), static_cast<std::int32_t>(v[1]), static_cast<std::int32_t>(v[2])});
  } else if (name == "component" || name == "item") {
    Component c;
    double id = 0;
    if (!Number(Attribute(attributes, "objectid"), &id)) m.problem = std::string(name) + " without an objectid";
    c.object = static_cast<int>(id);
    if (!ParseTransform(Attribute(attributes, "transform"), &c.transform))
      m.problem = std::string(name) + " with a transform that is not 12 finite numbers";
    if (name == "item")
      m.items.push_back(c);
    else if (m.current >= 0)
      m.objects[m.current].components.push_back(c);
  }
}

void End(void* data, const char* element) {
  Model& m = *static_cast<Model*>(data);
  if (LocalName(element) == "object") m.current = -1;
}

Model ParseModel(const std::filesystem::path& path, const std::string& xml) {
  Model m;
  ParseXml(path, "3MF model", xml, &m, Start, End, nullptr);
  if (!m.problem.empty()) throw InputError(path.string() + ": 3MF model: " + m.problem);
  return m;
}

// The model part's name, from the package relationships (3MF core 1.2, 2.1.1).
std::string ModelPart(const std::filesystem::path& path, std::string_view archive) {
  std::string rels;
  try {
    rels = ZipEntry(path, archive, "_rels/.rels");
  } catch (const InputError&) {
    return "3D/3dmodel.model";
  }
  const auto type = rels.find("3dmanufacturing/2013/01/3dmodel");
  if (type == std::string::npos) return "3D/3dmodel.model";
  const auto open = rels.rfind('<', type), close = rels.find('>', type);
  const std::string element = rels.substr(open, close - open);
  const auto target = element.find("Target=\"");
  if (target == std::string::npos) return "3D/3dmodel.model";
  std::string name = element.substr(target + 8, element.find('"', target + 8) - target - 8);
  if (!name.empty() && name[0] == '/') name.erase(0, 1);
  return name;
}

}  // namespace

TriangleMesh Read3mf(const std::filesystem::path& path, std::string_view data) {
  if (!IsZip(data)) throw InputError(path.string() + ": not a 3MF package (no ZIP signature)");
  const Model m = ParseModel(path, ZipEntry(path, data, ModelPart(path, data)));
  TriangleMesh out;
  std::function<void(int, const Transform&, int)> add = [&](int id, const Transform& t, int depth) {
    auto it = m.objects.find(id);
    if (it == m.objects.end()) throw InputError(path.string() + ": 3MF model: no object " + std::to_string(id));
    if (depth > 32) throw InputError(path.string() + ": 3MF model: components nested over 32 deep (a cycle?)");
    const Object& o = it->second;
    const auto base = static_cast<std::int64_t>(out.vertices.size());
    for (const auto& p : o.vertices) {
      std::array<double, 3> q{};
      for (int c = 0; c < 3; ++c) q[c] = (p[0] * t[c] + p[1] * t[3 + c] + p[2] * t[6 + c] + t[9 + c]);
      out.vertices.push_back(q);
    }
    for (const auto& tri : o.triangles) {
      for (std::int32_t v : tri)
        if (v < 0 || static_cast<std::size_t>(v) >= o.vertices.size())
          throw InputError(path.string() + ": 3MF model: object " + std::to_string(id) + " has a triangle index " +
                           std::to_string(v) + " out of range");
      out.triangles.push_back({static_cast<std::int32_t>(base + tri[0]), static_cast<std::int32_t>(base + tri[1]),
                               static_cast<std::int32_t>(base + tri[2])});
    }
    for (const Component& c : o.components) add(c.object, Compose(c.transform, t), depth + 1);
  };
  for (const Component& item : m.items) add(item.object, item.transform, 0);
  return out;
}

}  // namespace fabatlas::mesh::internal

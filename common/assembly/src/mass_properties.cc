#include "fabatlas/assembly/mass_properties.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <vector>

#include "fabatlas/error.h"

namespace fabatlas::assembly {
namespace {

struct Soup {
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<int, 3>> f;
};

void AddPolygon(Soup& s, const std::vector<int>& idx, const std::string& path) {
  for (int i : idx)
    if (i < 0 || i >= static_cast<int>(s.v.size()))
      throw InputError(path + ": face index " + std::to_string(i) + " out of range");
  for (size_t k = 1; k + 1 < idx.size(); ++k) s.f.push_back({idx[0], idx[k], idx[k + 1]});
}

Soup ReadObj(const std::string& path, std::istream& in) {
  Soup s;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "v") {
      Eigen::Vector3d p;
      if (!(ls >> p.x() >> p.y() >> p.z())) throw InputError(path + ": bad vertex line");
      s.v.push_back(p);
    } else if (tag == "f") {
      std::vector<int> idx;
      std::string tok;
      while (ls >> tok) {
        int i = std::stoi(tok.substr(0, tok.find('/')));
        idx.push_back(i > 0 ? i - 1 : static_cast<int>(s.v.size()) + i);
      }
      AddPolygon(s, idx, path);
    }
  }
  return s;
}

Soup ReadOff(const std::string& path, std::istream& in) {
  Soup s;
  std::string head;
  in >> head;
  if (head != "OFF") throw InputError(path + ": missing OFF header");
  long nv = 0, nf = 0, ne = 0;
  if (!(in >> nv >> nf >> ne)) throw InputError(path + ": bad OFF counts");
  s.v.resize(nv);
  for (auto& p : s.v)
    if (!(in >> p.x() >> p.y() >> p.z())) throw InputError(path + ": truncated OFF vertices");
  for (long i = 0; i < nf; ++i) {
    int n = 0;
    if (!(in >> n)) throw InputError(path + ": truncated OFF faces");
    std::vector<int> idx(n);
    for (int& k : idx) in >> k;
    AddPolygon(s, idx, path);
  }
  return s;
}

Soup ReadStl(const std::string& path, const std::string& data) {
  Soup s;
  const bool ascii =
      data.rfind("solid", 0) == 0 && data.find("facet", 0) != std::string::npos && data.find("facet") < 512;
  if (ascii) {
    std::istringstream in(data);
    std::string tok;
    while (in >> tok) {
      if (tok == "vertex") {
        Eigen::Vector3d p;
        in >> p.x() >> p.y() >> p.z();
        s.v.push_back(p);
      }
    }
  } else {
    if (data.size() < 84) throw InputError(path + ": truncated binary STL");
    uint32_t n;
    std::memcpy(&n, data.data() + 80, 4);
    if (data.size() < 84 + 50ull * n) throw InputError(path + ": truncated binary STL");
    for (uint32_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        float xyz[3];
        std::memcpy(xyz, data.data() + 84 + 50ull * i + 12 + 12 * k, 12);
        s.v.emplace_back(xyz[0], xyz[1], xyz[2]);
      }
  }
  for (int i = 0; i + 2 < static_cast<int>(s.v.size()); i += 3) s.f.push_back({i, i + 1, i + 2});
  return s;
}

}  // namespace

PartMesh ReadPartMesh(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError(path + ": cannot open mesh");
  std::stringstream buf;
  buf << file.rdbuf();
  const std::string data = buf.str();
  const std::string ext = path.substr(path.find_last_of('.') + 1);
  Soup s;
  if (ext == "obj") {
    std::istringstream in(data);
    s = ReadObj(path, in);
  } else if (ext == "off") {
    std::istringstream in(data);
    s = ReadOff(path, in);
  } else if (ext == "stl") {
    s = ReadStl(path, data);
  } else {
    throw InputError(path + ": unsupported mesh extension '" + ext + "'");
  }
  if (s.f.empty()) throw InputError(path + ": mesh has no faces");
  for (const auto& p : s.v)
    if (!p.allFinite()) throw InputError(path + ": non-finite vertex coordinate");
  return {std::move(s.v), std::move(s.f)};
}

MassProperties ComputeMassProperties(const std::string& path) {
  // Parts share meshes and every generated program reloads its library:
  // remember the result per path for the process lifetime.
  static std::mutex mutex;
  static std::map<std::string, MassProperties> known;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = known.find(path); it != known.end()) return it->second;
  }
  const PartMesh s = ReadPartMesh(path);
  MassProperties m;
  m.bbox_min = m.bbox_max = s.vertices[0];
  for (const auto& p : s.vertices) {
    m.bbox_min = m.bbox_min.cwiseMin(p);
    m.bbox_max = m.bbox_max.cwiseMax(p);
  }
  double vol6 = 0;
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  for (const auto& t : s.triangles) {
    const double d = s.vertices[t[0]].dot(s.vertices[t[1]].cross(s.vertices[t[2]]));
    vol6 += d;
    moment += d * (s.vertices[t[0]] + s.vertices[t[1]] + s.vertices[t[2]]);
  }
  m.triangles = static_cast<int>(s.triangles.size());
  m.volume_mm3 = std::abs(vol6) / 6.0;
  const double diag = (m.bbox_max - m.bbox_min).norm();
  if (m.volume_mm3 > 1e-6 * diag * diag * diag)
    m.centre_of_mass = moment / (4.0 * vol6);
  else
    m.centre_of_mass = 0.5 * (m.bbox_min + m.bbox_max);
  std::lock_guard<std::mutex> lock(mutex);
  known[path] = m;
  return m;
}

}  // namespace fabatlas::assembly

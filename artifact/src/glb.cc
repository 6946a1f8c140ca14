// Meshes as glTF binary through tinygltf (see glb.h).
#include "fabatlas/artifact/glb.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/mesh/crease_normals.h"

namespace fabatlas::artifact {

std::string SolidPreviewGlb(const mesh::TriangleMesh& surface, bool exact) {
  if (!exact) return MeshToGlb(surface);
  const mesh::CreasedMesh creased = mesh::CreaseNormals(surface, 30.0);
  return MeshToGlb(creased.mesh, &creased.normals);
}

namespace {

// Buffer 0 of a mesh's glTF model: its positions as floats, its triangles'
// indices as uint32, then `normals` when given; *lo and *hi take the
// positions' bounds (as floats). Throws InputError for an index out of range.
tinygltf::Buffer MeshBuffer(const mesh::TriangleMesh& m, const std::vector<std::array<float, 3>>* normals,
                            std::vector<double>* lo_out, std::vector<double>* hi_out) {
  tinygltf::Buffer buffer;
  const std::size_t position_bytes = m.vertices.size() * 3 * sizeof(float);
  const std::size_t index_bytes = m.triangles.size() * 3 * sizeof(std::uint32_t);
  const std::size_t normal_bytes = normals ? position_bytes : 0;
  buffer.data.resize(position_bytes + index_bytes + normal_bytes);
  std::vector<double>& lo = *lo_out;
  std::vector<double>& hi = *hi_out;
  unsigned char* out = buffer.data.data();
  for (const auto& v : m.vertices)
    for (int k = 0; k < 3; ++k) {
      const float f = static_cast<float>(v[k]);
      lo[k] = std::min(lo[k], static_cast<double>(f));
      hi[k] = std::max(hi[k], static_cast<double>(f));
      std::memcpy(out, &f, sizeof f);
      out += sizeof f;
    }
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= m.vertices.size())
        throw InputError("glb: triangle index " + std::to_string(t[k]) + " out of range");
      const auto i = static_cast<std::uint32_t>(t[k]);
      std::memcpy(out, &i, sizeof i);
      out += sizeof i;
    }
  if (normals) std::memcpy(out, normals->data(), normal_bytes);
  return buffer;
}

// The views, accessors and triangle mesh (mesh 0) of MeshBuffer's buffer in
// `model`, with a NORMAL attribute when `normals` is given; lo and hi the
// positions' bounds.
void DescribeMesh(tinygltf::Model& model, const mesh::TriangleMesh& m, const std::vector<std::array<float, 3>>* normals,
                  const std::vector<double>& lo, const std::vector<double>& hi) {
  const std::size_t position_bytes = m.vertices.size() * 3 * sizeof(float);
  const std::size_t index_bytes = m.triangles.size() * 3 * sizeof(std::uint32_t);
  const std::size_t normal_bytes = normals ? position_bytes : 0;
  tinygltf::BufferView positions;
  positions.buffer = 0;
  positions.byteOffset = 0;
  positions.byteLength = position_bytes;
  positions.target = TINYGLTF_TARGET_ARRAY_BUFFER;
  tinygltf::BufferView indices;
  indices.buffer = 0;
  indices.byteOffset = position_bytes;
  indices.byteLength = index_bytes;
  indices.target = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
  model.bufferViews = {positions, indices};

  tinygltf::Accessor position_accessor;
  position_accessor.bufferView = 0;
  position_accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  position_accessor.count = m.vertices.size();
  position_accessor.type = TINYGLTF_TYPE_VEC3;
  position_accessor.minValues = lo;
  position_accessor.maxValues = hi;
  tinygltf::Accessor index_accessor;
  index_accessor.bufferView = 1;
  index_accessor.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
  index_accessor.count = m.triangles.size() * 3;
  index_accessor.type = TINYGLTF_TYPE_SCALAR;
  model.accessors = {position_accessor, index_accessor};
  if (normals) {
    tinygltf::BufferView normal_view;
    normal_view.buffer = 0;
    normal_view.byteOffset = position_bytes + index_bytes;
    normal_view.byteLength = normal_bytes;
    normal_view.target = TINYGLTF_TARGET_ARRAY_BUFFER;
    model.bufferViews.push_back(normal_view);
    tinygltf::Accessor normal_accessor;
    normal_accessor.bufferView = 2;
    normal_accessor.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    normal_accessor.count = m.vertices.size();
    normal_accessor.type = TINYGLTF_TYPE_VEC3;
    model.accessors.push_back(normal_accessor);
  }

  tinygltf::Primitive primitive;
  primitive.attributes["POSITION"] = 0;
  if (normals) primitive.attributes["NORMAL"] = 2;
  primitive.indices = 1;
  primitive.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Mesh mesh;
  mesh.primitives.push_back(std::move(primitive));
  model.meshes.push_back(std::move(mesh));
}

}  // namespace

std::string MeshToGlb(const mesh::TriangleMesh& m, const std::vector<std::array<float, 3>>* normals) {
  if (normals && normals->size() != m.vertices.size()) throw InputError("glb: one normal per vertex expected");
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "fabatlas";
  tinygltf::Scene scene;
  tinygltf::Node node;
  node.name = "geometry";  // also keeps an empty node a JSON object
  // glTF 2.0 (Sec. 3.4 "Coordinate System and Units"): metres, +Y up. The
  // positions stay the design's millimetres with z up; the node scales them
  // by 1/1000 and turns z up into +Y up (-90 degrees about x: (x, y, z) ->
  // (x, z, -y)), so every glTF viewer places the model at its true size.
  node.scale = {1e-3, 1e-3, 1e-3};
  node.rotation = {-std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)};
  if (!m.empty()) {
    std::vector<double> lo(3, std::numeric_limits<double>::infinity()), hi(3, -std::numeric_limits<double>::infinity());
    model.buffers.push_back(MeshBuffer(m, normals, &lo, &hi));
    DescribeMesh(model, m, normals, lo, hi);
    node.mesh = 0;
  }
  model.nodes.push_back(node);
  scene.nodes.push_back(0);
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  std::ostringstream stream;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, stream, false, true))
    throw InputError("glb: tinygltf could not write the mesh");
  return stream.str();
}

namespace {

// sRGB to linear (IEC 61966-2-1).
double Linear(double c) { return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4); }

// Appends `bytes` to buffer 0 as a new buffer view (4-byte aligned); its index.
int AddView(tinygltf::Model& model, const void* bytes, std::size_t size, int target) {
  auto& data = model.buffers[0].data;
  while (data.size() % 4) data.push_back(0);
  tinygltf::BufferView view;
  view.buffer = 0;
  view.byteOffset = data.size();
  view.byteLength = size;
  view.target = target;
  const auto* b = static_cast<const unsigned char*>(bytes);
  data.insert(data.end(), b, b + size);
  model.bufferViews.push_back(view);
  return static_cast<int>(model.bufferViews.size()) - 1;
}

int AddAccessor(tinygltf::Model& model, int view, int component, std::size_t count, int type) {
  tinygltf::Accessor a;
  a.bufferView = view;
  a.componentType = component;
  a.count = count;
  a.type = type;
  model.accessors.push_back(a);
  return static_cast<int>(model.accessors.size()) - 1;
}

}  // namespace

std::string PartsToGlb(const std::vector<GlbPart>& parts, bool exact) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "fabatlas";
  model.buffers.emplace_back();
  tinygltf::Scene scene;
  for (const GlbPart& part : parts) {
    if (!part.mesh || part.mesh->empty()) continue;
    mesh::TriangleMesh m = *part.mesh;
    std::vector<std::array<float, 3>> normals;
    if (exact) {
      mesh::CreasedMesh creased = mesh::CreaseNormals(m, 30.0);
      m = std::move(creased.mesh);
      normals = std::move(creased.normals);
    }
    std::vector<float> positions;
    std::vector<double> lo(3, std::numeric_limits<double>::infinity()), hi(3, -std::numeric_limits<double>::infinity());
    for (const auto& v : m.vertices)
      for (int k = 0; k < 3; ++k) {
        const float f = static_cast<float>(v[k]);
        lo[k] = std::min(lo[k], static_cast<double>(f));
        hi[k] = std::max(hi[k], static_cast<double>(f));
        positions.push_back(f);
      }
    std::vector<std::uint32_t> indices;
    for (const auto& t : m.triangles)
      for (int k = 0; k < 3; ++k) {
        if (t[k] < 0 || static_cast<std::size_t>(t[k]) >= m.vertices.size())
          throw InputError("glb: triangle index " + std::to_string(t[k]) + " out of range");
        indices.push_back(static_cast<std::uint32_t>(t[k]));
      }
    tinygltf::Primitive primitive;
    const int pv = AddView(model, positions.data(), positions.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
    primitive.attributes["POSITION"] =
        AddAccessor(model, pv, TINYGLTF_COMPONENT_TYPE_FLOAT, m.vertices.size(), TINYGLTF_TYPE_VEC3);
    model.accessors.back().minValues = lo;
    model.accessors.back().maxValues = hi;
    const int iv =
        AddView(model, indices.data(), indices.size() * sizeof(std::uint32_t), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    primitive.indices =
        AddAccessor(model, iv, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, indices.size(), TINYGLTF_TYPE_SCALAR);
    if (!normals.empty()) {
      const int nv = AddView(model, normals.data(), normals.size() * sizeof(normals[0]), TINYGLTF_TARGET_ARRAY_BUFFER);
      primitive.attributes["NORMAL"] =
          AddAccessor(model, nv, TINYGLTF_COMPONENT_TYPE_FLOAT, normals.size(), TINYGLTF_TYPE_VEC3);
    }
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    if (part.coloured) {
      tinygltf::Material material;
      material.name = "part " + part.name;
      material.pbrMetallicRoughness.baseColorFactor = {Linear(part.rgba[0]), Linear(part.rgba[1]), Linear(part.rgba[2]),
                                                       part.rgba[3]};
      material.pbrMetallicRoughness.metallicFactor = 0;
      material.pbrMetallicRoughness.roughnessFactor = 0.6;
      if (part.rgba[3] < 1) material.alphaMode = "BLEND";
      model.materials.push_back(material);
      primitive.material = static_cast<int>(model.materials.size()) - 1;
    }
    tinygltf::Mesh gm;
    gm.name = part.name;
    gm.primitives.push_back(std::move(primitive));
    model.meshes.push_back(std::move(gm));
    tinygltf::Node node;
    node.name = part.name;
    node.scale = {1e-3, 1e-3, 1e-3};  // as MeshToGlb: millimetres, z up, to metres, +Y up
    node.rotation = {-std::sqrt(0.5), 0.0, 0.0, std::sqrt(0.5)};
    node.mesh = static_cast<int>(model.meshes.size()) - 1;
    model.nodes.push_back(node);
    scene.nodes.push_back(static_cast<int>(model.nodes.size()) - 1);
  }
  if (model.buffers[0].data.empty()) model.buffers.clear();
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  std::ostringstream stream;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, stream, false, true))
    throw InputError("glb: tinygltf could not write the parts");
  return stream.str();
}

mesh::TriangleMesh GlbToMesh(std::string_view glb, const std::string& source) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string error, warning;
  if (!loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(glb.data()),
                                   static_cast<unsigned int>(glb.size())))
    throw InputError(source +
                     ": not a glTF binary: " + (error.empty() ? "unreadable" : error.substr(0, error.find('\n'))));
  mesh::TriangleMesh out;
  if (model.meshes.empty()) return out;
  if (model.meshes[0].primitives.empty()) throw InputError(source + ": the first mesh has no primitive");
  const tinygltf::Primitive& p = model.meshes[0].primitives[0];
  auto accessor_data = [&](int index, int component_type, std::size_t component_size, int type) {
    if (index < 0 || index >= static_cast<int>(model.accessors.size()))
      throw InputError(source + ": accessor out of range");
    const auto& a = model.accessors[index];
    if (a.componentType != component_type || a.type != type) throw InputError(source + ": unexpected accessor type");
    const auto& view = model.bufferViews.at(a.bufferView);
    const auto& buffer = model.buffers.at(view.buffer);
    const std::size_t width = component_size * (type == TINYGLTF_TYPE_VEC3 ? 3 : 1);
    const std::size_t stride = view.byteStride ? view.byteStride : width;
    const std::size_t begin = view.byteOffset + a.byteOffset;
    if (a.count > 0 && begin + stride * (a.count - 1) + width > buffer.data.size())
      throw InputError(source + ": accessor runs past its buffer");
    return std::make_pair(buffer.data.data() + begin, stride);
  };
  auto it = p.attributes.find("POSITION");
  if (it == p.attributes.end()) throw InputError(source + ": the primitive has no POSITION");
  auto [pos, pos_stride] = accessor_data(it->second, TINYGLTF_COMPONENT_TYPE_FLOAT, 4, TINYGLTF_TYPE_VEC3);
  const std::size_t vertex_count = model.accessors[it->second].count;
  for (std::size_t i = 0; i < vertex_count; ++i) {
    float f[3];
    std::memcpy(f, pos + i * pos_stride, sizeof f);
    out.vertices.push_back({f[0], f[1], f[2]});
  }
  if (p.indices < 0) throw InputError(source + ": the primitive has no indices");
  const auto& ia = model.accessors.at(p.indices);
  const std::size_t size = ia.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT     ? 4
                           : ia.componentType == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2
                                                                                        : 1;
  auto [idx, idx_stride] = accessor_data(p.indices, ia.componentType, size, TINYGLTF_TYPE_SCALAR);
  if (ia.count % 3 != 0) throw InputError(source + ": index count is not a multiple of 3");
  for (std::size_t t = 0; t < ia.count / 3; ++t) {
    std::array<std::int32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      const unsigned char* q = idx + (3 * t + k) * idx_stride;
      std::uint32_t v = 0;
      if (size == 4)
        std::memcpy(&v, q, 4);
      else if (size == 2) {
        std::uint16_t s;
        std::memcpy(&s, q, 2);
        v = s;
      } else
        v = *q;
      if (v >= vertex_count) throw InputError(source + ": index out of range");
      tri[k] = static_cast<std::int32_t>(v);
    }
    out.triangles.push_back(tri);
  }
  return out;
}

}  // namespace fabatlas::artifact

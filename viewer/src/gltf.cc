#include "fabatlas/viewer/gltf.h"

#include <cstring>
#include <limits>
#include <sstream>

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>

namespace fabatlas::viewer {

std::string MeshToGlb(const mesh::TriangleMesh& mesh) {
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "fabatlas";
  tinygltf::Scene scene;
  if (!mesh.empty()) {
    const size_t nv = mesh.vertices.size(), nt = mesh.triangles.size();
    tinygltf::Buffer buffer;
    buffer.data.resize(nv * 3 * sizeof(float) + nt * 3 * sizeof(std::uint32_t));
    std::vector<double> lo(3, std::numeric_limits<double>::infinity()), hi(3, -std::numeric_limits<double>::infinity());
    float* positions = reinterpret_cast<float*>(buffer.data.data());
    for (size_t i = 0; i < nv; ++i)
      for (int k = 0; k < 3; ++k) {
        const float v = static_cast<float>(mesh.vertices[i][k]);
        positions[3 * i + k] = v;
        lo[k] = std::min(lo[k], static_cast<double>(v));
        hi[k] = std::max(hi[k], static_cast<double>(v));
      }
    unsigned char* index_bytes = buffer.data.data() + nv * 3 * sizeof(float);
    for (size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t index = static_cast<std::uint32_t>(mesh.triangles[t][k]);
        std::memcpy(index_bytes + (3 * t + k) * sizeof(std::uint32_t), &index, sizeof index);
      }
    model.buffers.push_back(std::move(buffer));

    tinygltf::BufferView vertex_view;
    vertex_view.buffer = 0;
    vertex_view.byteOffset = 0;
    vertex_view.byteLength = nv * 3 * sizeof(float);
    vertex_view.target = TINYGLTF_TARGET_ARRAY_BUFFER;
    tinygltf::BufferView index_view;
    index_view.buffer = 0;
    index_view.byteOffset = nv * 3 * sizeof(float);
    index_view.byteLength = nt * 3 * sizeof(std::uint32_t);
    index_view.target = TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER;
    model.bufferViews = {vertex_view, index_view};

    tinygltf::Accessor position;
    position.bufferView = 0;
    position.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
    position.count = nv;
    position.type = TINYGLTF_TYPE_VEC3;
    position.minValues = lo;
    position.maxValues = hi;
    tinygltf::Accessor indices;
    indices.bufferView = 1;
    indices.componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
    indices.count = nt * 3;
    indices.type = TINYGLTF_TYPE_SCALAR;
    model.accessors = {position, indices};

    tinygltf::Primitive primitive;
    primitive.attributes["POSITION"] = 0;
    primitive.indices = 1;
    primitive.mode = TINYGLTF_MODE_TRIANGLES;
    tinygltf::Mesh gltf_mesh;
    gltf_mesh.name = "preview";
    gltf_mesh.primitives.push_back(primitive);
    model.meshes.push_back(gltf_mesh);
    tinygltf::Node node;
    node.mesh = 0;
    model.nodes.push_back(node);
    scene.nodes.push_back(0);
  }
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  std::ostringstream out;
  tinygltf::TinyGLTF writer;
  writer.WriteGltfSceneToStream(&model, out, false, true);
  return out.str();
}

}  // namespace fabatlas::viewer

// The cutters of a design's carve_swept nodes as job outputs (see swept_volumes.h).
#include "fabatlas/pipeline/swept_volumes.h"

#include <functional>
#include <nlohmann/json.hpp>

#include "fabatlas/mesh/raw_mesh.h"
#include "fabatlas/mesh/write_mesh.h"
#include "fabatlas/precompute/form_outputs.h"

namespace fabatlas::pipeline {

std::vector<SweptVolumeTask> SweptVolumeTasks(const design::Design& design, const sampling::DesignSpace& space) {
  std::vector<std::string> paths;
  std::function<void(const design::Node&, const std::string&)> walk = [&](const design::Node& n,
                                                                          const std::string& path) {
    if (n.op == "carve_swept") paths.push_back(path);
    for (std::size_t i = 0; i < n.children.size(); ++i) walk(n.children[i], path + "/" + std::to_string(i));
  };
  walk(design.tree, "root");
  for (const auto& o : design.objects) walk(o.tree, "object:" + o.name);
  if (paths.empty()) return {};
  sampling::SamplePoint centre;
  for (int d = 0; d < space.dimension_count(); ++d) {
    const auto lo = space.key_lo(d), hi = space.key_hi(d);
    centre.key.push_back(space.can_split(d, lo, hi) ? space.split_key(d, lo, hi) : lo);
  }
  centre.u = space.point(centre.key);
  std::vector<SweptVolumeTask> tasks;
  for (auto& path : paths) tasks.push_back({std::move(path), centre});
  return tasks;
}

void WriteSweptVolumes(const sampling::DesignSpace& space, const std::vector<SweptVolumeTask>& tasks,
                       const std::vector<design::SweptVolumeResult>& results, const std::filesystem::path& out_dir) {
  if (tasks.empty()) return;
  nlohmann::ordered_json json;
  nlohmann::ordered_json point = nlohmann::ordered_json::object();
  for (int d = 0; d < space.dimension_count(); ++d) point[space.dimension(d).name] = tasks[0].point.u[d];
  json["point"] = point;
  json["swept_volumes"] = nlohmann::ordered_json::array();
  for (std::size_t k = 0; k < tasks.size(); ++k) {
    const design::SweptVolumeResult& r = results.at(k);
    std::string mesh_file;
    if (!r.surface_sha256.empty() && !r.surface_bytes.empty()) {
      mesh_file = "swept_" + std::to_string(k) + ".ply";
      mesh::WriteMesh(mesh::MeshOfRawBytes(r.surface_bytes, r.triangles), out_dir / mesh_file);
    }
    json["swept_volumes"].push_back({{"node", tasks[k].node_path},
                                     {"computed", !r.surface_sha256.empty()},
                                     {"volume_mm3", r.volume},
                                     {"triangles", r.triangles},
                                     {"time_steps", r.time_steps},
                                     {"active_voxels", r.active_voxels},
                                     {"surface_sha256", r.surface_sha256},
                                     {"mesh", mesh_file}});
  }
  precompute::WriteFileAtomically(out_dir / "swept_volumes.json", json.dump(2) + "\n");
}

}  // namespace fabatlas::pipeline

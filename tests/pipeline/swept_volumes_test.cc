// Swept volumes as job outputs (pipeline/swept_volumes.h), in this process:
// which nodes and where, and what the writer publishes.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "fabatlas/design/design.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/raw_mesh.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/pipeline/local_executor.h"
#include "fabatlas/pipeline/swept_volumes.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/sha256.h"
#include "fabatlas/testing/paths.h"

namespace fabatlas::pipeline {
namespace {

namespace fs = std::filesystem;

design::Design Capsule() {
  return design::LoadDesign(testing::SourceDir() / "tests/cluster/data/swept_capsule_design.yaml");
}

// One carve_swept node (the plate object's root), at the centre of r in
// [9, 11]; a design without carve_swept nodes has no task.
TEST(SweptVolumeTasks, OneTaskPerCarveSweptNodeAtTheCentreOfTheSpace) {
  const design::Design d = Capsule();
  const auto tasks = SweptVolumeTasks(d, precompute::DesignSpaceOf(d, 4));
  ASSERT_EQ(tasks.size(), 1u);
  EXPECT_EQ(tasks[0].node_path, "object:plate");
  ASSERT_EQ(tasks[0].point.u.size(), 1u);
  EXPECT_EQ(tasks[0].point.u[0], 10.0);
  const design::Design vase = design::LoadDesign(testing::SourceDir() / "configs/designs/vase.yaml");
  EXPECT_TRUE(SweptVolumeTasks(vase, precompute::DesignSpaceOf(vase, 2)).empty());
}

// The writer publishes what the task computed: the unit tetrahedron's bytes
// come back from swept_0.ply vertex for vertex, and the JSON names the node,
// the point and the digest; a result that was not computed has no mesh.
TEST(WriteSweptVolumes, PublishesTheCutterAndItsRecord) {
  const design::Design d = Capsule();
  const sampling::DesignSpace space = precompute::DesignSpaceOf(d, 2);
  auto tasks = SweptVolumeTasks(d, space);
  tasks.push_back(tasks[0]);
  tasks[1].node_path = "object:other";
  mesh::TriangleMesh tet;
  tet.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  tet.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  std::vector<design::SweptVolumeResult> results(2);
  results[0].volume = 1.0 / 6;
  results[0].triangles = 4;
  results[0].surface_bytes = mesh::RawMeshBytes(tet);
  results[0].surface_sha256 = Sha256Hex(results[0].surface_bytes);
  const fs::path dir = fs::temp_directory_path() / ("fabatlas_swept_writer_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  WriteSweptVolumes(space, tasks, results, dir);
  std::ifstream in(dir / "swept_volumes.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["point"]["r"], 10.0);
  ASSERT_EQ(j["swept_volumes"].size(), 2u);
  EXPECT_EQ(j["swept_volumes"][0]["node"], "object:plate");
  EXPECT_EQ(j["swept_volumes"][0]["computed"], true);
  EXPECT_EQ(j["swept_volumes"][0]["surface_sha256"], results[0].surface_sha256);
  EXPECT_EQ(j["swept_volumes"][0]["mesh"], "swept_0.ply");
  EXPECT_EQ(j["swept_volumes"][1]["computed"], false);
  EXPECT_EQ(j["swept_volumes"][1]["mesh"], "");
  EXPECT_FALSE(fs::exists(dir / "swept_1.ply"));
  const mesh::TriangleMesh back = mesh::ReadMesh(dir / "swept_0.ply");
  EXPECT_EQ(back.vertices, tet.vertices);
  EXPECT_EQ(back.triangles, tet.triangles);
  fs::remove_all(dir);
}

// Raw mesh bytes: 24 per vertex + 12 per triangle; sizes that do not fit are
// refused rather than read past.
TEST(RawMesh, SizesThatDoNotFitAreRefused) {
  mesh::TriangleMesh tri;
  tri.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  tri.triangles = {{0, 1, 2}};
  const std::string bytes = mesh::RawMeshBytes(tri);
  EXPECT_EQ(bytes.size(), 3u * 24 + 12);
  EXPECT_EQ(mesh::MeshOfRawBytes(bytes, 1).vertices, tri.vertices);
  EXPECT_THROW(mesh::MeshOfRawBytes(bytes, 2), InputError);
  EXPECT_THROW(mesh::MeshOfRawBytes(bytes.substr(0, bytes.size() - 1), 1), InputError);
}

// The in-process executor computes the capsule of the cluster test
// (tests/cluster/cluster_test.cc ClusterSwept): a sphere of radius 10 pushed
// 40 mm with a 0.5 mm offset, pi R^2 L + 4/3 pi R^3 with R = 10.5, within 1 %.
TEST(LocalExecutor, SweptVolumeOfTheCapsule) {
  const design::Design d = Capsule();
  LocalExecutor executor(d, {});
  const auto results = executor.RunSweptVolumeTasks(SweptVolumeTasks(d, precompute::DesignSpaceOf(d, 2)));
  ASSERT_EQ(results.size(), 1u);
  const double R = 10.5, L = 40;
  const double capsule = M_PI * R * R * L + 4.0 / 3.0 * M_PI * R * R * R;
  EXPECT_NEAR(results[0].volume, capsule, 0.01 * capsule);
  EXPECT_EQ(results[0].surface_sha256, Sha256Hex(results[0].surface_bytes));
}

}  // namespace
}  // namespace fabatlas::pipeline

// The artifact file (artifact/artifact.h): round trip, byte-identical output,
// atomic publication under SIGKILL, one-line errors for damaged files, glTF
// meshes that tinygltf reads back, and the checked-in version-1 artifact.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <thread>

#include "../sampling/analytic_designs.h"
#include "fabatlas/error.h"
#include "fabatlas/sha256.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/sampling/form_json.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/artifact/glb.h"
#include "fabatlas/testing/paths.h"
#include "fabatlas/testing/small_filesystem.h"

namespace fabatlas::artifact {
namespace {

namespace fs = std::filesystem;

std::string ReadBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

void WriteBytes(const fs::path& p, const std::string& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << bytes;
}

// A closed octahedron of "radius" r (8 faces, outward normals).
mesh::TriangleMesh Octahedron(double r) {
  mesh::TriangleMesh m;
  m.vertices = {{r, 0, 0}, {-r, 0, 0}, {0, r, 0}, {0, -r, 0}, {0, 0, r}, {0, 0, -r}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

// The analytic hollow cylinder of tests/sampling sampled for real, plus a
// cache, curves, starting points and a bundle, so every table has rows.
Artifact SmallArtifact() {
  sampling::testing::HollowCylinder2D evaluator;
  sampling::DesignSpace space(sampling::testing::HollowCylinder2D::Dimensions(), 4);
  sampling::ThreadPoolExecutor executor(2);
  sampling::SamplingOptions options;
  options.max_depth = 3;
  options.dg_threshold = 0.1;
  auto summary = sampling::SampleDesignSpace(space, evaluator, executor, options);
  Artifact a;
  a.form = summary.form;
  a.manifest.design_name = "hollow_cylinder";
  a.manifest.design_hash = Sha256Hex("hollow cylinder");
  a.manifest.code_version = "test";
  a.manifest.subdivisions = 4;
  a.manifest.max_depth = options.max_depth;
  a.manifest.dg_threshold = options.dg_threshold;
  a.manifest.max_samples = options.max_samples;
  a.manifest.statistics = StatisticsOf(a.form);
  a.manifest.cache.strategy = "opt_max";
  a.manifest.cache.cost_model = "test";
  for (int i = 0; i < 3; ++i) {
    CacheEntry e;
    e.grid = "grid bytes " + std::to_string(i);
    e.key = Sha256Hex(e.grid);
    e.op = i == 2 ? "union" : "revolve";
    e.bytes = 1000 * (i + 1);
    e.cost_seconds = 0.25 * (i + 1);
    e.in_opt = i != 1;
    e.glb = MeshToGlb(Octahedron(1.0 + i));
    a.cache.push_back(e);
  }
  a.cache[2].children = {a.cache[0].key, a.cache[1].key};
  a.cache_curves = {{"opt_max", 0, 0, 0, 1.5, 3.0}, {"opt_max", 1, 1, 3000, 1.0, 2.0}, {"naive", 0, 0, 0, 1.5, 3.0}};
  for (std::int64_t id = 0; id < static_cast<std::int64_t>(a.form.samples.size()); ++id)
    if (a.form.samples[id].outcome.valid) {
      a.starting_points.push_back({id, 0, {}});
      break;
    }
  a.bundle.job_file_name = "job.yaml";
  a.bundle.job_file = "design: ../designs/d.yaml\n";
  a.bundle.design_file_name = "d.yaml";
  a.bundle.design_file = "name: d\n";
  a.bundle.files["meshes/part.stl"] = std::string("solid\0binary", 12);
  return a;
}

TEST(Artifact, RoundTripKeepsEveryTable) {
  const Artifact a = SmallArtifact();
  ASSERT_GT(a.form.samples.size(), 25u);
  const fs::path path = testing::FreshTempDir("artifact") / "hollow.fabatlas";
  WriteArtifact(a, path);
  const Artifact b = ReadArtifact(path);
  // The form is compared through its canonical JSON (every sample, node and ΔG).
  EXPECT_EQ(sampling::FormToJson(b.form), sampling::FormToJson(a.form));
  EXPECT_EQ(b.manifest.schema_version, kArtifactSchemaVersion);
  EXPECT_EQ(b.manifest.design_hash, a.manifest.design_hash);
  EXPECT_EQ(b.manifest.statistics.samples, static_cast<std::int64_t>(a.form.samples.size()));
  EXPECT_EQ(b.manifest.statistics.valid_volume_percent, a.manifest.statistics.valid_volume_percent);
  EXPECT_EQ(b.manifest.statistics.failure_shares, a.manifest.statistics.failure_shares);
  EXPECT_EQ(b.manifest.dg_threshold, 0.1);
  EXPECT_EQ(b.manifest.checksums.size(), 10u);
  ASSERT_EQ(b.cache.size(), 3u);
  for (const auto& e : b.cache) {
    auto it = std::find_if(a.cache.begin(), a.cache.end(), [&](const CacheEntry& x) { return x.key == e.key; });
    ASSERT_NE(it, a.cache.end());
    EXPECT_EQ(e.grid, it->grid);
    EXPECT_EQ(e.glb, it->glb);
    EXPECT_EQ(e.children, it->children);
    EXPECT_EQ(e.in_opt, it->in_opt);
    EXPECT_EQ(e.grid_sha256, Sha256Hex(e.grid));
  }
  EXPECT_EQ(b.cache_curves.size(), 3u);
  EXPECT_EQ(b.cache_curves[0].strategy, "naive");  // sorted by (strategy, step)
  ASSERT_EQ(b.starting_points.size(), 1u);
  EXPECT_EQ(b.starting_points[0].u, a.form.samples[a.starting_points[0].sample_id].u);
  EXPECT_EQ(b.bundle.files, a.bundle.files);
  EXPECT_EQ(b.bundle.design_file, a.bundle.design_file);
  EXPECT_EQ(b.bundle.job_file_name, "job.yaml");

  // Metadata-only reads skip the geometry bytes.
  const Artifact c = ReadArtifact(path, {.load_geometry = false});
  EXPECT_TRUE(c.cache[0].grid.empty());
  EXPECT_FALSE(c.cache[0].grid_sha256.empty());
  // The stored valid volume % against two independent values: (1) the
  // valid region t >= 0.5 + 0.01 R^2 is convex, so every all-valid leaf lies
  // inside it and the estimate cannot exceed the analytic 61.11 %; (2) the
  // share of a 600 x 600 grid of cell centres that the read-back form puts
  // in its estimated valid region (point location, not the leaf volumes the
  // statistic sums) agrees to within the grid's resolution.
  const double stored = b.manifest.statistics.valid_volume_percent;
  EXPECT_LE(stored, 100.0 * 41.25 / 67.5);
  const auto space = b.form.space();
  int inside = 0;
  constexpr int kGrid = 600;
  for (int i = 0; i < kGrid; ++i)
    for (int j = 0; j < kGrid; ++j)
      inside += sampling::InEstimatedValidRegion(b.form, space,
                                                 {5.0 + 15.0 * (i + 0.5) / kGrid, 0.5 + 4.5 * (j + 0.5) / kGrid});
  EXPECT_NEAR(stored, 100.0 * inside / (kGrid * kGrid), 0.5);
}

TEST(Artifact, EqualContentGivesIdenticalBytes) {
  const fs::path dir = testing::FreshTempDir("artifact");
  Artifact a = SmallArtifact();
  WriteArtifact(a, dir / "one.fabatlas");
  // Same content, cache entries and curves given in another order.
  std::reverse(a.cache.begin(), a.cache.end());
  std::reverse(a.cache_curves.begin(), a.cache_curves.end());
  WriteArtifact(a, dir / "two.fabatlas");
  // And what a reader got back, written again.
  WriteArtifact(ReadArtifact(dir / "one.fabatlas"), dir / "three.fabatlas");
  const std::string one = ReadBytes(dir / "one.fabatlas");
  EXPECT_EQ(one.size() % 4096, 0u);
  EXPECT_EQ(one, ReadBytes(dir / "two.fabatlas"));
  EXPECT_EQ(one, ReadBytes(dir / "three.fabatlas"));
  // A different ΔG value changes the bytes.
  a.form.geometry_changes.begin()->second += 1e-9;
  WriteArtifact(a, dir / "four.fabatlas");
  EXPECT_NE(one, ReadBytes(dir / "four.fabatlas"));
}

TEST(Artifact, StandardToolsReadIt) {
  const fs::path path = testing::FreshTempDir("artifact") / "hollow.fabatlas";
  const Artifact a = SmallArtifact();
  WriteArtifact(a, path);
  const fs::path out = path.parent_path() / "count.txt";
  const std::string command =
      "sqlite3 " + path.string() + " \"SELECT count(*) || ' ' || sum(valid) FROM samples\" > " + out.string();
  ASSERT_EQ(std::system(command.c_str()), 0);
  std::int64_t valid = 0;
  for (const auto& s : a.form.samples) valid += s.outcome.valid;
  EXPECT_EQ(ReadBytes(out), std::to_string(a.form.samples.size()) + " " + std::to_string(valid) + "\n");
}

TEST(Artifact, GlbRoundTripsThroughTinygltf) {
  const mesh::TriangleMesh m = Octahedron(2.5);
  const std::string glb = MeshToGlb(m);
  EXPECT_EQ(glb.substr(0, 4), "glTF");
  EXPECT_EQ(glb, MeshToGlb(m));
  const mesh::TriangleMesh back = GlbToMesh(glb);
  ASSERT_EQ(back.vertices.size(), 6u);
  ASSERT_EQ(back.triangles, m.triangles);
  for (std::size_t i = 0; i < 6; ++i)
    for (int k = 0; k < 3; ++k) EXPECT_EQ(back.vertices[i][k], m.vertices[i][k]);
  EXPECT_THROW(GlbToMesh("not a glb at all"), InputError);
  EXPECT_TRUE(GlbToMesh(MeshToGlb({})).empty());
}

// One line, starting with the path, containing `what`.
void ExpectReadError(const fs::path& path, const std::string& what) {
  try {
    ReadArtifact(path);
    ADD_FAILURE() << "no error for " << path << " (expected '" << what << "')";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.rfind(path.string() + ": ", 0), 0u) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
}

TEST(Artifact, DamagedFilesGiveOneLineErrors) {
  const fs::path dir = testing::FreshTempDir("artifact");
  const fs::path good = dir / "good.fabatlas";
  WriteArtifact(SmallArtifact(), good);
  const std::string bytes = ReadBytes(good);

  ExpectReadError(dir / "missing.fabatlas", "no such file");
  WriteBytes(dir / "text.fabatlas", "design: vase\n");
  ExpectReadError(dir / "text.fabatlas", "not an SQLite database");
  WriteBytes(dir / "empty.fabatlas", "");
  ExpectReadError(dir / "empty.fabatlas", "not an SQLite database");
  WriteBytes(dir / "half.fabatlas", bytes.substr(0, bytes.size() / 2));
  ExpectReadError(dir / "half.fabatlas", "truncated");
  WriteBytes(dir / "header.fabatlas", bytes.substr(0, 60));
  ExpectReadError(dir / "header.fabatlas", "truncated");

  // Another SQLite database (the job store's kind of file).
  const fs::path other = dir / "other.db";
  ASSERT_EQ(std::system(("sqlite3 " + other.string() + " 'CREATE TABLE t(x); INSERT INTO t VALUES (1);'").c_str()), 0);
  ExpectReadError(other, "not a fabatlas artifact");

  // A newer schema version in the header (user_version, offset 60).
  std::string newer = bytes;
  newer[63] = static_cast<char>(kArtifactSchemaVersion + 1);
  WriteBytes(dir / "newer.fabatlas", newer);
  ExpectReadError(dir / "newer.fabatlas",
                  "written by a newer fabatlas (schema version " + std::to_string(kArtifactSchemaVersion + 1) +
                      "; this reader knows versions 1 to " + std::to_string(kArtifactSchemaVersion) + ")");

  // A ΔG value altered in place (the file stays a valid database).
  const fs::path altered = dir / "altered.fabatlas";
  fs::copy_file(good, altered);
  ASSERT_EQ(std::system(("sqlite3 " + altered.string() +
                         " 'UPDATE geometry_changes SET dg = dg + 0.5 WHERE a = (SELECT min(a) FROM geometry_changes)'")
                            .c_str()),
            0);
  ExpectReadError(altered, "table geometry_changes does not match its checksum");

  // A dropped table.
  const fs::path dropped = dir / "dropped.fabatlas";
  fs::copy_file(good, dropped);
  ASSERT_EQ(std::system(("sqlite3 " + dropped.string() + " 'DROP TABLE samples'").c_str()), 0);
  ExpectReadError(dropped, "no such table: samples");

  // Bytes flipped inside the data pages: every 512th byte after the header
  // page. Whatever SQLite or the checksums notice, it is one line.
  std::string flipped = bytes;
  for (std::size_t i = 4096 + 100; i < flipped.size(); i += 512) flipped[i] = static_cast<char>(flipped[i] ^ 0x5a);
  WriteBytes(dir / "flipped.fabatlas", flipped);
  ExpectReadError(dir / "flipped.fabatlas", "");
}

// Kills a process that publishes a large artifact over an existing one, at
// moments spread over the write: the final name always holds one complete
// artifact (the old or the new), never a partial file.
TEST(Artifact, KilledWriterNeverLeavesAPartialArtifact) {
  const fs::path dir = testing::FreshTempDir("artifact");
  const fs::path path = dir / "job.fabatlas";
  Artifact small = SmallArtifact();
  Artifact large = small;
  // ~24 MiB of cache geometry makes the write take long enough to interrupt.
  for (auto& e : large.cache) e.grid.assign(8 << 20, static_cast<char>('a' + e.bytes / 1000));
  WriteArtifact(small, path);
  const std::string old_bytes = ReadBytes(path);

  // Time one undisturbed write to spread the kills over it.
  const auto t0 = std::chrono::steady_clock::now();
  WriteArtifact(large, dir / "timing.fabatlas");
  const double write_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const std::string new_bytes = ReadBytes(dir / "timing.fabatlas");
  ASSERT_NE(old_bytes, new_bytes);

  int saw_old = 0, saw_new = 0;
  for (int trial = 0; trial < 8; ++trial) {
    WriteArtifact(small, path);
    pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      try {
        WriteArtifact(large, path);
      } catch (...) {
        ::_exit(3);
      }
      ::_exit(0);
    }
    const double at_ms = write_ms * (0.1 + 0.2 * trial);
    std::this_thread::sleep_for(std::chrono::microseconds(static_cast<long>(at_ms * 1000)));
    ::kill(pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    const std::string now = ReadBytes(path);
    ASSERT_TRUE(now == old_bytes || now == new_bytes) << "trial " << trial << ": " << now.size() << " bytes";
    (now == old_bytes ? saw_old : saw_new)++;
    EXPECT_NO_THROW(ReadArtifact(path, {.load_geometry = false}));
  }
  // At least the early kills interrupted a write.
  EXPECT_GT(saw_old, 0);
  // Leftover temporary files never carry the final name.
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "job.fabatlas" || name == "timing.fabatlas" || name.find(".tmp-") != std::string::npos) << name;
  }
  std::cout << "write " << write_ms << " ms; kills left the old file " << saw_old << "x, the new one " << saw_new
            << "x\n";
}

// A full disk (a 4 MiB tmpfs; the new artifact needs ~24 MiB): publishing
// over an existing artifact fails with one line naming the file and the
// full disk, the old artifact stays byte for byte, no temporary file is
// left behind, and once space is back (the temporary file's was given back
// at once) the next write succeeds.
TEST(Artifact, FullDiskKeepsTheOldArtifactAndLeavesNothingBehind) {
  if (!testing::SmallFileSystem::Possible()) GTEST_SKIP() << "mounting a small tmpfs needs root";
  const fs::path dir = testing::FreshTempDir("artifact-full");
  testing::SmallFileSystem disk(dir / "mnt", 4);
  ASSERT_TRUE(disk.mounted()) << disk.error();
  const fs::path path = disk.dir() / "job.fabatlas";
  Artifact small = SmallArtifact();
  Artifact large = small;
  for (auto& e : large.cache) e.grid.assign(8 << 20, static_cast<char>('a' + e.bytes / 1000));
  WriteArtifact(small, path);
  const std::string old_bytes = ReadBytes(path);
  try {
    WriteArtifact(large, path);
    ADD_FAILURE() << "a 24 MiB artifact was written into 4 MiB";
  } catch (const ResourceError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what, path.string() + ": disk full while writing the artifact");
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
  EXPECT_TRUE(ReadBytes(path) == old_bytes) << "the old artifact was changed";
  EXPECT_NO_THROW(ReadArtifact(path));
  for (const auto& entry : fs::directory_iterator(disk.dir()))
    EXPECT_EQ(entry.path().filename(), "job.fabatlas") << "left behind: " << entry.path();
  // Space is back: a write that fits succeeds.
  Artifact other = small;
  other.manifest.code_version = "after the full disk";
  WriteArtifact(other, path);
  EXPECT_EQ(ReadArtifact(path, {.load_geometry = false}).manifest.code_version, "after the full disk");
}

TEST(Artifact, WriterRejectsInconsistentContent) {
  const fs::path dir = testing::FreshTempDir("artifact");
  Artifact a = SmallArtifact();
  a.starting_points.push_back({999999, 0, {}});
  EXPECT_THROW(WriteArtifact(a, dir / "bad.fabatlas"), InputError);
  EXPECT_FALSE(fs::exists(dir / "bad.fabatlas"));
  Artifact b = SmallArtifact();
  b.cache.push_back(b.cache[0]);
  EXPECT_THROW(WriteArtifact(b, dir / "bad.fabatlas"), InputError);
  for (const auto& entry : fs::directory_iterator(dir)) ADD_FAILURE() << "left " << entry.path();
}

}  // namespace
}  // namespace fabatlas::artifact

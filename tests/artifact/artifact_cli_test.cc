// The artifact end to end, as a user runs it: `fabatlas run` publishes
// <design>.fabatlas, byte-identical for 1 and 2 workers and for the in-process
// `fabatlas sample`; `fabatlas inspect` reports its Table 3 and Fig. 14 rows;
// damaged files give one-line errors and exit status 2; the checked-in
// version-1 artifact keeps reading. The design is the closed-form tube
// (valid iff wall >= 1 + 0.01 radius^2 and radius - wall >= 2), so every
// sample's validity is checked against the formula, not against a recording.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "fabatlas/error.h"
#include "fabatlas/sampling/form.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/storage/job_store.h"
#include "fabatlas/artifact/glb.h"
#include "fabatlas/testing/command_run.h"
#include "fabatlas/testing/paths.h"
#include "fabatlas/testing/small_filesystem.h"
#include "fabatlas/viewer/customiser.h"

namespace {

namespace fs = std::filesystem;
using fabatlas::testing::BinDir;
using fabatlas::testing::FreshTempDir;
using fabatlas::testing::SourceDir;

using fabatlas::testing::CommandRun;
using fabatlas::testing::Fabatlas;

std::string Bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

fs::path Job() { return SourceDir() / "tests/cluster/data/tube_small.yaml"; }

bool TubeValid(const std::vector<double>& u) {
  const double radius = u[0], wall = u[1];
  return wall >= 1 + 0.01 * radius * radius && radius - wall >= 2;
}

// Every sample's validity agrees with the closed form (up to the constraint
// solver's tolerance at the boundary: samples within 1e-6 of it are skipped).
void ExpectTubeForm(const fabatlas::sampling::Form& form) {
  int checked = 0;
  for (const auto& s : form.samples) {
    const double r = s.u[0], w = s.u[1];
    const double margin = std::min(std::abs(w - (1 + 0.01 * r * r)), std::abs(r - w - 2));
    if (margin < 1e-6) continue;
    EXPECT_EQ(s.outcome.valid, TubeValid(s.u)) << "radius " << r << " wall " << w;
    ++checked;
  }
  EXPECT_GT(checked, 20);
}

// `fabatlas sample` onto a full disk (a filled 1 MiB tmpfs): one line naming
// the file it could not write and the full disk, exit status 2, and nothing
// half-written in the output directory; once space is back the same command
// publishes the artifact a run on an ordinary disk publishes, byte for byte.
TEST(ArtifactCli, SampleOntoAFullDiskFailsCleanlyAndSucceedsOnceSpaceIsBack) {
  if (!fabatlas::testing::SmallFileSystem::Possible()) GTEST_SKIP() << "mounting a small tmpfs needs root";
  const fs::path dir = FreshTempDir("artifact-full");
  fabatlas::testing::SmallFileSystem disk(dir / "mnt", 1);
  ASSERT_TRUE(disk.mounted()) << disk.error();
  disk.Fill();
  const fs::path out = disk.dir() / "out";
  CommandRun full = Fabatlas("sample " + Job().string() + " --out " + out.string());
  EXPECT_EQ(full.status, 2) << full.out << full.err;
  EXPECT_EQ(std::count(full.err.begin(), full.err.end(), '\n'), 1) << full.err;
  EXPECT_NE(full.err.find(": " + out.string() + "/"), std::string::npos) << full.err;
  EXPECT_NE(full.err.find("disk full"), std::string::npos) << full.err;
  if (fs::exists(out))
    for (const auto& entry : fs::recursive_directory_iterator(out))
      ADD_FAILURE() << "left behind on the full disk: " << entry.path();
  disk.Free();
  CommandRun again = Fabatlas("sample " + Job().string() + " --out " + out.string());
  ASSERT_EQ(again.status, 0) << again.err;
  CommandRun local = Fabatlas("sample " + Job().string() + " --out " + (dir / "local").string());
  ASSERT_EQ(local.status, 0) << local.err;
  EXPECT_TRUE(Bytes(out / "tube_wall_2d.fabatlas") == Bytes(dir / "local/tube_wall_2d.fabatlas"));
  EXPECT_EQ(Bytes(out / "form.json"), Bytes(dir / "local/form.json"));
}

TEST(ArtifactCli, RunPublishesTheSameBytesForOneAndTwoWorkersAndInProcess) {
  const fs::path dir = FreshTempDir("artifact-cli");
  CommandRun one = Fabatlas("run " + Job().string() + " --workers 1 --quiet --out " + (dir / "one").string());
  ASSERT_EQ(one.status, 0) << one.err;
  EXPECT_NE(one.out.find("tube_wall_2d.fabatlas"), std::string::npos) << one.out;
  CommandRun two = Fabatlas("run " + Job().string() + " --workers 2 --quiet --out " + (dir / "two").string());
  ASSERT_EQ(two.status, 0) << two.err;
  CommandRun local = Fabatlas("sample " + Job().string() + " --out " + (dir / "local").string());
  ASSERT_EQ(local.status, 0) << local.err;
  const std::string a = Bytes(dir / "one/tube_wall_2d.fabatlas");
  ASSERT_GT(a.size(), 4096u);
  EXPECT_TRUE(a == Bytes(dir / "two/tube_wall_2d.fabatlas")) << "1 vs 2 workers";
  EXPECT_TRUE(a == Bytes(dir / "local/tube_wall_2d.fabatlas")) << "cluster vs in-process";

  const auto artifact = fabatlas::artifact::ReadArtifact(dir / "one/tube_wall_2d.fabatlas");
  ExpectTubeForm(artifact.form);
  EXPECT_EQ(artifact.manifest.design_name, "tube_wall_2d");
  EXPECT_EQ(artifact.bundle.job_file_name, "tube_small.yaml");
  // The form inside is the form.json published beside it.
  std::ifstream form_json(dir / "one/form.json");
  const auto j = nlohmann::json::parse(form_json);
  EXPECT_EQ(j.at("samples").size(), artifact.form.samples.size());
}

// A job with a cache section: the cluster plans the cache from what its
// workers reported (subtree records, uploaded blobs) and publishes the same
// bytes as the in-process run that collects the subtrees itself.
TEST(ArtifactCli, CachedJobPublishesTheSameBytesOnTheClusterAndInProcess) {
  const fs::path dir = FreshTempDir("artifact-cli");
  const fs::path job = dir / "tube_cache.yaml";
  std::ofstream(job) << "design: " << (SourceDir() / "configs/designs/tube_wall_2d.yaml").string()
                     << "\nsampling: {subdivisions: 2, max_depth: 0}\n"
                     << "cache: {strategy: opt_max, min_subtree_seconds: 0}\n";
  CommandRun run = Fabatlas("run " + job.string() + " --workers 2 --quiet --out " + (dir / "run").string());
  ASSERT_EQ(run.status, 0) << run.err;
  CommandRun local = Fabatlas("sample " + job.string() + " --out " + (dir / "local").string());
  ASSERT_EQ(local.status, 0) << local.err;
  const auto a = fabatlas::artifact::ReadArtifact(dir / "run/tube_wall_2d.fabatlas");
  EXPECT_EQ(a.manifest.cache.strategy, "opt_max");
  EXPECT_GT(a.cache.size(), 0u);
  EXPECT_EQ(a.manifest.cache.top_entries, a.manifest.statistics.valid_samples);
  EXPECT_TRUE(Bytes(dir / "run/tube_wall_2d.fabatlas") == Bytes(dir / "local/tube_wall_2d.fabatlas"));
}

TEST(ArtifactCli, InspectPrintsTable3AndFig14Rows) {
  const fs::path dir = FreshTempDir("artifact-cli");
  CommandRun run = Fabatlas("sample " + Job().string() + " --out " + dir.string());
  ASSERT_EQ(run.status, 0) << run.err;
  const fs::path art = dir / "tube_wall_2d.fabatlas";
  CommandRun r = Fabatlas("inspect " + art.string() + " --json --points 20");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  std::ifstream stats_in(dir / "statistics.json");
  const auto stats = nlohmann::json::parse(stats_in);
  // Table 3 agrees with what the sampler reported for the same run.
  EXPECT_EQ(j["table3"]["samples"], stats["samples"]);
  EXPECT_DOUBLE_EQ(j["table3"]["valid_volume_percent"].get<double>(), stats["valid_volume_percent"].get<double>());
  EXPECT_DOUBLE_EQ(j["table3"]["cpu_seconds"].get<double>(), stats["evaluator_cpu_seconds"].get<double>());
  EXPECT_EQ(j["table3"]["failure_shares"], stats["failure_shares"]);
  // Fig. 14: 20 points of the valid region, all previewed with geometry.
  EXPECT_EQ(j["fig14"]["points"], 20);
  ASSERT_TRUE(j["fig14"]["t_nocache"].is_object());
  EXPECT_EQ(j["fig14"]["t_nocache"]["failures"], 0);
  EXPECT_GT(j["fig14"]["t_nocache"]["mean_seconds"].get<double>(), 0.0);
  EXPECT_GE(j["fig14"]["t_nocache"]["worst_seconds"].get<double>(),
            j["fig14"]["t_nocache"]["mean_seconds"].get<double>());

  CommandRun text = Fabatlas("inspect " + art.string() + " --points 5");
  ASSERT_EQ(text.status, 0) << text.err;
  EXPECT_NE(text.out.find("Table 3: tube_wall_2d  |U|=2  samples " + stats["samples"].dump()), std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("Fig. 14:"), std::string::npos) << text.out;
}

TEST(ArtifactCli, DamagedArtifactsAreOneLineErrorsWithStatus2) {
  const fs::path dir = FreshTempDir("artifact-cli");
  CommandRun run = Fabatlas("sample " + Job().string() + " --out " + dir.string());
  ASSERT_EQ(run.status, 0) << run.err;
  const std::string bytes = Bytes(dir / "tube_wall_2d.fabatlas");
  std::ofstream(dir / "cut.fabatlas", std::ios::binary) << bytes.substr(0, bytes.size() - 4096);
  std::ofstream(dir / "text.fabatlas") << "hello\n";
  // As a newer fabatlas would write it: user_version (header offset 60) one
  // above what this reader knows.
  std::string newer = bytes;
  newer[63] = static_cast<char>(fabatlas::artifact::kArtifactSchemaVersion + 1);
  std::ofstream(dir / "newer.fabatlas", std::ios::binary) << newer;
  for (const auto& [file, what] : std::vector<std::pair<std::string, std::string>>{
           {"cut.fabatlas", "truncated"},
           {"text.fabatlas", "not a fabatlas artifact"},
           {"none.fabatlas", "no such file"},
           {"newer.fabatlas", "written by a newer fabatlas (schema version " +
                                  std::to_string(fabatlas::artifact::kArtifactSchemaVersion + 1)}}) {
    CommandRun r = Fabatlas("inspect " + (dir / file).string());
    EXPECT_EQ(r.status, 2) << file;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find((dir / file).string() + ": "), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
  }
}

TEST(ArtifactCli, SampleWithCacheStoresHoptAndHrfreeEntriesThatInspectReloads) {
  const fs::path dir = FreshTempDir("artifact-cli");
  const fs::path job = dir / "tube_cache.yaml";
  std::ofstream(job) << "design: " << (SourceDir() / "configs/designs/tube_wall_2d.yaml").string()
                     << "\nsampling: {subdivisions: 3, max_depth: 1, dg_threshold: 0.05}\n"
                     << "cache: {strategy: opt_max, min_subtree_seconds: 0, store_rfree: true}\n";
  CommandRun run = Fabatlas("sample " + job.string() + " --cache --out " + (dir / "out").string());
  ASSERT_EQ(run.status, 0) << run.err;
  EXPECT_NE(run.out.find("cache opt_max: H_TOP"), std::string::npos) << run.out;
  const auto a = fabatlas::artifact::ReadArtifact(dir / "out/tube_wall_2d.fabatlas");
  const auto& c = a.manifest.cache;
  EXPECT_EQ(c.strategy, "opt_max");
  // H_TOP is one root per valid sample.
  EXPECT_EQ(c.top_entries, a.manifest.statistics.valid_samples);
  EXPECT_GT(c.rfree_entries, 0);
  EXPECT_LE(c.rfree_bytes, c.top_bytes);
  std::int64_t rfree = 0;
  for (const auto& e : a.cache) {
    rfree += e.in_rfree;
    EXPECT_FALSE(fabatlas::artifact::GlbToMesh(e.glb).empty()) << e.key;
  }
  EXPECT_EQ(rfree, c.rfree_entries);
  EXPECT_FALSE(a.cache_curves.empty());
  EXPECT_FALSE(a.starting_points.empty());
  CommandRun r = Fabatlas("inspect " + (dir / "out/tube_wall_2d.fabatlas").string() + " --json --points 10");
  ASSERT_EQ(r.status, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j["fig14"]["t_rfree"].is_object()) << r.out;
  EXPECT_EQ(j["fig14"]["t_rfree"]["failures"], 0);
  EXPECT_EQ(j["fig14"]["h_rfree"]["entries"], c.rfree_entries);
  ASSERT_TRUE(j["fig13_png"].is_string());
  EXPECT_TRUE(fs::file_size(j["fig13_png"].get<std::string>()) > 1000);

  // Without store_rfree (the default) and with a budget below H_rfree, the
  // file holds H_opt's entries only; the manifest still has H_rfree's size
  // and inspect reports no t_rfree rather than a time over part of it.
  const std::int64_t budget = c.rfree_bytes / 2;
  std::ofstream(dir / "tight.yaml") << "design: " << (SourceDir() / "configs/designs/tube_wall_2d.yaml").string()
                                    << "\nsampling: {subdivisions: 3, max_depth: 1, dg_threshold: 0.05}\n"
                                    << "cache: {strategy: opt_max, min_subtree_seconds: 0, budget_mb: "
                                    << static_cast<double>(budget) / (1 << 20) << "}\n";
  CommandRun tight = Fabatlas("sample " + (dir / "tight.yaml").string() + " --out " + (dir / "tight").string());
  ASSERT_EQ(tight.status, 0) << tight.err;
  const auto t = fabatlas::artifact::ReadArtifact(dir / "tight/tube_wall_2d.fabatlas", {.load_geometry = false});
  EXPECT_EQ(t.manifest.cache.rfree_entries, c.rfree_entries);
  EXPECT_EQ(t.manifest.cache.rfree_bytes, c.rfree_bytes);
  EXPECT_LT(t.manifest.cache.budget_bytes, c.rfree_bytes);
  EXPECT_LE(t.manifest.cache.opt_bytes, t.manifest.cache.budget_bytes);
  EXPECT_LT(t.manifest.cache.opt_entries, c.rfree_entries);
  EXPECT_EQ(static_cast<std::int64_t>(t.cache.size()), t.manifest.cache.opt_entries);
  for (const auto& e : t.cache) EXPECT_TRUE(e.in_opt) << e.key;
  CommandRun ti = Fabatlas("inspect " + (dir / "tight/tube_wall_2d.fabatlas").string() + " --json --points 5");
  ASSERT_EQ(ti.status, 0) << ti.err;
  const auto tj = nlohmann::json::parse(ti.out);
  EXPECT_TRUE(tj["fig14"]["t_opt"].is_object()) << ti.out;
  EXPECT_TRUE(tj["fig14"]["t_rfree"].is_null()) << ti.out;

  // A bad cache section is a one-line error naming the job file.
  std::ofstream(dir / "bad.yaml") << "design: " << (SourceDir() / "configs/designs/tube_wall_2d.yaml").string()
                                  << "\ncache: {strategy: fastest}\n";
  CommandRun bad = Fabatlas("sample " + (dir / "bad.yaml").string() + " --cache --out " + (dir / "bad").string());
  EXPECT_EQ(bad.status, 2);
  EXPECT_NE(bad.err.find("bad.yaml: cache: strategy 'fastest'"), std::string::npos) << bad.err;
}

// tests/data/artifact_v1/ holds an artifact written by schema version 1 from
// a real `fabatlas run` (command in its README). Later readers must read it.
TEST(ArtifactCli, CheckedInVersion1ArtifactStaysReadable) {
  const fs::path v1 = SourceDir() / "tests/data/artifact_v1/tube_wall_2d.fabatlas";
  const auto a = fabatlas::artifact::ReadArtifact(v1);
  EXPECT_EQ(a.manifest.schema_version, 1);
  EXPECT_EQ(a.manifest.design_name, "tube_wall_2d");
  EXPECT_EQ(a.manifest.statistics.samples, static_cast<std::int64_t>(a.form.samples.size()));
  ExpectTubeForm(a.form);
  // The stored statistics are those of the stored form.
  const auto recomputed = fabatlas::artifact::StatisticsOf(a.form);
  EXPECT_EQ(recomputed.valid_samples, a.manifest.statistics.valid_samples);
  EXPECT_DOUBLE_EQ(recomputed.valid_volume_percent, a.manifest.statistics.valid_volume_percent);
  // The valid region is convex (the epigraph of a parabola cut by a half
  // plane), so a leaf box whose corners are all valid lies inside it: every
  // point of the estimated valid region must be truly valid.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> radius(5, 30), wall(0.5, 12);
  int inside = 0;
  for (int i = 0; i < 2000; ++i) {
    const std::vector<double> u{radius(rng), wall(rng)};
    if (!fabatlas::sampling::InEstimatedValidRegion(a.form, u)) continue;
    ++inside;
    EXPECT_TRUE(TubeValid(u)) << u[0] << " " << u[1];
  }
  EXPECT_GT(inside, 100);
  const fs::path pictures = FreshTempDir("artifact-cli");  // not beside the checked-in artifact
  CommandRun r = Fabatlas("inspect " + v1.string() + " --points 5 --json --png " + (pictures / "f.png").string() +
                          " --fig14-png " + (pictures / "f14.png").string());
  EXPECT_EQ(r.status, 0) << r.err;
}

}  // namespace

// More than 6 dimensions end to end: the closed-form 8-D box
// (configs/designs/box_8d.yaml, valid iff a0 + a1 <= 4.5) sampled by
// `fabatlas sample`, published as a schema-v2 artifact with one u column per
// dimension, read back, inspected and looked up by the customiser runtime.
TEST(ArtifactCli, EightDimensionalJobEndToEnd) {
  const fs::path dir = FreshTempDir("artifact-8d");
  CommandRun r = Fabatlas("sample " + (SourceDir() / "tests/artifact/data/box_8d.yaml").string() + " --out " +
                          (dir / "out").string());
  ASSERT_EQ(r.status, 0) << r.err;
  const fs::path path = dir / "out/box_8d.fabatlas";
  const auto a = fabatlas::artifact::ReadArtifact(path);
  EXPECT_EQ(a.manifest.schema_version, fabatlas::artifact::kArtifactSchemaVersion);
  ASSERT_EQ(a.form.dimensions.size(), 8u);
  auto truly_valid = [](const std::vector<double>& u) { return u[0] + u[1] <= 4.5; };
  // 3^8 would be the whole subdivision-2 grid; the bootstrap alone is 2^8.
  ASSERT_GE(a.form.samples.size(), 256u);
  for (const auto& s : a.form.samples) {
    ASSERT_EQ(s.u.size(), 8u);
    EXPECT_EQ(s.outcome.valid, truly_valid(s.u)) << s.u[0] << " " << s.u[1];
  }
  // The valid region is convex (a half-space), so every point of the
  // estimated valid region is truly valid, and the estimate is at most the
  // analytic 71.875 %.
  EXPECT_LE(a.manifest.statistics.valid_volume_percent, 71.875);
  EXPECT_GT(a.manifest.statistics.valid_volume_percent, 0.0);
  fabatlas::viewer::Customiser customiser(fabatlas::viewer::LoadArtifact(path));
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> value(1, 3);
  int inside = 0;
  for (int i = 0; i < 2000; ++i) {
    std::vector<double> u(8);
    for (auto& x : u) x = value(rng);
    if (!customiser.IsValid(u)) continue;
    ++inside;
    EXPECT_TRUE(truly_valid(u)) << u[0] << " " << u[1];
    // The valid stretches along a0 through u end no later than 4.5 - a1.
    for (const auto& s : customiser.Stretches(u, 0))
      if (s.valid) {
        EXPECT_LE(s.hi, 4.5 - u[1] + 1e-9);
      }
  }
  EXPECT_GT(inside, 100);
  // The table has exactly the 8 coordinate columns.
  CommandRun schema = {};
  {
    const std::string cmd = "sqlite3 " + path.string() + " 'SELECT name FROM pragma_table_info(\"samples\")'";
    FILE* pipe = ::popen(cmd.c_str(), "r");
    std::array<char, 4096> buf;
    std::size_t n;
    while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) schema.out.append(buf.data(), n);
    ::pclose(pipe);
  }
  EXPECT_EQ(schema.out, "id\nkey\nu0\nu1\nu2\nu3\nu4\nu5\nu6\nu7\nvalid\nfailure\n");
  CommandRun inspect = Fabatlas("inspect " + path.string() + " --points 5 --json");
  ASSERT_EQ(inspect.status, 0) << inspect.err;
  const auto j = nlohmann::json::parse(inspect.out);
  EXPECT_EQ(j["schema_version"], fabatlas::artifact::kArtifactSchemaVersion);
  EXPECT_EQ(j["table3"]["samples"], a.form.samples.size());
  EXPECT_EQ(j["fig14"]["t_nocache"]["points"], 5);
}

// The checked-in version-1 artifact, read and written again, becomes a
// current-version file with the same content: same form, bundle and cache,
// one u column per dimension instead of u0..u5.
TEST(ArtifactCli, Version1ArtifactMigratesToTheCurrentVersion) {
  const fs::path v1 = SourceDir() / "tests/data/artifact_v1/tube_wall_2d.fabatlas";
  const auto old = fabatlas::artifact::ReadArtifact(v1);
  const fs::path path = FreshTempDir("artifact-migrate") / "tube_wall_2d.fabatlas";
  fabatlas::artifact::WriteArtifact(old, path);
  const auto now = fabatlas::artifact::ReadArtifact(path);
  EXPECT_EQ(old.manifest.schema_version, 1);
  EXPECT_EQ(now.manifest.schema_version, fabatlas::artifact::kArtifactSchemaVersion);
  ASSERT_EQ(now.form.samples.size(), old.form.samples.size());
  for (std::size_t i = 0; i < old.form.samples.size(); ++i) {
    EXPECT_EQ(now.form.samples[i].u, old.form.samples[i].u);
    EXPECT_EQ(now.form.samples[i].key, old.form.samples[i].key);
    EXPECT_EQ(now.form.samples[i].outcome.valid, old.form.samples[i].outcome.valid);
    EXPECT_EQ(now.form.samples[i].outcome.properties, old.form.samples[i].outcome.properties);
  }
  EXPECT_EQ(now.form.geometry_changes, old.form.geometry_changes);
  EXPECT_EQ(now.manifest.design_hash, old.manifest.design_hash);
  EXPECT_EQ(now.manifest.statistics.valid_volume_percent, old.manifest.statistics.valid_volume_percent);
  EXPECT_EQ(now.bundle.design_file, old.bundle.design_file);
  EXPECT_EQ(now.cache.size(), old.cache.size());
  // Only the samples table's checksum changes (its columns did).
  for (const auto& [table, sum] : old.manifest.checksums)
    if (table == "samples") {
      EXPECT_NE(now.manifest.checksums.at(table), sum);
    } else {
      EXPECT_EQ(now.manifest.checksums.at(table), sum) << table;
    }
}

// A job store written by a newer fabatlas: the coordinator refuses it with one
// line naming the file and exit status 2, and leaves it as it was.
TEST(ArtifactCli, CoordinatorRefusesANewerJobStore) {
  const fs::path dir = FreshTempDir("newer-store");
  const fs::path db = dir / "state.db";
  ASSERT_EQ(std::system(("sqlite3 " + db.string() + " 'CREATE TABLE t(x); PRAGMA user_version = " +
                         std::to_string(fabatlas::storage::kJobStoreSchemaVersion + 1) + ";'")
                            .c_str()),
            0);
  const std::string before = Bytes(db);
  const fs::path err = dir / "err.txt";
  const std::string cmd = (BinDir() / "fabatlas-coordinator").string() + " --listen 127.0.0.1:0 --state-dir " +
                          dir.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const std::string text = Bytes(err);
  EXPECT_NE(text.find(db.string() + ": job store written by a newer fabatlas (schema version " +
                      std::to_string(fabatlas::storage::kJobStoreSchemaVersion + 1)),
            std::string::npos)
      << text;
  EXPECT_EQ(Bytes(db), before);
}

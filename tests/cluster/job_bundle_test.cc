// Job bundles carry every file a design references, so a worker that only
// sees the bundle evaluates the same design (protocol/job_bundle.h).
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>

#include <fstream>
#include <sstream>

#include "fabatlas/assembly/part_library.h"
#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/testing/paths.h"

namespace fs = std::filesystem;
using namespace fabatlas;
using fabatlas::testing::FreshTempDir;
using fabatlas::testing::SharedDir;
using fabatlas::testing::SourceDir;

// The sofa bunk names its prototype program one directory above itself
// (../prototypes/sofa_bunk.yaml): the bundle keeps the design under its own
// directory name so that reference resolves after materializing.
TEST(JobBundle, FileAboveTheDesignDirectoryIsBundledAndResolves) {
  const v1::JobBundle bundle = protocol::MakeJobBundle(SourceDir() / "configs/jobs/sofa_bunk.yaml");
  EXPECT_EQ(bundle.design_file_name(), "designs/sofa_bunk.yaml");
  ASSERT_EQ(bundle.files().count("prototypes/sofa_bunk.yaml"), 1u);
  const fs::path dir = FreshTempDir("bundle");
  const protocol::MaterializedBundle m = protocol::Materialize(bundle, dir);
  EXPECT_EQ(m.design_file, dir / "design" / "designs" / "sofa_bunk.yaml");
  EXPECT_TRUE(fs::is_regular_file(dir / "design" / "prototypes" / "sofa_bunk.yaml"));
  const design::Design d = design::LoadDesign(m.design_file);  // throws if the reference dangles
  EXPECT_EQ(d.exposed.size(), 2u);
}

// A design whose files all sit beside it keeps its plain file name, so the
// bundles (and the task keys derived from them) of such jobs do not change.
TEST(JobBundle, FilesBesideTheDesignKeepPlainNames) {
  const v1::JobBundle bundle = protocol::MakeJobBundle(SourceDir() / "configs/jobs/pawn.yaml");
  EXPECT_EQ(bundle.design_file_name(), "pawn.yaml");
  for (const auto& [name, bytes] : bundle.files()) EXPECT_EQ(name.find(".."), std::string::npos) << name;
}

namespace {
std::string Bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}
}  // namespace

// The clip-lights family names only its part library; the bundle also
// carries every part mesh the library names (design/data_files.h), so a
// worker without the FabHacks data (FABATLAS_SHARED_DIR pointing nowhere)
// solves and builds the same assembly from the bundle alone.
TEST(JobBundle, AssemblyPartMeshesTravelInTheBundle) {
  const char* shared = std::getenv("FABATLAS_SHARED_DIR");
  const std::string saved = shared ? shared : "";
  ::setenv("FABATLAS_SHARED_DIR", SharedDir().c_str(), 1);  // the submitting machine has the data
  const v1::JobBundle bundle = protocol::MakeJobBundle(SourceDir() / "configs/jobs/clip_lights.yaml");
  const auto meshes = assembly::PartLibraryMeshes((SourceDir() / "configs/assemblies/parts.yaml").string());
  ASSERT_GE(meshes.size(), 5u);
  for (const std::string& name : meshes) {
    auto it = bundle.files().find("assembly_meshes/" + name);
    ASSERT_NE(it, bundle.files().end()) << name;
    EXPECT_EQ(it->second, Bytes(SharedDir() / "data/fabhacks/meshes" / name)) << name;
  }
  const design::Design here = design::LoadDesign(SourceDir() / "configs/assemblies/clip_lights_family.yaml");
  const design::Point u = design::DefaultPoint(here);
  const design::SampleResult expected = design::EvaluateSample(here, u);
  // The default variation hangs but does not come to rest (docs/benchmarks.md,
  // clip-lights job): the reason quotes the relaxation's motion, which the
  // part masses from the meshes decide.
  ASSERT_FALSE(expected.failure_reason.empty());

  const fs::path dir = FreshTempDir("bundle_assembly");
  const protocol::MaterializedBundle m = protocol::Materialize(bundle, dir);
  ::setenv("FABATLAS_SHARED_DIR", (dir / "no-shared-data").c_str(), 1);  // the worker has only the bundle
  const design::SampleResult got = design::EvaluateSample(design::LoadDesign(m.design_file), u);
  if (shared)
    ::setenv("FABATLAS_SHARED_DIR", saved.c_str(), 1);
  else
    ::unsetenv("FABATLAS_SHARED_DIR");
  EXPECT_EQ(got.valid, expected.valid);
  EXPECT_EQ(got.failure, expected.failure);
  EXPECT_EQ(got.failure_reason, expected.failure_reason);
  ASSERT_EQ(got.checks.size(), expected.checks.size());
  for (std::size_t i = 0; i < got.checks.size(); ++i) EXPECT_EQ(got.checks[i].passed, expected.checks[i].passed) << i;
}

// Bundle confinement (issue 31): a model naming a file outside its
// directory, by an absolute path, by '..' out of it, or through a link that
// points out, is refused when the bundle is made (at submit and run), with
// one line naming the model file, the line and the statement; nothing of the
// outside file is read (it is a FIFO here: opening it to read would block).
namespace {

// A job of one OpenSCAD model in ROOT/job, whose line 3 is `statement`;
// ROOT/outside holds the files the model must not reach.
fs::path HostileModelJob(const fs::path& root, const std::string& statement) {
  fs::create_directories(root / "job");
  std::ofstream(root / "job/model.scad") << "size = 10;\ncube(size);\n" << statement << "\n";
  std::ofstream(root / "job/design.yaml") << "name: hostile_model\nparameters:\n"
                                             "  size: {type: real, min: 5, max: 15, default: 10}\n"
                                             "tree: {op: openscad, file: model.scad, set: {size: size}}\n";
  std::ofstream(root / "job/job.yaml") << "design: design.yaml\nsampling: {subdivisions: 2, max_depth: 0}\n";
  return root / "job/job.yaml";
}

}  // namespace

TEST(JobBundle, ModelFilesOutsideTheModelsDirectoryAreRefusedWithTheirLine) {
  const fs::path root = FreshTempDir("confine");
  fs::create_directories(root / "outside");
  std::ofstream(root / "outside/secret.scad") << "cube(1);\n";
  ASSERT_EQ(::mkfifo((root / "outside/secret.stl").c_str(), 0600), 0);
  const std::string abs_scad = (root / "outside/secret.scad").string();
  const std::string abs_stl = (root / "outside/secret.stl").string();
  struct Case {
    std::string statement, shown, why;
  };
  const std::vector<Case> cases = {
      {"include <" + abs_scad + ">", "include <" + abs_scad + ">", "names an absolute path"},
      {"use <../outside/secret.scad>", "use <../outside/secret.scad>", "leaves the model's directory"},
      {"import(\"" + abs_stl + "\");", "import(\"" + abs_stl + "\")", "names an absolute path"},
      {"import(file = \"../outside/secret.stl\");", "import(\"../outside/secret.stl\")",
       "leaves the model's directory"},
      {"surface(file = \"sub/../../outside/secret.dat\");", "surface(\"sub/../../outside/secret.dat\")",
       "leaves the model's directory"},
      {"include <link.scad>", "include <link.scad>", "is a link to " + abs_scad},
  };
  int k = 0;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.statement);
    const fs::path dir = root / ("case" + std::to_string(k++));
    const fs::path job = HostileModelJob(dir, c.statement);
    fs::create_symlink(abs_scad, dir / "job/link.scad");
    const std::string want = (dir / "job/model.scad").string() + ":3: " + c.shown + " " + c.why;
    try {
      protocol::MakeJobBundle(job);
      ADD_FAILURE() << "bundled";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(want, 0), 0u) << what << "\nwanted: " << want;
      EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    }
  }
  // The same model with the statement commented out bundles (block comments
  // keep the line count: the refusal's line is the statement's own).
  const fs::path fine = HostileModelJob(root / "fine", "/* use <../outside/secret.scad>\n*/ cube(2);");
  EXPECT_NO_THROW(protocol::MakeJobBundle(fine));
  fs::remove_all(root);
}

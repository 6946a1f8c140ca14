// Job bundles carry every file a design references, so a worker that only
// sees the bundle evaluates the same design (protocol/job_bundle.h).
#include <gtest/gtest.h>

#include "fabatlas/design/design.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/testing/paths.h"

namespace fs = std::filesystem;
using namespace fabatlas;
using fabatlas::testing::FreshTempDir;
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

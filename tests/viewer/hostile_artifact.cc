// hostile_artifact RUN OUT — writes OUT, the artifact of run directory RUN
// (its one *.fabatlas) with markup where the
// design cannot put it but a hand-made artifact can: every invalid sample's
// failure type becomes kHostileFailure (unsat_constraints) or
// kHostileFailure2 (any other type), and every valid sample gains the
// property kHostileProperty = 1. The checksums are recomputed by
// WriteArtifact, so the customiser serves it like any artifact: what a shared
// customiser serving artifacts from people it does not know would read.
// Used by browser_hostile_test.mjs, which knows the same three strings.
#include <filesystem>
#include <iostream>

#include "fabatlas/artifact/artifact.h"

namespace {
const char* const kHostileFailure = "<img src=x onerror=\"document.title='XSS-failure'\">";
const char* const kHostileFailure2 = "\"><script>document.title='XSS-failure2'</script>";
const char* const kHostileProperty = "<svg onload=\"document.title='XSS-property'\">";
}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: hostile_artifact RUN OUT\n";
    return 2;
  }
  namespace fs = std::filesystem;
  fs::path in;
  for (const auto& e : fs::directory_iterator(argv[1]))
    if (e.path().extension() == ".fabatlas") in = e.path();
  if (in.empty()) {
    std::cerr << argv[1] << ": no *.fabatlas\n";
    return 2;
  }
  fabatlas::artifact::Artifact a = fabatlas::artifact::ReadArtifact(in);
  for (auto& s : a.form.samples) {
    if (s.outcome.valid)
      s.outcome.properties[kHostileProperty] = 1.0;
    else
      s.outcome.failure_type = s.outcome.failure_type == "unsat_constraints" ? kHostileFailure : kHostileFailure2;
  }
  a.manifest.statistics = fabatlas::artifact::StatisticsOf(a.form);
  fs::create_directories(fs::path(argv[2]).parent_path());
  fabatlas::artifact::WriteArtifact(a, argv[2]);
  return 0;
}

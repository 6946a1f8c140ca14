// --version text of the coordinator and the CLI (version_text.h).
#include "fabatlas/coordinator/version_text.h"

#include "fabatlas/protocol/tasks.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/storage/job_store.h"
#include "fabatlas/version.h"

namespace fabatlas::coordinator {

std::string VersionText(const std::string& program) {
  return program + " " + kVersion + " (task code " + protocol::kCodeVersion +
         ", protocol fabatlas.v1, artifact schema " + std::to_string(artifact::kArtifactSchemaVersion) +
         ", job store schema " + std::to_string(storage::kJobStoreSchemaVersion) + ")";
}

}  // namespace fabatlas::coordinator

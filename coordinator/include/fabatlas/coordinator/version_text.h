// fabatlas/coordinator/version_text.h — what `--version` prints for the
// coordinator and the CLI: the release, the task code version (part of every
// task key, so results of another code version are never reused), the wire
// protocol package and the schema versions of the files they write.
//   "fabatlas 0.1.0 (task code fabatlas-0.1/tasks-1, protocol fabatlas.v1,
//    artifact schema 1, job store schema 1)"
#pragma once

#include <string>

namespace fabatlas::coordinator {

std::string VersionText(const std::string& program);

}  // namespace fabatlas::coordinator

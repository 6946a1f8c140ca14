// fabatlas/write_file_atomically.h — a file written whole or not at all.
#pragma once

#include <filesystem>
#include <string>

namespace fabatlas {

// Writes `bytes` to `path` through a temporary file beside it
// ("<path>.tmp-<pid>-<n>", n counting the calls of the process), fsync and
// rename, so neither a crash nor a failed write leaves a partial file under
// the final name; a failed write removes the temporary file. Errors are one
// line naming `path`: ResourceError "<path>: disk full while writing" on
// ENOSPC (or EDQUOT, EFBIG), otherwise InputError with the system's reason.
// Thread-safe: threads writing one path each put a whole file there, the
// last rename wins.
void WriteFileAtomically(const std::filesystem::path& path, const std::string& bytes);

}  // namespace fabatlas

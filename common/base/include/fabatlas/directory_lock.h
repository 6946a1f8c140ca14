// fabatlas/directory_lock.h — one process at a time on a directory.
//
// The coordinator's state directory and a worker's cache directory each
// belong to one process: two coordinators on one state directory would both
// resume the same jobs, lease, collect blobs and publish (split brain).
// DirectoryLock holds an exclusive flock(2) on `<dir>/LOCK` for its lifetime
// and writes who holds it into that file ("pid 4242 host node-3 since
// 2026-11-28T05:40:00Z"). The kernel releases the flock when the holding
// process ends, however it ends (kill -9 included), so a lock left by a dead
// process is taken over by the next one without any cleanup; the file's
// text is only information and is rewritten by each new holder.
//
// The file is opened close-on-exec (child processes do not inherit the
// lock). flock is advisory and local: it excludes processes on one machine,
// and on NFS only where the server supports it (docs/operations.md).
#pragma once

#include <filesystem>
#include <string>

namespace fabatlas {

class DirectoryLock {
 public:
  // Creates `dir` if it does not exist and locks it. `what` names the
  // directory in the error, e.g. "state directory". Throws InputError, one
  // line, when another process (or another DirectoryLock of this process)
  // holds it: "<dir>: state directory in use by pid 4242 on host node-3
  // since 2026-11-28T05:40:00Z (<dir>/LOCK)". Throws InputError naming the
  // file when the directory or its LOCK file cannot be created. A failure to
  // write the holder's text (a full disk) does not fail the lock.
  DirectoryLock(const std::filesystem::path& dir, const std::string& what);
  ~DirectoryLock();  // releases the lock (the file stays)
  DirectoryLock(const DirectoryLock&) = delete;
  DirectoryLock& operator=(const DirectoryLock&) = delete;

  const std::filesystem::path& path() const { return path_; }  // <dir>/LOCK

 private:
  std::filesystem::path path_;
  int fd_ = -1;
};

}  // namespace fabatlas

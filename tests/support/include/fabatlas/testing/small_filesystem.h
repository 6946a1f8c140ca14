// fabatlas/testing/small_filesystem.h — a real full disk for the disk-full
// tests: a tmpfs of a few MiB mounted on a directory (needs root, i.e.
// CAP_SYS_ADMIN; the tests skip without it), filled to the last byte with a
// filler file, and freed again. Writes into it fail with ENOSPC ("No space
// left on device") exactly as on a full volume.
#pragma once

#include <fcntl.h>
#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>

namespace fabatlas::testing {

class SmallFileSystem {
 public:
  // True when this process may mount a tmpfs (root).
  static bool Possible() { return ::geteuid() == 0; }

  // Mounts a tmpfs of `mib` MiB on `dir` (created). error() says why not.
  SmallFileSystem(const std::filesystem::path& dir, int mib) : dir_(dir) {
    std::filesystem::create_directories(dir_);
    const std::string options = "size=" + std::to_string(mib) + "m";
    if (::mount("tmpfs", dir_.c_str(), "tmpfs", 0, options.c_str()) == 0)
      mounted_ = true;
    else
      error_ = dir_.string() + ": mount tmpfs: " + std::strerror(errno);
  }
  // Unmounts (lazily, so an open file of a dying process cannot block it).
  ~SmallFileSystem() {
    if (mounted_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  SmallFileSystem(const SmallFileSystem&) = delete;
  SmallFileSystem& operator=(const SmallFileSystem&) = delete;

  bool mounted() const { return mounted_; }
  const std::string& error() const { return error_; }
  const std::filesystem::path& dir() const { return dir_; }

  // Writes a filler file until the file system is full (a write fails
  // with ENOSPC), in 64 KiB blocks and then byte by byte.
  void Fill() {
    const int fd = ::open(FillerPath().c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd < 0) return;
    static const char block[1 << 16] = {};
    for (std::size_t size : {sizeof block, std::size_t{1}})
      while (::write(fd, block, size) == static_cast<ssize_t>(size)) {
      }
    ::close(fd);
  }
  // Removes the filler: the space is back.
  void Free() { std::filesystem::remove(FillerPath()); }

 private:
  std::filesystem::path FillerPath() const { return dir_ / ".filler"; }
  std::filesystem::path dir_;
  bool mounted_ = false;
  std::string error_;
};

}  // namespace fabatlas::testing

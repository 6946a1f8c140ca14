#include "fabatlas/write_file_atomically.h"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstring>

#include "fabatlas/error.h"

namespace fabatlas {

namespace {

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& what, int err) {
  if (err == ENOSPC || err == EDQUOT || err == EFBIG) throw ResourceError(path.string() + ": disk full while writing");
  throw InputError(path.string() + ": " + what + ": " + std::strerror(err));
}

}  // namespace

void WriteFileAtomically(const std::filesystem::path& path, const std::string& bytes) {
  // One temporary name per call: two threads writing one path (a Submit
  // materialising a job's files while its resumed driver does) each rename
  // a whole file; with one name per process one renamed the other's file
  // and the other's rename failed (ENOENT), found by power_loss_test.
  static std::atomic<std::uint64_t> calls{0};
  std::filesystem::path tmp = path;
  tmp += ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(calls++);
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) Fail(path, "cannot create file", errno);
  std::size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      int err = n < 0 ? errno : ENOSPC;
      ::close(fd);
      std::filesystem::remove(tmp);
      Fail(path, "cannot write", err);
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    int err = errno;
    std::filesystem::remove(tmp);
    Fail(path, "cannot flush to disk", err);
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp);
    throw InputError(path.string() + ": cannot rename into place: " + ec.message());
  }
}

}  // namespace fabatlas

// power_loss_shim.cc — an LD_PRELOAD library that puts a power cut or an I/O
// fault under one directory of a real process (the coordinator's state
// directory), for tests/cluster/power_loss_test.cc (docs/testing.md, "Power
// loss and I/O faults").
//
// The model of a power cut (after SQLite's own crash tests, which discard the
// pages not synced when the test "crashes", docs/references.md): what a file
// holds after the cut is its content at its last fsync/fdatasync; every
// write, truncation or O_TRUNC since then is undone, in 4 KiB blocks. With
// FABATLAS_CRASH_TORN each unsynced block reaches the disk or not at random,
// and a file grown since its sync keeps its new size or not (a disk that
// reorders and tears writes; a block dropped from a kept size reads as
// zeros). Names (create, rename, unlink, mkdir) are not undone: they survive
// in order, as a journaling file system's metadata do, so the cut follows a
// file's inode across a rename (a file renamed before its fsync keeps its
// last synced content under the new name).
//
// Environment (all optional but the root):
//   FABATLAS_SHIM_ROOT     absolute directory whose files are watched; SQLite's
//                          "-shm" index files are not (SQLite rebuilds them)
//   FABATLAS_SHIM_EVENTS   at exit, "events N\nstore_writes S\nblob_writes B\n"
//                          is written here: N watched events (each write,
//                          pwrite, writev, ftruncate, truncating open, fsync,
//                          fdatasync, rename, unlink, remove), S and B the
//                          write calls (write, pwrite, writev, ftruncate) on
//                          paths containing "state.db" and "/blobs/"
//   FABATLAS_CRASH_AT      k >= 1: before the k-th watched event runs, the
//                          power fails: files are rolled back as above, one
//                          line goes to stderr and the process SIGKILLs itself
//   FABATLAS_CRASH_TORN    a seed != 0: torn/reordered blocks as above (else
//                          every unsynced block is dropped)
//   FABATLAS_FAULT_MATCH   a substring of the path ("state.db", "/blobs/")
//   FABATLAS_FAULT_AT      k >= 1: the k-th write call on a matching path and
//                          every write, truncation or sync of one after it
//                          fail with FABATLAS_FAULT_ERRNO ("EIO" or "ENOSPC")
//                          for FABATLAS_FAULT_MS milliseconds (default 500),
//                          then succeed again; with FABATLAS_FAULT_EVERY = s
//                          the fault comes back at write k + s, k + 2s, ...
//                          (counting the writes that succeed)
// Threading: every call on a watched file runs under one mutex, so a cut is
// taken between two calls and no other thread writes while files roll back.
// The shim's own I/O uses raw system calls (never its wrappers).
#ifndef _GNU_SOURCE
#define _GNU_SOURCE
#endif
#include <dlfcn.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/uio.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <utility>

namespace {

constexpr off_t kBlock = 4096;

long RawOpen(const char* path, int flags, mode_t mode = 0) { return syscall(SYS_openat, AT_FDCWD, path, flags, mode); }
long RawPread(int fd, void* buf, size_t n, off_t off) { return syscall(SYS_pread64, fd, buf, n, off); }
long RawPwrite(int fd, const void* buf, size_t n, off_t off) { return syscall(SYS_pwrite64, fd, buf, n, off); }
void RawLine(const std::string& text) { syscall(SYS_write, 2, text.data(), text.size()); }

template <typename F>
F Next(const char* name) {
  return reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
}

// A watched file written since its last sync: its content then, block by
// block, as far as this process changed it.
struct Unsynced {
  int fd = -1;                          // the shim's own O_RDWR descriptor of the inode
  off_t synced_size = 0;                // size at the last sync
  std::map<off_t, std::string> before;  // block index -> its bytes at the last sync (short at the end)
};

struct Shim {
  std::mutex mu;
  bool configured = false;
  std::string root;  // with a trailing '/'
  std::string events_file;
  std::int64_t crash_at = 0;
  std::uint64_t torn_seed = 0;
  std::string fault_match;
  std::int64_t fault_at = 0, fault_every = 0, fault_ms = 500;
  int fault_errno = EIO;

  std::map<int, std::string> watched;  // fd -> absolute path
  std::map<std::pair<dev_t, ino_t>, Unsynced> unsynced;
  std::int64_t events = 0, store_writes = 0, blob_writes = 0, matching_writes = 0;
  std::int64_t next_fault = 0;  // matching write that starts the next fault
  std::chrono::steady_clock::time_point fault_until{};
  bool faulting = false;

  void Configure() {
    if (configured) return;
    configured = true;
    if (const char* r = std::getenv("FABATLAS_SHIM_ROOT"); r && *r) {
      root = r;
      if (root.back() != '/') root += '/';
    }
    if (const char* e = std::getenv("FABATLAS_SHIM_EVENTS")) events_file = e;
    if (const char* c = std::getenv("FABATLAS_CRASH_AT")) crash_at = std::atoll(c);
    if (const char* t = std::getenv("FABATLAS_CRASH_TORN")) torn_seed = std::strtoull(t, nullptr, 10);
    if (const char* m = std::getenv("FABATLAS_FAULT_MATCH")) fault_match = m;
    if (const char* k = std::getenv("FABATLAS_FAULT_AT")) fault_at = std::atoll(k);
    if (const char* s = std::getenv("FABATLAS_FAULT_EVERY")) fault_every = std::atoll(s);
    if (const char* d = std::getenv("FABATLAS_FAULT_MS")) fault_ms = std::atoll(d);
    if (const char* e = std::getenv("FABATLAS_FAULT_ERRNO"); e && std::string(e) == "ENOSPC") fault_errno = ENOSPC;
    next_fault = fault_at;
  }

  bool Watches(const char* path) {
    Configure();
    if (root.empty() || !path) return false;
    std::string p = path;
    if (p.empty()) return false;
    if (p[0] != '/') {
      char cwd[4096];
      if (!getcwd(cwd, sizeof cwd)) return false;
      p = std::string(cwd) + "/" + p;
    }
    if (p.size() >= 4 && p.compare(p.size() - 4, 4, "-shm") == 0) return false;
    return p.compare(0, root.size(), root) == 0 || p + "/" == root;
  }

  // Counts a watched event; the power fails before the crash_at-th one runs.
  void Event() {
    ++events;
    if (crash_at > 0 && events == crash_at) Cut();
  }

  // A write call on `path`: counted; true (errno set) when it must fail.
  bool WriteFails(const std::string& path) {
    if (path.find("state.db") != std::string::npos) ++store_writes;
    if (path.find("/blobs/") != std::string::npos) ++blob_writes;
    if (fault_at <= 0 || path.find(fault_match) == std::string::npos) return false;
    if (faulting) return SyncFails(path);
    ++matching_writes;
    if (next_fault <= 0 || matching_writes < next_fault) return false;
    faulting = true;
    fault_until = std::chrono::steady_clock::now() + std::chrono::milliseconds(fault_ms);
    next_fault = fault_every > 0 ? matching_writes + fault_every : 0;
    RawLine("power_loss_shim: " + std::string(fault_errno == EIO ? "EIO" : "ENOSPC") + " on write " +
            std::to_string(matching_writes) + " of '" + fault_match + "' (" + path + ") for " +
            std::to_string(fault_ms) + " ms\n");
    errno = fault_errno;
    return true;
  }
  // Any call on a matching path while a fault lasts fails.
  bool SyncFails(const std::string& path) {
    if (!faulting || path.find(fault_match) == std::string::npos) return false;
    if (std::chrono::steady_clock::now() >= fault_until) {
      faulting = false;
      return false;
    }
    errno = fault_errno;
    return true;
  }

  // Records the bytes at the last sync of the blocks [offset, offset + n)
  // of fd's inode, before a write or truncation changes them.
  void BeforeChange(int fd, off_t offset, off_t n) {
    struct stat st {};
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return;
    auto key = std::make_pair(st.st_dev, st.st_ino);
    auto it = unsynced.find(key);
    if (it == unsynced.end()) {
      Unsynced u;
      u.fd = static_cast<int>(RawOpen(("/proc/self/fd/" + std::to_string(fd)).c_str(), O_RDWR | O_CLOEXEC));
      if (u.fd < 0) return;
      u.synced_size = st.st_size;
      it = unsynced.emplace(key, std::move(u)).first;
    }
    Unsynced& u = it->second;
    if (n <= 0) return;
    for (off_t b = offset / kBlock; b <= (offset + n - 1) / kBlock; ++b) {
      if (u.before.count(b)) continue;
      std::string bytes(kBlock, '\0');
      long got = RawPread(u.fd, bytes.data(), kBlock, b * kBlock);
      bytes.resize(got > 0 ? static_cast<std::size_t>(got) : 0);
      u.before.emplace(b, std::move(bytes));
    }
  }
  void BeforeWrite(int fd, off_t offset_or_minus1, std::size_t n) {
    off_t offset = offset_or_minus1;
    int flags = fcntl(fd, F_GETFL);
    if (offset < 0 || (flags >= 0 && (flags & O_APPEND))) {
      struct stat st {};
      offset = (flags >= 0 && (flags & O_APPEND) && fstat(fd, &st) == 0) ? st.st_size : lseek(fd, 0, SEEK_CUR);
    }
    BeforeChange(fd, offset, static_cast<off_t>(n));
  }
  void BeforeTruncate(int fd, off_t length) {
    struct stat st {};
    if (fstat(fd, &st) != 0) return;
    BeforeChange(fd, length, st.st_size > length ? st.st_size - length : 0);
  }
  void Synced(int fd) {
    struct stat st {};
    if (fstat(fd, &st) != 0) return;
    auto it = unsynced.find({st.st_dev, st.st_ino});
    if (it == unsynced.end()) return;
    syscall(SYS_close, it->second.fd);
    unsynced.erase(it);
  }

  // The power cut: every file back to its last sync (or a torn mix), then
  // SIGKILL. Runs under mu, so no other watched call runs meanwhile.
  [[noreturn]] void Cut() {
    std::mt19937_64 rng(torn_seed);
    std::int64_t files = 0, dropped = 0, kept = 0;
    for (auto& [key, u] : unsynced) {
      ++files;
      struct stat st {};
      off_t size = u.synced_size;
      if (torn_seed != 0 && fstat(u.fd, &st) == 0 && (rng() & 1)) size = st.st_size;
      syscall(SYS_ftruncate, u.fd, size);
      for (const auto& [block, bytes] : u.before) {
        if (torn_seed != 0 && (rng() & 1)) {
          ++kept;
          continue;
        }
        ++dropped;
        const off_t at = block * kBlock;
        if (at >= size) continue;
        std::string restored = bytes;
        restored.resize(static_cast<std::size_t>(std::min<off_t>(kBlock, size - at)), '\0');
        RawPwrite(u.fd, restored.data(), restored.size(), at);
      }
    }
    RawLine("power_loss_shim: power cut at event " + std::to_string(events) + ": " + std::to_string(dropped) +
            " unsynced blocks of " + std::to_string(files) + " files dropped, " + std::to_string(kept) + " kept\n");
    syscall(SYS_kill, getpid(), SIGKILL);
    for (;;) pause();
  }

  void WriteEvents() {
    if (events_file.empty()) return;
    std::string text = "events " + std::to_string(events) + "\nstore_writes " + std::to_string(store_writes) +
                       "\nblob_writes " + std::to_string(blob_writes) + "\n";
    long fd = RawOpen(events_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) return;
    syscall(SYS_write, fd, text.data(), text.size());
    syscall(SYS_close, fd);
  }
};

Shim& TheShim() {
  static Shim* shim = new Shim;  // never destroyed: other libraries' destructors may still write
  return *shim;
}

__attribute__((destructor)) void WriteEventsAtExit() {
  Shim& s = TheShim();
  std::lock_guard lock(s.mu);
  s.WriteEvents();
}

// The path of a watched descriptor, or nullptr.
const std::string* WatchedFd(Shim& s, int fd) {
  auto it = s.watched.find(fd);
  return it == s.watched.end() ? nullptr : &it->second;
}

int OpenWatched(Shim& s, const char* path, int flags, mode_t mode, int (*real)(int, const char*, int, ...), int dirfd) {
  // A truncating open of a file with content changes it: recorded first.
  if (flags & O_TRUNC) {
    long fd = RawOpen(path, O_RDONLY | O_CLOEXEC);
    if (fd >= 0) {
      s.Event();
      s.BeforeTruncate(static_cast<int>(fd), 0);
      syscall(SYS_close, fd);
    }
  }
  int fd = real(dirfd, path, flags, mode);
  if (fd >= 0) {
    std::string p = path;
    if (p[0] != '/') {
      char cwd[4096];
      if (getcwd(cwd, sizeof cwd)) p = std::string(cwd) + "/" + p;
    }
    s.watched[fd] = p;
  }
  return fd;
}

using OpenAt = int (*)(int, const char*, int, ...);

int DoOpen(const char* name, int dirfd, const char* path, int flags, mode_t mode) {
  static OpenAt real = Next<OpenAt>(name);
  Shim& s = TheShim();
  if (dirfd != AT_FDCWD && path && path[0] != '/') return real(dirfd, path, flags, mode);
  std::lock_guard lock(s.mu);
  if (!s.Watches(path)) return real(dirfd, path, flags, mode);
  return OpenWatched(s, path, flags, mode, real, dirfd);
}

template <typename Call>
ssize_t DoWrite(int fd, off_t offset, std::size_t n, Call call) {
  Shim& s = TheShim();
  std::unique_lock lock(s.mu);
  const std::string* path = WatchedFd(s, fd);
  if (!path) {
    lock.unlock();
    return call();
  }
  s.Event();
  if (s.WriteFails(*path)) return -1;
  s.BeforeWrite(fd, offset, n);
  return call();
}

template <typename Call>
int DoSync(int fd, Call call) {
  Shim& s = TheShim();
  std::unique_lock lock(s.mu);
  const std::string* path = WatchedFd(s, fd);
  if (!path) {
    lock.unlock();
    return call();
  }
  s.Event();
  if (s.SyncFails(*path)) return -1;
  int r = call();
  if (r == 0) s.Synced(fd);
  return r;
}

template <typename Call>
int DoName(const char* a, const char* b, Call call) {
  Shim& s = TheShim();
  std::unique_lock lock(s.mu);
  if (!s.Watches(a) && !(b && s.Watches(b))) {
    lock.unlock();
    return call();
  }
  s.Event();
  return call();
}

}  // namespace

extern "C" {

int openat(int dirfd, const char* path, int flags, ...) {
  mode_t mode = 0;
  if (flags & (O_CREAT | O_TMPFILE)) {
    va_list ap;
    va_start(ap, flags);
    mode = va_arg(ap, mode_t);
    va_end(ap);
  }
  return DoOpen("openat", dirfd, path, flags, mode);
}
int openat64(int dirfd, const char* path, int flags, ...) {
  mode_t mode = 0;
  if (flags & (O_CREAT | O_TMPFILE)) {
    va_list ap;
    va_start(ap, flags);
    mode = va_arg(ap, mode_t);
    va_end(ap);
  }
  return DoOpen("openat64", dirfd, path, flags, mode);
}
int open(const char* path, int flags, ...) {
  mode_t mode = 0;
  if (flags & (O_CREAT | O_TMPFILE)) {
    va_list ap;
    va_start(ap, flags);
    mode = va_arg(ap, mode_t);
    va_end(ap);
  }
  return DoOpen("openat", AT_FDCWD, path, flags, mode);
}
int open64(const char* path, int flags, ...) {
  mode_t mode = 0;
  if (flags & (O_CREAT | O_TMPFILE)) {
    va_list ap;
    va_start(ap, flags);
    mode = va_arg(ap, mode_t);
    va_end(ap);
  }
  return DoOpen("openat64", AT_FDCWD, path, flags, mode);
}

int close(int fd) {
  static auto real = Next<int (*)(int)>("close");
  Shim& s = TheShim();
  {
    std::lock_guard lock(s.mu);
    s.watched.erase(fd);
  }
  return real(fd);
}

ssize_t write(int fd, const void* buf, size_t n) {
  static auto real = Next<ssize_t (*)(int, const void*, size_t)>("write");
  return DoWrite(fd, -1, n, [&] { return real(fd, buf, n); });
}
ssize_t pwrite(int fd, const void* buf, size_t n, off_t offset) {
  static auto real = Next<ssize_t (*)(int, const void*, size_t, off_t)>("pwrite");
  return DoWrite(fd, offset, n, [&] { return real(fd, buf, n, offset); });
}
ssize_t pwrite64(int fd, const void* buf, size_t n, off_t offset) {
  static auto real = Next<ssize_t (*)(int, const void*, size_t, off_t)>("pwrite64");
  return DoWrite(fd, offset, n, [&] { return real(fd, buf, n, offset); });
}
ssize_t writev(int fd, const struct iovec* iov, int count) {
  static auto real = Next<ssize_t (*)(int, const struct iovec*, int)>("writev");
  std::size_t n = 0;
  for (int i = 0; i < count; ++i) n += iov[i].iov_len;
  return DoWrite(fd, -1, n, [&] { return real(fd, iov, count); });
}
int ftruncate(int fd, off_t length) {
  static auto real = Next<int (*)(int, off_t)>("ftruncate");
  Shim& s = TheShim();
  std::unique_lock lock(s.mu);
  const std::string* path = WatchedFd(s, fd);
  if (!path) {
    lock.unlock();
    return real(fd, length);
  }
  s.Event();
  if (s.WriteFails(*path)) return -1;
  s.BeforeTruncate(fd, length);
  return real(fd, length);
}
int ftruncate64(int fd, off_t length) { return ftruncate(fd, length); }
int fsync(int fd) {
  static auto real = Next<int (*)(int)>("fsync");
  return DoSync(fd, [&] { return real(fd); });
}
int fdatasync(int fd) {
  static auto real = Next<int (*)(int)>("fdatasync");
  return DoSync(fd, [&] { return real(fd); });
}
int rename(const char* from, const char* to) {
  static auto real = Next<int (*)(const char*, const char*)>("rename");
  return DoName(from, to, [&] { return real(from, to); });
}
int unlink(const char* path) {
  static auto real = Next<int (*)(const char*)>("unlink");
  return DoName(path, nullptr, [&] { return real(path); });
}
int remove(const char* path) {
  static auto real = Next<int (*)(const char*)>("remove");
  return DoName(path, nullptr, [&] { return real(path); });
}

}  // extern "C"

// Content-addressed blob store (see blob_store.h).
#include "fabatlas/storage/blob_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <memory>

#include "fabatlas/error.h"
#include "fabatlas/sha256.h"

namespace fabatlas::storage {

namespace fs = std::filesystem;

namespace {

[[noreturn]] void IoFail(const fs::path& path, const std::string& what, int err) {
  throw ResourceError(path.string() + ": " + what + ": " + std::strerror(err));
}

void CheckDigest(const std::string& digest) {
  if (!IsDigest(digest)) throw InputError("blob digest '" + digest.substr(0, 80) + "': not 64 lowercase hex digits");
}

void WriteAll(int fd, const fs::path& path, const char* data, std::size_t size) {
  while (size > 0) {
    ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      IoFail(path, "write", errno);
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

void FsyncDirectory(const fs::path& dir) {
  int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

bool IsDigest(const std::string& digest) {
  return digest.size() == 64 && std::all_of(digest.begin(), digest.end(),
                                            [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

std::string Sha256OfFile(const fs::path& path) {
  int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) IoFail(path, "open", errno);
  Sha256 sha;
  // 64 KiB: a blob is mostly tens of KiB, and a 1 MiB buffer cost more
  // (zero-filled and page-faulted on every call) than hashing the blob.
  std::string buffer(1 << 16, '\0');
  while (true) {
    ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      int err = errno;
      ::close(fd);
      IoFail(path, "read", err);
    }
    if (n == 0) break;
    sha.Update(std::string_view(buffer.data(), static_cast<std::size_t>(n)));
  }
  ::close(fd);
  return sha.Hex();
}

BlobStore::BlobStore(fs::path root) : root_(std::move(root)) {
  std::error_code ec;
  fs::create_directories(root_ / "partial", ec);
  if (ec) throw ResourceError(root_.string() + ": cannot create the blob store: " + ec.message());
}

fs::path BlobStore::PathOf(const std::string& digest) const { return root_ / digest.substr(0, 2) / digest; }

fs::path BlobStore::PartialPath(const std::string& digest) const { return root_ / "partial" / digest; }

bool BlobStore::Contains(const std::string& digest) const {
  if (!IsDigest(digest)) return false;
  std::error_code ec;
  return fs::is_regular_file(PathOf(digest), ec);
}

std::int64_t BlobStore::Size(const std::string& digest) const {
  if (!IsDigest(digest)) return -1;
  std::error_code ec;
  auto size = fs::file_size(PathOf(digest), ec);
  return ec ? -1 : static_cast<std::int64_t>(size);
}

std::int64_t BlobStore::CommittedSize(const std::string& digest) const {
  CheckDigest(digest);
  std::int64_t full = Size(digest);
  if (full >= 0) return full;
  std::error_code ec;
  auto size = fs::file_size(PartialPath(digest), ec);
  return ec ? 0 : static_cast<std::int64_t>(size);
}

std::int64_t BlobStore::Append(const std::string& digest, std::int64_t offset, const std::string& data) {
  CheckDigest(digest);
  std::lock_guard lock(mutex_);
  std::int64_t full = Size(digest);
  if (full >= 0) return full;  // already published: nothing to do
  fs::path partial = PartialPath(digest);
  std::error_code ec;
  auto held_u = fs::file_size(partial, ec);
  std::int64_t held = ec ? 0 : static_cast<std::int64_t>(held_u);
  if (offset < held && offset + static_cast<std::int64_t>(data.size()) <= held) return held;
  if (offset != held)
    throw InputError("blob " + digest + ": chunk at offset " + std::to_string(offset) + " but " + std::to_string(held) +
                     " bytes are held (resume at that offset)");
  int fd = ::open(partial.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  if (fd < 0) IoFail(partial, "open", errno);
  try {
    WriteAll(fd, partial, data.data(), data.size());
  } catch (...) {
    ::close(fd);
    throw;
  }
  ::close(fd);
  return held + static_cast<std::int64_t>(data.size());
}

void BlobStore::Finish(const std::string& digest) {
  CheckDigest(digest);
  std::lock_guard lock(mutex_);
  if (Touch(digest)) return;
  fs::path partial = PartialPath(digest);
  if (!fs::exists(partial)) {
    // An empty blob has no chunks: create it.
    int fd = ::open(partial.c_str(), O_WRONLY | O_CREAT, 0644);
    if (fd < 0) IoFail(partial, "open", errno);
    ::close(fd);
  }
  int fd = ::open(partial.c_str(), O_RDONLY);
  if (fd < 0) IoFail(partial, "open", errno);
  if (::fsync(fd) != 0) {
    int err = errno;
    ::close(fd);
    IoFail(partial, "fsync", err);
  }
  ::close(fd);
  std::string actual = Sha256OfFile(partial);
  if (actual != digest) {
    std::error_code ec;
    fs::remove(partial, ec);
    throw InputError("blob " + digest + ": the uploaded bytes hash to " + actual + " (upload discarded)");
  }
  fs::path final_path = PathOf(digest);
  std::error_code ec;
  // A new ab/ directory's name is durable once ROOT is synced: without it a
  // power loss could take the directory, and the blob with it, away after
  // the blob was reported stored.
  if (fs::create_directories(final_path.parent_path(), ec)) FsyncDirectory(root_);
  if (ec) throw ResourceError(final_path.parent_path().string() + ": " + ec.message());
  if (::rename(partial.c_str(), final_path.c_str()) != 0) IoFail(final_path, "rename", errno);
  FsyncDirectory(final_path.parent_path());
}

std::string BlobStore::Put(const std::string& bytes) {
  std::string digest = Sha256Hex(bytes);
  if (Touch(digest)) return digest;  // held: fresh again for Collect's cutoff
  {
    std::lock_guard lock(mutex_);
    std::error_code ec;
    fs::remove(PartialPath(digest), ec);
  }
  Append(digest, 0, bytes);
  Finish(digest);
  return digest;
}

std::string BlobStore::PutFile(const fs::path& path) {
  std::string digest = Sha256OfFile(path);
  if (Touch(digest)) return digest;
  {
    std::lock_guard lock(mutex_);
    std::error_code ec;
    fs::remove(PartialPath(digest), ec);
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ResourceError(path.string() + ": cannot read");
  std::string chunk(std::size_t{4} << 20, '\0');
  std::int64_t offset = 0;
  while (in) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    const std::streamsize n = in.gcount();
    if (n <= 0) break;
    offset = Append(digest, offset, chunk.substr(0, static_cast<std::size_t>(n)));
  }
  if (in.bad()) throw ResourceError(path.string() + ": read failed");
  Finish(digest);
  return digest;
}

std::string BlobStore::Read(const std::string& digest, std::int64_t offset, std::int64_t max_bytes) const {
  CheckDigest(digest);
  fs::path path = PathOf(digest);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError("blob " + digest + ": not in the store " + root_.string());
  in.seekg(0, std::ios::end);
  std::int64_t size = in.tellg();
  offset = std::clamp<std::int64_t>(offset, 0, size);
  std::int64_t n = size - offset;
  if (max_bytes >= 0) n = std::min(n, max_bytes);
  std::string out(static_cast<std::size_t>(n), '\0');
  in.seekg(offset);
  in.read(out.data(), n);
  if (!in) throw ResourceError(path.string() + ": read failed");
  return out;
}

bool BlobStore::Verify(const std::string& digest) const {
  if (!Contains(digest)) return false;
  try {
    return Sha256OfFile(PathOf(digest)) == digest;
  } catch (const ResourceError&) {
    return false;
  }
}

std::vector<std::string> BlobStore::List() const {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& dir : fs::directory_iterator(root_, ec)) {
    if (!dir.is_directory() || dir.path().filename() == "partial") continue;
    for (const auto& f : fs::directory_iterator(dir.path(), ec)) {
      std::string name = f.path().filename().string();
      if (IsDigest(name)) out.push_back(name);
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool BlobStore::Touch(const std::string& digest) {
  if (!IsDigest(digest)) return false;
  return ::utimensat(AT_FDCWD, PathOf(digest).c_str(), nullptr, 0) == 0;
}

namespace {

std::int64_t ModifiedUnixMs(const struct stat& st) {
  return static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000 + st.st_mtim.tv_nsec / 1000000;
}

}  // namespace

BlobStore::Collection BlobStore::Collect(const std::vector<std::string>& keep, std::int64_t cutoff_unix_ms,
                                         const std::function<void()>& before_removing) {
  bool removing = false;
  std::vector<std::string> sorted = keep;
  std::sort(sorted.begin(), sorted.end());
  Collection c;
  std::error_code ec;
  for (const auto& dir : fs::directory_iterator(root_, ec)) {
    if (!dir.is_directory()) continue;
    const bool partial = dir.path().filename() == "partial";
    for (const auto& f : fs::directory_iterator(dir.path(), ec)) {
      const std::string name = f.path().filename().string();
      if (!IsDigest(name)) continue;
      struct stat st {};
      if (::stat(f.path().c_str(), &st) != 0) continue;
      const std::int64_t modified = ModifiedUnixMs(st);
      const bool referenced = !partial && std::binary_search(sorted.begin(), sorted.end(), name);
      const bool old = partial ? modified < cutoff_unix_ms - 86400000 : modified < cutoff_unix_ms;
      if (referenced || !old) {
        ++c.blobs_kept;
        c.bytes_kept += st.st_size;
        continue;
      }
      if (!removing && before_removing) before_removing();
      removing = true;
      std::lock_guard lock(mutex_);  // not while an upload of this digest publishes
      if (::unlink(f.path().c_str()) == 0) {
        ++c.blobs_removed;
        c.bytes_removed += st.st_size;
      }
    }
  }
  return c;
}

}  // namespace fabatlas::storage

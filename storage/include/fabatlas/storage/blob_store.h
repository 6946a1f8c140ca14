// fabatlas/storage/blob_store.h — content-addressed blobs on local disk
// (docs/protocol.md).
//
// A blob is named by the lowercase hex SHA-256 of its bytes and lives at
// ROOT/ab/abcd... (first two hex digits as a directory). Uploads go to
// ROOT/partial/<digest> and may be resumed at the size already held; Finish()
// fsyncs, verifies the digest and renames into place, so a crash never
// exposes a partial or corrupt blob under its final name.
//
// Thread-safe: every method may be called concurrently (uploads of the same
// digest are serialised by an internal mutex).
// Errors: I/O failures (full disk, permissions) throw fabatlas::ResourceError
// naming the path; a malformed digest, an offset that does not match the
// partial upload or a digest mismatch throw fabatlas::InputError.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace fabatlas::storage {

// True for 64 lowercase hex characters.
bool IsDigest(const std::string& digest);

class BlobStore {
 public:
  // Creates ROOT and ROOT/partial when missing.
  explicit BlobStore(std::filesystem::path root);

  const std::filesystem::path& root() const { return root_; }
  std::filesystem::path PathOf(const std::string& digest) const;

  bool Contains(const std::string& digest) const;
  // Size of a finished blob, or -1.
  std::int64_t Size(const std::string& digest) const;
  // Bytes held of an unfinished upload (0 if none); the full size if finished.
  std::int64_t CommittedSize(const std::string& digest) const;

  // Appends `data` at `offset` to the partial upload of `digest`. offset must
  // equal CommittedSize (a repeated chunk at an earlier offset whose bytes
  // are already held is accepted and ignored). Returns the new size.
  std::int64_t Append(const std::string& digest, std::int64_t offset, const std::string& data);
  // Verifies and publishes the partial upload. On a digest mismatch the
  // partial file is deleted and InputError is thrown.
  void Finish(const std::string& digest);

  // Whole-blob convenience: stores `bytes`, returns the digest.
  std::string Put(const std::string& bytes);
  // Stores a file's bytes as a blob, reading it in 4 MiB chunks (a
  // published artifact is up to a few GB), returns the digest.
  std::string PutFile(const std::filesystem::path& path);
  // Reads [offset, offset + max_bytes) of a finished blob (max_bytes < 0:
  // to the end). Throws InputError when the blob is missing.
  std::string Read(const std::string& digest, std::int64_t offset = 0, std::int64_t max_bytes = -1) const;
  // Re-hashes a finished blob; false if missing or corrupt.
  bool Verify(const std::string& digest) const;
  // Every finished blob's digest, sorted.
  std::vector<std::string> List() const;

  // Sets a finished blob's modification time to now (Collect keeps blobs
  // written or touched since its cutoff). False when the blob is missing.
  bool Touch(const std::string& digest);

  struct Collection {
    std::int64_t blobs_removed = 0;
    std::int64_t bytes_removed = 0;
    std::int64_t blobs_kept = 0;
    std::int64_t bytes_kept = 0;
  };
  // Garbage collection (mark and sweep, docs/protocol.md "Blob lifecycle"):
  // removes every finished blob whose digest is not in `keep` and whose
  // modification time is before cutoff_unix_ms, and partial uploads
  // untouched for a day. Idempotent, so a crash part-way leaves only blobs
  // the next call removes. The caller derives `keep` from durable references
  // and the cutoff from the oldest live lease, so a blob uploaded for a
  // result not yet reported survives. before_removing, when given, is
  // called once before the first removal (the caller makes the references
  // `keep` came from durable there; a pass that removes nothing costs none).
  Collection Collect(const std::vector<std::string>& keep, std::int64_t cutoff_unix_ms,
                     const std::function<void()>& before_removing = {});

 private:
  std::filesystem::path PartialPath(const std::string& digest) const;
  std::filesystem::path root_;
  mutable std::mutex mutex_;
};

// SHA-256 hex of a file's contents, streamed. Throws ResourceError if unreadable.
std::string Sha256OfFile(const std::filesystem::path& path);

}  // namespace fabatlas::storage

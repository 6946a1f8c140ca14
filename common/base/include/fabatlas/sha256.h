// fabatlas/sha256.h — SHA-256 digests as lowercase hex, the one content
// address used for subtree keys, task keys and blobs.
#pragma once

#include <string>
#include <string_view>

namespace fabatlas {

// Hex SHA-256 of the bytes (64 lowercase hex characters).
std::string Sha256Hex(std::string_view bytes);

// SHA-256 of bytes fed in pieces (files and tables too large to hold whole):
// Update any number of times, then Hex() once. Throws std::runtime_error if
// the digest cannot be computed. Not thread-safe; not copyable.
class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(const Sha256&) = delete;
  Sha256& operator=(const Sha256&) = delete;
  void Update(std::string_view bytes);
  // The digest of everything fed so far, as 64 lowercase hex characters.
  std::string Hex();

 private:
  struct Context;  // OpenSSL's EVP_MD_CTX, kept out of this header
  Context* context_;
};

}  // namespace fabatlas

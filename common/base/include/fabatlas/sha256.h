// fabatlas/sha256.h — SHA-256 digests as lowercase hex, the one content
// address used for subtree keys, task keys and blobs.
#pragma once

#include <string>
#include <string_view>

namespace fabatlas {

// Hex SHA-256 of the bytes (64 lowercase hex characters).
std::string Sha256Hex(std::string_view bytes);

}  // namespace fabatlas

// fabatlas/protocol/solid_blob.h — the bytes of a geometry blob ("solid" in
// tasks.proto "Geometry blobs"): geometry::Solid::Serialize() compressed as
// one zstd frame (level 1, single-threaded, so the same solid always gives
// the same bytes and so the same digest).
//
// A level set's serialised grid compresses 3-6x (measured in
// docs/benchmarks.md "Blob lifecycle"); blobs written before compression
// (the raw serialised grid) still decode: GridOfBlob passes bytes that do
// not start with the zstd magic number through unchanged.
//
// Errors: a truncated or corrupt zstd frame throws fabatlas::InputError.
#pragma once

#include <string>
#include <string_view>

namespace fabatlas::geometry {
class Solid;
}

namespace fabatlas::protocol {

// The blob bytes of a solid: zstd(solid.Serialize()).
std::string SolidBlobOf(const geometry::Solid& solid);

// The serialised grid (geometry::Solid::Serialize() bytes) in a blob, as the
// artifact stores it; raw (uncompressed) blobs are returned as they are.
std::string GridOfBlob(std::string_view blob);

// The solid in a blob (GridOfBlob, then geometry::Solid::Deserialize).
geometry::Solid SolidOfBlob(std::string_view blob);

}  // namespace fabatlas::protocol

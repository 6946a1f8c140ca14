// fabatlas/protocol/solid_blob.h — the bytes of a geometry blob ("solid" in
// tasks.proto "Geometry blobs"): the solid's node encoding
// (geometry/solid_nodes.h; geometry::Solid::Serialize() for the rare solid it
// cannot encode exactly) compressed as one zstd frame (level 1, with a content
// checksum, single-threaded, so the same solid always gives the same bytes
// and so the same digest).
//
// Blobs move between the processes of one job (worker, its shelf,
// coordinator); what leaves the job as a file (the artifact's cache grids)
// is Solid::Serialize(), which GridOfBlob gives. Blobs of earlier versions
// still decode: a zstd frame of a serialised grid, and the raw serialised
// grid (bytes that do not start with the zstd magic number).
//
// Errors: a truncated or corrupt blob throws fabatlas::InputError.
#pragma once

#include <string>
#include <string_view>

namespace fabatlas::geometry {
class Solid;
}

namespace fabatlas::protocol {

// The blob bytes of a solid: zstd(node bytes).
std::string SolidBlobOf(const geometry::Solid& solid);

// The serialised grid (geometry::Solid::Serialize() bytes) of the solid in a
// blob, as the artifact stores it; raw (uncompressed) blobs are returned as
// they are.
std::string GridOfBlob(std::string_view blob);

// The solid in a blob (no OpenVDB stream in between for node-encoded blobs).
geometry::Solid SolidOfBlob(std::string_view blob);

}  // namespace fabatlas::protocol

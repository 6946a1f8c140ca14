// Geometry blobs (protocol/solid_blob.h): a solid comes back exactly, through
// its blob and as the serialised grid the artifact stores; blobs of earlier
// versions (zstd of an OpenVDB stream, a raw OpenVDB stream) still decode;
// truncated and bit-flipped blobs are an InputError.
#include "fabatlas/protocol/solid_blob.h"

#include <gtest/gtest.h>
#include <zstd.h>

#include <random>
#include <string>

#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"

namespace fg = fabatlas::geometry;
namespace protocol = fabatlas::protocol;
using fabatlas::InputError;

namespace {

// The tube of bench/scale/tube_coarse.yaml at its defaults (2 mm voxel).
fg::Solid Tube() {
  fg::GridSpec g;
  g.voxel_size = 2.0;
  return fg::Difference(fg::Cylinder(g, 15, 20), fg::Cylinder(g, 9, 22));
}

// A blob as versions before the node encoding wrote it: zstd(Serialize()).
std::string OldBlob(const fg::Solid& s) {
  const std::string grid = s.Serialize();
  std::string out(ZSTD_compressBound(grid.size()), '\0');
  out.resize(ZSTD_compress(out.data(), out.size(), grid.data(), grid.size(), 1));
  return out;
}

}  // namespace

TEST(ProtocolSolidBlob, SolidsComeBackExactly) {
  fg::GridSpec fine;
  fine.voxel_size = 0.1;
  for (const fg::Solid& s : {Tube(), fg::Solid(), fg::Translate(fg::Box(fine, {2, 3, 4}), {5, 5, 5})}) {
    const std::string blob = protocol::SolidBlobOf(s);
    EXPECT_EQ(blob, protocol::SolidBlobOf(s));  // same solid, same bytes, same digest
    EXPECT_EQ(protocol::SolidOfBlob(blob).Serialize(), s.Serialize());
    EXPECT_EQ(protocol::GridOfBlob(blob), s.Serialize());  // what the artifact stores
  }
  // Smaller than the previous versions' blob of the same solid.
  EXPECT_LT(protocol::SolidBlobOf(Tube()).size(), OldBlob(Tube()).size());
}

TEST(ProtocolSolidBlob, BlobsOfEarlierVersionsStillDecode) {
  const fg::Solid tube = Tube();
  const std::string grid = tube.Serialize();
  for (const std::string& old : {OldBlob(tube), grid}) {
    EXPECT_EQ(protocol::SolidOfBlob(old).Serialize(), grid);
    EXPECT_EQ(protocol::GridOfBlob(old), grid);
  }
}

TEST(ProtocolSolidBlob, TruncatedAndFlippedBlobsAreInputErrors) {
  const std::string blob = protocol::SolidBlobOf(Tube());
  for (std::size_t n = 0; n < blob.size(); n += 1 + n / 8) {
    EXPECT_THROW(protocol::SolidOfBlob(blob.substr(0, n)), InputError) << n;
    // (GridOfBlob passes bytes without the zstd magic number through: an
    // earlier version's raw grid.)
    if (n >= 4) {
      EXPECT_THROW(protocol::GridOfBlob(blob.substr(0, n)), InputError) << n;
    }
  }
  // A flipped bit is an InputError (the frame's content checksum), or, where
  // zstd's entropy coding leaves a bit unused, the very same solid: never a
  // different one.
  const std::string grid = Tube().Serialize();
  std::mt19937 random(13);
  int errors = 0;
  for (int i = 0; i < 600; ++i) {
    std::string flipped = blob;
    const std::size_t at = random() % blob.size();
    flipped[at] = static_cast<char>(flipped[at] ^ (1 << (random() % 8)));
    try {
      EXPECT_EQ(protocol::SolidOfBlob(flipped).Serialize(), grid) << "bit flipped in byte " << at;
    } catch (const InputError&) {
      ++errors;
    }
  }
  EXPECT_GT(errors, 550);
}

// Geometry blobs as zstd frames (see solid_blob.h).
#include "fabatlas/protocol/solid_blob.h"

#include <zstd.h>

#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"

namespace fabatlas::protocol {

namespace {

constexpr int kLevel = 1;  // the fastest level: a ΔG solid is compressed once per valid sample

bool IsZstdFrame(std::string_view bytes) {
  return bytes.size() >= 4 && static_cast<unsigned char>(bytes[0]) == 0x28 &&
         static_cast<unsigned char>(bytes[1]) == 0xb5 && static_cast<unsigned char>(bytes[2]) == 0x2f &&
         static_cast<unsigned char>(bytes[3]) == 0xfd;
}

}  // namespace

std::string SolidBlobOf(const geometry::Solid& solid) {
  const std::string grid = solid.Serialize();
  std::string out(ZSTD_compressBound(grid.size()), '\0');
  const std::size_t n = ZSTD_compress(out.data(), out.size(), grid.data(), grid.size(), kLevel);
  if (ZSTD_isError(n)) throw InputError(std::string("solid blob: zstd: ") + ZSTD_getErrorName(n));
  // An exact copy, not resize(): the bound's capacity would stay allocated
  // (the worker's shelf holds thousands of these and budgets their size).
  return out.substr(0, n);
}

std::string GridOfBlob(std::string_view blob) {
  if (!IsZstdFrame(blob)) return std::string(blob);
  const unsigned long long size = ZSTD_getFrameContentSize(blob.data(), blob.size());
  if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN || size > (1ull << 34))
    throw InputError("solid blob: not a complete zstd frame");
  std::string out(static_cast<std::size_t>(size), '\0');
  const std::size_t n = ZSTD_decompress(out.data(), out.size(), blob.data(), blob.size());
  if (ZSTD_isError(n) || n != out.size())
    throw InputError(std::string("solid blob: corrupt zstd frame: ") + (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short"));
  return out;
}

geometry::Solid SolidOfBlob(std::string_view blob) { return geometry::Solid::Deserialize(GridOfBlob(blob)); }

}  // namespace fabatlas::protocol

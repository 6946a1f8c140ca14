// Geometry blobs as zstd frames (see solid_blob.h).
#include "fabatlas/protocol/solid_blob.h"

#include <zstd.h>

#include <memory>

#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/geometry/solid_nodes.h"

namespace fabatlas::protocol {

namespace {

constexpr int kLevel = 1;  // the fastest level: a ΔG solid is compressed once per valid sample

bool IsZstdFrame(std::string_view bytes) {
  return bytes.size() >= 4 && static_cast<unsigned char>(bytes[0]) == 0x28 &&
         static_cast<unsigned char>(bytes[1]) == 0xb5 && static_cast<unsigned char>(bytes[2]) == 0x2f &&
         static_cast<unsigned char>(bytes[3]) == 0xfd;
}

// One compression and one decompression context per thread: creating them
// per call costs more than compressing a small solid.
struct ZstdContexts {
  std::unique_ptr<ZSTD_CCtx, size_t (*)(ZSTD_CCtx*)> c{ZSTD_createCCtx(), ZSTD_freeCCtx};
  std::unique_ptr<ZSTD_DCtx, size_t (*)(ZSTD_DCtx*)> d{ZSTD_createDCtx(), ZSTD_freeDCtx};
};
ZstdContexts& Contexts() {
  thread_local ZstdContexts contexts;
  return contexts;
}

std::string Compress(std::string_view bytes) {
  ZSTD_CCtx* c = Contexts().c.get();
  ZSTD_CCtx_reset(c, ZSTD_reset_session_and_parameters);
  ZSTD_CCtx_setParameter(c, ZSTD_c_compressionLevel, kLevel);
  ZSTD_CCtx_setParameter(c, ZSTD_c_checksumFlag, 1);  // a flipped bit is an error, not another solid
  std::string out(ZSTD_compressBound(bytes.size()), '\0');
  const std::size_t n = ZSTD_compress2(c, out.data(), out.size(), bytes.data(), bytes.size());
  if (ZSTD_isError(n)) throw InputError(std::string("solid blob: zstd: ") + ZSTD_getErrorName(n));
  // An exact copy, not resize(): the bound's capacity would stay allocated
  // (the worker's shelf holds thousands of these and budgets their size).
  return out.substr(0, n);
}

// The bytes a blob holds: its zstd frame decompressed, or the blob itself.
std::string Decompress(std::string_view blob) {
  if (!IsZstdFrame(blob)) return std::string(blob);
  const unsigned long long size = ZSTD_getFrameContentSize(blob.data(), blob.size());
  if (size == ZSTD_CONTENTSIZE_ERROR || size == ZSTD_CONTENTSIZE_UNKNOWN || size > (1ull << 34))
    throw InputError("solid blob: not a complete zstd frame");
  std::string out(static_cast<std::size_t>(size), '\0');
  const std::size_t n = ZSTD_decompressDCtx(Contexts().d.get(), out.data(), out.size(), blob.data(), blob.size());
  if (ZSTD_isError(n) || n != out.size())
    throw InputError(std::string("solid blob: corrupt zstd frame: ") +
                     (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "short"));
  return out;
}

}  // namespace

std::string SolidBlobOf(const geometry::Solid& solid) {
  if (auto nodes = geometry::SolidNodeBytes(solid)) return Compress(*nodes);
  return Compress(solid.Serialize());
}

std::string GridOfBlob(std::string_view blob) {
  std::string bytes = Decompress(blob);
  if (geometry::IsSolidNodeBytes(bytes)) return geometry::SolidOfNodeBytes(bytes).Serialize();
  return bytes;
}

geometry::Solid SolidOfBlob(std::string_view blob) {
  const std::string bytes = Decompress(blob);
  if (geometry::IsSolidNodeBytes(bytes)) return geometry::SolidOfNodeBytes(bytes);
  return geometry::Solid::Deserialize(bytes);
}

}  // namespace fabatlas::protocol

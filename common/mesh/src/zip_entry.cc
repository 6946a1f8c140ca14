// One entry of a ZIP archive (PKWARE APPNOTE 6.3: end of central directory,
// central directory headers, local headers; stored and deflated entries).
#include <zlib.h>

#include <cstdint>
#include <cstring>

#include "fabatlas/error.h"
#include "mesh_formats.h"

namespace fabatlas::mesh::internal {
namespace {

constexpr std::uint64_t kMaxEntryBytes = std::uint64_t{1} << 30;

std::uint32_t U16(std::string_view d, std::size_t at) {
  return static_cast<unsigned char>(d[at]) | static_cast<unsigned char>(d[at + 1]) << 8;
}
std::uint32_t U32(std::string_view d, std::size_t at) { return U16(d, at) | U16(d, at + 2) << 16; }

[[noreturn]] void Damaged(const std::filesystem::path& path, const std::string& what) {
  throw InputError(path.string() + ": not a readable ZIP archive: " + what);
}

std::string Inflate(const std::filesystem::path& path, std::string_view packed, std::uint64_t size) {
  std::string out(size, '\0');
  z_stream z{};
  if (inflateInit2(&z, -MAX_WBITS) != Z_OK) throw ResourceError(path.string() + ": zlib inflateInit2 failed");
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(packed.data()));
  z.avail_in = static_cast<uInt>(packed.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  const int rc = inflate(&z, Z_FINISH);
  const std::uint64_t produced = z.total_out;
  inflateEnd(&z);
  if (rc != Z_STREAM_END || produced != size) Damaged(path, "an entry does not inflate to its recorded size");
  return out;
}

}  // namespace

bool IsZip(std::string_view data) { return data.size() >= 4 && data.substr(0, 4) == std::string_view("PK\3\4", 4); }

std::string ZipEntry(const std::filesystem::path& path, std::string_view d, const std::string& name) {
  // The end-of-central-directory record: the last "PK\5\6" within 64 KiB + 22 bytes of the end.
  if (d.size() < 22) Damaged(path, "too short");
  std::size_t eocd = std::string_view::npos;
  const std::size_t lowest = d.size() > 22 + 65535 ? d.size() - 22 - 65535 : 0;
  for (std::size_t at = d.size() - 22 + 1; at-- > lowest;)
    if (U32(d, at) == 0x06054b50) {
      eocd = at;
      break;
    }
  if (eocd == std::string_view::npos) Damaged(path, "no end of central directory");
  const std::uint32_t entries = U16(d, eocd + 10), directory = U32(d, eocd + 16);
  if (entries == 0xffff || directory == 0xffffffff) Damaged(path, "ZIP64 archives are not read");
  std::size_t at = directory;
  for (std::uint32_t i = 0; i < entries; ++i) {
    if (at + 46 > d.size() || U32(d, at) != 0x02014b50) Damaged(path, "central directory entry " + std::to_string(i));
    const std::uint32_t flags = U16(d, at + 8), method = U16(d, at + 10);
    const std::uint64_t packed = U32(d, at + 20), size = U32(d, at + 24);
    const std::size_t name_length = U16(d, at + 28), extra = U16(d, at + 30), comment = U16(d, at + 32);
    const std::size_t local = U32(d, at + 42);
    if (at + 46 + name_length > d.size()) Damaged(path, "central directory entry " + std::to_string(i));
    const std::string_view entry_name = d.substr(at + 46, name_length);
    at += 46 + name_length + extra + comment;
    if (!name.empty() && entry_name != name && entry_name != "/" + name) continue;
    if (flags & 1) Damaged(path, "entry " + std::string(entry_name) + " is encrypted");
    if (size > kMaxEntryBytes) Damaged(path, "entry " + std::string(entry_name) + " is over 1 GiB uncompressed");
    if (local + 30 > d.size() || U32(d, local) != 0x04034b50)
      Damaged(path, "local header of " + std::string(entry_name));
    const std::size_t begin = local + 30 + U16(d, local + 26) + U16(d, local + 28);
    if (begin > d.size() || packed > d.size() - begin)
      Damaged(path, "entry " + std::string(entry_name) + " is truncated");
    const std::string_view bytes = d.substr(begin, packed);
    if (method == 0) {
      if (packed != size) Damaged(path, "stored entry " + std::string(entry_name) + " has two sizes");
      return std::string(bytes);
    }
    if (method == 8) return Inflate(path, bytes, size);
    Damaged(path, "entry " + std::string(entry_name) + " uses compression method " + std::to_string(method));
  }
  throw InputError(path.string() + ": the archive has no entry " + (name.empty() ? std::string("at all") : name));
}

}  // namespace fabatlas::mesh::internal

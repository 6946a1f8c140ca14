// solid_bytes.cc — Solid::Serialize and Solid::Deserialize: a mesh solid's
// own little-endian layout, a level set as an OpenVDB stream (io::Stream).
#include <openvdb/io/Stream.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>

#include "solid_impl.h"

namespace fabatlas::geometry {

using openvdb::FloatGrid;

namespace {
// The archive header written by io::Stream contains a random UUID (36 ASCII
// characters: 8-4-4-4-12 hex digits). Replace it by a constant so that equal
// solids give equal bytes.
void BlankArchiveUuid(std::string& bytes) {
  const std::size_t search_end = std::min<std::size_t>(bytes.size(), 128);
  for (std::size_t start = 0; start + 36 <= search_end; ++start) {
    bool match = true;
    for (std::size_t k = 0; k < 36 && match; ++k) {
      const char ch = bytes[start + k];
      const bool dash = (k == 8 || k == 13 || k == 18 || k == 23);
      match = dash ? ch == '-' : std::isxdigit(static_cast<unsigned char>(ch)) != 0;
    }
    if (match) {
      for (std::size_t k = 0; k < 36; ++k) {
        const bool dash = (k == 8 || k == 13 || k == 18 || k == 23);
        bytes[start + k] = dash ? '-' : '0';
      }
      return;
    }
  }
  throw std::logic_error("Solid::Serialize: no archive UUID found in the OpenVDB stream header");
}
}  // namespace

namespace {
// A mesh solid's bytes: the magic, the spec (voxel size, half width, voxel
// budget), the counts, then vertices as doubles and triangles as int32, all
// little-endian (the machines fabatlas runs on).
constexpr std::string_view kMeshMagic = "fabatlas-mesh-solid-1\n";

template <typename T>
void Put(std::string& out, const T& v) {
  out.append(reinterpret_cast<const char*>(&v), sizeof v);
}
template <typename T>
T Take(std::string_view& in) {
  if (in.size() < sizeof(T)) throw InputError("Solid::Deserialize: truncated mesh solid");
  T v;
  std::memcpy(&v, in.data(), sizeof v);
  in.remove_prefix(sizeof v);
  return v;
}
}  // namespace

std::string Solid::Serialize() const {
  if (impl_ && impl_->boundary) {
    const mesh::TriangleMesh& b = *impl_->boundary;
    std::string out(kMeshMagic);
    Put(out, impl_->spec.voxel_size);
    Put(out, impl_->spec.half_width_voxels);
    Put(out, static_cast<std::uint64_t>(impl_->spec.max_active_voxels));
    Put(out, static_cast<std::uint64_t>(b.vertices.size()));
    Put(out, static_cast<std::uint64_t>(b.triangles.size()));
    out.append(reinterpret_cast<const char*>(b.vertices.data()), b.vertices.size() * sizeof(b.vertices[0]));
    out.append(reinterpret_cast<const char*>(b.triangles.data()), b.triangles.size() * sizeof(b.triangles[0]));
    return out;
  }
  internal::EnsureOpenVdbInitialized();
  FloatGrid::Ptr grid;
  GridSpec spec;
  if (impl_) {
    grid = impl_->Grid();
    spec = impl_->spec;
  } else {
    // The default-constructed Solid: an empty grid with voxel size 0 marker.
    grid = FloatGrid::create(1.0f);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName("solid");
    spec.voxel_size = 0;
  }
  std::ostringstream os(std::ios_base::binary);
  openvdb::io::Stream stream(os);
  // Active-mask compression only: lossless and deterministic; callers that
  // want smaller blobs compress the bytes themselves.
  stream.setCompression(openvdb::io::COMPRESS_ACTIVE_MASK);
  stream.setGridStatsMetadataEnabled(false);
  openvdb::MetaMap meta;
  meta.insertMeta("fabatlas_voxel_size", openvdb::DoubleMetadata(spec.voxel_size));
  meta.insertMeta("fabatlas_half_width_voxels", openvdb::DoubleMetadata(spec.half_width_voxels));
  meta.insertMeta("fabatlas_max_active_voxels", openvdb::Int64Metadata(static_cast<int64_t>(spec.max_active_voxels)));
  openvdb::GridCPtrVec grids{grid};
  stream.write(grids, meta);
  std::string bytes = os.str();
  BlankArchiveUuid(bytes);
  return bytes;
}

Solid Solid::Deserialize(std::string_view bytes) {
  if (bytes.substr(0, kMeshMagic.size()) == kMeshMagic) {
    std::string_view in = bytes.substr(kMeshMagic.size());
    GridSpec spec;
    spec.voxel_size = Take<double>(in);
    spec.half_width_voxels = Take<double>(in);
    spec.max_active_voxels = Take<std::uint64_t>(in);
    const auto nv = Take<std::uint64_t>(in), nt = Take<std::uint64_t>(in);
    mesh::TriangleMesh m;
    if (nv > in.size() / 24 || nt > in.size() / 12 || in.size() != nv * 24 + nt * 12)
      throw InputError("Solid::Deserialize: mesh solid of the wrong length");
    m.vertices.resize(nv);
    m.triangles.resize(nt);
    std::memcpy(m.vertices.data(), in.data(), nv * 24);
    std::memcpy(m.triangles.data(), in.data() + nv * 24, nt * 12);
    return MeshSolid(spec, std::move(m));
  }
  internal::EnsureOpenVdbInitialized();
  try {
    std::istringstream is(std::string(bytes), std::ios_base::binary);
    openvdb::io::Stream stream(is, /*delayLoad=*/false);
    openvdb::GridPtrVecPtr grids = stream.getGrids();
    if (is.fail()) throw InputError("Solid::Deserialize: truncated or corrupt grid stream");
    openvdb::MetaMap::Ptr meta = stream.getMetadata();
    if (!grids || grids->size() != 1) throw InputError("Solid::Deserialize: expected exactly one grid");
    FloatGrid::Ptr grid = openvdb::gridPtrCast<FloatGrid>(grids->front());
    if (!grid || grid->getGridClass() != openvdb::GRID_LEVEL_SET) {
      throw InputError("Solid::Deserialize: the grid is not a float level set");
    }
    GridSpec spec;
    spec.voxel_size = meta->metaValue<double>("fabatlas_voxel_size");
    spec.half_width_voxels = meta->metaValue<double>("fabatlas_half_width_voxels");
    spec.max_active_voxels = static_cast<std::size_t>(meta->metaValue<int64_t>("fabatlas_max_active_voxels"));
    if (spec.voxel_size == 0) return Solid();
    internal::ValidateSpec(spec, "Solid::Deserialize");
    if (std::abs(grid->voxelSize()[0] - spec.voxel_size) > 1e-12 * spec.voxel_size) {
      throw InputError("Solid::Deserialize: grid transform does not match its recorded voxel size");
    }
    return internal::MakeSolid(grid, spec);
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(std::string("Solid::Deserialize: not a fabatlas solid (") + e.what() + ")");
  }
}
}  // namespace fabatlas::geometry

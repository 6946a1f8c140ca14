// sample_occupancy.cc — SampleOccupancy: a solid's inside on a regular grid
// of cells, sampled at cell centres by trilinear interpolation.
#include <openvdb/tools/Interpolation.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "solid_impl.h"

namespace fabatlas::geometry {

using openvdb::FloatGrid;

Occupancy SampleOccupancy(const Solid& s, double cell_size, std::size_t max_cells) {
  internal::RequirePositive(cell_size, "SampleOccupancy", "cell_size");
  Occupancy occ;
  occ.cell_size = cell_size;
  if (s.empty()) return occ;
  const Box3 box = s.BoundingBox();
  std::array<long long, 3> lo{}, hi{};
  double cells = 1;
  for (int a = 0; a < 3; ++a) {
    lo[a] = static_cast<long long>(std::floor(box.min[a] / cell_size));
    hi[a] = static_cast<long long>(std::ceil(box.max[a] / cell_size));
    if (hi[a] <= lo[a]) hi[a] = lo[a] + 1;
    cells *= static_cast<double>(hi[a] - lo[a]);
  }
  if (cells > static_cast<double>(max_cells)) {
    std::ostringstream m;
    m << "SampleOccupancy: cell size " << cell_size << " mm over a " << box.max[0] - box.min[0] << " x "
      << box.max[1] - box.min[1] << " x " << box.max[2] - box.min[2] << " mm box needs " << cells << " cells (limit "
      << max_cells << ")";
    throw InputError(m.str());
  }
  for (int a = 0; a < 3; ++a) {
    occ.origin[a] = static_cast<double>(lo[a]) * cell_size;
    occ.dims[a] = static_cast<int>(hi[a] - lo[a]);
  }
  const std::size_t nx = occ.dims[0], ny = occ.dims[1], nz = occ.dims[2];
  occ.inside.assign(nx * ny * nz, 0);
  const FloatGrid& grid = *s.impl()->Grid();
  tbb::parallel_for(std::size_t{0}, nz, [&](std::size_t k) {
    FloatGrid::ConstAccessor accessor = grid.getConstAccessor();
    openvdb::tools::GridSampler<FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler(accessor,
                                                                                              grid.transform());
    for (std::size_t j = 0; j < ny; ++j)
      for (std::size_t i = 0; i < nx; ++i) {
        const openvdb::Vec3d p(occ.origin[0] + (i + 0.5) * cell_size, occ.origin[1] + (j + 0.5) * cell_size,
                               occ.origin[2] + (k + 0.5) * cell_size);
        if (sampler.wsSample(p) < 0) occ.inside[i + nx * (j + ny * k)] = 1;
      }
  });
  occ.inside_count = static_cast<std::size_t>(std::count(occ.inside.begin(), occ.inside.end(), 1));
  return occ;
}

}  // namespace fabatlas::geometry

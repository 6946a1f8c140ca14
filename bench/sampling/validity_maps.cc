// Writes validity maps (PNG) of the analytic designs, for docs/sampling.md:
//   bench_sampling_validity_maps OUT_DIR
#include <cstdio>
#include <string>

#include "analytic_designs.h"
#include "fabatlas/sampling/validity_map.h"

using namespace fabatlas::sampling;

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : ".";
  ThreadPoolExecutor ex(2);
  SamplingOptions o;
  o.max_depth = 7;
  o.dg_threshold = 0.3;
  testing::HollowCylinder3D cylinder;
  const auto c = SampleDesignSpace(DesignSpace(cylinder.Dimensions(), 5), cylinder, ex, o);
  WriteValidityMap(c.form, ValidityMapOptions{0, 1, {0, 0, 45.0}, 480}, out + "/cylinder3d_R_wall_h45.png");
  WriteValidityMap(c.form, ValidityMapOptions{0, 2, {0, 2.0, 0}, 480}, out + "/cylinder3d_R_height_wall2.png");
  testing::MaterialBar bar;
  const auto b = SampleDesignSpace(DesignSpace(bar.Dimensions(), 5), bar, ex, o);
  WriteValidityMap(b.form, ValidityMapOptions{0, 1, {}, 400}, out + "/material_bar.png");
  std::printf("cylinder 3-D: %lld samples, valid volume %.2f %%; bar: %lld samples\n",
              static_cast<long long>(c.statistics.samples), c.statistics.valid_volume_percent,
              static_cast<long long>(b.statistics.samples));
  return 0;
}

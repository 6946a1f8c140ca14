// Swept-volume SDF: the narrow-band sparse method (fabatlas::swept) side by
// side with the dense method of Reconfigurables section 6.7 as libigl implements it
// (every grid vertex, every time step, one closest-point query on an AABB
// tree, keep the minimum), on the same lattice.
//
// The dense baseline here computes *unsigned* distance (no winding-number
// sign), which makes it cheaper than libigl's signed version. Both run on all
// cores through TBB. The dense method's cost per time step is measured on
// --dense-steps evenly spaced steps (median) and multiplied by the number of
// steps; its accuracy is checked against the sparse field on the full motion
// for one z-slice of the grid.
//
// Usage: bench_swept [--span 256] [--steps 100] [--dense-steps 5] [--repeats 3]
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numeric>
#include <vector>

#include "../../tests/swept/test_shapes.h"
#include "fabatlas/swept/box_tree.h"
#include "fabatlas/swept/swept_volume.h"

namespace {

using fabatlas::mesh::TriangleMesh;
using fabatlas::swept::Transform;
using fabatlas::swept::Vec3;

double Seconds(std::chrono::steady_clock::time_point a) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// ---- Dense baseline: AABB tree closest-point queries ---------------------------
Vec3 Sub(const Vec3& a, const Vec3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double Dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// Squared distance from p to triangle abc (Ericson, Real-Time Collision
// Detection, 5.1.5: closest point by Voronoi regions).
double PointTriangleDistance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = Sub(b, a), ac = Sub(c, a), ap = Sub(p, a);
  const double d1 = Dot(ab, ap), d2 = Dot(ac, ap);
  auto dist2 = [&](const Vec3& q) {
    const Vec3 d = Sub(p, q);
    return Dot(d, d);
  };
  if (d1 <= 0 && d2 <= 0) return dist2(a);
  const Vec3 bp = Sub(p, b);
  const double d3 = Dot(ab, bp), d4 = Dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return dist2(b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return dist2({a[0] + v * ab[0], a[1] + v * ab[1], a[2] + v * ab[2]});
  }
  const Vec3 cp = Sub(p, c);
  const double d5 = Dot(ab, cp), d6 = Dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return dist2(c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return dist2({a[0] + w * ac[0], a[1] + w * ac[1], a[2] + w * ac[2]});
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return dist2({b[0] + w * (c[0] - b[0]), b[1] + w * (c[1] - b[1]), b[2] + w * (c[2] - b[2])});
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, w = vc * denom;
  return dist2({a[0] + ab[0] * v + ac[0] * w, a[1] + ab[1] * v + ac[1] * w, a[2] + ab[2] * v + ac[2] * w});
}

// The mesh's triangles in a BoxTree of their bounding boxes.
class TriangleTree {
 public:
  explicit TriangleTree(const TriangleMesh& m) : mesh_(m), tree_(TriangleBoxes(m)) {}

  // Distance from p to the mesh, or `cutoff` if it is farther (nodes beyond
  // the cutoff are pruned: the seed's culling of far grid vertices during the
  // tree evaluation).
  double Distance(const Vec3& p, double cutoff = std::numeric_limits<double>::infinity()) const {
    double best = cutoff * cutoff;
    const auto& nodes = tree_.nodes();
    if (nodes.empty()) return cutoff;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const auto& n = nodes[stack[--top]];
      if (BoxDistance2(n.box, p) >= best) continue;
      if (n.count > 0) {
        for (int i = n.first; i < n.first + n.count; ++i) {
          const auto& t = mesh_.triangles[tree_.order()[i]];
          best = std::min(best,
                          PointTriangleDistance2(p, mesh_.vertices[t[0]], mesh_.vertices[t[1]], mesh_.vertices[t[2]]));
        }
        continue;
      }
      const double dl = BoxDistance2(nodes[n.left].box, p), dr = BoxDistance2(nodes[n.right].box, p);
      // Push the farther child first so the nearer one is visited first.
      if (dl < dr) {
        stack[top++] = n.right;
        stack[top++] = n.left;
      } else {
        stack[top++] = n.left;
        stack[top++] = n.right;
      }
    }
    return std::sqrt(best);
  }

 private:
  using Tree = fabatlas::swept::BoxTree<3>;
  static std::vector<Tree::Box> TriangleBoxes(const TriangleMesh& m) {
    std::vector<Tree::Box> boxes;
    boxes.reserve(m.triangles.size());
    for (const auto& t : m.triangles) {
      Tree::Box b{{{1e300, 1e300, 1e300}, {-1e300, -1e300, -1e300}}};
      for (int v : t)
        for (int k = 0; k < 3; ++k) {
          b[0][k] = std::min(b[0][k], m.vertices[v][k]);
          b[1][k] = std::max(b[1][k], m.vertices[v][k]);
        }
      boxes.push_back(b);
    }
    return boxes;
  }
  static double BoxDistance2(const Tree::Box& b, const Vec3& p) {
    double d = 0;
    for (int k = 0; k < 3; ++k) {
      const double e = std::max({b[0][k] - p[k], 0.0, p[k] - b[1][k]});
      d += e * e;
    }
    return d;
  }

  const TriangleMesh& mesh_;
  Tree tree_;
};

struct Lattice {
  std::array<int, 3> lo, count;
  double h;
  std::size_t size() const { return std::size_t(count[0]) * count[1] * count[2]; }
};

// One dense time step: every lattice point (optionally one z-slice) takes
// min(current, distance to f(t)B) through one closest-point query.
void DenseStep(const TriangleTree& tree, const Lattice& g, const Transform& f, int only_z, std::vector<float>& d,
               double cutoff = std::numeric_limits<double>::infinity()) {
  const Transform inv = f.Inverse();
  const int z0 = only_z >= 0 ? only_z : 0, z1 = only_z >= 0 ? only_z + 1 : g.count[2];
  tbb::parallel_for(tbb::blocked_range<int>(z0 * g.count[1], z1 * g.count[1]), [&](const auto& r) {
    for (int zy = r.begin(); zy != r.end(); ++zy) {
      const int z = zy / g.count[1], y = zy % g.count[1];
      for (int x = 0; x < g.count[0]; ++x) {
        const Vec3 p{(g.lo[0] + x) * g.h, (g.lo[1] + y) * g.h, (g.lo[2] + z) * g.h};
        const float dist = static_cast<float>(tree.Distance(inv.Apply(p), cutoff));
        float& slot = d[(std::size_t(z) * g.count[1] + y) * g.count[0] + x];
        slot = std::min(slot, dist);
      }
    }
  });
}

}  // namespace

int main(int argc, char** argv) {
  int span = 256, steps = 100, dense_steps = 5, repeats = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--span"))
      span = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--steps"))
      steps = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--dense-steps"))
      dense_steps = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--repeats"))
      repeats = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "usage: bench_swept [--span N] [--steps N] [--dense-steps N] [--repeats N]\n");
      return 2;
    }
  }
  if (span < 8 || steps < 2 || dense_steps < 1 || repeats < 1) {
    std::fprintf(stderr, "bench_swept: bad arguments\n");
    return 2;
  }

  // Body: a torus of 100 x 50 quads = 10,000 triangles (major 20 mm, minor 6 mm).
  const TriangleMesh body = fabatlas::swept::testing::Torus(20.0, 6.0, 100, 50);
  // Motion: a curved Bezier translation with a quarter turn about a tilted axis.
  fabatlas::swept::RigidMotion motion = fabatlas::swept::RigidMotion::Turn({1, 1, 0}, 90, {0, 0, 0});
  motion.translation = {{{0, 0, 0}, {20, 25, 0}, {45, 25, 10}, {60, 0, 10}}};
  std::vector<Transform> poses;
  for (int i = 0; i < steps; ++i) poses.push_back(motion.At(double(i) / (steps - 1)));

  // Lattice over the swept bounding box, padded; voxel size = largest extent / span.
  Vec3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (const auto& f : poses)
    for (const auto& v : body.vertices) {
      const Vec3 p = f.Apply(v);
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    }
  const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
  const double h = extent / (span - 8);  // 4 voxels of padding on each side
  Lattice g;
  g.h = h;
  for (int k = 0; k < 3; ++k) {
    g.lo[k] = static_cast<int>(std::floor(lo[k] / h)) - 4;
    g.count[k] = static_cast<int>(std::ceil(hi[k] / h)) + 4 - g.lo[k] + 1;
  }
  fabatlas::swept::SweptVolumeOptions options;
  options.voxel_size = h;
  options.offset = 2 * h;

  std::printf("body: %zu triangles; %d time steps; voxel %.4f mm; lattice %d x %d x %d = %zu points\n",
              body.triangles.size(), steps, h, g.count[0], g.count[1], g.count[2], g.size());

  // Sparse narrow-band method, full motion.
  std::vector<double> sparse_times;
  fabatlas::swept::SweptDistanceField field;
  fabatlas::swept::SweptVolumeSummary summary;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    field = fabatlas::swept::ComputeSweptDistance(body, poses, options, &summary);
    sparse_times.push_back(Seconds(t0));
  }
  const auto tm = std::chrono::steady_clock::now();
  const auto surface = field.Surface(options.offset);
  const double mesh_time = Seconds(tm);

  // Dense method: per-step cost on dense_steps evenly spaced steps.
  const auto tb = std::chrono::steady_clock::now();
  TriangleTree tree(body);
  const double tree_time = Seconds(tb);
  std::vector<float> dense(g.size(), std::numeric_limits<float>::infinity());
  std::vector<double> step_times;
  for (int s = 0; s < dense_steps; ++s) {
    const int i = dense_steps == 1 ? 0 : s * (steps - 1) / (dense_steps - 1);
    const auto t0 = std::chrono::steady_clock::now();
    DenseStep(tree, g, poses[i], -1, dense);
    step_times.push_back(Seconds(t0));
  }
  const double dense_total = tree_time + Median(step_times) * steps;
  // Dense with culling: queries stop at the sparse method's band half width.
  std::vector<float> culled(g.size(), std::numeric_limits<float>::infinity());
  std::vector<double> culled_times;
  for (int s = 0; s < dense_steps; ++s) {
    const int i = dense_steps == 1 ? 0 : s * (steps - 1) / (dense_steps - 1);
    const auto t0 = std::chrono::steady_clock::now();
    DenseStep(tree, g, poses[i], -1, culled, field.band_half_width());
    culled_times.push_back(Seconds(t0));
  }
  const double culled_total = tree_time + Median(culled_times) * steps;

  // Accuracy on one z-slice through the middle, all steps, both methods.
  const int zmid = g.count[2] / 2;
  std::vector<float> slice(g.size(), std::numeric_limits<float>::infinity());
  for (const auto& f : poses) DenseStep(tree, g, f, zmid, slice);
  double max_err = 0;
  std::size_t compared = 0, disagree = 0;
  const double band = field.band_half_width();
  for (int y = 0; y < g.count[1]; ++y)
    for (int x = 0; x < g.count[0]; ++x) {
      const float d = slice[(std::size_t(zmid) * g.count[1] + y) * g.count[0] + x];
      const double s = field.ValueAtVoxel({g.lo[0] + x, g.lo[1] + y, g.lo[2] + zmid});
      if (d < band - h && s > 0) {
        ++compared;
        max_err = std::max(max_err, std::abs(s - d));
      }
      if (s > -h && (d > options.offset) != (s > options.offset)) ++disagree;  // d is unsigned
    }

  const double sparse_med = Median(sparse_times);
  std::printf(
      "sparse: median %.3f s over %d runs (%d steps, band %.3f mm, %zu body band voxels, %llu voxel "
      "updates, %zu active voxels); meshing iso %.3f mm: %.3f s, %zu triangles\n",
      sparse_med, repeats, summary.time_steps, summary.band_half_width, summary.body_band_voxels,
      static_cast<unsigned long long>(summary.voxel_updates), summary.active_voxels, options.offset, mesh_time,
      surface.triangles.size());
  std::printf("dense:  median %.3f s per step over %d steps -> %.1f s for %d steps (tree %.3f s)\n", Median(step_times),
              dense_steps, dense_total, steps, tree_time);
  std::printf("dense, queries culled at the band (%.3f mm): median %.3f s per step -> %.1f s for %d steps\n",
              field.band_half_width(), Median(culled_times), culled_total, steps);
  std::printf("speedup dense/sparse: %.1fx; culled dense/sparse: %.1fx\n", dense_total / sparse_med,
              culled_total / sparse_med);
  std::printf(
      "accuracy (z-slice %d, all steps): %zu outside voxels in band, max |sparse - dense| = %.4f mm "
      "(%.3f voxel); %zu voxels on different sides of the offset surface\n",
      zmid, compared, max_err, max_err / h, disagree);
  return 0;
}

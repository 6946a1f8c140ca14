// Shape diameter function (Shapira, Shamir, Cohen-Or 2008, section 3) with
// Embree 3 ray casting. See docs/mesh.md for the estimator and its tolerances.
#include "fabatlas/mesh/shape_diameter.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "fabatlas/error.h"

namespace fabatlas::mesh {
namespace {

using Vec = std::array<double, 3>;

Vec Sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec Cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double Dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
double Norm(const Vec& a) { return std::sqrt(Dot(a, a)); }

// Orthonormal basis around unit vector n (Duff et al. 2017, branchless).
void Basis(const Vec& n, Vec* t, Vec* b) {
  const double sign = std::copysign(1.0, n[2]);
  const double a = -1.0 / (sign + n[2]);
  const double c = n[0] * n[1] * a;
  *t = {1.0 + sign * n[0] * n[0] * a, sign * c, -sign * n[0]};
  *b = {c, sign + n[1] * n[1] * a, -n[1]};
}

// The process's Embree device, created on first use and kept (its first
// creation costs about 1 ms, later ones 0.05 ms; a worker measures sample
// after sample). Embree devices are thread-safe; each call builds its own
// scene on it. Its kernels are at most AVX2 (`max_isa`): Embree's AVX-512
// kernels round some hit distances differently in the last float bit, so
// workers with and without AVX-512 gave different per-face values; and on
// this project's AMD EPYC machine (Zen 4 runs 512-bit vectors as two 256-bit
// halves) the AVX2 kernels trace the tray's rays 9% faster (docs/mesh.md).
RTCDevice Device() {
  static const RTCDevice device = rtcNewDevice("max_isa=avx2");
  if (!device) throw std::runtime_error("shape diameter: cannot create Embree device");
  return device;
}

// RAII for the Embree scene.
struct EmbreeScene {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  ~EmbreeScene() {
    if (scene) rtcReleaseScene(scene);
  }
};

// Weighted median: smallest value whose cumulative weight reaches half the total.
double WeightedMedian(std::vector<std::pair<double, double>>& values) {
  std::sort(values.begin(), values.end());
  double total = 0;
  for (const auto& v : values) total += v.second;
  double acc = 0;
  for (const auto& v : values) {
    acc += v.second;
    if (acc >= 0.5 * total) return v.first;
  }
  return values.back().first;
}

// Throws InputError for options out of range or a triangle's vertex index
// outside `mesh.vertices`.
void CheckInput(const TriangleMesh& mesh, const ShapeDiameterOptions& options) {
  if (options.rays < 1 || options.rays > 10000) {
    throw InputError("shape diameter: rays must be in [1, 10000], got " + std::to_string(options.rays));
  }
  if (!(options.wall_angle_degrees > 0 && options.wall_angle_degrees <= 180)) {
    throw InputError("shape diameter: wall_angle_degrees must be in (0, 180], got " +
                     std::to_string(options.wall_angle_degrees));
  }
  if (!(options.cone_angle_degrees > 0 && options.cone_angle_degrees < 180)) {
    throw InputError("shape diameter: cone_angle_degrees must be in (0, 180), got " +
                     std::to_string(options.cone_angle_degrees));
  }
  const auto nv = static_cast<std::int64_t>(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (std::int32_t v : mesh.triangles[t])
      if (v < 0 || v >= nv) {
        throw InputError("shape diameter: triangle " + std::to_string(t) + " has vertex index " + std::to_string(v) +
                         " out of range");
      }
}

// The measured faces (every stride-th): unit outward normal (zero for a
// degenerate face), area (mm^2) and centroid (mm), entry i for face i * stride;
// and the diagonal of the bounding box of all faces' corners (mm).
struct MeasuredFaces {
  std::size_t stride = 1;
  std::vector<Vec> normal, centroid;
  std::vector<double> area;
  double diagonal = 0;
};

// MeasuredFaces of `mesh` (at least one triangle) over face ranges in
// parallel (min and max: the same for any schedule).
MeasuredFaces MeasureFaces(const TriangleMesh& mesh, std::size_t stride) {
  const std::size_t nf = mesh.triangles.size();
  const std::size_t measured_faces = (nf + stride - 1) / stride;
  MeasuredFaces faces;
  faces.stride = stride;
  faces.normal.resize(measured_faces);
  faces.centroid.resize(measured_faces);
  faces.area.resize(measured_faces);
  std::vector<Vec>& normal = faces.normal;
  std::vector<Vec>& centroid = faces.centroid;
  std::vector<double>& area = faces.area;
  using Bounds = std::pair<Vec, Vec>;
  constexpr double inf = std::numeric_limits<double>::infinity();
  const Bounds bounds = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, nf, 1024), Bounds{{inf, inf, inf}, {-inf, -inf, -inf}},
      [&](const tbb::blocked_range<std::size_t>& range, Bounds box) {
        for (std::size_t f = range.begin(); f != range.end(); ++f) {
          const auto& t = mesh.triangles[f];
          const Vec& a = mesh.vertices[t[0]];
          const Vec& b = mesh.vertices[t[1]];
          const Vec& c = mesh.vertices[t[2]];
          if (f % stride == 0) {
            const Vec n = Cross(Sub(b, a), Sub(c, a));
            const double len = Norm(n);
            const std::size_t i = f / stride;
            area[i] = 0.5 * len;
            normal[i] = len > 0 ? Vec{n[0] / len, n[1] / len, n[2] / len} : Vec{0, 0, 0};
            for (int k = 0; k < 3; ++k) centroid[i][k] = (a[k] + b[k] + c[k]) / 3.0;
          }
          for (const Vec* p : {&a, &b, &c})
            for (int k = 0; k < 3; ++k) {
              box.first[k] = std::min(box.first[k], (*p)[k]);
              box.second[k] = std::max(box.second[k], (*p)[k]);
            }
        }
        return box;
      },
      [](Bounds x, const Bounds& y) {
        for (int k = 0; k < 3; ++k) {
          x.first[k] = std::min(x.first[k], y.first[k]);
          x.second[k] = std::max(x.second[k], y.second[k]);
        }
        return x;
      });
  const Vec& lo = bounds.first;
  const Vec& hi = bounds.second;
  faces.diagonal = Norm(Sub(hi, lo));
  return faces;
}

// The triangles as Embree quads: two consecutive triangles (a, b, c),
// (a, d, b) that share their edge a-b, as Solid::ToMesh writes each quad of
// the level-set extraction, are the quad (c, a, d, b), which Embree
// intersects as the triangles (c, a, b) and (d, b, a): the same two
// triangles, in a tree of half as many primitives (the tray's 83k
// triangles: build 4.1 -> 1.4 ms, rays 10% faster; hit distances equal to
// a few float roundings). Any other triangle is the quad (a, b, c, c),
// whose second triangle (c, c, b) is empty.
struct QuadPairing {
  // first[q]: the quad's first triangle; its second is first[q] + 1 when
  // paired[q].
  std::vector<std::uint32_t> first;
  std::vector<char> paired;
  // quad_of[i]: the quad holding measured face i * stride.
  std::vector<std::uint32_t> quad_of;
};

QuadPairing PairTriangles(const TriangleMesh& mesh, std::size_t stride, std::size_t measured_faces) {
  const std::size_t nf = mesh.triangles.size();
  QuadPairing quads;
  std::vector<std::uint32_t>& first = quads.first;
  std::vector<char>& paired = quads.paired;
  std::vector<std::uint32_t>& quad_of = quads.quad_of;
  quad_of.resize(measured_faces);
  first.reserve(nf);
  paired.reserve(nf);
  for (std::size_t f = 0; f < nf;) {
    const bool pair = f + 1 < nf && mesh.triangles[f + 1][0] == mesh.triangles[f][0] &&
                      mesh.triangles[f + 1][2] == mesh.triangles[f][1];
    const auto q = static_cast<std::uint32_t>(first.size());
    for (std::size_t g = f; g < f + (pair ? 2 : 1); ++g)
      if (g % stride == 0) quad_of[g / stride] = q;
    first.push_back(static_cast<std::uint32_t>(f));
    paired.push_back(pair ? 1 : 0);
    f += pair ? 2 : 1;
  }
  return quads;
}

// Builds embree->scene (on embree->device) from the mesh's vertices in
// float32 and `quads`, at build quality `quality`.
void BuildScene(const TriangleMesh& mesh, const QuadPairing& quads, RTCBuildQuality quality, EmbreeScene* embree) {
  const std::vector<std::uint32_t>& first = quads.first;
  const std::vector<char>& paired = quads.paired;
  embree->scene = rtcNewScene(embree->device);
  const std::size_t nq = first.size();
  RTCGeometry geometry = rtcNewGeometry(embree->device, RTC_GEOMETRY_TYPE_QUAD);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), mesh.vertices.size()));
  auto* ib = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), nq));
  if (!vb || !ib) {
    rtcReleaseGeometry(geometry);
    throw std::runtime_error("shape diameter: Embree buffer allocation failed");
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mesh.vertices.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t v = range.begin(); v != range.end(); ++v)
                        for (int k = 0; k < 3; ++k) vb[3 * v + k] = static_cast<float>(mesh.vertices[v][k]);
                    });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nq, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t q = range.begin(); q != range.end(); ++q) {
      const auto& t = mesh.triangles[first[q]];
      const std::array<std::int32_t, 4> quad =
          paired[q] ? std::array<std::int32_t, 4>{t[2], t[0], mesh.triangles[first[q] + 1][1], t[1]}
                    : std::array<std::int32_t, 4>{t[0], t[1], t[2], t[2]};
      for (int k = 0; k < 4; ++k) ib[4 * q + k] = static_cast<unsigned>(quad[k]);
    }
  });
  rtcSetSceneBuildQuality(embree->scene, quality);
  rtcSetGeometryBuildQuality(geometry, quality);
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(embree->scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(embree->scene);
}

// Fixed ray pattern in the cone frame: polar angle uniform in (0, cone/2),
// azimuth by the golden angle. Weight 1/theta (Shapira et al. 2008).
// Entries (sin th cos ph, sin th sin ph, cos th, weight).
std::vector<std::array<double, 4>> RayPattern(const ShapeDiameterOptions& options) {
  const int n_rays = options.rays;
  const double half = 0.5 * options.cone_angle_degrees * std::numbers::pi / 180.0;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  std::vector<std::array<double, 4>> pattern(n_rays);
  for (int i = 0; i < n_rays; ++i) {
    const double theta = half * (i + 0.5) / n_rays;
    const double phi = golden * i;
    pattern[i] = {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta), 1.0 / theta};
  }
  return pattern;
}

// What every face's rays share: the scene, the quads, the measured faces,
// the ray pattern, the near limit of hits (mm) and the wall test's cosine.
struct RayCast {
  RTCScene scene = nullptr;
  const QuadPairing* quads = nullptr;
  const MeasuredFaces* faces = nullptr;
  const std::vector<std::array<double, 4>>* pattern = nullptr;
  float t_near = 0;
  double min_opposition = 0;
};

// Fills packet with eight rays from measured face i's centroid, rays k0 ..
// k0 + 7 of the pattern around `axis` (lanes past the last ray invalid), and
// their directions in double in dir.
void FillPacket(const RayCast& cast, std::size_t i, const Vec& axis, const Vec& t, const Vec& b, int k0, int valid[8],
                RTCRayHit8* packet, std::array<Vec, 8>* dir) {
  const std::vector<std::array<double, 4>>& pattern = *cast.pattern;
  const std::vector<Vec>& centroid = cast.faces->centroid;
  const int n_rays = static_cast<int>(pattern.size());
  for (int l = 0; l < 8; ++l) {
    const int k = std::min(k0 + l, n_rays - 1);
    valid[l] = k0 + l < n_rays ? -1 : 0;
    const auto& r = pattern[k];
    (*dir)[l] = {r[0] * t[0] + r[1] * b[0] + r[2] * axis[0], r[0] * t[1] + r[1] * b[1] + r[2] * axis[1],
                 r[0] * t[2] + r[1] * b[2] + r[2] * axis[2]};
    packet->ray.org_x[l] = static_cast<float>(centroid[i][0]);
    packet->ray.org_y[l] = static_cast<float>(centroid[i][1]);
    packet->ray.org_z[l] = static_cast<float>(centroid[i][2]);
    packet->ray.dir_x[l] = static_cast<float>((*dir)[l][0]);
    packet->ray.dir_y[l] = static_cast<float>((*dir)[l][1]);
    packet->ray.dir_z[l] = static_cast<float>((*dir)[l][2]);
    packet->ray.tnear[l] = cast.t_near;
    packet->ray.tfar[l] = std::numeric_limits<float>::infinity();
    packet->ray.time[l] = 0;
    packet->ray.mask[l] = 0xFFFFFFFFu;
    packet->ray.id[l] = 0;
    packet->ray.flags[l] = 0;
    packet->hit.geomID[l] = RTC_INVALID_GEOMETRY_ID;
    packet->hit.primID[l] = RTC_INVALID_GEOMETRY_ID;
    packet->hit.instID[0][l] = RTC_INVALID_GEOMETRY_ID;
  }
}

// Whether lane l's hit in `packet`, a ray along dir from measured face i, is
// a wall's far side (and not the face itself).
bool HitsWall(const RayCast& cast, std::size_t i, const RTCRayHit8& packet, int l, const Vec& dir) {
  const QuadPairing& quads = *cast.quads;
  const std::size_t f = i * cast.faces->stride;
  const Vec& normal = cast.faces->normal[i];
  const double min_opposition = cast.min_opposition;
  // The face itself: its own quad, and in it the triangle hit (a
  // quad's second when u + v > 1, Embree's quad parametrisation).
  // Only a hit on its own quad reads first and paired (a cache miss
  // per ray otherwise).
  const unsigned q = packet.hit.primID[l];
  if (q == quads.quad_of[i] && quads.first[q] + (quads.paired[q] && packet.hit.u[l] + packet.hit.v[l] > 1 ? 1 : 0) == f)
    return false;
  // The hit face's unit normal from Embree's geometric normal (the
  // counter-clockwise one, as ours; rounded to float, equal to the
  // double one to 1e-9 in cosine on the tray): reading ours would be
  // a cache miss per ray into an array of every face's.
  const Vec ng = {packet.hit.Ng_x[l], packet.hit.Ng_y[l], packet.hit.Ng_z[l]};
  const double ng_length = Norm(ng);
  if (!(ng_length > 0)) return false;
  // Valid only on the inner side of a wall: the hit face's outward
  // normal points along the ray (dot(ng, dir) / |ng| > 0) ...
  // ... and only on the far side of a wall: the hit face turns back
  // towards this one (normals more than 180 - wall_angle degrees
  // apart, dot(ng, n) / |ng| <= -min_opposition). A neighbouring
  // face across a convex edge (a cube's, 90 degrees) is no wall:
  // near such an edge its short rays would outvote the opposite
  // face's in the median and the outlier test.
  // Both on the unnormalised normal where it decides them by more
  // than 1e-9 of |ng| (rounding moves these dot products by ~1e-15
  // of it), else on the normalised one: the same decisions as
  // normalising always, without three divisions per hit.
  const double along = Dot(ng, dir), turned = Dot(ng, normal) + min_opposition * ng_length;
  const double margin = 1e-9 * ng_length;
  if (std::abs(along) > margin && std::abs(turned) > margin) {
    if (along <= 0 || turned > 0) return false;
  } else {
    const Vec hit_normal = {ng[0] / ng_length, ng[1] / ng_length, ng[2] / ng_length};
    if (Dot(hit_normal, dir) <= 0) return false;
    if (Dot(hit_normal, normal) > -min_opposition) return false;
  }
  return true;
}

// The valid hits of measured face i's rays, as (length mm, weight), in ray
// order, into *hits (cleared first).
void CastFaceRays(const RayCast& cast, std::size_t i, RTCIntersectContext* context,
                  std::vector<std::pair<double, double>>* hits) {
  const std::vector<std::array<double, 4>>& pattern = *cast.pattern;
  const int n_rays = static_cast<int>(pattern.size());
  const Vec& normal = cast.faces->normal[i];
  const Vec axis = {-normal[0], -normal[1], -normal[2]};
  Vec t, b;
  Basis(axis, &t, &b);
  hits->clear();
  // The face's rays in packets of eight (one ray per lane of Embree's
  // AVX2 packet traversal, rtcIntersect8): they share an origin and
  // spread over a cone, so a packet walks the tree together, and each
  // lane's hit is the one rtcIntersect1 finds: per-face values bit for
  // bit the same on the tray, sign.scad and candleStand.scad (every face),
  // in 14-22% less time (docs/benchmarks.md "OpenSCAD"; a try before
  // the AVX2 cap, on AVX-512 kernels, moved some hit lengths).
  for (int k0 = 0; k0 < n_rays; k0 += 8) {
    alignas(32) int valid[8];
    alignas(32) RTCRayHit8 packet;
    std::array<Vec, 8> dir;
    FillPacket(cast, i, axis, t, b, k0, valid, &packet, &dir);
    rtcInitIntersectContext(context);
    rtcIntersect8(valid, cast.scene, context, &packet);
    for (int l = 0; l < 8 && k0 + l < n_rays; ++l) {
      if (packet.hit.geomID[l] == RTC_INVALID_GEOMETRY_ID) continue;
      if (!HitsWall(cast, i, packet, l, dir[l])) continue;
      hits->push_back({static_cast<double>(packet.ray.tfar[l]), pattern[k0 + l][3]});
    }
  }
}

// Outlier removal: drops from *hits (length, weight) the lengths further than
// one standard deviation from their median; `lengths` is scratch.
void DropOutliers(std::vector<std::pair<double, double>>* hits, std::vector<double>* lengths) {
  lengths->clear();
  for (const auto& h : *hits) lengths->push_back(h.first);
  std::sort(lengths->begin(), lengths->end());
  const std::size_t m = lengths->size();
  const double median = m % 2 ? (*lengths)[m / 2] : 0.5 * ((*lengths)[m / 2 - 1] + (*lengths)[m / 2]);
  double mean = 0;
  for (double l : *lengths) mean += l;
  mean /= m;
  double var = 0;
  for (double l : *lengths) var += (l - mean) * (l - mean);
  const double sigma = std::sqrt(var / m);
  std::erase_if(*hits, [&](const auto& h) { return std::abs(h.first - median) > sigma; });
}

// Area-weighted statistics over the measured faces with a value: counts
// faces_without_value and sets min, percentile_5, median (mm) and
// area_fraction_below in *summary (left NaN when no face has a value).
void AreaStatistics(const MeasuredFaces& faces, double thin_threshold, ShapeDiameterSummary* summary) {
  const std::size_t nf = summary->per_face.size();
  const std::size_t stride = faces.stride;
  const std::vector<double>& area = faces.area;
  std::vector<std::pair<double, double>> valued;  // (value, area)
  double total = 0, below = 0;
  for (std::size_t f = 0; f < nf; f += stride) {
    if (std::isnan(summary->per_face[f])) {
      ++summary->faces_without_value;
      continue;
    }
    valued.push_back({summary->per_face[f], area[f / stride]});
    total += area[f / stride];
    if (summary->per_face[f] < thin_threshold) below += area[f / stride];
  }
  if (valued.empty() || !(total > 0)) return;
  std::sort(valued.begin(), valued.end());
  summary->min = valued.front().first;
  auto quantile = [&](double q) {
    double acc = 0;
    for (const auto& v : valued) {
      acc += v.second;
      if (acc >= q * total) return v.first;
    }
    return valued.back().first;
  };
  summary->percentile_5 = quantile(0.05);
  summary->median = quantile(0.5);
  summary->area_fraction_below = below / total;
}

}  // namespace

ShapeDiameterSummary ShapeDiameter(const TriangleMesh& mesh, const ShapeDiameterOptions& options) {
  CheckInput(mesh, options);
  const std::size_t nf = mesh.triangles.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  ShapeDiameterSummary summary;
  summary.per_face.assign(nf, nan);
  summary.min = summary.percentile_5 = summary.median = summary.area_fraction_below = nan;
  if (nf == 0) return summary;

  // The measured faces: every stride-th.
  const std::size_t stride =
      options.max_faces > 0 && nf > static_cast<std::size_t>(options.max_faces)
          ? (nf + static_cast<std::size_t>(options.max_faces) - 1) / static_cast<std::size_t>(options.max_faces)
          : 1;
  const MeasuredFaces faces = MeasureFaces(mesh, stride);
  const std::size_t measured_faces = faces.area.size();
  // Rays start on the face; hits closer than this are the face itself or its
  // float32 rounding (1e-6 of the model size, well below any printable feature).
  const float t_near = static_cast<float>(1e-6 * faces.diagonal);

  const QuadPairing quads = PairTriangles(mesh, stride, measured_faces);
  // The tree's build quality by the work it serves: with fewer than 8 rays
  // per triangle (a stride sample of a large mesh: 4,000 faces x 30 rays
  // against the tray's 83k triangles) Embree's quick Morton build (LOW) costs
  // a third of the default's and the rays take no longer; with many rays per
  // triangle the default (MEDIUM) tree pays. Hits are exact either way.
  const std::size_t measured = options.max_faces > 0 && nf > static_cast<std::size_t>(options.max_faces)
                                   ? static_cast<std::size_t>(options.max_faces)
                                   : nf;
  const RTCBuildQuality quality =
      measured * static_cast<std::size_t>(options.rays) < 8 * nf ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_MEDIUM;
  EmbreeScene embree;
  embree.device = Device();
  BuildScene(mesh, quads, quality, &embree);

  const std::vector<std::array<double, 4>> pattern = RayPattern(options);
  RayCast cast;
  cast.scene = embree.scene;
  cast.quads = &quads;
  cast.faces = &faces;
  cast.pattern = &pattern;
  cast.t_near = t_near;
  cast.min_opposition = std::cos(options.wall_angle_degrees * std::numbers::pi / 180.0);

  summary.faces_measured = static_cast<std::int64_t>(measured_faces);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, measured_faces),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      std::vector<std::pair<double, double>> hits;  // (length, weight)
                      std::vector<double> lengths;
                      RTCIntersectContext context;
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        if (faces.area[i] <= 0) continue;
                        CastFaceRays(cast, i, &context, &hits);
                        if (hits.empty()) continue;
                        DropOutliers(&hits, &lengths);
                        if (hits.empty()) continue;  // cannot happen: some length is within sigma of the median
                        summary.per_face[i * stride] = WeightedMedian(hits);
                      }
                    });

  AreaStatistics(faces, options.thin_threshold, &summary);
  return summary;
}

}  // namespace fabatlas::mesh

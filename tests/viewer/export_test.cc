// `fabatlas export` as a real process over the viewer_tube_run fixture (the
// closed-form tube: valid where wall >= 1 + 0.01 radius^2 and radius - wall
// >= 2; a hollow cylinder of height 20 mm): the files are checked against the
// tube's analytic volume and size, read by code of this test (STL), by the
// glTF 2.0 node transform rules (glb) and by Python's zipfile and XML parser
// (3MF).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <map>
#include <numbers>
#include <regex>

#include <nlohmann/json.hpp>

#include "../cluster/cluster_process.h"
#include "fabatlas/testing/paths.h"
#include "viewer_runs.h"

namespace fabatlas::viewer {
namespace {

namespace fs = std::filesystem;
using cluster_test::ReadText;
using cluster_test::Spawn;
using cluster_test::WaitExit;
using viewer_test::PegRunDir;
using viewer_test::RunDir;

using viewer_test::TrulyValid;
using viewer_test::TubeVolume;

struct Outcome {
  int status = -1;
  std::string output;
};

Outcome Fabatlas(const std::vector<std::string>& args, const fs::path& dir) {
  std::vector<std::string> argv = {(testing::BinDir() / "fabatlas").string()};
  argv.insert(argv.end(), args.begin(), args.end());
  const fs::path log = dir / ("log-" + std::to_string(std::rand()));
  const pid_t pid = Spawn(argv, log);
  Outcome r;
  r.status = WaitExit(pid, std::chrono::minutes(4));
  r.output = ReadText(log);
  return r;
}

std::string ReadBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Binary STL: triangle count, edges not shared by exactly two triangles,
// signed volume (divergence theorem), bounding box.
struct StlFacts {
  std::size_t triangles = 0, open_edges = 0;
  double volume = 0;
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
};
StlFacts ReadStl(const std::string& b) {
  StlFacts f;
  std::uint32_t n = 0;
  std::memcpy(&n, b.data() + 80, 4);
  EXPECT_EQ(b.size(), 84 + 50 * std::size_t{n});
  f.triangles = n;
  std::map<std::pair<std::array<float, 3>, std::array<float, 3>>, int> edges;
  for (std::uint32_t t = 0; t < n; ++t) {
    std::array<std::array<float, 3>, 3> v;
    std::memcpy(v.data(), b.data() + 84 + 50 * t + 12, 36);
    const auto& [a, c, d] = v;
    f.volume +=
        (a[0] * (c[1] * d[2] - c[2] * d[1]) - a[1] * (c[0] * d[2] - c[2] * d[0]) + a[2] * (c[0] * d[1] - c[1] * d[0])) /
        6.0;
    for (int k = 0; k < 3; ++k) {
      for (int i = 0; i < 3; ++i) {
        f.lo[i] = std::min<double>(f.lo[i], v[k][i]);
        f.hi[i] = std::max<double>(f.hi[i], v[k][i]);
      }
      auto p = v[k], q = v[(k + 1) % 3];
      if (q < p) std::swap(p, q);
      ++edges[{p, q}];
    }
  }
  for (const auto& [e, count] : edges) f.open_edges += count != 2;
  return f;
}

class Export : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(RunDir() / "form.json")) << "run the viewer_tube_run fixture first: " << RunDir();
    dir_ = testing::FreshTempDir("viewer-export");
  }
  fs::path dir_;
};

TEST_F(Export, StlIsClosedWithTheTubesAnalyticVolume) {
  const Outcome r = Fabatlas(
      {"export", RunDir().string(), "--at", "radius=15,wall=6", "--format", "stl", "--out", (dir_ / "t.stl").string()},
      dir_);
  ASSERT_EQ(r.status, 0) << r.output;
  const StlFacts f = ReadStl(ReadBytes(dir_ / "t.stl"));
  EXPECT_GT(f.triangles, 1000u);
  EXPECT_EQ(f.open_edges, 0u);
  const double exact = TubeVolume(15, 6);  // 9047.8 mm^3
  EXPECT_NEAR(f.volume, exact, 0.01 * exact);
  // Exactly the requested point, not a snapped sample: outer diameter 30,
  // height 20 (within a fabrication voxel, 0.25 mm).
  EXPECT_NEAR(f.hi[0] - f.lo[0], 30.0, 0.25);
  EXPECT_NEAR(f.hi[2] - f.lo[2], 20.0, 0.25);
  EXPECT_NE(r.output.find("voxel 0.25 mm"), std::string::npos) << r.output;
}

TEST_F(Export, GlbIsInMetresWithYUp) {
  const Outcome r =
      Fabatlas({"export", RunDir().string(), "--at", "radius=15,wall=6", "--out", (dir_ / "t.glb").string()}, dir_);
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string g = ReadBytes(dir_ / "t.glb");
  ASSERT_EQ(g.substr(0, 4), "glTF");
  std::uint32_t json_length = 0;
  std::memcpy(&json_length, g.data() + 12, 4);
  const auto j = nlohmann::json::parse(g.substr(20, json_length));
  const auto& acc = j["accessors"][j["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<int>()];
  // World position = T R S p for the mesh's node (glTF 2.0 Sec. 3.5.3):
  // transform the 8 corners of the accessor's bounds.
  const auto& node = j["nodes"][j["scenes"][0]["nodes"][0].get<int>()];
  std::array<double, 3> s{1, 1, 1};
  std::array<double, 4> q{0, 0, 0, 1};
  if (node.contains("scale")) s = node["scale"].get<std::array<double, 3>>();
  if (node.contains("rotation")) q = node["rotation"].get<std::array<double, 4>>();
  const auto rotate = [&](std::array<double, 3> v) {  // v' = q v q*
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    const std::array<double, 3> t = {2 * (y * v[2] - z * v[1]), 2 * (z * v[0] - x * v[2]), 2 * (x * v[1] - y * v[0])};
    return std::array<double, 3>{v[0] + w * t[0] + (y * t[2] - z * t[1]), v[1] + w * t[1] + (z * t[0] - x * t[2]),
                                 v[2] + w * t[2] + (x * t[1] - y * t[0])};
  };
  std::array<double, 3> lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
  for (int corner = 0; corner < 8; ++corner) {
    std::array<double, 3> p;
    for (int i = 0; i < 3; ++i) p[i] = s[i] * acc[(corner >> i) & 1 ? "max" : "min"][i].get<double>();
    p = rotate(p);
    for (int i = 0; i < 3; ++i) lo[i] = std::min(lo[i], p[i]), hi[i] = std::max(hi[i], p[i]);
  }
  // The tube's axis is the design's z (height 20 mm, centred on z = 0): in
  // glTF it is 0.020 m tall along +Y and 0.030 m wide along x and z.
  EXPECT_NEAR(hi[1] - lo[1], 0.020, 0.0005);
  EXPECT_NEAR(hi[1] + lo[1], 0.0, 0.0005);
  EXPECT_NEAR(hi[0] - lo[0], 0.030, 0.0005);
  EXPECT_NEAR(hi[2] - lo[2], 0.030, 0.0005);
}

TEST_F(Export, ThreeMfOpensInPythonWithTheTubesVolume) {
  const Outcome r = Fabatlas(
      {"export", RunDir().string(), "--at", "radius=20,wall=8", "--format", "3mf", "--out", (dir_ / "t.3mf").string()},
      dir_);
  ASSERT_EQ(r.status, 0) << r.output;
  // An independent reader: Python's zipfile (CRCs checked) and ElementTree.
  const fs::path script = dir_ / "read3mf.py";
  std::ofstream(script) << R"(import sys, zipfile, xml.etree.ElementTree as ET
z = zipfile.ZipFile(sys.argv[1]); assert z.testzip() is None
assert '[Content_Types].xml' in z.namelist() and '_rels/.rels' in z.namelist()
ns = {'m': 'http://schemas.microsoft.com/3dmanufacturing/core/2015/02'}
root = ET.fromstring(z.read('3D/3dmodel.model')); assert root.get('unit') == 'millimeter'
v = [(float(e.get('x')), float(e.get('y')), float(e.get('z'))) for e in root.iterfind('.//m:vertex', ns)]
edges = {}; vol = 0.0; n = 0
for t in root.iterfind('.//m:triangle', ns):
    i = [int(t.get(k)) for k in ('v1', 'v2', 'v3')]; a, b, c = (v[k] for k in i); n += 1
    vol += (a[0]*(b[1]*c[2]-b[2]*c[1]) - a[1]*(b[0]*c[2]-b[2]*c[0]) + a[2]*(b[0]*c[1]-b[1]*c[0])) / 6
    for p, q in ((i[0], i[1]), (i[1], i[2]), (i[2], i[0])): edges[(p, q)] = edges.get((p, q), 0) + 1
bad = sum(1 for (p, q), k in edges.items() if k != 1 or edges.get((q, p)) != 1)
print(n, bad, vol)
)";
  const fs::path out = dir_ / "py.txt";
  ASSERT_EQ(
      std::system(("python3 " + script.string() + " " + (dir_ / "t.3mf").string() + " > " + out.string()).c_str()), 0);
  std::istringstream facts(ReadText(out));
  std::size_t triangles = 0, bad_edges = 1;
  double volume = 0;
  facts >> triangles >> bad_edges >> volume;
  EXPECT_GT(triangles, 1000u);
  EXPECT_EQ(bad_edges, 0u);  // closed and consistently oriented
  EXPECT_NEAR(volume, TubeVolume(20, 8), 0.01 * TubeVolume(20, 8));
}

TEST_F(Export, AnInvalidPointIsRefusedNamingATrulyValidNearestPoint) {
  const Outcome r =
      Fabatlas({"export", RunDir().string(), "--at", "radius=29,wall=1", "--out", (dir_ / "bad.stl").string()}, dir_);
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "bad.stl"));
  std::smatch m;
  ASSERT_TRUE(std::regex_search(r.output, m, std::regex(R"(nearest valid point: radius=([0-9.]+),wall=([0-9.]+))")))
      << r.output;
  const double radius = std::stod(m[1]), wall = std::stod(m[2]);
  EXPECT_TRUE(TrulyValid(radius, wall)) << r.output;
  // ... and that point exports.
  const Outcome ok = Fabatlas({"export", RunDir().string(), "--at", "radius=" + m[1].str() + ",wall=" + m[2].str(),
                               "--out", (dir_ / "ok.stl").string()},
                              dir_);
  EXPECT_EQ(ok.status, 0) << ok.output;
  const StlFacts f = ReadStl(ReadBytes(dir_ / "ok.stl"));
  EXPECT_NEAR(f.volume, TubeVolume(radius, wall), 0.01 * TubeVolume(radius, wall));
  // Bad arguments: one line, exit 2.
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"export", RunDir().string(), "--at", "radius=15,wall=6", "--out",
                                 (dir_ / "x.3ds").string()},
        std::vector<std::string>{"export", RunDir().string(), "--at", "radius=nan", "--out", (dir_ / "x.stl").string()},
        std::vector<std::string>{"export", (dir_ / "missing").string(), "--at", "radius=15", "--out",
                                 (dir_ / "x.stl").string()}}) {
    const Outcome bad = Fabatlas(args, dir_);
    EXPECT_EQ(bad.status, 2) << bad.output;
    EXPECT_EQ(std::count(bad.output.begin(), bad.output.end(), '\n'), 1) << bad.output;
  }
}

// The peg rail run (viewer_peg_run: tests/viewer/data/peg_rail_design.yaml,
// sampled on its bootstrap grid only): the rail is 2 mm high except for a
// 20 mm bulge at exactly length 17.5, where no sample lies.
double RailHeight(double length) { return 2 + 20 * std::exp(-std::pow((length - 17.5) / 0.4, 2)); }

TEST_F(Export, APointValidOnlyBetweenSamplesIsCheckedAtExactlyThatPoint) {
  ASSERT_TRUE(fs::exists(PegRunDir() / "form.json")) << "run the viewer_peg_run fixture first: " << PegRunDir();
  // The samples on both sides, (15, 1, thin) and (20, 1, thin), are valid,
  // so the form's valid region holds length 17.5 between them ...
  const auto form = nlohmann::json::parse(ReadText(PegRunDir() / "form.json"));
  int neighbours_valid = 0;
  for (const auto& s : form["samples"]) {
    const auto u = s["u"].get<std::vector<double>>();
    if ((u[0] == 15 || u[0] == 20) && u[1] == 1 && u[2] == 0) neighbours_valid += s["valid"].get<bool>();
  }
  ASSERT_EQ(neighbours_valid, 2);
  // ... but there the rail is 22 mm high: 17.5 x 6 x 22 = 2310 mm^3 of
  // material (the peg stands inside it), above the design's max_volume 1000.
  ASSERT_GT(17.5 * 6 * RailHeight(17.5), 1000);
  const Outcome r = Fabatlas(
      {"export", PegRunDir().string(), "--at", "length=17.5,pegs=1,peg=thin", "--out", (dir_ / "bulge.stl").string()},
      dir_);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_EQ(std::count(r.output.begin(), r.output.end(), '\n'), 1) << r.output;
  EXPECT_NE(r.output.find("fails check 'max_volume' at exactly this point (too_much_material"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir_ / "bulge.stl"));
  // Off the bulge (at 16 the bump is 20 e^-14 mm) the checks pass at the
  // exact point and the file holds the analytic volume: the 16 x 6 x 2 rail
  // and the peg's 5.5 mm above it (radius 1).
  const Outcome ok = Fabatlas(
      {"export", PegRunDir().string(), "--at", "length=16,pegs=1,peg=thin", "--out", (dir_ / "rail.stl").string()},
      dir_);
  ASSERT_EQ(ok.status, 0) << ok.output;
  EXPECT_NE(ok.output.find("checks passed there: constraints, geometry, max_volume"), std::string::npos) << ok.output;
  const double exact = 16 * 6 * RailHeight(16) + std::numbers::pi * (7.5 - RailHeight(16));
  const StlFacts f = ReadStl(ReadBytes(dir_ / "rail.stl"));
  EXPECT_EQ(f.open_edges, 0u);
  EXPECT_NEAR(f.volume, exact, 0.01 * exact);
}

}  // namespace
}  // namespace fabatlas::viewer

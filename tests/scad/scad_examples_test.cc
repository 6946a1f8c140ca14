// The OpenSCAD designs of Fab Forms Table 2 as example jobs
// (configs/jobs/yinyang_cup2.yaml, toy_car.yaml, holey_vase.yaml): each
// job's design loads with the paper's number of exposed parameters, one
// sample evaluates valid with every check, and its volume matches OpenSCAD's
// own STL render of the same design at the same solved values. The peer is
// an OpenSCAD program that writes the design's own nodes (revolve, box,
// cylinder, arrays) in OpenSCAD and includes the same .scad model with the
// values the `openscad` node passes, so the two sides share nothing but the
// model file and the numbers.
//
// Tolerance, 1% of OpenSCAD's volume (half the 2% bar for native
// against OpenSCAD volumes), so that each design's OpenSCAD part matters:
// leaving out the hole ring changes the vase's volume by 2.7%, one wheel the
// car's by 3.4%, the handle the cup's by about 8% (OpenSCAD renders of the
// parts alone at these values). The sample's volume is the level set's at
// the design's voxel (0.8-1 mm); its zero crossing lies within a small
// fraction of a voxel of the surface, so the difference is about that
// offset times the surface area: measured at these points cup -0.61% (about
// 34,000 mm^2 of surface: a mean offset of 0.007 mm), car -0.07%, vase
// -0.07%. Both sides are deterministic for a given OpenSCAD.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/testing/paths.h"

namespace {

namespace design = fabatlas::design;
namespace fs = std::filesystem;
using fabatlas::testing::SourceDir;

// The design of configs/jobs/<name>.yaml, loaded as the job names it.
design::Design JobDesign(const std::string& name) {
  const fabatlas::sampling::JobFile job =
      fabatlas::sampling::ReadJobFile((SourceDir() / "configs/jobs" / (name + ".yaml")).string());
  return design::LoadDesign(job.design_path);
}

// One sample at the design's defaults, every check run; must be valid.
design::SampleResult DefaultSample(const design::Design& d) {
  design::SampleResult r = design::EvaluateSample(d, design::ParsePoint(d, "", "--at"));
  EXPECT_TRUE(r.valid) << r.failure << ": " << r.failure_reason;
  return r;
}

// `name = value;` for each solved value the peer program uses.
std::string Values(const design::SampleResult& r, std::initializer_list<const char*> names) {
  std::ostringstream s;
  s.precision(17);
  for (const char* n : names) s << n << " = " << r.values.at(n) << ";\n";
  return s.str();
}

// OpenSCAD's own render of `program` (written to DIR/peer.scad): its volume.
double OpenScadVolume(const fs::path& dir, const std::string& program) {
  std::ofstream(dir / "peer.scad") << program;
  const std::string stl = (dir / "peer.stl").string();
  const std::string cmd = "openscad --quiet -o " + stl + " " + (dir / "peer.scad").string() + " 2>/dev/null";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  return std::abs(fabatlas::mesh::EnclosedVolume(fabatlas::mesh::ReadMesh(stl)));
}

std::string Model(const char* file) { return (SourceDir() / "configs/scad" / file).string(); }

// The design of configs/jobs/<job>.yaml against OpenSCAD: the paper's number
// of exposed parameters (Fab Forms Table 2), a valid sample at the defaults,
// and its volume within the tolerance above of OpenSCAD's render of `peer`
// (after the solved `values` as OpenSCAD variables). The figures are printed
// for docs/benchmarks.md.
void ExpectMatchesOpenScad(const std::string& job, std::size_t exposed, std::initializer_list<const char*> values,
                           const std::string& peer) {
  design::Design d = JobDesign(job);
  EXPECT_EQ(d.exposed.size(), exposed);
  design::SampleResult r = DefaultSample(d);
  ASSERT_TRUE(r.valid);
  const double ours = r.properties.at("volume");
  const double theirs = OpenScadVolume(fabatlas::testing::FreshTempDir("scad-" + job), Values(r, values) + peer);
  std::printf("%s: fabatlas %.1f mm^3, OpenSCAD %.1f mm^3 (%+.2f%%)\n", job.c_str(), ours, theirs,
              100 * (ours - theirs) / theirs);
  EXPECT_NEAR(ours, theirs, 0.01 * theirs);
}

// The samples of the job's design at `points` in order, sharing one subtree
// cache, checks off: what the cache plan records.
std::vector<design::SampleResult> CachedSamples(const std::string& job, std::initializer_list<const char*> points) {
  design::Design d = JobDesign(job);
  design::InMemorySubtreeCache cache;
  design::EvaluateOptions options;
  options.cache = &cache;
  options.run_checks = false;
  std::vector<design::SampleResult> out;
  for (const char* at : points) {
    out.push_back(design::EvaluateSample(d, design::ParsePoint(d, at, "--at"), options));
    EXPECT_TRUE(out.back().valid) << at << ": " << out.back().failure_reason;
  }
  return out;
}

// Every child key r's records name is itself recorded in r (sampling
// records the descendants of a subtree found in the cache too: the cache
// plan may keep any of them, and a cluster job's coordinator takes a kept
// subtree's geometry from a valid sample listing it).
void ExpectClosedUnderChildren(const design::SampleResult& r) {
  std::set<std::string> listed;
  for (const auto& s : r.subtrees) listed.insert(s.key);
  for (const auto& s : r.subtrees)
    for (const auto& child : s.children)
      EXPECT_TRUE(listed.count(child)) << s.op << " " << s.path << " without its child " << child.substr(0, 8);
}

TEST(ScadExampleJobs, YinYangCup2MatchesOpenScad) {
  // The body as the design's smooth revolutions (128 fragments: 0.04% below
  // the circle), the handle as the model with the node's -D values.
  ExpectMatchesOpenScad("yinyang_cup2", 3,
                        {"radius", "foot_r", "foot_h", "height", "wall", "inner_r", "handle_x", "handle_z",
                         "handle_reach", "handle_thick"},
                        "module handle() { include <" + Model("yinyang_handle.scad") +
                            ">\n reach = handle_reach; thick = handle_thick; }\n"
                            "difference() {\n"
                            "  rotate_extrude($fn = 128) polygon([[0, 0], [foot_r, 0], [radius, foot_h], [radius, "
                            "height], [0, height]]);\n"
                            "  rotate_extrude($fn = 128) polygon([[0, wall], [foot_r - wall, wall], [inner_r, foot_h + "
                            "wall], [inner_r, height + 2], [0, height + 2]]);\n"
                            "}\n"
                            "difference() {\n"
                            "  translate([handle_x, 0, handle_z]) handle();\n"
                            "  translate([0, 0, wall]) cylinder(r = inner_r, h = height, $fn = 128);\n"
                            "}\n");
}

TEST(ScadExampleJobs, ToyCarMatchesOpenScad) {
  ExpectMatchesOpenScad(
      "toy_car", 4,
      {"length", "body_w", "body_h", "axle_z", "cabin_x", "cabin_l", "cabin_w", "cabin_height", "window_l", "window_h",
       "wheelbase", "track", "wheel_radius", "tyre_w", "spokes"},
      "module wheel() { include <" + Model("toy_car_wheel.scad") +
          ">\n radius = wheel_radius; width = tyre_w; spokes = spokes_; }\n"
          "spokes_ = spokes;\n"
          "union() {\n"
          "  translate([0, 0, axle_z]) cube([length, body_w, body_h], center = true);\n"
          "  translate([cabin_x, 0, axle_z + body_h / 2 + cabin_height / 2]) difference() {\n"
          "    cube([cabin_l, cabin_w, cabin_height], center = true);\n"
          "    cube([window_l, cabin_w + 4, window_h], center = true);\n"
          "  }\n"
          "  for (x = [-wheelbase / 2, wheelbase / 2]) {\n"
          "    translate([x, 0, axle_z]) rotate([90, 0, 0]) cylinder(r = 2.5, h = track, center = true, $fn = 96);\n"
          "    for (y = [-track / 2, track / 2]) translate([x, y, axle_z]) rotate([90, 0, 0]) wheel();\n"
          "  }\n"
          "}\n");
}

// The car's spokes: by the wheel model's geometry (openings of radius
// 0.45 (rim - hub) centred at (rim + hub) / 2, rim = wheel radius - tyre
// width, hub 4 mm) two openings leave (rim + hub) sin(pi / spokes) -
// 0.9 (rim - hub) between them. At wheel radius 20 mm (tyre 7.5 mm) 6 spokes
// are 0.60 mm wide, thinner than the design's 1.2 mm check, and fail it; 4
// spokes are 4.3 mm wide and pass; at 30 mm 8 spokes would be -5.0 mm (the
// openings merge and the hub falls off), which the design's constraints
// reject. The spokes are under 1% of the car's surface, so this fails when
// the check allows the default 1% of thin surface.
TEST(ScadExampleJobs, ToyCarThinSpokesFailMinThickness) {
  design::Design d = JobDesign("toy_car");
  auto at = [&](const char* point) { return design::EvaluateSample(d, design::ParsePoint(d, point, "--at")); };
  const design::SampleResult thin = at("length=110,wheel_radius=20,spokes=6,cabin_height=23");
  EXPECT_NEAR(thin.values.at("spoke"), 0.60, 0.01);
  EXPECT_EQ(thin.failure, design::kThinParts) << thin.failure_reason;
  const design::SampleResult thick = at("length=110,wheel_radius=20,spokes=4,cabin_height=23");
  EXPECT_TRUE(thick.valid) << thick.failure << ": " << thick.failure_reason;
  EXPECT_EQ(at("length=110,wheel_radius=30,spokes=8,cabin_height=23").failure, design::kUnsatConstraints);
}

// The vase's bridges between holes: 16 holes of radius 4.5 mm at the ring
// leave bridges of about 0.8 mm (the design's `bridge` estimate), thinner
// than the 1.5 mm check, and fail it; radius 3 leaves 3.8 mm and passes. The
// bridges are under 1% of the vase's surface, so this fails when the check
// allows the default 1% of thin surface.
TEST(ScadExampleJobs, HoleyVaseThinBridgesFailMinThickness) {
  design::Design d = JobDesign("holey_vase");
  auto at = [&](const char* point) { return design::EvaluateSample(d, design::ParsePoint(d, point, "--at")); };
  const design::SampleResult thin = at("sides=8,bulge_r=30,bulge_z=45,holes=16,hole_r=4.5,hole_z=60");
  EXPECT_NEAR(thin.values.at("bridge"), 0.79, 0.01);
  EXPECT_EQ(thin.failure, design::kThinParts) << thin.failure_reason;
  const design::SampleResult thick = at("sides=8,bulge_r=30,bulge_z=45,holes=16,hole_r=3,hole_z=60");
  EXPECT_TRUE(thick.valid) << thick.failure << ": " << thick.failure_reason;
}

TEST(ScadExampleJobs, HoleyVaseMatchesOpenScad) {
  // fabatlas's n-sided revolve has a vertex on +x; OpenSCAD's rotate_extrude
  // starts at -x, hence the half turn.
  ExpectMatchesOpenScad(
      "holey_vase", 6,
      {"sides", "base_r", "bulge_r", "bulge_z", "neck_r", "wall", "holes", "hole_r", "hole_z", "drill"},
      "module drills() { include <" + Model("holey_vase_holes.scad") +
          ">\n count = holes; radius = hole_r; reach = drill; }\n"
          "off = wall / cos(180 / sides);  // the cavity's radial offset: `wall` across the flats\n"
          "difference() {\n"
          "  rotate([0, 0, 180]) rotate_extrude($fn = sides) polygon([[0, 0], [base_r, 0], [bulge_r, bulge_z], "
          "[neck_r, 100], [0, 100]]);\n"
          "  rotate([0, 0, 180]) rotate_extrude($fn = sides) polygon([[0, 4], [base_r - off, 4], [bulge_r - off, "
          "bulge_z], [neck_r - off, 100],\n"
          "    [neck_r - off + (neck_r - bulge_r) * 2 / (100 - bulge_z), 102], [0, 102]]);\n"
          "  translate([0, 0, hole_z]) drills();\n"
          "}\n");
}

// The cup's handle is the same model at the same values for two radii: the
// second sample finds the `openscad` node in the cache, and its record
// names the same CSG root as the first, as the cache plan requires (one set
// of children per key; `fabatlas sample --cache` stopped with "recorded
// with different children" when a hit recorded none).
TEST(ScadExampleJobs, CachedOpenScadNodeKeepsItsCsgChild) {
  std::vector<design::SubtreeRecord> handles;
  for (const design::SampleResult& r : CachedSamples("yinyang_cup2", {"radius=30", "radius=31"})) {
    ExpectClosedUnderChildren(r);  // the hit brings the handle's CSG subtrees
    for (const auto& s : r.subtrees)
      if (s.op == "openscad") handles.push_back(s);
  }
  ASSERT_EQ(handles.size(), 2u);
  EXPECT_EQ(handles[0].key, handles[1].key);
  EXPECT_FALSE(handles[0].from_cache);
  EXPECT_TRUE(handles[1].from_cache);
  ASSERT_EQ(handles[0].children.size(), 1u);
  EXPECT_EQ(handles[1].children, handles[0].children);
}

// The same for CSG subtrees inside the model: 8 and 9 holes share the first
// drill (the same cylinder under the same rotation); its record found in
// the cache names the same children as when it was computed.
TEST(ScadExampleJobs, CachedCsgSubtreesKeepTheirChildren) {
  std::map<std::string, std::vector<std::string>> children;
  int hits_with_children = 0;
  for (const design::SampleResult& r : CachedSamples("holey_vase", {"holes=8", "holes=9"})) {
    ExpectClosedUnderChildren(r);
    for (const auto& s : r.subtrees) {
      auto [it, first] = children.emplace(s.key, s.children);
      if (!first) {
        EXPECT_EQ(s.children, it->second) << s.op << " " << s.path;
      }
      hits_with_children += s.from_cache && s.op.rfind("csg:", 0) == 0 && !s.children.empty();
    }
  }
  EXPECT_GT(hits_with_children, 0);
}

}  // namespace

// `fabatlas serve` as a real process over a real run of the tube design
// (tests/viewer/data/tube_wall_2d.yaml, run by the viewer_tube_run fixture,
// served from the artifact it published):
// the API's answers are checked against the design's closed-form region
// (valid where wall >= 1 + 0.01 radius^2 and radius - wall >= 2) and volume,
// bad requests get 400 with one line, and no path outside the page and the
// API is reachable.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <numbers>
#include <regex>

#include <httplib.h>
#include <nlohmann/json.hpp>

#include "../cluster/cluster_process.h"
#include "fabatlas/testing/paths.h"
#include "viewer_runs.h"

namespace fabatlas::viewer {
namespace {

namespace fs = std::filesystem;
using cluster_test::KillAndReap;
using cluster_test::ReadText;
using cluster_test::Spawn;
using cluster_test::WaitExit;
using nlohmann::json;
using viewer_test::RunDir;
using viewer_test::TubeVolume;

class Server : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(RunDir() / "form.json")) << "run the viewer_tube_run fixture first: " << RunDir();
    dir_ = testing::FreshTempDir("viewer-serve");
    // A page of our own with a secret beside it: the secret must stay unreachable.
    fs::create_directories(dir_ / "web/assets");
    std::ofstream(dir_ / "web/index.html") << "<!doctype html><title>page</title>";
    std::ofstream(dir_ / "web/assets/app.js") << "console.log('app')";
    std::ofstream(dir_ / "secret.txt") << "SECRET-OUTSIDE-THE-PAGE";
    const fs::path log = dir_ / "serve.log";
    // The run directory holds the published artifact <design>.fabatlas.
    pid_ = Spawn({(testing::BinDir() / "fabatlas").string(), "serve", RunDir().string(), "--port", "0", "--web",
                  (dir_ / "web").string()},
                 log);
    const std::regex listening(R"(at http://127\.0\.0\.1:(\d+)/)");
    for (int i = 0; i < 1000 && port_ == 0; ++i) {
      std::smatch m;
      const std::string text = ReadText(log);
      if (std::regex_search(text, m, listening))
        port_ = std::stoi(m[1]);
      else if (WaitExit(pid_, std::chrono::milliseconds(20)) != -1)
        break;
    }
    ASSERT_GT(port_, 0) << ReadText(log);
    client_ = std::make_unique<httplib::Client>("127.0.0.1", port_);
    // An export evaluates the design at the point: on a loaded machine that
    // takes longer than the client's default 5 s, so wait for the answer.
    client_->set_read_timeout(std::chrono::seconds(120));
  }
  void TearDown() override {
    if (pid_ > 0) KillAndReap(pid_);
  }
  httplib::Result Get(const std::string& path) { return client_->Get(path); }
  json GetJson(const std::string& path) {
    auto r = Get(path);
    EXPECT_TRUE(r);
    if (!r) return {};
    EXPECT_EQ(r->status, 200) << path << ": " << r->body;
    return json::parse(r->body);
  }

  fs::path dir_;
  pid_t pid_ = -1;
  int port_ = 0;
  std::unique_ptr<httplib::Client> client_;
};

bool TrulyValid(double radius, double wall) { return wall >= 1 + 0.01 * radius * radius && radius - wall >= 2; }

TEST_F(Server, FormDescribesTheDesignAndItsStartingPoints) {
  const json form = GetJson("/api/form");
  EXPECT_EQ(form["name"], "tube_wall_2d");
  ASSERT_EQ(form["dimensions"].size(), 2u);
  EXPECT_EQ(form["dimensions"][0]["name"], "radius");
  EXPECT_EQ(form["dimensions"][0]["lo"], 5.0);
  EXPECT_EQ(form["dimensions"][0]["hi"], 30.0);
  EXPECT_EQ(form["dimensions"][1]["name"], "wall");
  ASSERT_EQ(form["materials"].size(), 2u);
  EXPECT_GE(form["starting_points"].size(), 1u);
  for (const auto& s : form["starting_points"]) {
    EXPECT_TRUE(s["valid"].get<bool>());
    EXPECT_TRUE(TrulyValid(s["u"][0], s["u"][1])) << s.dump();
  }
}

TEST_F(Server, IntervalsAreConservativeAgainstTheClosedFormRegion) {
  // At radius 15 the true valid walls are [3.25, 12] (the upper bound 13 from
  // radius - wall >= 2 is beyond the range); at wall 6 the true radii are
  // [8, sqrt(500) = 22.36].
  const json j = GetJson("/api/intervals?u=15,6");
  EXPECT_TRUE(j["valid"].get<bool>());
  const auto check = [](const json& stretches, double true_lo, double true_hi, double lo_bound, double hi_bound) {
    int valid = 0;
    for (const auto& s : stretches) {
      if (!s["valid"].get<bool>()) {
        EXPECT_EQ(s["failures"], json::array({"unsat_constraints"})) << s.dump();
        continue;
      }
      ++valid;
      EXPECT_GE(s["lo"].get<double>(), true_lo - 1e-9);
      EXPECT_LE(s["hi"].get<double>(), true_hi + 1e-9);
      // No worse than one bootstrap cell (this run splits at most twice).
      EXPECT_LE(s["lo"].get<double>(), lo_bound);
      EXPECT_GE(s["hi"].get<double>(), hi_bound);
    }
    EXPECT_EQ(valid, 1);
  };
  check(j["dimensions"][1], 3.25, 12.0, 3.25 + 11.5 / 5, 12.0);
  check(j["dimensions"][0], 8.0, std::sqrt(500.0), 8.0 + 25.0 / 5, std::sqrt(500.0) - 25.0 / 5);
  // Every valid interval end is itself valid and truly valid.
  for (int d = 0; d < 2; ++d)
    for (const auto& s : j["dimensions"][d])
      if (s["valid"].get<bool>())
        for (double end : {s["lo"].get<double>(), s["hi"].get<double>()}) {
          std::vector<double> u = {15.0, 6.0};
          u[d] = end;
          EXPECT_TRUE(TrulyValid(u[0], u[1])) << d << " " << end;
          const json at = GetJson("/api/intervals?u=" + std::to_string(u[0]) + "," + std::to_string(u[1]));
          EXPECT_TRUE(at["valid"].get<bool>()) << d << " " << end;
        }
  // Outside the region: invalid, with the recorded reason.
  const json bad = GetJson("/api/intervals?u=29,1");
  EXPECT_FALSE(bad["valid"].get<bool>());
  EXPECT_EQ(bad["failures"], json::array({"unsat_constraints"}));
}

TEST_F(Server, SnapAndPropertiesGiveAValidSampleWithTheTubesVolume) {
  const json p = GetJson("/api/properties?u=15,6");
  ASSERT_TRUE(p["valid"].get<bool>());
  const double r = p["u"][0], w = p["u"][1];
  EXPECT_TRUE(TrulyValid(r, w));
  // Hollow cylinder of height 20: pi (r^2 - (r - w)^2) 20, within 2 % (0.5 mm voxels).
  const double exact = std::numbers::pi * (r * r - (r - w) * (r - w)) * 20.0;
  EXPECT_NEAR(p["properties"]["volume"].get<double>(), exact, 0.02 * exact);
  ASSERT_EQ(p["materials"].size(), 2u);
  EXPECT_EQ(p["materials"][0]["name"], "PLA");
  EXPECT_NEAR(p["materials"][0]["weight_g"].get<double>(), p["properties"]["volume"].get<double>() / 1000 * 1.24, 1e-9);
  const json s = GetJson("/api/snap?u=15,6");
  EXPECT_EQ(s["sample"], p["sample"]);
}

// A GLB's first mesh primitive read here from the glTF 2.0 layout (12-byte
// header, JSON chunk, BIN chunk; float VEC3 positions, uint32 indices),
// without fabatlas's reader: the volume the triangles enclose (divergence
// theorem; positions as stored, millimetres) and the largest distance of a
// vertex from the z axis. volume is NaN when the bytes are not such a GLB.
struct GlbMesh {
  double volume = std::nan(""), max_radius = 0, z_lo = 1e300, z_hi = -1e300;
};
GlbMesh ReadGlbMesh(const std::string& glb) {
  GlbMesh m;
  const auto u32 = [&](std::size_t at) {
    std::uint32_t v = 0;
    std::memcpy(&v, glb.data() + at, 4);
    return v;
  };
  if (glb.size() < 20 || glb.compare(0, 4, "glTF") != 0 || u32(16) != 0x4E4F534Au) return m;
  const std::size_t json_length = u32(12), bin_at = 20 + json_length + 8;
  if (bin_at > glb.size()) return m;
  const json doc = json::parse(glb.substr(20, json_length));
  const auto& prim = doc["meshes"][0]["primitives"][0];
  const auto view = [&](int accessor, std::size_t* count) {
    const auto& a = doc["accessors"][accessor];
    const auto& v = doc["bufferViews"][a["bufferView"].get<int>()];
    *count = a["count"];
    return bin_at + v.value("byteOffset", std::size_t{0}) + a.value("byteOffset", std::size_t{0});
  };
  if (doc["accessors"][prim["indices"].get<int>()]["componentType"] != 5125) return m;  // uint32
  std::size_t vertices = 0, indices = 0;
  const std::size_t pos_at = view(prim["attributes"]["POSITION"], &vertices),
                    index_at = view(prim["indices"], &indices);
  std::vector<std::array<float, 3>> p(vertices);
  std::memcpy(p.data(), glb.data() + pos_at, 12 * vertices);
  for (const auto& v : p) {
    m.max_radius = std::max(m.max_radius, std::hypot(double{v[0]}, double{v[1]}));
    m.z_lo = std::min(m.z_lo, double{v[2]});
    m.z_hi = std::max(m.z_hi, double{v[2]});
  }
  m.volume = 0;
  for (std::size_t t = 0; t + 2 < indices; t += 3) {
    const auto& a = p[u32(index_at + 4 * t)];
    const auto& b = p[u32(index_at + 4 * t + 4)];
    const auto& c = p[u32(index_at + 4 * t + 8)];
    m.volume += (double{a[0]} * (double{b[1]} * c[2] - double{b[2]} * c[1]) -
                 double{a[1]} * (double{b[0]} * c[2] - double{b[2]} * c[0]) +
                 double{a[2]} * (double{b[0]} * c[1] - double{b[1]} * c[0])) /
                6;
  }
  return m;
}

TEST_F(Server, PreviewIsGlbOfTheSnappedSampleAndChangesWithU) {
  auto a = Get("/api/preview.glb?u=15,6");
  auto b = Get("/api/preview.glb?u=20,9");
  ASSERT_TRUE(a && b);
  ASSERT_EQ(a->status, 200);
  ASSERT_EQ(b->status, 200);
  EXPECT_EQ(a->get_header_value("Content-Type"), "model/gltf-binary");
  EXPECT_NE(a->get_header_value("X-Sample"), b->get_header_value("X-Sample"));
  // Each is the tube at the point it says it shows (X-Preview-U): its
  // closed-form volume within 2 % (0.5 mm voxels), its outer radius within
  // half a voxel, 20 mm high.
  for (const auto* r : {&a, &b}) {
    const std::string shown = (*r)->get_header_value("X-Preview-U");
    const double radius = std::stod(shown), wall = std::stod(shown.substr(shown.find(',') + 1));
    const GlbMesh m = ReadGlbMesh((*r)->body);
    ASSERT_FALSE(std::isnan(m.volume)) << "not a GLB of float positions and uint32 indices";
    EXPECT_NEAR(m.volume, TubeVolume(radius, wall), 0.02 * TubeVolume(radius, wall)) << shown;
    EXPECT_NEAR(m.max_radius, radius, 0.25) << shown;
    EXPECT_NEAR(m.z_hi - m.z_lo, 20, 0.5) << shown;
  }
}

TEST_F(Server, BadRequestsGet400WithOneLine) {
  for (const std::string q :
       {"/api/intervals?u=nan,1", "/api/intervals?u=1", "/api/intervals?u=15,6,1", "/api/intervals?u=15,100",
        "/api/snap?u=abc,1", "/api/intervals?u=inf,1", "/api/intervals", "/api/preview.glb?u=4,6",
        "/api/map?a=0&b=0&u=15,6", "/api/map?a=0&b=1&n=100000&u=15,6"}) {
    auto r = Get(q);
    ASSERT_TRUE(r) << q;
    EXPECT_EQ(r->status, 400) << q;
    EXPECT_FALSE(r->body.empty()) << q;
    EXPECT_EQ(r->body.find('\n'), r->body.size() - 1) << q << ": " << r->body;
  }
  auto r = Get("/api/nothing");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 404);
}

TEST_F(Server, OnlyThePageAndTheApiAreReachable) {
  auto page = Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<title>page</title>"), std::string::npos);
  auto asset = Get("/assets/app.js");
  ASSERT_TRUE(asset);
  EXPECT_EQ(asset->status, 200);
  // Traversal attempts, raw and encoded, toward files that do exist.
  httplib::Client raw("127.0.0.1", port_);
  for (const std::string& path : std::vector<std::string>{
           "/../secret.txt", "/assets/../../secret.txt", "/%2e%2e/secret.txt", "/..%2fsecret.txt",
           "/assets/%2e%2e/%2e%2e/secret.txt", "/api/../../secret.txt", "//etc/passwd", "/../../../../etc/passwd",
           "/index.html/../../secret.txt", "/form.json", "/" + RunDir().string() + "/form.json"}) {
    auto r = raw.Get(path);
    // Refused outright is fine too, but the server must still be answering.
    auto alive = Get("/api/form");
    ASSERT_TRUE(alive && alive->status == 200) << "server gone after " << path;
    if (!r) continue;
    EXPECT_NE(r->status, 200) << path;
    EXPECT_EQ(r->body.find("SECRET"), std::string::npos) << path;
    EXPECT_EQ(r->body.find("root:"), std::string::npos) << path;
  }
}

// Every response, the page's files, API answers and errors alike, carries a
// Content-Security-Policy without inline script, and nosniff; an error that
// echoes hostile input is plain text, never HTML.
TEST_F(Server, EveryResponseCarriesTheContentSecurityPolicyAndErrorsArePlainText) {
  httplib::Client raw("127.0.0.1", port_);
  const std::string hostile = "<script>document.title='XSS'</script>";
  const std::string encoded = "%3Cscript%3Edocument.title%3D%27XSS%27%3C%2Fscript%3E";  // hostile, URL-encoded
  const std::vector<std::pair<std::string, int>> gets = {{"/", 200},
                                                         {"/assets/app.js", 200},
                                                         {"/api/form", 200},
                                                         {"/api/intervals?u=15,6", 200},
                                                         {"/api/snap?u=" + encoded + ",1", 400},
                                                         {"/api/" + encoded, 404},
                                                         {"/nothing.html", 404}};
  for (const auto& [path, status] : gets) {
    auto r = raw.Get(path.c_str());
    ASSERT_TRUE(r) << path;
    EXPECT_EQ(r->status, status) << path;
    const std::string csp = r->get_header_value("Content-Security-Policy");
    EXPECT_NE(csp.find("script-src 'self'"), std::string::npos) << path << ": " << csp;
    EXPECT_EQ(csp.find("unsafe-inline"), std::string::npos) << path << ": " << csp;
    EXPECT_EQ(csp.find("unsafe-eval"), std::string::npos) << path << ": " << csp;
    EXPECT_EQ(r->get_header_value("X-Content-Type-Options"), "nosniff") << path;
    if (status >= 400) {
      EXPECT_EQ(r->get_header_value("Content-Type").rfind("text/plain", 0), 0u) << path;
      EXPECT_EQ(r->body.find('\n'), r->body.size() - 1) << path << ": " << r->body;
    }
  }
  // The 400's one line names the hostile value as typed, as text.
  auto bad = raw.Get(("/api/snap?u=" + encoded + ",1").c_str());
  ASSERT_TRUE(bad);
  EXPECT_NE(bad->body.find(hostile), std::string::npos) << bad->body;
  auto post = raw.Post("/api/form", "x", "text/plain");
  ASSERT_TRUE(post);
  EXPECT_EQ(post->status, 405);
  EXPECT_NE(post->get_header_value("Content-Security-Policy").find("script-src 'self'"), std::string::npos);
}

TEST_F(Server, MapMarksTheCurrentPointsCellValid) {
  const json m = GetJson("/api/map?a=0&b=1&n=25&u=15,6");
  ASSERT_EQ(m["cells"].size(), 625u);
  // Cell centres: radius 5.5 + i, wall 0.73 + 0.46 j. (15.5, 5.79) is well
  // inside; (29.5, 0.73) is far outside.
  EXPECT_EQ(m["cells"][11 * 25 + 10], -1);
  const int bad = m["cells"][0 * 25 + 24];
  ASSERT_GE(bad, 0);
  EXPECT_EQ(m["failures"][bad], "unsat_constraints");
}

TEST_F(Server, ExportSendsTheSameBytesAsTheCommandAndRefusesWithItsText) {
  // The command's file for the same point.
  const fs::path stl = dir_ / "cli.stl";
  const pid_t pid = Spawn({(testing::BinDir() / "fabatlas").string(), "export", RunDir().string(), "--at",
                           "radius=15,wall=6", "--out", stl.string()},
                          dir_ / "export.log");
  ASSERT_EQ(WaitExit(pid, std::chrono::minutes(3)), 0) << ReadText(dir_ / "export.log");
  auto r = Get("/api/export?u=15,6&format=stl");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->body, ReadText(stl));
  EXPECT_NE(
      r->get_header_value("Content-Disposition").find("attachment; filename=\"tube_wall_2d-radius=15_wall=6.stl\""),
      std::string::npos);
  auto three = Get("/api/export?u=15,6&format=3mf");
  ASSERT_TRUE(three);
  EXPECT_EQ(three->status, 200);
  EXPECT_EQ(three->body.substr(0, 4), std::string("PK\x03\x04"));
  // An invalid point: 400 with the command's one line (after "fabatlas: ").
  const pid_t bad = Spawn({(testing::BinDir() / "fabatlas").string(), "export", RunDir().string(), "--at",
                           "radius=29,wall=1", "--out", (dir_ / "bad.stl").string()},
                          dir_ / "bad.log");
  ASSERT_EQ(WaitExit(bad, std::chrono::minutes(3)), 2);
  auto refused = Get("/api/export?u=29,1&format=stl");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 400);
  EXPECT_EQ("fabatlas: " + refused->body, ReadText(dir_ / "bad.log"));
  auto format = Get("/api/export?u=15,6&format=3ds");
  ASSERT_TRUE(format);
  EXPECT_EQ(format->status, 400);
}

// The two queries that also take a JSON body answer POST over HTTP as GET.
TEST_F(Server, OptimiseAndParetoAnswerPostAsGet) {
  auto get = Get("/api/optimise?min=volume&hold=radius%3D15");
  auto post = client_->Post("/api/optimise", R"({"min": "volume", "hold": {"radius": 15}})", "application/json");
  ASSERT_TRUE(get && post);
  EXPECT_EQ(get->status, 200) << get->body;
  EXPECT_EQ(post->status, 200) << post->body;
  EXPECT_EQ(get->body, post->body);
  auto pareto = client_->Post("/api/pareto", R"({"axes": ["volume", "max:radius"]})", "application/json");
  ASSERT_TRUE(pareto);
  EXPECT_EQ(pareto->status, 200) << pareto->body;
  EXPECT_EQ(pareto->body, Get("/api/pareto?axes=volume,max:radius")->body);
  auto bad = client_->Post("/api/optimise", "not json", "application/json");
  ASSERT_TRUE(bad);
  EXPECT_EQ(bad->status, 400);
}

TEST_F(Server, OtherMethodsGet405AndTheServerStaysUp) {
  for (const std::string path : {"/api/form", "/", "/api/export"}) {
    auto post = client_->Post(path.c_str(), "x", "text/plain");
    ASSERT_TRUE(post) << path;
    EXPECT_EQ(post->status, 405) << path;
    EXPECT_EQ(post->get_header_value("Allow"), "GET");
    auto del = client_->Delete(path.c_str());
    ASSERT_TRUE(del) << path;
    EXPECT_EQ(del->status, 405) << path;
  }
  auto form = Get("/api/form");
  ASSERT_TRUE(form);
  EXPECT_EQ(form->status, 200);
}

TEST_F(Server, PreviewsComeFromTheCacheOnceEvaluated) {
  auto first = Get("/api/preview.glb?u=15,6");
  auto again = Get("/api/preview.glb?u=15.01,6.01");  // snaps to the same sample
  ASSERT_TRUE(first && again);
  ASSERT_EQ(first->get_header_value("X-Sample"), again->get_header_value("X-Sample"));
  EXPECT_EQ(again->get_header_value("X-Preview-Cache"), "hit");
  EXPECT_EQ(first->body, again->body);
}

// `fabatlas serve --exact-budget-ms`: 0 always snaps; a budget nothing on
// this host can exceed shows the design at exactly u between samples (the
// run has no sample with a wall between 7.4 and 9.7 mm).
TEST(ServeExactPreview, TheBudgetOptionDecidesExactOrSnapped) {
  const fs::path dir = testing::FreshTempDir("viewer-serve-exact");
  for (const std::string budget : {"0", "600000"}) {
    const pid_t pid = Spawn({(testing::BinDir() / "fabatlas").string(), "serve", RunDir().string(), "--port", "0",
                             "--preview-cache-mb", "0", "--exact-budget-ms", budget},
                            dir / (budget + ".log"));
    int port = 0;
    const std::regex listening(R"(at http://127\.0\.0\.1:(\d+)/)");
    for (int i = 0; i < 3000 && port == 0; ++i) {
      std::smatch m;
      const std::string text = ReadText(dir / (budget + ".log"));
      if (std::regex_search(text, m, listening))
        port = std::stoi(m[1]);
      else if (WaitExit(pid, std::chrono::milliseconds(20)) != -1)
        break;
    }
    ASSERT_GT(port, 0) << ReadText(dir / (budget + ".log"));
    httplib::Client client("127.0.0.1", port);
    client.set_read_timeout(std::chrono::seconds(120));
    auto r = client.Get("/api/preview.glb?u=20.6,8.55&exact=1");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 200) << r->body;
    if (budget == "0") {
      EXPECT_EQ(r->get_header_value("X-Preview"), "snapped");
      EXPECT_EQ(r->get_header_value("X-Preview-Fallback"), "budget");
      EXPECT_NE(r->get_header_value("X-Preview-U"), "20.6,8.55");
    } else {
      EXPECT_EQ(r->get_header_value("X-Preview"), "exact");
      EXPECT_EQ(r->get_header_value("X-Preview-U"), "20.6,8.55");
    }
    KillAndReap(pid);
  }
}

// `fabatlas serve` refuses what it cannot serve with one line and exit 2.
TEST(ServeErrors, MissingOrDamagedArtifactAndABusyPortAreOneLine) {
  const fs::path dir = testing::FreshTempDir("viewer-serve-errors");
  const auto serve = [&](const std::vector<std::string>& args, const std::string& name) {
    std::vector<std::string> argv = {(testing::BinDir() / "fabatlas").string(), "serve"};
    argv.insert(argv.end(), args.begin(), args.end());
    const pid_t pid = Spawn(argv, dir / name);
    const int status = WaitExit(pid, std::chrono::seconds(60));
    if (status == -1) KillAndReap(pid);
    return std::make_pair(status, ReadText(dir / name));
  };
  auto [missing_status, missing] = serve({(dir / "nothing").string(), "--port", "0"}, "missing.log");
  EXPECT_EQ(missing_status, 2);
  EXPECT_EQ(std::count(missing.begin(), missing.end(), '\n'), 1) << missing;
  EXPECT_NE(missing.find("nothing"), std::string::npos) << missing;
  // A damaged artifact: the real one cut in half.
  fs::path art;
  for (const auto& e : fs::directory_iterator(RunDir()))
    if (e.path().extension() == ".fabatlas") art = e.path();
  const std::string bytes = ReadText(art);
  std::ofstream(dir / "cut.fabatlas", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  auto [cut_status, cut] = serve({(dir / "cut.fabatlas").string(), "--port", "0"}, "cut.log");
  EXPECT_EQ(cut_status, 2);
  EXPECT_EQ(std::count(cut.begin(), cut.end(), '\n'), 1) << cut;
  EXPECT_NE(cut.find("cut.fabatlas"), std::string::npos) << cut;
  // A port already taken: another fabatlas serve listens on it.
  const pid_t first = Spawn(
      {(testing::BinDir() / "fabatlas").string(), "serve", art.string(), "--port", "0", "--preview-cache-mb", "0"},
      dir / "first.log");
  int port = 0;
  const std::regex listening(R"(at http://127\.0\.0\.1:(\d+)/)");
  for (int i = 0; i < 3000 && port == 0; ++i) {
    std::smatch m;
    const std::string text = ReadText(dir / "first.log");
    if (std::regex_search(text, m, listening))
      port = std::stoi(m[1]);
    else if (WaitExit(first, std::chrono::milliseconds(20)) != -1)
      break;
  }
  ASSERT_GT(port, 0) << ReadText(dir / "first.log");
  auto [busy_status, busy] = serve({art.string(), "--port", std::to_string(port)}, "busy.log");
  EXPECT_EQ(busy_status, 2);
  EXPECT_EQ(std::count(busy.begin(), busy.end(), '\n'), 1) << busy;
  EXPECT_NE(busy.find(std::to_string(port)), std::string::npos) << busy;
  KillAndReap(first);
}

}  // namespace
}  // namespace fabatlas::viewer

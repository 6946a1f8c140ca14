// ReadMesh / WriteMesh: every format, round trips, and bad input (each error is
// an InputError naming the file; garbage never crashes).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "fabatlas/error.h"
#include "fabatlas/mesh/encode_3mf.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/mesh/write_mesh.h"
#include "synthetic_meshes.h"
#include "test_paths.h"

namespace fabatlas::mesh {
namespace {

namespace fs = std::filesystem;

class MeshIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("fabatlas_mesh_io_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path Write(const std::string& name, const std::string& bytes) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }
  // Expects ReadMesh(p) to throw an InputError naming the file and containing `what`.
  void ExpectRejected(const fs::path& p, const std::string& what) {
    try {
      ReadMesh(p);
      ADD_FAILURE() << p << " was accepted";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(p.filename().string()), std::string::npos) << message;
      EXPECT_NE(message.find(what), std::string::npos) << message;
      EXPECT_EQ(message.find('\n'), std::string::npos) << "not one line: " << message;
    }
  }
  fs::path dir_;
};

std::string BinaryStl(const TriangleMesh& m) {
  std::string s(80, ' ');
  const auto n = static_cast<std::uint32_t>(m.triangles.size());
  s.append(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : m.triangles) {
    const float zero[3] = {0, 0, 0};
    s.append(reinterpret_cast<const char*>(zero), 12);
    for (std::int32_t v : t)
      for (double x : m.vertices[v]) {
        const float f = static_cast<float>(x);
        s.append(reinterpret_cast<const char*>(&f), 4);
      }
    s.append(2, '\0');
  }
  return s;
}

TEST_F(MeshIo, ReadsAsciiStlAsIndexedMesh) {
  std::string text = "solid cube\n";
  const TriangleMesh cube = testing::UnitCube();
  for (const auto& t : cube.triangles) {
    text += "  facet normal 0 0 0\n    outer loop\n";
    for (std::int32_t v : t) {
      const auto& p = cube.vertices[v];
      text += "      vertex " + std::to_string(p[0]) + " " + std::to_string(p[1]) + " " + std::to_string(p[2]) + "\n";
    }
    text += "    endloop\n  endfacet\n";
  }
  text += "endsolid cube\n";
  const TriangleMesh m = ReadMesh(Write("cube.STL", text));
  EXPECT_EQ(m.vertices.size(), 8u);
  EXPECT_EQ(m.triangles.size(), 12u);
  EXPECT_EQ(InspectMesh(m).volume, 1.0);
}

TEST_F(MeshIo, ReadsBinaryStlEvenWhenHeaderSaysSolid) {
  std::string bytes = BinaryStl(testing::UnitCube());
  std::memcpy(bytes.data(), "solid looks like ascii", 22);
  const TriangleMesh m = ReadMesh(Write("cube.stl", bytes));
  EXPECT_EQ(m.vertices.size(), 8u);
  const MeshReport r = InspectMesh(m);
  EXPECT_TRUE(r.closed);
  EXPECT_EQ(r.volume, 1.0);
}

TEST_F(MeshIo, ReadsObjPolygonsSlashesAndNegativeIndices) {
  const TriangleMesh m = ReadMesh(Write("cube.obj",
                                        "# cube with quads\nmtllib x.mtl\no cube\n"
                                        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                                        "vn 0 0 1\nvt 0 0\ns off\n"
                                        "f 1 4 3 2\nf 5/1 6/1 7/1 8/1\nf 1//1 2//1 6//1 5//1\n"
                                        "f 2/1/1 3/1/1 7/1/1 6/1/1\nf -5 -1 -2 -6\nf 4 1 5 8\n"));
  EXPECT_EQ(m.triangles.size(), 12u);
  const MeshReport r = InspectMesh(m);
  EXPECT_TRUE(r.closed && r.manifold && r.outward) << r.Reasons();
  EXPECT_EQ(r.volume, 1.0);
}

TEST_F(MeshIo, ReadsOffWithQuadsCommentsAndColours) {
  const TriangleMesh m = ReadMesh(Write("cube.off",
                                        "COFF\n# comment\n8 6 12\n"
                                        "0 0 0 255 0 0 255\n1 0 0 255 0 0 255\n1 1 0 1 1 1 1\n0 1 0 1 1 1 1\n"
                                        "0 0 1 1 1 1 1\n1 0 1 1 1 1 1\n1 1 1 1 1 1 1\n0 1 1 1 1 1 1\n"
                                        "4 0 3 2 1\n4 4 5 6 7\n4 0 1 5 4 255 0 0\n4 1 2 6 5\n4 2 3 7 6\n4 3 0 4 7\n"));
  EXPECT_EQ(m.triangles.size(), 12u);
  EXPECT_EQ(InspectMesh(m).volume, 1.0);
}

TEST_F(MeshIo, ReadsAsciiAndBigEndianPly) {
  const std::string header_tail =
      "element vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
      "element face 4\nproperty list uchar int vertex_indices\nelement extra 1\nproperty list uchar short junk\n"
      "end_header\n";
  const TriangleMesh ascii =
      ReadMesh(Write("tet.ply", "ply\nformat ascii 1.0\ncomment unit tetrahedron\n" + header_tail +
                                    "0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 2 0 3\n2 7 8\n"));
  ASSERT_EQ(ascii.triangles.size(), 4u);
  EXPECT_DOUBLE_EQ(InspectMesh(ascii).volume, 1.0 / 6.0);

  std::string bin = "ply\nformat binary_big_endian 1.0\n" + header_tail;
  auto put = [&](const void* p, int n) {
    const char* c = static_cast<const char*>(p);
    for (int i = n - 1; i >= 0; --i) bin.push_back(c[i]);  // host little endian -> big
  };
  const float coords[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (const auto& v : coords) {
    for (float x : v) put(&x, 4);
    bin.push_back('\x01');
  }
  const std::int32_t faces[4][3] = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {2, 0, 3}};
  for (const auto& f : faces) {
    bin.push_back('\x03');
    for (std::int32_t i : f) put(&i, 4);
  }
  bin += std::string("\x02\x00\x07\x00\x08", 5);
  const TriangleMesh big = ReadMesh(Write("tet_be.ply", bin));
  EXPECT_EQ(big.vertices, ascii.vertices);
  EXPECT_EQ(big.triangles, ascii.triangles);
}

TEST_F(MeshIo, ReadsEveryFormatOfARealMeshAlike) {
  // The FabHacks ring (OFF) written and re-read in every format gives the same
  // triangles and, except for float32 STL, the same coordinates.
  const TriangleMesh ring = ReadMesh(testing::SharedDir() / "data/fabhacks/meshes/ringXS.off");
  const double volume = InspectMesh(ring).volume;
  for (const char* ext : {".obj", ".off", ".ply", ".stl"}) {
    SCOPED_TRACE(ext);
    const fs::path p = dir_ / (std::string("ring") + ext);
    WriteMesh(ring, p);
    const TriangleMesh back = ReadMesh(p);
    EXPECT_EQ(back.triangles.size(), ring.triangles.size());
    if (std::string(ext) == ".stl") {
      EXPECT_NEAR(InspectMesh(back).volume, volume, 1e-5 * volume);
    } else {
      EXPECT_EQ(back.vertices, ring.vertices);
      EXPECT_EQ(back.triangles, ring.triangles);
    }
  }
}

TEST_F(MeshIo, RoundTripsEveryFormatExactly) {
  // Coordinates exactly representable in float32, so STL is exact too; a
  // vertex repeated at two indices must survive OBJ/OFF/PLY unmerged.
  TriangleMesh m = testing::GridBox(6, 3, 1.5, 4);
  for (const char* ext : {".stl", ".obj", ".off", ".ply", ".OBJ"}) {
    SCOPED_TRACE(ext);
    const fs::path p = dir_ / (std::string("box") + ext);
    WriteMesh(m, p);
    const TriangleMesh back = ReadMesh(p);
    EXPECT_EQ(back.triangles.size(), m.triangles.size());
    if (std::string(ext) == ".stl") {
      // STL re-indexes vertices in first-use order; geometry is identical.
      for (std::size_t t = 0; t < m.triangles.size(); ++t)
        for (int k = 0; k < 3; ++k) EXPECT_EQ(back.vertices[back.triangles[t][k]], m.vertices[m.triangles[t][k]]);
    } else {
      EXPECT_EQ(back.vertices, m.vertices);
      EXPECT_EQ(back.triangles, m.triangles);
    }
  }
  // Irrational coordinates round-trip bit-exactly through the text formats.
  TriangleMesh sphere = testing::IcoSphere(7.3, 2);
  for (const char* ext : {".obj", ".off", ".ply"}) {
    const fs::path p = dir_ / (std::string("sphere") + ext);
    WriteMesh(sphere, p);
    EXPECT_EQ(ReadMesh(p).vertices, sphere.vertices) << ext;
  }
}

TEST_F(MeshIo, WriteReplacesAtomicallyAndLeavesNoTemporary) {
  const fs::path p = dir_ / "out.obj";
  WriteMesh(testing::UnitCube(), p);
  WriteMesh(testing::IcoSphere(1, 1), p);
  EXPECT_EQ(ReadMesh(p).triangles.size(), 80u);
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++files;
  EXPECT_EQ(files, 1u);
}

TEST_F(MeshIo, WriteErrorsNameThePath) {
  const fs::path missing_dir = dir_ / "no_such_dir" / "out.stl";
  try {
    WriteMesh(testing::UnitCube(), missing_dir);
    ADD_FAILURE() << "write into a missing directory succeeded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missing_dir.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(WriteMesh(testing::UnitCube(), dir_ / "out.xyz"), InputError);
  TriangleMesh bad = testing::UnitCube();
  bad.triangles[3][1] = 8;
  EXPECT_THROW(WriteMesh(bad, dir_ / "bad.off"), InputError);
}

TEST_F(MeshIo, WriteFailureWhenTheFileSizeLimitIsHitIsAnInputError) {
  // A file size limit makes write() fail with EFBIG, as a full disk fails with
  // ENOSPC: the error must be reported and no partial file left behind.
  const fs::path p = dir_ / "big.ply";
  rlimit old{};
  ASSERT_EQ(getrlimit(RLIMIT_FSIZE, &old), 0);
  auto* old_handler = signal(SIGXFSZ, SIG_IGN);
  rlimit small = old;
  small.rlim_cur = 4096;
  ASSERT_EQ(setrlimit(RLIMIT_FSIZE, &small), 0);
  std::string message;
  try {
    WriteMesh(testing::IcoSphere(1, 4), p);  // 5120 triangles, ~100 kB
  } catch (const InputError& e) {
    message = e.what();
  }
  setrlimit(RLIMIT_FSIZE, &old);
  signal(SIGXFSZ, old_handler);
  EXPECT_NE(message.find(p.string()), std::string::npos) << message;
  EXPECT_NE(message.find("write failed"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(p));
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++files;
  EXPECT_EQ(files, 0u);
}

TEST_F(MeshIo, Reads3mfPackagesAsWrittenAndRefusesDamagedOnes) {
  const TriangleMesh cube = testing::UnitCube();
  const std::string package = Encode3mf(cube);
  const TriangleMesh back = ReadMesh(Write("cube.3mf", package));
  EXPECT_EQ(back.triangles.size(), cube.triangles.size());
  EXPECT_NEAR(EnclosedVolume(back), EnclosedVolume(cube), 1e-9);
  ExpectRejected(Write("text.3mf", "solid not a package\n"), "not a 3MF package");
  ExpectRejected(Write("cut.3mf", package.substr(0, package.size() / 2)), "not a readable ZIP archive");
}

TEST_F(MeshIo, ReadsAmfAndRefusesBrokenXml) {
  Write("two.amf",
        "<?xml version=\"1.0\"?><amf unit=\"millimeter\"><object id=\"0\"><mesh><vertices>"
        "<vertex><coordinates><x>0</x><y>0</y><z>0</z></coordinates></vertex>"
        "<vertex><coordinates><x>1</x><y>0</y><z>0</z></coordinates></vertex>"
        "<vertex><coordinates><x>0</x><y>1</y><z>0</z></coordinates></vertex>"
        "<vertex><coordinates><x>0</x><y>0</y><z>1</z></coordinates></vertex></vertices>"
        "<volume><triangle><v1>0</v1><v2>2</v2><v3>1</v3></triangle><triangle><v1>0</v1><v2>1</v2><v3>3</v3></triangle>"
        "<triangle><v1>0</v1><v2>3</v2><v3>2</v3></triangle><triangle><v1>1</v1><v2>2</v2><v3>3</v3></triangle>"
        "</volume></mesh></object></amf>");
  EXPECT_NEAR(EnclosedVolume(ReadMesh(dir_ / "two.amf")), 1.0 / 6, 1e-12);  // the unit tetrahedron
  ExpectRejected(Write("open.amf", "<amf><object id=\"0\"><mesh>"), "AMF line 1");
  ExpectRejected(Write("index.amf",
                       "<amf><object id=\"0\"><mesh><vertices></vertices><volume><triangle><v1>0</v1>"
                       "<v2>1</v2><v3>2</v3></triangle></volume></mesh></object></amf>"),
                 "out of range");
  const fs::path broken = "/usr/share/openscad/testdata/amf/amf_broken.amf";  // OpenSCAD's own broken file
  if (fs::exists(broken)) {
    EXPECT_THROW(ReadMesh(broken), InputError);
  }
}

TEST_F(MeshIo, RejectsMissingFileAndUnknownExtension) {
  ExpectRejected(dir_ / "nothing_here.stl", "does not exist");
  ExpectRejected(Write("mesh.3ds", "whatever"), "unknown mesh extension");
  ExpectRejected(dir_, "unknown mesh extension");
}

TEST_F(MeshIo, RejectsEmptyFiles) {
  for (const char* name : {"empty.stl", "empty.obj", "empty.off", "empty.ply"})
    ExpectRejected(Write(name, ""), "empty");
}

TEST_F(MeshIo, RejectsTruncatedBinaryStl) {
  const std::string bytes = BinaryStl(testing::UnitCube());
  ExpectRejected(Write("cut.stl", bytes.substr(0, bytes.size() - 7)), "truncated");
  ExpectRejected(Write("short.stl", bytes.substr(0, 50)), "truncated");
}

TEST_F(MeshIo, RejectsNaNAndInfiniteCoordinates) {
  ExpectRejected(Write("nan.obj", "v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n"), "vertex 2 has a NaN coordinate");
  ExpectRejected(Write("inf.off", "OFF\n3 1 0\n0 0 0\n1 0 inf\n0 1 0\n3 0 1 2\n"), "infinite");
  TriangleMesh m = testing::UnitCube();
  m.vertices[5][1] = std::nan("");
  ExpectRejected(Write("nan.stl", BinaryStl(m)), "NaN");
}

TEST_F(MeshIo, RejectsOutOfRangeIndices) {
  ExpectRejected(Write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n"), "out of range");
  ExpectRejected(Write("neg.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n"), "out of range");
  ExpectRejected(Write("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"), "out of range");
  ExpectRejected(
      Write("range.ply",
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n"),
      "out of range");
}

TEST_F(MeshIo, RejectsFilesWithoutTriangles) {
  ExpectRejected(Write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"), "zero triangles");
  ExpectRejected(Write("nofaces.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n"), "zero triangles");
  ExpectRejected(Write("header.stl", std::string(80, 'x') + std::string(4, '\0')), "zero triangles");
}

TEST_F(MeshIo, RejectsTruncatedTextFormats) {
  ExpectRejected(Write("cut.off", "OFF\n8 12 0\n0 0 0\n1 0 0\n"), "truncated");
  ExpectRejected(Write("cut.ply",
                       "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                       "property float y\nproperty float z\nend_header\n\x01\x02"),
                 "truncated");
  ExpectRejected(Write("cut.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"), "truncated");
}

// Random bytes, and every truncation of valid files of each format: each read
// either succeeds or throws InputError naming the file (never crashes or
// throws anything else).
TEST_F(MeshIo, GarbageAndTruncationsNeverCrash) {
  std::mt19937 rng(20260411);
  std::uniform_int_distribution<int> byte(0, 255);
  int rejected = 0, attempts = 0;
  auto attempt = [&](const std::string& name, const std::string& bytes) {
    const fs::path p = Write(name, bytes);
    ++attempts;
    try {
      const TriangleMesh m = ReadMesh(p);
      for (const auto& t : m.triangles)
        for (std::int32_t v : t) ASSERT_TRUE(v >= 0 && static_cast<std::size_t>(v) < m.vertices.size());
      InspectMesh(m);  // accepted meshes are safe to inspect
    } catch (const InputError& e) {
      ++rejected;
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  for (const char* ext : {".stl", ".obj", ".off", ".ply"}) {
    for (int i = 0; i < 40; ++i) {
      std::string bytes(1 + i * 37, '\0');
      for (char& c : bytes) c = static_cast<char>(byte(rng));
      attempt(std::string("random") + std::to_string(i) + ext, bytes);
    }
  }
  const TriangleMesh sphere = testing::IcoSphere(3, 1);
  for (const char* ext : {".stl", ".obj", ".off", ".ply"}) {
    const fs::path full = dir_ / (std::string("full") + ext);
    WriteMesh(sphere, full);
    std::ifstream in(full, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (std::size_t cut = 0; cut < bytes.size(); cut += 1 + bytes.size() / 97) {
      attempt(std::string("cut") + std::to_string(cut) + ext, bytes.substr(0, cut));
      // Also flip one byte in the middle of the intact file.
      std::string flipped = bytes;
      flipped[cut] = static_cast<char>(byte(rng));
      attempt(std::string("flip") + std::to_string(cut) + ext, flipped);
    }
  }
  EXPECT_GT(rejected, attempts / 2);
}

}  // namespace
}  // namespace fabatlas::mesh

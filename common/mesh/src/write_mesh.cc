// Mesh export: STL (binary), OBJ, OFF, PLY (binary little endian), 3MF,
// encoded in memory and written to a temporary sibling file renamed into place.
#include "fabatlas/mesh/write_mesh.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>

#include "fabatlas/error.h"
#include "fabatlas/mesh/encode_3mf.h"

namespace fabatlas::mesh {
namespace {

[[noreturn]] void Fail(const std::filesystem::path& path, const std::string& what) {
  throw InputError(path.string() + ": " + what);
}

// A FILE* that records the first error and removes the temporary on failure.
class TempFile {
 public:
  TempFile(const std::filesystem::path& target)
      : target_(target), temp_(target.string() + ".tmp-" + std::to_string(::getpid())) {
    file_ = std::fopen(temp_.c_str(), "wb");
    if (!file_) Fail(target_, std::string("cannot create file: ") + std::strerror(errno));
  }
  ~TempFile() {
    if (file_) std::fclose(file_);
    if (!committed_) std::remove(temp_.c_str());
  }
  void Write(const void* data, std::size_t n) {
    if (error_ == 0 && std::fwrite(data, 1, n, file_) != n) error_ = errno ? errno : EIO;
  }
  void Print(const std::string& s) { Write(s.data(), s.size()); }
  void Commit() {
    if (error_ == 0 && std::fflush(file_) != 0) error_ = errno ? errno : EIO;
    if (error_ == 0 && ::fsync(::fileno(file_)) != 0) error_ = errno;
    if (std::fclose(file_) != 0 && error_ == 0) error_ = errno ? errno : EIO;
    file_ = nullptr;
    if (error_ != 0) Fail(target_, std::string("write failed: ") + std::strerror(error_));
    if (std::rename(temp_.c_str(), target_.c_str()) != 0) {
      Fail(target_, std::string("cannot rename temporary file into place: ") + std::strerror(errno));
    }
    committed_ = true;
  }

 private:
  std::filesystem::path target_;
  std::string temp_;
  std::FILE* file_ = nullptr;
  int error_ = 0;
  bool committed_ = false;
};

std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The bytes of a file being encoded.
class Bytes {
 public:
  void Write(const void* data, std::size_t n) { out_.append(static_cast<const char*>(data), n); }
  void Print(const std::string& s) { out_ += s; }
  std::string Take() { return std::move(out_); }

 private:
  std::string out_;
};

template <typename T>
void PutLittle(Bytes* f, T value) {
  unsigned char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) std::reverse(b, b + sizeof(T));
  f->Write(b, sizeof(T));
}

void WriteStl(const TriangleMesh& mesh, Bytes* f) {
  char header[80] = {};
  std::snprintf(header, sizeof header, "fabatlas binary STL, millimetres");
  f->Write(header, 80);
  PutLittle<std::uint32_t>(f, static_cast<std::uint32_t>(mesh.triangles.size()));
  for (const auto& t : mesh.triangles) {
    const auto& a = mesh.vertices[t[0]];
    const auto& b = mesh.vertices[t[1]];
    const auto& c = mesh.vertices[t[2]];
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (double& x : n) x = len > 0 ? x / len : 0.0;
    for (double x : n) PutLittle<float>(f, static_cast<float>(x));
    for (int k = 0; k < 3; ++k) {
      for (double x : mesh.vertices[t[k]]) PutLittle<float>(f, static_cast<float>(x));
    }
    PutLittle<std::uint16_t>(f, 0);
  }
}

void WriteObj(const TriangleMesh& mesh, Bytes* f) {
  f->Print("# fabatlas mesh, millimetres\n");
  for (const auto& p : mesh.vertices) f->Print("v " + Num(p[0]) + " " + Num(p[1]) + " " + Num(p[2]) + "\n");
  for (const auto& t : mesh.triangles) {
    f->Print("f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " + std::to_string(t[2] + 1) + "\n");
  }
}

void WriteOff(const TriangleMesh& mesh, Bytes* f) {
  f->Print("OFF\n" + std::to_string(mesh.vertices.size()) + " " + std::to_string(mesh.triangles.size()) + " 0\n");
  for (const auto& p : mesh.vertices) f->Print(Num(p[0]) + " " + Num(p[1]) + " " + Num(p[2]) + "\n");
  for (const auto& t : mesh.triangles) {
    f->Print("3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n");
  }
}

void WritePly(const TriangleMesh& mesh, Bytes* f) {
  f->Print("ply\nformat binary_little_endian 1.0\ncomment fabatlas mesh, millimetres\nelement vertex " +
           std::to_string(mesh.vertices.size()) +
           "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
           std::to_string(mesh.triangles.size()) + "\nproperty list uchar int vertex_indices\nend_header\n");
  for (const auto& p : mesh.vertices) {
    for (double x : p) PutLittle<double>(f, x);
  }
  for (const auto& t : mesh.triangles) {
    PutLittle<std::uint8_t>(f, 3);
    for (std::int32_t i : t) PutLittle<std::int32_t>(f, i);
  }
}

std::string Lower(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

}  // namespace

std::string EncodeMesh(const TriangleMesh& mesh, const std::string& extension) {
  const std::string ext = Lower(extension);
  if (ext != ".stl" && ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".3mf")
    throw InputError("unknown mesh extension '" + extension + "' (expected .stl, .obj, .off, .ply or .3mf)");
  const auto n = static_cast<std::int64_t>(mesh.vertices.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (std::int32_t v : mesh.triangles[t]) {
      if (v < 0 || v >= n)
        throw InputError("cannot write: triangle " + std::to_string(t) + " has vertex index " + std::to_string(v) +
                         " out of range");
    }
  }
  if (ext == ".3mf") return Encode3mf(mesh);
  Bytes bytes;
  if (ext == ".stl")
    WriteStl(mesh, &bytes);
  else if (ext == ".obj")
    WriteObj(mesh, &bytes);
  else if (ext == ".off")
    WriteOff(mesh, &bytes);
  else
    WritePly(mesh, &bytes);
  return bytes.Take();
}

void WriteMesh(const TriangleMesh& mesh, const std::filesystem::path& path) {
  std::string bytes;
  try {
    bytes = EncodeMesh(mesh, path.extension().string());
  } catch (const InputError& e) {
    Fail(path, e.what());
  }
  TempFile file(path);
  file.Write(bytes.data(), bytes.size());
  file.Commit();
}

}  // namespace fabatlas::mesh

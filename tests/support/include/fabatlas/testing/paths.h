// fabatlas/testing/paths.h — where tests find things: the repository, the
// shared reference data (../shared), the built programs, and fresh scratch
// directories. CTest sets FABATLAS_SOURCE_DIR, FABATLAS_SHARED_DIR and
// FABATLAS_BIN_DIR; a test binary run by hand falls back to the paths
// compiled in by fabatlas_add_test (cmake/FabatlasTesting.cmake).
#pragma once

#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace fabatlas::testing {

inline std::filesystem::path SourceDir() {
  const char* s = std::getenv("FABATLAS_SOURCE_DIR");
  return s ? s : FABATLAS_SOURCE_DIR_DEFAULT;
}

inline std::filesystem::path SharedDir() {
  const char* s = std::getenv("FABATLAS_SHARED_DIR");
  return s ? s : FABATLAS_SHARED_DIR_DEFAULT;
}

inline std::filesystem::path BinDir() {
  const char* s = std::getenv("FABATLAS_BIN_DIR");
  return s ? s : FABATLAS_BIN_DIR_DEFAULT;
}

// A new empty directory under the system temporary directory, unique to this
// process and call.
inline std::filesystem::path FreshTempDir(const std::string& tag = "test") {
  static std::atomic<int> counter{0};
  auto dir = std::filesystem::temp_directory_path() /
             ("fabatlas-" + tag + "-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// Writes `text` as `name` into a fresh temporary directory; returns its path.
inline std::filesystem::path TempDesign(const std::string& text, const std::string& name = "design.yaml") {
  auto path = FreshTempDir() / name;
  std::ofstream(path) << text;
  return path;
}

}  // namespace fabatlas::testing

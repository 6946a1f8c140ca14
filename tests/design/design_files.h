// Test support: write a design file to a fresh temporary directory.
#pragma once

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace fabatlas::testing {

inline std::filesystem::path TempDesign(const std::string& text, const std::string& name = "design.yaml") {
  static std::atomic<int> counter{0};
  auto dir = std::filesystem::temp_directory_path() /
             ("fabatlas-test-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::filesystem::create_directories(dir);
  auto path = dir / name;
  std::ofstream(path) << text;
  return path;
}

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

}  // namespace fabatlas::testing

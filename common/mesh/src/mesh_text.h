// Internal to fabatlas_mesh: reading the text formats (STL, OBJ, OFF, PLY)
// line by line and token by token, and the one way they fail.
#pragma once

#include <cctype>
#include <charconv>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "fabatlas/error.h"
#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh::internal {

// Throws InputError "PATH: what".
[[noreturn]] inline void Fail(const std::filesystem::path& path, const std::string& what) {
  throw InputError(path.string() + ": " + what);
}

inline std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

inline bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v'; }

// Splits a line into whitespace-separated tokens.
inline std::vector<std::string_view> Tokens(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsSpace(line[i])) ++i;
    std::size_t j = i;
    while (j < line.size() && !IsSpace(line[j])) ++j;
    if (j > i) out.push_back(line.substr(i, j - i));
    i = j;
  }
  return out;
}

// Parses a whole token as a double (accepts nan/inf so they can be reported).
inline bool ParseDouble(std::string_view t, double* out) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), *out);
  return ec == std::errc() && p == t.data() + t.size();
}

inline bool ParseInt(std::string_view t, long long* out) {
  if (!t.empty() && t.front() == '+') t.remove_prefix(1);
  auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), *out);
  return ec == std::errc() && p == t.data() + t.size();
}

// Line iterator over the file contents with 1-based line numbers.
class Lines {
 public:
  explicit Lines(std::string_view text) : text_(text) {}
  bool Next(std::string_view* line) {
    if (pos_ >= text_.size()) return false;
    std::size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    *line = text_.substr(pos_, end - pos_);
    pos_ = end + 1;
    ++number_;
    return true;
  }
  int number() const { return number_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  int number_ = 0;
};

inline void AddPolygon(const std::vector<long long>& corners, TriangleMesh* mesh) {
  for (std::size_t k = 1; k + 1 < corners.size(); ++k) {
    mesh->triangles.push_back({static_cast<std::int32_t>(corners[0]), static_cast<std::int32_t>(corners[k]),
                               static_cast<std::int32_t>(corners[k + 1])});
  }
}

}  // namespace fabatlas::mesh::internal

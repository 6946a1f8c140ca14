// tests/mesh/js_mesh.h — loader for the meshes of the npm packages `bunny` and
// `teapot` (node_modules/bunny/index.js, node_modules/teapot/teapot.js). Those
// files are JavaScript of the form
//   exports.positions=[[x,y,z],...];exports.cells=[[i,j,k],...]
// with 0-based indices. The loader finds the two arrays by name and reads the
// numbers inside them; polygons with more than three corners become fans.
// Throws std::runtime_error when the file or an array is missing.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh::testing {

// Parses the nested numeric array that starts at the first '[' after `name`:
// returns one vector per inner [..] group.
inline std::vector<std::vector<double>> ReadJsArray(const std::string& text, const std::string& name) {
  const std::size_t at = text.find(name);
  if (at == std::string::npos) throw std::runtime_error("no '" + name + "' array");
  std::size_t i = text.find('[', at);
  if (i == std::string::npos) throw std::runtime_error("no '[' after '" + name + "'");
  ++i;  // inside the outer array
  std::vector<std::vector<double>> rows;
  while (i < text.size()) {
    while (i < text.size() && (text[i] == ',' || std::isspace(static_cast<unsigned char>(text[i])))) ++i;
    if (i >= text.size() || text[i] == ']') break;
    if (text[i] != '[') throw std::runtime_error("unexpected character in '" + name + "'");
    ++i;
    std::vector<double> row;
    while (i < text.size() && text[i] != ']') {
      if (text[i] == ',' || std::isspace(static_cast<unsigned char>(text[i]))) {
        ++i;
        continue;
      }
      char* end = nullptr;
      row.push_back(std::strtod(text.c_str() + i, &end));
      if (end == text.c_str() + i) throw std::runtime_error("bad number in '" + name + "'");
      i = static_cast<std::size_t>(end - text.c_str());
    }
    ++i;
    rows.push_back(std::move(row));
  }
  return rows;
}

inline TriangleMesh LoadJsMesh(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  TriangleMesh mesh;
  for (const auto& p : ReadJsArray(text, "positions")) {
    if (p.size() != 3) throw std::runtime_error(path.string() + ": position without 3 coordinates");
    mesh.vertices.push_back({p[0], p[1], p[2]});
  }
  for (const auto& c : ReadJsArray(text, "cells")) {
    for (std::size_t k = 1; k + 1 < c.size(); ++k) {
      mesh.triangles.push_back(
          {static_cast<std::int32_t>(c[0]), static_cast<std::int32_t>(c[k]), static_cast<std::int32_t>(c[k + 1])});
    }
  }
  return mesh;
}

}  // namespace fabatlas::mesh::testing

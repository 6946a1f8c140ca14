// OpenSCAD's surface(): its height-map readers and its mesh (surface_mesh.h).
#include "fabatlas/scad/surface_mesh.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#include <stb/stb_image.h>

#include "fabatlas/mesh/enclosed_volume.h"

namespace fabatlas::scad {
namespace {

bool IsPng(const std::string& bytes) {
  static const unsigned char kSignature[8] = {0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a};
  return bytes.size() >= 8 && std::memcmp(bytes.data(), kSignature, 8) == 0;
}

HeightMap PngHeights(const std::string& bytes, bool invert, const std::string& name,
                     std::vector<std::string>* warnings) {
  int width = 0, height = 0, channels = 0;
  unsigned char* rgba = stbi_load_from_memory(reinterpret_cast<const unsigned char*>(bytes.data()),
                                              static_cast<int>(bytes.size()), &width, &height, &channels, 4);
  HeightMap map;
  if (!rgba) {
    warnings->push_back("cannot read the PNG image " + name + " (" + stbi_failure_reason() + ")");
    return map;
  }
  map.rows = height;
  map.columns = width;
  map.heights.resize(static_cast<std::size_t>(width) * height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const unsigned char* p = rgba + 4 * (static_cast<std::size_t>(y) * width + x);
      const double luminance = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
      // The image's top row is the map's last (y grows upward).
      map.heights[static_cast<std::size_t>(height - 1 - y) * width + x] =
          100.0 / 255 * (invert ? 1 - luminance : luminance);
    }
  stbi_image_free(rgba);
  for (double v : map.heights) map.floor = std::min(map.floor, v - 1);
  return map;
}

HeightMap DatHeights(const std::string& text, const std::string& name, std::vector<std::string>* warnings) {
  std::vector<std::vector<double>> rows;
  std::istringstream in(text);
  std::string line;
  bool stopped = false;
  while (!stopped && std::getline(in, line)) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::vector<double> row;
    std::size_t at = first;
    while (at < line.size()) {
      const auto end = line.find_first_of(" \t\r", at);
      const std::string token = line.substr(at, end == std::string::npos ? std::string::npos : end - at);
      char* rest = nullptr;
      const double v = std::strtod(token.c_str(), &rest);
      if (token.empty() || *rest != '\0') {
        warnings->push_back("illegal value '" + token + "' in " + name + "; the rest of the file is ignored");
        stopped = true;
        break;
      }
      row.push_back(v);
      at = end == std::string::npos ? line.size() : line.find_first_not_of(" \t\r", end);
      if (at == std::string::npos) at = line.size();
    }
    // A row cut short by a bad value keeps what it read (OpenSCAD keeps it too).
    if (!row.empty())
      rows.push_back(std::move(row));
    else if (stopped)
      break;
  }
  HeightMap map;
  map.rows = static_cast<int>(rows.size());
  for (const auto& r : rows) map.columns = std::max(map.columns, static_cast<int>(r.size()));
  map.heights.assign(static_cast<std::size_t>(map.rows) * map.columns, 0.0);
  for (int r = 0; r < map.rows; ++r) {
    std::copy(rows[r].begin(), rows[r].end(), map.heights.begin() + static_cast<std::size_t>(r) * map.columns);
    for (double v : rows[r]) map.floor = std::min(map.floor, v - 1);
  }
  return map;
}

}  // namespace

HeightMap ReadHeightMap(const std::filesystem::path& file, bool invert, std::vector<std::string>* warnings) {
  std::error_code ec;
  std::ifstream in;
  if (std::filesystem::is_regular_file(file, ec)) in.open(file, std::ios::binary);
  if (!in) {
    warnings->push_back("cannot open " + file.string() + "; the surface is empty");
    return {};
  }
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return IsPng(bytes) ? PngHeights(bytes, invert, file.string(), warnings) : DatHeights(bytes, file.string(), warnings);
}

mesh::TriangleMesh SurfaceMesh(const HeightMap& map, bool center) {
  mesh::TriangleMesh out;
  const int rows = map.rows, cols = map.columns;
  if (rows < 2 || cols < 2) return out;
  auto h = [&](int r, int c) { return map.heights[static_cast<std::size_t>(r) * cols + c]; };
  const double floor = map.floor;
  const double ox = center ? -(cols - 1) / 2.0 : 0, oy = center ? -(rows - 1) / 2.0 : 0;
  auto& V = out.vertices;
  auto& T = out.triangles;
  // Top: grid vertices, then each cell's centre.
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) V.push_back({ox + c, oy + r, h(r, c)});
  auto top = [&](int r, int c) { return static_cast<std::int32_t>(r * cols + c); };
  for (int r = 1; r < rows; ++r)
    for (int c = 1; c < cols; ++c) {
      const auto centre = static_cast<std::int32_t>(V.size());
      V.push_back({ox + c - 0.5, oy + r - 0.5, (h(r - 1, c - 1) + h(r - 1, c) + h(r, c - 1) + h(r, c)) / 4});
      const std::int32_t a = top(r - 1, c - 1), b = top(r - 1, c), d = top(r, c), e = top(r, c - 1);
      T.push_back({a, b, centre});
      T.push_back({b, d, centre});
      T.push_back({d, e, centre});
      T.push_back({e, a, centre});
    }
  // The boundary of the grid counter-clockwise seen from above, each grid
  // point with a floor vertex below it.
  std::vector<std::int32_t> ring;
  for (int c = 0; c < cols - 1; ++c) ring.push_back(top(0, c));
  for (int r = 0; r < rows - 1; ++r) ring.push_back(top(r, cols - 1));
  for (int c = cols - 1; c > 0; --c) ring.push_back(top(rows - 1, c));
  for (int r = rows - 1; r > 0; --r) ring.push_back(top(r, 0));
  std::vector<std::int32_t> below(ring.size());
  for (std::size_t i = 0; i < ring.size(); ++i) {
    below[i] = static_cast<std::int32_t>(V.size());
    V.push_back({V[ring[i]][0], V[ring[i]][1], floor});
  }
  const auto middle = static_cast<std::int32_t>(V.size());
  V.push_back({ox + (cols - 1) / 2.0, oy + (rows - 1) / 2.0, floor});
  for (std::size_t i = 0; i < ring.size(); ++i) {
    const std::size_t j = (i + 1) % ring.size();
    T.push_back({ring[j], ring[i], below[i]});  // wall, outward
    T.push_back({ring[j], below[i], below[j]});
    T.push_back({below[j], below[i], middle});  // floor, facing down
  }
  if (mesh::EnclosedVolume(out) < 0)
    for (auto& t : T) std::swap(t[1], t[2]);
  return out;
}

}  // namespace fabatlas::scad

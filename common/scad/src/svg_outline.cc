// OpenSCAD's 2D SVG export read back as loops (fabatlas/scad/svg_outline.h).
#include "fabatlas/scad/svg_outline.h"

#include <cctype>
#include <cstdlib>

#include "fabatlas/error.h"

namespace fabatlas::scad {

std::vector<Loop> ReadSvgOutline(const std::string& svg, const std::string& file) {
  std::vector<Loop> loops;
  std::size_t at = 0;
  while ((at = svg.find("<path", at)) != std::string::npos) {
    const std::size_t d = svg.find(" d=\"", at);
    if (d == std::string::npos) break;
    const std::size_t end = svg.find('"', d + 4);
    if (end == std::string::npos) throw InputError(file + ": unterminated path data");
    const std::string data = svg.substr(d + 4, end - d - 4);
    at = end;
    Loop loop;
    std::size_t i = 0;
    auto skip = [&] {
      while (i < data.size() && (std::isspace(static_cast<unsigned char>(data[i])) || data[i] == ',')) ++i;
    };
    auto number = [&]() {
      skip();
      const char* begin = data.c_str() + i;
      char* stop = nullptr;
      const double v = std::strtod(begin, &stop);
      if (stop == begin) throw InputError(file + ": path data: expected a number at '" + data.substr(i, 20) + "'");
      i += static_cast<std::size_t>(stop - begin);
      return v;
    };
    for (skip(); i < data.size(); skip()) {
      const char c = data[i++];
      if (c == 'M' || c == 'L') {
        if (c == 'M' && !loop.empty()) {
          loops.push_back(loop);
          loop.clear();
        }
        const double x = number();
        const double y = number();
        loop.push_back({x, -y});
      } else if (c == 'z' || c == 'Z') {
        if (loop.size() >= 3) loops.push_back(loop);
        loop.clear();
      } else {
        throw InputError(file + ": path data: unsupported command '" + std::string(1, c) + "'");
      }
    }
    if (loop.size() >= 3) loops.push_back(loop);
  }
  return loops;
}

}  // namespace fabatlas::scad

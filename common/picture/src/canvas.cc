#include "fabatlas/picture/canvas.h"

#include <algorithm>
#include <cmath>

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>
#include <stb/stb_easy_font.h>

#include "fabatlas/error.h"
#include "fabatlas/write_file_atomically.h"

namespace fabatlas::picture {

Canvas::Canvas(int width, int height, unsigned background)
    : width_(std::max(width, 1)), height_(std::max(height, 1)), rgb_(std::size_t(width_) * height_ * 3) {
  for (std::size_t i = 0; i < rgb_.size(); i += 3) {
    rgb_[i] = (background >> 16) & 255;
    rgb_[i + 1] = (background >> 8) & 255;
    rgb_[i + 2] = background & 255;
  }
}

void Canvas::Set(int x, int y, unsigned c) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_) return;
  unsigned char* p = &rgb_[(std::size_t(y) * width_ + x) * 3];
  p[0] = (c >> 16) & 255;
  p[1] = (c >> 8) & 255;
  p[2] = c & 255;
}

void Canvas::Blend(int x, int y, unsigned c, double alpha) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_ || alpha <= 0) return;
  if (alpha >= 1) return Set(x, y, c);
  unsigned char* p = &rgb_[(std::size_t(y) * width_ + x) * 3];
  const int target[3] = {int((c >> 16) & 255), int((c >> 8) & 255), int(c & 255)};
  for (int k = 0; k < 3; ++k) p[k] = static_cast<unsigned char>(std::lround(p[k] + alpha * (target[k] - p[k])));
}

void Canvas::Rect(int x0, int y0, int x1, int y1, unsigned c) {
  for (int y = std::min(y0, y1); y < std::max(y0, y1); ++y)
    for (int x = std::min(x0, x1); x < std::max(x0, x1); ++x) Set(x, y, c);
}

void Canvas::Line(double x0, double y0, double x1, double y1, unsigned c, int pen, int dash) {
  const double len = std::hypot(x1 - x0, y1 - y0);
  const int steps = std::max(1, static_cast<int>(std::ceil(len)));
  for (int i = 0; i <= steps; ++i) {
    if (dash > 0 && (i / dash) % 2 == 1) continue;
    const double t = static_cast<double>(i) / steps;
    const int x = static_cast<int>(std::lround(x0 + t * (x1 - x0)));
    const int y = static_cast<int>(std::lround(y0 + t * (y1 - y0)));
    Rect(x - pen / 2, y - pen / 2, x - pen / 2 + pen, y - pen / 2 + pen, c);
  }
}

void Canvas::HLine(int x0, int x1, int y, unsigned c, int pen) { Rect(x0, y - pen / 2, x1 + 1, y - pen / 2 + pen, c); }

void Canvas::VLine(int x, int y0, int y1, unsigned c, int pen) { Rect(x - pen / 2, y0, x - pen / 2 + pen, y1 + 1, c); }

void Canvas::Text(int x, int y, const std::string& text, unsigned c, int scale) {
  std::vector<char> buffer(1024 * text.size() + 64);  // stb_easy_font: ~270 bytes of quads a character on average
  const int quads = stb_easy_font_print(0, 0, const_cast<char*>(text.c_str()), nullptr, buffer.data(),
                                        static_cast<int>(buffer.size()));
  for (int q = 0; q < quads; ++q) {
    const float* v = reinterpret_cast<const float*>(buffer.data() + q * 64);
    // Vertex k of the quad at v + 4k floats (x, y, z, colour).
    const float qx0 = v[0], qy0 = v[1], qx1 = v[8], qy1 = v[9];
    Rect(x + static_cast<int>(qx0 * scale), y + static_cast<int>(qy0 * scale), x + static_cast<int>(qx1 * scale),
         y + static_cast<int>(qy1 * scale), c);
  }
}

int Canvas::TextWidth(const std::string& text, int scale) {
  return stb_easy_font_width(const_cast<char*>(text.c_str())) * scale;
}

void Canvas::WritePng(const std::filesystem::path& path) const {
  int size = 0;
  unsigned char* png = stbi_write_png_to_mem(rgb_.data(), width_ * 3, width_, height_, 3, &size);
  if (!png) throw InputError(path.string() + ": cannot encode the PNG");
  std::string bytes(reinterpret_cast<const char*>(png), static_cast<std::size_t>(size));
  STBIW_FREE(png);
  WriteFileAtomically(path, bytes);
}

}  // namespace fabatlas::picture

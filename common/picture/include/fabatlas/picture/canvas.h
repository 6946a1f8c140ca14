// fabatlas/picture/canvas.h — an 8-bit RGB raster to draw plots on and
// write as PNG. Pixel (0, 0) is the top-left corner; colours are 0xRRGGBB.
// Drawing outside the canvas is clipped. Not thread-safe (one writer).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace fabatlas::picture {

class Canvas {
 public:
  // A width x height canvas filled with `background`.
  Canvas(int width, int height, unsigned background = 0xFFFFFF);

  int width() const { return width_; }
  int height() const { return height_; }
  // Rows top to bottom, 3 bytes (R, G, B) per pixel.
  const std::vector<unsigned char>& rgb() const { return rgb_; }

  void Set(int x, int y, unsigned colour);
  // Mixes `colour` into the pixel: alpha 0 keeps it, 1 replaces it.
  void Blend(int x, int y, unsigned colour, double alpha);
  // The pixels x in [min(x0, x1), max(x0, x1)), y likewise.
  void Rect(int x0, int y0, int x1, int y1, unsigned colour);
  // A line of a square pen `pen` pixels wide through the rounded points of
  // the segment, one per pixel of length; dashed (on and off every `dash`
  // pixels) when dash > 0.
  void Line(double x0, double y0, double x1, double y1, unsigned colour, int pen = 1, int dash = 0);
  // Horizontal / vertical strokes of `pen` pixels, ends included.
  void HLine(int x0, int x1, int y, unsigned colour, int pen = 1);
  void VLine(int x, int y0, int y1, unsigned colour, int pen = 1);

  // Text in stb_easy_font's pixel font (about 6 px a character and 7 px
  // high at scale 1), top-left at (x, y); TextWidth is its width in pixels.
  void Text(int x, int y, const std::string& text, unsigned colour, int scale = 2);
  static int TextWidth(const std::string& text, int scale = 2);

  // Encodes the canvas as PNG and writes it through WriteFileAtomically
  // (fabatlas/write_file_atomically.h): whole or not at all; errors as
  // there, InputError naming `path` when encoding fails.
  void WritePng(const std::filesystem::path& path) const;

 private:
  int width_, height_;
  std::vector<unsigned char> rgb_;
};

}  // namespace fabatlas::picture

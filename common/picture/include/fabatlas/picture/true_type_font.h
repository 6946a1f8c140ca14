// fabatlas/picture/true_type_font.h — text of a TrueType font drawn
// anti-aliased onto a Canvas (stb_truetype), for the plots fabatlas writes
// (Fab Forms Fig. 13 curves, Fig. 14 box plots).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "fabatlas/picture/canvas.h"

namespace fabatlas::picture {

// Debian's fonts-dejavu-core face, the plots' default.
inline const std::filesystem::path kDefaultFontFile = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";

class TrueTypeFont {
 public:
  // Reads the first face of `file`. Throws InputError naming the file when
  // it cannot be read as TrueType.
  explicit TrueTypeFont(const std::filesystem::path& file = kDefaultFontFile);
  ~TrueTypeFont();
  TrueTypeFont(const TrueTypeFont&) = delete;
  TrueTypeFont& operator=(const TrueTypeFont&) = delete;

  // Width in pixels of `text` (ASCII) at pixel height `px`.
  int Width(const std::string& text, double px) const;
  // `text` with its baseline at y, starting at x.
  void Draw(Canvas& canvas, int x, int y, const std::string& text, unsigned colour, double px = 16) const;
  // As Draw, centred on cx.
  void DrawCentred(Canvas& canvas, int cx, int y, const std::string& text, unsigned colour, double px = 16) const;
  // As Draw, turned a quarter counter-clockwise (reading bottom to top), its
  // baseline at x and starting at y: a vertical axis label.
  void DrawUpward(Canvas& canvas, int x, int y, const std::string& text, unsigned colour, double px = 16) const;

 private:
  struct Face;
  std::unique_ptr<Face> face_;
};

}  // namespace fabatlas::picture

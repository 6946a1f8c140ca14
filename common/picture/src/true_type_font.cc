// TrueType text on a Canvas (see true_type_font.h), rasterised by
// stb_truetype.
#include "fabatlas/picture/true_type_font.h"

#include <cmath>
#include <fstream>
#include <sstream>

#define STBTT_STATIC
#define STB_TRUETYPE_IMPLEMENTATION
#include <stb/stb_truetype.h>

#include "fabatlas/error.h"

namespace fabatlas::picture {

struct TrueTypeFont::Face {
  std::string bytes;
  stbtt_fontinfo info{};
};

TrueTypeFont::TrueTypeFont(const std::filesystem::path& file) : face_(std::make_unique<Face>()) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream read;
  read << in.rdbuf();
  face_->bytes = read.str();
  const auto* data = reinterpret_cast<const unsigned char*>(face_->bytes.data());
  if (!in || face_->bytes.empty() || !stbtt_InitFont(&face_->info, data, stbtt_GetFontOffsetForIndex(data, 0)))
    throw InputError(file.string() + ": cannot read the TrueType font (install fonts-dejavu-core)");
}

TrueTypeFont::~TrueTypeFont() = default;

int TrueTypeFont::Width(const std::string& text, double px) const {
  const float scale = stbtt_ScaleForPixelHeight(&face_->info, static_cast<float>(px));
  int width = 0;
  for (unsigned char ch : text) {
    int advance = 0, lsb = 0;
    stbtt_GetCodepointHMetrics(&face_->info, ch, &advance, &lsb);
    width += static_cast<int>(std::lround(advance * scale));
  }
  return width;
}

namespace {

// Each glyph of `text` along a pen line: `blend(along, i, j, ox, oy, alpha)`
// gets the pen's distance along the line (pixels), the glyph pixel (i, j)
// right of and below the glyph's origin offset (ox, oy), and its coverage.
template <class Blend>
void Rasterise(const stbtt_fontinfo& info, const std::string& text, double px, Blend blend) {
  const float scale = stbtt_ScaleForPixelHeight(&info, static_cast<float>(px));
  int along = 0;
  for (unsigned char ch : text) {
    int advance = 0, lsb = 0, bw = 0, bh = 0, ox = 0, oy = 0;
    stbtt_GetCodepointHMetrics(&info, ch, &advance, &lsb);
    unsigned char* bitmap = stbtt_GetCodepointBitmap(&info, 0, scale, ch, &bw, &bh, &ox, &oy);
    for (int j = 0; j < bh; ++j)
      for (int i = 0; i < bw; ++i) blend(along, i, j, ox, oy, bitmap[j * bw + i] / 255.0);
    stbtt_FreeBitmap(bitmap, nullptr);
    along += static_cast<int>(std::lround(advance * scale));
  }
}

}  // namespace

void TrueTypeFont::Draw(Canvas& canvas, int x, int y, const std::string& text, unsigned colour, double px) const {
  Rasterise(face_->info, text, px, [&](int along, int i, int j, int ox, int oy, double alpha) {
    canvas.Blend(x + along + ox + i, y + oy + j, colour, alpha);
  });
}

void TrueTypeFont::DrawCentred(Canvas& canvas, int cx, int y, const std::string& text, unsigned colour,
                               double px) const {
  Draw(canvas, cx - Width(text, px) / 2, y, text, colour, px);
}

void TrueTypeFont::DrawUpward(Canvas& canvas, int x, int y, const std::string& text, unsigned colour, double px) const {
  // A glyph pixel (i, j) right of and below the pen goes up and right of it:
  // (x + j, y - i) for a pen at (x, y) moving up.
  Rasterise(face_->info, text, px, [&](int along, int i, int j, int ox, int oy, double alpha) {
    canvas.Blend(x + oy + j, y - along - ox - i, colour, alpha);
  });
}

}  // namespace fabatlas::picture

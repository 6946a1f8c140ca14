#include "png_file.h"

#include <string>

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

#include "fabatlas/error.h"
#include "fabatlas/precompute/form_outputs.h"

namespace fabatlas::precompute {

void WritePngFile(const std::filesystem::path& path, const std::vector<unsigned char>& rgb, int width, int height) {
  int size = 0;
  unsigned char* png = stbi_write_png_to_mem(rgb.data(), width * 3, width, height, 3, &size);
  if (!png) throw InputError(path.string() + ": cannot encode the PNG");
  std::string bytes(reinterpret_cast<const char*>(png), static_cast<std::size_t>(size));
  STBIW_FREE(png);
  WriteFileAtomically(path, bytes);
}

}  // namespace fabatlas::precompute

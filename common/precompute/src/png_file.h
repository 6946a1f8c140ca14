// The one PNG writer of the precompute plots (Fig. 13 curves, Fig. 14 box
// plots): 8-bit RGB rows, top to bottom, written atomically.
#pragma once

#include <filesystem>
#include <vector>

namespace fabatlas::precompute {

// Encodes `rgb` (width * height * 3 bytes) as PNG and writes it to `path`
// atomically. Throws InputError naming `path` when encoding fails.
void WritePngFile(const std::filesystem::path& path, const std::vector<unsigned char>& rgb, int width, int height);

}  // namespace fabatlas::precompute

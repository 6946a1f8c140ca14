// fabatlas/sampling/point_key_text.h — integer keys as text: a point key
// (design_space.h) or any list of integers written in decimal, separated by
// commas ("3,0,-2"; "" for none). The one format of the job store's sample
// keys, the coordinator's solid keys, the task keys' hashed text and the
// artifact file's keys, cells and node boxes (docs/artifact.md).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace fabatlas::sampling {

std::string PointKeyText(const std::vector<std::int64_t>& key);

// The integers PointKeyText wrote; std::nullopt unless every part between
// commas is a whole decimal integer ("" is the empty list).
std::optional<std::vector<std::int64_t>> ParsePointKeyText(const std::string& text);

}  // namespace fabatlas::sampling

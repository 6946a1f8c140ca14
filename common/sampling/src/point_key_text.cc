// Integer keys as text (fabatlas/sampling/point_key_text.h).
#include "fabatlas/sampling/point_key_text.h"

#include <exception>

namespace fabatlas::sampling {

std::string PointKeyText(const std::vector<std::int64_t>& key) {
  std::string out;
  for (std::size_t i = 0; i < key.size(); ++i) out += (i ? "," : "") + std::to_string(key[i]);
  return out;
}

std::optional<std::vector<std::int64_t>> ParsePointKeyText(const std::string& text) {
  std::vector<std::int64_t> out;
  if (text.empty()) return out;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = text.find(',', start);
    const std::string part = text.substr(start, end == std::string::npos ? std::string::npos : end - start);
    try {
      std::size_t used = 0;
      out.push_back(std::stoll(part, &used));
      if (used != part.size()) return std::nullopt;
    } catch (const std::exception&) {
      return std::nullopt;
    }
    if (end == std::string::npos) return out;
    start = end + 1;
  }
}

}  // namespace fabatlas::sampling

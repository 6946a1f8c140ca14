// A list of keys as text (fabatlas/key_list_text.h).
#include "fabatlas/key_list_text.h"

namespace fabatlas {

std::string KeyListText(const std::vector<std::string>& keys) {
  std::string out;
  for (std::size_t i = 0; i < keys.size(); ++i) out += (i ? "," : "") + keys[i];
  return out;
}

std::vector<std::string> ParseKeyListText(const std::string& text) {
  std::vector<std::string> out;
  for (std::size_t at = 0; at < text.size();) {
    std::size_t comma = text.find(',', at);
    if (comma == std::string::npos) comma = text.size();
    out.push_back(text.substr(at, comma - at));
    at = comma + 1;
  }
  return out;
}

}  // namespace fabatlas

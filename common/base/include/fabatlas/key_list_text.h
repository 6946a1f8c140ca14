// fabatlas/key_list_text.h — a list of keys (subtree keys, hex digests: no
// commas in them) as one text: the keys separated by commas, "" for none.
// The one format of a subtree's children in the job store and in the
// artifact's cache entries (docs/artifact.md).
#pragma once

#include <string>
#include <vector>

namespace fabatlas {

std::string KeyListText(const std::vector<std::string>& keys);

// The keys KeyListText wrote (a trailing comma ends the list).
std::vector<std::string> ParseKeyListText(const std::string& text);

}  // namespace fabatlas

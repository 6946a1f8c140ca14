// A design's text with its defaults at a point. See design_at_point.h.
#include "fabatlas/design/design_at_point.h"

#include <charconv>
#include <sstream>
#include <vector>

#include "fabatlas/error.h"

namespace fabatlas::design {
namespace {

// The shortest decimal that reads back as v.
std::string Shortest(double v) {
  char buffer[64];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v);
  return std::string(buffer, r.ptr);
}

std::size_t Indent(const std::string& line) {
  const std::size_t i = line.find_first_not_of(' ');
  return i == std::string::npos ? line.size() : i;
}

// The end of a scalar value in a flow map starting at `from` (the next ','
// or '}' outside quotes and brackets, or a comment).
std::size_t ValueEnd(const std::string& line, std::size_t from) {
  int depth = 0;
  for (std::size_t i = from; i < line.size(); ++i) {
    const char c = line[i];
    if (c == '[' || c == '{') ++depth;
    if ((c == ']' || c == '}') && depth > 0) {
      --depth;
      continue;
    }
    if (depth == 0 && (c == ',' || c == '}' || c == '#')) return i;
  }
  return line.size();
}

}  // namespace

std::string DesignTextAt(const Design& design, const Point& u) {
  std::vector<std::string> lines;
  {
    std::istringstream in(design.canonical_text);
    for (std::string line; std::getline(in, line);) lines.push_back(line);
  }
  const std::string file = design.file.string();
  for (const ExposedParameter& p : design.exposed) {
    const auto it = u.find(p.name);
    if (it == u.end()) continue;
    std::string value;
    if (p.kind == ParameterKind::kEnumerated)
      value = p.labels.at(static_cast<std::size_t>(it->second));
    else
      value = Shortest(it->second);
    const std::size_t row = static_cast<std::size_t>(p.place.line) - 1;
    if (p.place.line < 1 || row >= lines.size())
      throw InputError(file + ": cannot place the default of parameter '" + p.name + "'");
    std::string& line = lines[row];
    const std::size_t open = line.find('{', p.place.column > 0 ? p.place.column - 1 : 0);
    if (open != std::string::npos) {
      // Flow map on the key's line.
      const std::size_t d = line.find("default:", open);
      if (d != std::string::npos) {
        const std::size_t v = d + 8;
        line.replace(v, ValueEnd(line, v) - v, " " + value);
      } else {
        const std::size_t close = ValueEnd(line, open + 1);
        if (close >= line.size() || line[close] != '}') {
          std::size_t end = open + 1;
          while (end < line.size() && line[end] != '}') end = ValueEnd(line, end) + 1;
          if (end >= line.size())
            throw InputError(file + ":" + std::to_string(p.place.line) + ": cannot place the default of parameter '" +
                             p.name + "'");
          line.insert(end, ", default: " + value);
        } else {
          line.insert(close, ", default: " + value);
        }
      }
      continue;
    }
    // Block map: a `default:` line indented below the key.
    bool placed = false;
    const std::size_t key_indent = Indent(line);
    for (std::size_t r = row + 1; r < lines.size() && !placed; ++r) {
      if (lines[r].find_first_not_of(' ') == std::string::npos) continue;
      if (Indent(lines[r]) <= key_indent) break;
      const std::size_t d = lines[r].find("default:");
      if (d == Indent(lines[r])) {
        const std::size_t v = d + 8;
        const std::size_t hash = lines[r].find(" #", v);
        lines[r].replace(v, (hash == std::string::npos ? lines[r].size() : hash) - v, " " + value);
        placed = true;
      }
    }
    if (!placed)
      throw InputError(file + ":" + std::to_string(p.place.line) + ": parameter '" + p.name +
                       "' has no default: line to set");
  }
  std::string text;
  for (const auto& line : lines) text += line + "\n";
  // It must load back with u as its defaults.
  const Design back = ParseDesign(text, design.file);
  const Point defaults = DefaultPoint(back);
  for (const auto& [name, v] : u)
    if (defaults.count(name) && defaults.at(name) != v)
      throw InputError(file + ": the written design does not hold " + name + " = " + Shortest(v));
  return text;
}

}  // namespace fabatlas::design

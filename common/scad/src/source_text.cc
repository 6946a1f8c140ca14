// Scanning OpenSCAD source text (fabatlas/scad/source_text.h).
#include "fabatlas/scad/source_text.h"

#include <cctype>

namespace fabatlas::scad {

void SkipWhiteSpace(const std::string& text, SourcePosition& p) {
  while (p.at < text.size() && std::isspace(static_cast<unsigned char>(text[p.at]))) {
    if (text[p.at] == '\n') ++p.line;
    ++p.at;
  }
}

bool SkipComment(const std::string& text, SourcePosition& p, std::string* body) {
  if (text.compare(p.at, 2, "//") == 0) {
    std::size_t end = text.find('\n', p.at);
    if (end == std::string::npos) end = text.size();
    if (body) *body = text.substr(p.at + 2, end - p.at - 2);
    p.at = end;
    return true;
  }
  if (text.compare(p.at, 2, "/*") == 0) {
    const std::size_t close = text.find("*/", p.at + 2);
    const std::size_t end = close == std::string::npos ? text.size() : close;
    if (body) *body = text.substr(p.at + 2, end - p.at - 2);
    for (std::size_t k = p.at; k < end; ++k) p.line += text[k] == '\n';
    p.at = close == std::string::npos ? text.size() : close + 2;
    return true;
  }
  return false;
}

void SkipBlank(const std::string& text, SourcePosition& p) {
  do SkipWhiteSpace(text, p);
  while (SkipComment(text, p));
}

std::string ReadStringLiteral(const std::string& text, SourcePosition& p, bool& terminated) {
  std::string value;
  std::size_t i = p.at + 1;  // past the opening quote
  while (i < text.size() && text[i] != '"') {
    if (text[i] == '\\' && i + 1 < text.size()) {
      const char e = text[i + 1];
      value += e == 'n' ? '\n' : e == 't' ? '\t' : e == 'r' ? '\r' : e;
      i += 2;
    } else {
      if (text[i] == '\n') ++p.line;
      value += text[i++];
    }
  }
  terminated = i < text.size();
  p.at = terminated ? i + 1 : text.size();
  return value;
}

}  // namespace fabatlas::scad

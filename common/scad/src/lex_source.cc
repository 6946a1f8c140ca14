// The tokens of OpenSCAD source text (fabatlas/scad/lex_source.h).
#include "fabatlas/scad/lex_source.h"

#include <cctype>
#include <cstddef>
#include <stdexcept>

#include "fabatlas/scad/source_text.h"

namespace fabatlas::scad {
namespace {

bool Digit(char c) { return std::isdigit(static_cast<unsigned char>(c)) != 0; }

// The end of an exponent (`e5`, `E-3`) starting at `at`, or `at` when there is none.
std::size_t ExponentEnd(const std::string& s, std::size_t at) {
  if (at >= s.size() || (s[at] != 'e' && s[at] != 'E')) return at;
  std::size_t e = at + 1;
  if (e < s.size() && (s[e] == '+' || s[e] == '-')) ++e;
  if (e >= s.size() || !Digit(s[e])) return at;
  while (e < s.size() && Digit(s[e])) ++e;
  return e;
}

// Digits followed by a letter or '_' (not an exponent `1e5`, `2E-3`).
bool DigitsThenName(const std::string& s, std::size_t at) {
  while (at < s.size() && Digit(s[at])) ++at;
  if (at >= s.size() || ExponentEnd(s, at) != at) return false;
  return std::isalpha(static_cast<unsigned char>(s[at])) || s[at] == '_';
}

}  // namespace

LexSummary LexSource(const std::string& s, const LexOptions& options) {
  LexSummary out;
  const auto problem = [&out](int line, std::string what) {
    if (out.problem_line == 0) {
      out.problem_line = line;
      out.problem = std::move(what);
    }
  };
  static const char* const kTwo[] = {"<=", ">=", "==", "!=", "&&", "||"};
  const std::size_t n = s.size();
  SourcePosition p;
  for (SkipWhiteSpace(s, p); p.at < n; SkipWhiteSpace(s, p)) {
    SourceToken t;
    t.line = p.line;
    const std::size_t i = p.at;
    const char c = s[i];
    if (SkipComment(s, p, &t.text)) {
      if (!options.keep_comments) continue;
      t.kind = s[i + 1] == '/' ? SourceToken::Kind::kLineComment : SourceToken::Kind::kBlockComment;
    } else if (c == '"') {
      for (std::size_t q = i + 1; q < n && s[q] != '"'; ++q)
        if (s[q] == '\\' && q + 1 < n) {
          if (s[q + 1] == 'x' || s[q + 1] == 'u' || s[q + 1] == 'U') problem(t.line, "a \\x or \\u escape");
          ++q;
        }
      bool terminated = false;
      t.kind = SourceToken::Kind::kString;
      t.text = ReadStringLiteral(s, p, terminated);
      if (!terminated) problem(t.line, "unterminated string");
    } else if (Digit(c) && DigitsThenName(s, i)) {
      std::size_t end = i;
      while (end < n && (std::isalnum(static_cast<unsigned char>(s[end])) || s[end] == '_')) ++end;
      t.kind = SourceToken::Kind::kIdent;
      t.text = s.substr(i, end - i);
      p.at = end;
    } else if (Digit(c) || (c == '.' && i + 1 < n && Digit(s[i + 1]))) {
      std::size_t end = i;
      while (end < n && (Digit(s[end]) || s[end] == '.')) ++end;
      end = ExponentEnd(s, end);
      t.kind = SourceToken::Kind::kNumber;
      t.text = s.substr(i, end - i);
      try {
        t.number = std::stod(t.text);
      } catch (const std::exception&) {
        problem(t.line, "number '" + t.text + "'");
      }
      p.at = end;
      if (end < n && (std::isalpha(static_cast<unsigned char>(s[end])) || s[end] == '_'))
        problem(t.line, "identifier starting with a digit");
    } else if (std::isalpha(static_cast<unsigned char>(c)) || c == '_' || c == '$') {
      std::size_t end = i + 1;
      while (end < n && (std::isalnum(static_cast<unsigned char>(s[end])) || s[end] == '_')) ++end;
      t.kind = SourceToken::Kind::kIdent;
      t.text = s.substr(i, end - i);
      p.at = end;
    } else {
      t.kind = SourceToken::Kind::kSymbol;
      t.text = std::string(1, c);
      for (const char* two : kTwo)
        if (s.compare(i, 2, two) == 0) t.text = two;
      if (t.text.size() == 1 && std::string("()[]{},;=:?.+-*/%^!<>#").find(c) == std::string::npos)
        problem(t.line, std::string("character '") + c + "'");
      p.at += t.text.size();
    }
    out.tokens.push_back(std::move(t));
  }
  SourceToken end;
  end.line = p.line;
  out.tokens.push_back(end);
  return out;
}

}  // namespace fabatlas::scad

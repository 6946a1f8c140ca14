// fabatlas/scad/lex_source.h — the tokens of OpenSCAD source text. One lexer
// for the Customizer's annotation reader (customizer.cc: comments kept, the
// annotations live in them) and the native evaluator (evaluate_model.cc:
// comments dropped). OpenSCAD's lexical rules (OpenSCAD User Manual, "The
// OpenSCAD Language"; white space, comments and strings as source_text.h
// scans them):
//  - names are `$`, a letter or `_`, then letters, digits and `_`; digits
//    followed by a letter or `_` that is not an exponent are a name too
//    (`8bit_font`);
//  - numbers are digits with `.` and an optional exponent (`1e5`, `2.5E-3`);
//  - `<= >= == != && ||` are one symbol each, any other character is one.
// Single-threaded per call; no shared state.
#pragma once

#include <string>
#include <vector>

namespace fabatlas::scad {

struct SourceToken {
  enum class Kind { kEnd, kNumber, kString, kIdent, kSymbol, kLineComment, kBlockComment };
  Kind kind = Kind::kEnd;
  // The name, the number as written, the string's value (escapes applied),
  // the symbol, or the comment's body (between its delimiters).
  std::string text;
  double number = 0;  // kNumber's value
  int line = 1;       // 1-based line of its first character
};

struct LexOptions {
  bool keep_comments = false;  // true: comments become kLineComment / kBlockComment tokens
};

struct LexSummary {
  // In text order, then one kEnd token on the text's last line. Lexing never
  // stops early: an unterminated string or comment ends at the end of the
  // text, an unknown character is a symbol of its own.
  std::vector<SourceToken> tokens;
  // The first place where the text is not OpenSCAD or not read as OpenSCAD
  // reads it (problem_line 0: none): "unterminated string", "a \x or \u
  // escape" (kept as the letter), "number 'TEXT'" (out of range), "identifier
  // starting with a digit" (`1.5x`: a number, then a name), "character 'C'"
  // (not in OpenSCAD's syntax).
  int problem_line = 0;
  std::string problem;
};

LexSummary LexSource(const std::string& text, const LexOptions& options = {});

}  // namespace fabatlas::scad

// fabatlas/scad/source_text.h — scanning OpenSCAD source text (.scad files
// and OpenSCAD's .csg export): white space, comments and string literals, the
// pieces every reader of that text steps over or keeps. One implementation
// for the lexer of .scad files (lex_source.h), the .csg parser (csg_tree.cc)
// and the scan for the files a model reads (model_files.cc). Lexical rules
// as in the OpenSCAD User Manual: `//` line and `/* */` block comments, double
// quoted strings with backslash escapes.
#pragma once

#include <cstddef>
#include <string>

namespace fabatlas::scad {

// A place in source text: the byte offset `at` and its 1-based line.
struct SourcePosition {
  std::size_t at = 0;
  int line = 1;
};

// Steps `p` over white space (std::isspace), counting the lines it passes.
// Comments are not white space here.
void SkipWhiteSpace(const std::string& text, SourcePosition& p);

// At a `//` or `/*` comment: steps `p` past it, counting lines, and returns
// true with `body` (when not null) set to the text between the delimiters. A
// line comment ends before its '\n'; a block comment without `*/` ends at the
// end of the text. Elsewhere returns false and leaves `p` as it is.
bool SkipComment(const std::string& text, SourcePosition& p, std::string* body = nullptr);

// Steps `p` over white space and comments (SkipWhiteSpace, SkipComment)
// until anything else or the end of the text.
void SkipBlank(const std::string& text, SourcePosition& p);

// At a '"': reads the string literal, steps `p` past its closing quote
// (counting the lines inside) and returns its value with the escapes applied
// (\n, \t and \r; a backslash before any other character stands for that
// character). `terminated` says whether the closing quote was found; without
// it `p` ends at the end of the text.
std::string ReadStringLiteral(const std::string& text, SourcePosition& p, bool& terminated);

}  // namespace fabatlas::scad

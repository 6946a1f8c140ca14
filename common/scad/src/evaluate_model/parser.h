// evaluate_model/parser.h (internal to fabatlas_scad) — OpenSCAD source text (as
// lex_source.h's tokens) to the syntax tree of syntax.h, for the
// language subset evaluate_model.h lists; anything else declines with
// NotNative naming the line.
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "syntax.h"

namespace fabatlas::scad::internal {

// The tokens of src, comments dropped (lex_source.h), ending with kEnd;
// declines at the first place lexing does not read as OpenSCAD does.
std::vector<Token> Lex(const std::string& src);

// What `include <name>` (include true) or `use <name>` at `line` does: adds
// the included statements to `out` (source_files.h).
using Directive = std::function<void(bool include, const std::string& name, int line, std::vector<StmtPtr>& out)>;

// A recursive-descent parser over one file's tokens. An `include <...>` or
// `use <...>` reaches the parser as the symbol "include" or "use" and the
// name as a string (source_files.cc lexes them); without `directive` it
// declines them.
class Parser {
 public:
  explicit Parser(std::vector<Token> tokens, Directive directive = nullptr,
                  std::shared_ptr<const std::string> file = nullptr)
      : t_(std::move(tokens)), directive_(std::move(directive)), file_(std::move(file)) {}

  // The statements of a whole model.
  std::vector<StmtPtr> Program();
  // One expression and nothing after it (a -D value).
  ExprPtr OneExpression();

 private:
  const Token& Peek(std::size_t k = 0) const { return t_[std::min(i_ + k, t_.size() - 1)]; }
  bool Is(const char* punct, std::size_t k = 0) const { return Peek(k).kind == Tok::kSymbol && Peek(k).text == punct; }
  bool IsWord(const char* word) const { return Peek().kind == Tok::kIdent && Peek().text == word; }
  [[noreturn]] void Fail(const std::string& what) const { throw NotNative{Peek().line, what}; }
  void Expect(const char* punct);
  std::string Ident();

  // Statements.
  void Statements(std::vector<StmtPtr>& out);
  std::vector<StmtPtr> ChildStatement();
  StmtPtr Statement();
  StmtPtr Block(std::shared_ptr<Stmt> s);
  StmtPtr Modified();
  StmtPtr Keyword(std::shared_ptr<Stmt> s);
  StmtPtr Definition(std::shared_ptr<Stmt> s);
  StmtPtr IfStatement(std::shared_ptr<Stmt> s);
  template <typename Item>
  std::vector<Binding> List(Item item);
  std::vector<Binding> Parameters();
  std::vector<Binding> Arguments();

  // Expressions, from the loosest binding to the tightest.
  ExprPtr Binary(const std::string& op, ExprPtr a, ExprPtr b, int line);
  ExprPtr Expression();
  const char* BinaryOperatorAt(std::size_t level) const;
  ExprPtr BinaryChain(std::size_t level = 0);
  ExprPtr Unary();
  ExprPtr Exponent();
  ExprPtr Postfix();
  ExprPtr Primary();
  ExprPtr Bracket();
  ExprPtr Element();

  std::vector<Token> t_;
  std::size_t i_ = 0;
  Directive directive_;
  std::shared_ptr<const std::string> file_;
};

}  // namespace fabatlas::scad::internal

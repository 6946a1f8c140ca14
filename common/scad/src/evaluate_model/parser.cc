// The parser of parser.h: statements, then expressions.
#include "parser.h"

#include <map>

namespace fabatlas::scad::internal {

std::vector<Token> Lex(const std::string& src) {
  LexSummary lexed = LexSource(src);
  if (lexed.problem_line != 0) throw NotNative{lexed.problem_line, lexed.problem};
  return std::move(lexed.tokens);
}

namespace {

// OpenSCAD's rule for a variable assigned again in the same scope (it
// warns): the last value, evaluated at the first assignment's place; the
// later assignments are dropped.
void MergeReassignments(std::vector<StmtPtr>& body) {
  std::map<std::string, std::size_t> first;
  std::vector<StmtPtr> kept;
  for (const StmtPtr& s : body) {
    if (s->kind != Stmt::Kind::kAssign) {
      kept.push_back(s);
      continue;
    }
    auto [it, added] = first.emplace(s->name, kept.size());
    if (added) {
      kept.push_back(s);
      continue;
    }
    auto merged = std::make_shared<Stmt>(*kept[it->second]);
    merged->expr = s->expr;
    kept[it->second] = merged;
  }
  if (kept.size() != body.size()) body = std::move(kept);
}

}  // namespace

std::vector<StmtPtr> Parser::Program() {
  std::vector<StmtPtr> out;
  while (Peek().kind != Tok::kEnd) Statements(out);
  MergeReassignments(out);
  return out;
}

ExprPtr Parser::OneExpression() {
  ExprPtr e = Expression();
  if (Peek().kind != Tok::kEnd) Fail("text after the value");
  return e;
}

void Parser::Expect(const char* punct) {
  if (!Is(punct)) Fail(std::string("expected '") + punct + "'");
  ++i_;
}

std::string Parser::Ident() {
  if (Peek().kind != Tok::kIdent) Fail("expected a name");
  return t_[i_++].text;
}

// ---------------------------------------------------------------- statements

// The next statement appended to out: an include's statements, nothing for
// a use, a bare `{ }` block's statements (OpenSCAD 2021.01 adds them to the
// enclosing scope: its assignments and definitions are the scope's, its
// instantiations count as the scope's children).
void Parser::Statements(std::vector<StmtPtr>& out) {
  if (Peek().kind == Tok::kSymbol && (Peek().text == "include" || Peek().text == "use")) {
    const bool include = Peek().text == "include";
    const int line = Peek().line;
    if (!directive_) Fail(Peek().text + " <...>");
    const std::string name = Peek(1).text;
    i_ += 2;
    directive_(include, name, line, out);
    return;
  }
  StmtPtr s = Statement();
  if (s->kind == Stmt::Kind::kBlock) {  // a bare { }: its statements belong to the enclosing scope, as in OpenSCAD
    out.insert(out.end(), s->children.begin(), s->children.end());
    return;
  }
  out.push_back(std::move(s));
}

// The child of a module instantiation, if, for, let or module definition:
// nothing, one statement, or the statements of a `{ }` block.
std::vector<StmtPtr> Parser::ChildStatement() {
  if (Is(";")) {
    ++i_;
    return {};
  }
  StmtPtr s = Statement();
  if (s->kind == Stmt::Kind::kBlock) return s->children;
  return {s};
}

StmtPtr Parser::Statement() {
  auto s = std::make_shared<Stmt>();
  s->line = Peek().line;
  s->file = file_;
  if (Is(";") || Is("{")) return Block(s);
  if (Is("*")) {  // disabled: parsed, never instantiated
    ++i_;
    Statement();
    s->kind = Stmt::Kind::kDisabled;
    return s;
  }
  if (Is("#") || Is("%")) return Modified();
  if (Is("!")) Fail("modifier '!'");
  if (Peek().kind != Tok::kIdent) Fail("unexpected '" + Peek().text + "'");
  return Keyword(s);
}

// `;` (an empty block) or `{ statements }`.
StmtPtr Parser::Block(std::shared_ptr<Stmt> s) {
  s->kind = Stmt::Kind::kBlock;
  if (Is(";")) {
    ++i_;
    return s;
  }
  ++i_;
  while (!Is("}")) {
    if (Peek().kind == Tok::kEnd) Fail("unclosed '{'");
    Statements(s->children);
  }
  ++i_;
  MergeReassignments(s->children);
  return s;
}

// `#` (highlight) or `%` (background) before a statement: written before
// the node. Both (`%#` or `#%`) are written "%#", as OpenSCAD 2021.01 writes
// a node that is both.
StmtPtr Parser::Modified() {
  const std::string modifier = Peek().text;
  ++i_;
  StmtPtr inner = Statement();
  if (inner->kind != Stmt::Kind::kCall && inner->kind != Stmt::Kind::kIf && inner->kind != Stmt::Kind::kFor &&
      inner->kind != Stmt::Kind::kLet)
    Fail("modifier '" + modifier + "' on a definition, assignment or block");
  auto copy = std::make_shared<Stmt>(*inner);
  const std::string both = modifier + inner->modifier;
  copy->modifier =
      std::string(both.find('%') != std::string::npos ? "%" : "") + (both.find('#') != std::string::npos ? "#" : "");
  return copy;
}

// A statement that starts with a name: a definition, if, for, let,
// intersection_for, an assignment or a module instantiation.
StmtPtr Parser::Keyword(std::shared_ptr<Stmt> s) {
  const std::string word = Peek().text;
  if (word == "module" || word == "function") return Definition(s);
  if (word == "if") return IfStatement(s);
  if (word == "for" || word == "let" || word == "intersection_for") {
    ++i_;
    s->kind = word == "for" ? Stmt::Kind::kFor : word == "let" ? Stmt::Kind::kLet : Stmt::Kind::kIntersectionFor;
    s->bindings = Arguments();
    s->children = ChildStatement();
    return s;
  }
  if (Is("=", 1)) {
    s->kind = Stmt::Kind::kAssign;
    s->name = Ident();
    ++i_;
    s->expr = Expression();
    Expect(";");
    return s;
  }
  s->kind = Stmt::Kind::kCall;
  s->name = Ident();
  s->bindings = Arguments();
  s->children = ChildStatement();
  return s;
}

// `module name(params) child` or `function name(params) = expr;`.
StmtPtr Parser::Definition(std::shared_ptr<Stmt> s) {
  const bool module = IsWord("module");
  ++i_;
  s->kind = module ? Stmt::Kind::kModuleDef : Stmt::Kind::kFunctionDef;
  s->name = Ident();
  std::vector<Binding> params = Parameters();
  if (module) {
    auto m = std::make_shared<ModuleDef>();
    m->params = std::move(params);
    m->body = ChildStatement();
    s->module = m;
    return s;
  }
  auto f = std::make_shared<FunctionDef>();
  f->params = std::move(params);
  f->file = file_;
  Expect("=");
  f->body = Expression();
  Expect(";");
  s->function = f;
  return s;
}

StmtPtr Parser::IfStatement(std::shared_ptr<Stmt> s) {
  ++i_;
  s->kind = Stmt::Kind::kIf;
  Expect("(");
  s->expr = Expression();
  Expect(")");
  s->children = ChildStatement();
  if (IsWord("else")) {
    ++i_;
    s->otherwise = ChildStatement();
  }
  return s;
}

// `( item, item, ... )`, each item read by `item`.
template <typename Item>
std::vector<Binding> Parser::List(Item item) {
  std::vector<Binding> out;
  Expect("(");
  while (!Is(")")) {
    out.push_back(item());
    if (!Is(")")) Expect(",");
  }
  ++i_;
  return out;
}

// `(a, b = 1, ...)` of a definition.
std::vector<Binding> Parser::Parameters() {
  return List([this] {
    Binding b;
    b.name = Ident();
    if (Is("=")) {
      ++i_;
      b.expr = Expression();
    }
    return b;
  });
}

// `(expr, name = expr, ...)` of a call, let or for.
std::vector<Binding> Parser::Arguments() {
  return List([this] {
    Binding b;
    if (Peek().kind == Tok::kIdent && Is("=", 1)) {
      b.name = Ident();
      ++i_;
    }
    b.expr = Expression();
    return b;
  });
}

// ---------------------------------------------------------------- expressions

namespace {

// OpenSCAD's binary operators, one level per row from the loosest binding
// to the tightest; every level is left-associative. Below the last row
// come the unary operators and then ^ (Exponent).
constexpr std::size_t kBinaryLevels = 6;
constexpr const char* kBinaryOperators[kBinaryLevels][4] = {
    {"||"}, {"&&"}, {"==", "!="}, {"<", ">", "<=", ">="}, {"+", "-"}, {"*", "/", "%"}};

}  // namespace

ExprPtr Parser::Binary(const std::string& op, ExprPtr a, ExprPtr b, int line) {
  auto e = NewExpr(Expr::Kind::kBinary, line);
  e->text = op;
  e->items = {std::move(a), std::move(b)};
  return e;
}

ExprPtr Parser::Expression() {
  const int line = Peek().line;
  if (IsWord("let") && Is("(", 1)) {
    ++i_;
    auto e = NewExpr(Expr::Kind::kLet, line);
    e->bindings = Arguments();
    e->items = {Expression()};
    return e;
  }
  if ((IsWord("echo") || IsWord("assert")) && Is("(", 1)) {  // echo(...) expr, assert(...) expr
    auto e = NewExpr(IsWord("echo") ? Expr::Kind::kEcho : Expr::Kind::kAssert, line);
    ++i_;
    e->bindings = Arguments();
    e->items = {Expression()};
    return e;
  }
  if (IsWord("function")) Fail("function literal");
  ExprPtr c = BinaryChain();
  if (!Is("?")) return c;
  ++i_;
  ExprPtr a = Expression();
  Expect(":");
  ExprPtr b = Expression();
  auto e = NewExpr(Expr::Kind::kTernary, line);
  e->items = {c, a, b};
  return e;
}

// The operator of `level` at the cursor, or nullptr.
const char* Parser::BinaryOperatorAt(std::size_t level) const {
  for (const char* op : kBinaryOperators[level])
    if (op && Is(op)) return op;
  return nullptr;
}

// An operand chain of `level`'s operators (level 0: ||, the loosest).
ExprPtr Parser::BinaryChain(std::size_t level) {
  if (level == kBinaryLevels) return Unary();
  ExprPtr a = BinaryChain(level + 1);
  while (const char* op = BinaryOperatorAt(level)) {
    const int line = Peek().line;
    ++i_;
    a = Binary(op, a, BinaryChain(level + 1), line);
  }
  return a;
}

ExprPtr Parser::Unary() {
  if (Is("+") || Is("-") || Is("!")) {
    auto e = NewExpr(Expr::Kind::kUnary, Peek().line);
    e->text = Peek().text;
    ++i_;
    e->items = {Unary()};
    return e;
  }
  return Exponent();
}

ExprPtr Parser::Exponent() {
  ExprPtr a = Postfix();
  if (!Is("^")) return a;
  const int line = Peek().line;
  ++i_;
  return Binary("^", a, Unary(), line);
}

// Calls, indexing and `.x` after a primary.
ExprPtr Parser::Postfix() {
  ExprPtr a = Primary();
  for (;;) {
    const int line = Peek().line;
    if (Is("(")) {
      if (a->kind != Expr::Kind::kIdent) Fail("call of a computed function");
      auto e = NewExpr(Expr::Kind::kCall, line);
      e->text = a->text;
      e->bindings = Arguments();
      a = e;
    } else if (Is("[")) {
      ++i_;
      auto e = NewExpr(Expr::Kind::kIndex, line);
      e->items = {a, Expression()};
      Expect("]");
      a = e;
    } else if (Is(".")) {
      ++i_;
      auto e = NewExpr(Expr::Kind::kMember, line);
      e->text = Ident();
      e->items = {a};
      a = e;
    } else {
      return a;
    }
  }
}

// A number, string, true/false/undef, name, `( expr )` or `[ ... ]`.
ExprPtr Parser::Primary() {
  const Token& t = Peek();
  const int line = t.line;
  if (t.kind == Tok::kNumber) {
    auto e = NewExpr(Expr::Kind::kNumber, line);
    e->number = t.number;
    ++i_;
    return e;
  }
  if (t.kind == Tok::kString) {
    auto e = NewExpr(Expr::Kind::kString, line);
    e->text = t.text;
    ++i_;
    return e;
  }
  if (t.kind == Tok::kIdent) {
    auto e = std::make_shared<Expr>();
    e->line = line;
    if (t.text == "true" || t.text == "false") {
      e->kind = Expr::Kind::kBool;
      e->boolean = t.text == "true";
    } else if (t.text == "undef") {
      e->kind = Expr::Kind::kUndef;
    } else {
      e->kind = Expr::Kind::kIdent;
      e->text = t.text;
    }
    ++i_;
    return e;
  }
  if (Is("(")) {
    ++i_;
    ExprPtr e = Expression();
    Expect(")");
    return e;
  }
  if (Is("[")) return Bracket();
  Fail("unexpected '" + t.text + "'");
}

// `[...]`: a range, or a vector of expressions and comprehension elements.
ExprPtr Parser::Bracket() {
  const int line = Peek().line;
  Expect("[");
  auto e = NewExpr(Expr::Kind::kVector, line);
  if (Is("]")) {
    ++i_;
    return e;
  }
  ExprPtr first = Element();
  if (Is(":")) {
    ++i_;
    e->kind = Expr::Kind::kRange;
    ExprPtr second = Expression();
    if (Is(":")) {
      ++i_;
      e->items = {first, second, Expression()};
    } else {
      e->items = {first, nullptr, second};
    }
    Expect("]");
    return e;
  }
  e->items.push_back(first);
  while (Is(",")) {
    ++i_;
    if (Is("]")) break;  // trailing comma
    e->items.push_back(Element());
  }
  Expect("]");
  return e;
}

// A vector item: an expression or a list comprehension element (for, let,
// if/else, each).
ExprPtr Parser::Element() {
  const int line = Peek().line;
  if ((IsWord("for") || IsWord("let")) && Is("(", 1)) {
    auto e = NewExpr(IsWord("for") ? Expr::Kind::kCompFor : Expr::Kind::kCompLet, line);
    ++i_;
    e->bindings = Arguments();
    e->items = {Element()};
    return e;
  }
  if (IsWord("if") && Is("(", 1)) {
    auto e = NewExpr(Expr::Kind::kCompIf, line);
    ++i_;
    Expect("(");
    e->items.push_back(Expression());
    Expect(")");
    e->items.push_back(Element());
    if (IsWord("else")) {
      ++i_;
      e->items.push_back(Element());
    }
    return e;
  }
  if (IsWord("each")) {
    auto e = NewExpr(Expr::Kind::kEach, line);
    ++i_;
    e->items = {Element()};
    return e;
  }
  return Expression();
}

}  // namespace fabatlas::scad::internal

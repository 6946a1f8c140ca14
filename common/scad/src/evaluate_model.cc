// A Customizer model's CSG tree evaluated natively (fabatlas/scad/evaluate_model.h):
// parser (of lex_source.h's tokens), evaluator and the .csg writer,
// declining with NotNative for anything outside the subset.
#include "fabatlas/scad/evaluate_model.h"

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstddef>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "fabatlas/scad/lex_source.h"

namespace fabatlas::scad {
namespace {

// Thrown for anything the evaluator does not implement; the caller asks
// OpenSCAD instead.
struct NotNative {
  int line;
  std::string what;
};

// ---------------------------------------------------------------- lexer

using Token = SourceToken;
using Tok = SourceToken::Kind;

// The tokens of src, comments dropped (lex_source.h), ending with kEnd;
// declines at the first place lexing does not read as OpenSCAD does.
std::vector<Token> Lex(const std::string& src) {
  LexSummary lexed = LexSource(src);
  if (lexed.problem_line != 0) throw NotNative{lexed.problem_line, lexed.problem};
  return std::move(lexed.tokens);
}

// ---------------------------------------------------------------- syntax

struct Expr;
using ExprPtr = std::shared_ptr<const Expr>;

struct Binding {  // `name = expr` in argument lists, let, for; positional when name is empty
  std::string name;
  ExprPtr expr;
};

struct Expr {
  enum class Kind {
    kNumber, kString, kBool, kUndef, kIdent, kVector, kRange, kUnary, kBinary, kTernary, kCall, kIndex,
    kMember, kLet, kEcho, kAssert,
    // list comprehension elements (only inside kVector items)
    kCompFor, kCompIf, kCompLet, kEach
  } kind;
  int line = 0;
  double number = 0;
  bool boolean = false;
  std::string text;             // identifier, string, operator, member or callee name
  std::vector<ExprPtr> items;   // vector items; range begin, step, end; operands
  std::vector<Binding> bindings;  // call arguments, let / for bindings
};

// A new expression node of `kind` read at source line `line`.
std::shared_ptr<Expr> NewExpr(Expr::Kind kind, int line) {
  auto e = std::make_shared<Expr>();
  e->kind = kind;
  e->line = line;
  return e;
}

struct Stmt;
using StmtPtr = std::shared_ptr<const Stmt>;

struct ModuleDef {
  std::vector<Binding> params;  // defaults in expr (null when none)
  std::vector<StmtPtr> body;
};

struct FunctionDef {
  std::vector<Binding> params;
  ExprPtr body;
};

struct Stmt {
  enum class Kind { kAssign, kCall, kBlock, kIf, kFor, kIntersectionFor, kLet, kModuleDef, kFunctionDef, kDisabled } kind;
  int line = 0;
  std::string name;               // assigned variable, called or defined module/function
  std::string modifier;           // a call's "%" or "#"
  ExprPtr expr;                   // assigned value, if condition
  std::vector<Binding> bindings;  // call arguments, for / let bindings
  std::vector<StmtPtr> children;  // call's children, block's statements, if's then-branch
  std::vector<StmtPtr> otherwise; // if's else-branch
  std::shared_ptr<const ModuleDef> module;
  std::shared_ptr<const FunctionDef> function;
};

class Parser {
 public:
  explicit Parser(std::vector<Token> tokens) : t_(std::move(tokens)) {}

  std::vector<StmtPtr> Program() {
    std::vector<StmtPtr> out;
    while (Peek().kind != Tok::kEnd) out.push_back(Statement());
    return out;
  }

  ExprPtr OneExpression() {
    ExprPtr e = Expression();
    if (Peek().kind != Tok::kEnd) Fail("text after the value");
    return e;
  }

 private:
  const Token& Peek(std::size_t k = 0) const { return t_[std::min(i_ + k, t_.size() - 1)]; }
  bool Is(const char* punct, std::size_t k = 0) const { return Peek(k).kind == Tok::kSymbol && Peek(k).text == punct; }
  bool IsWord(const char* word) const { return Peek().kind == Tok::kIdent && Peek().text == word; }
  [[noreturn]] void Fail(const std::string& what) const { throw NotNative{Peek().line, what}; }
  void Expect(const char* punct) {
    if (!Is(punct)) Fail(std::string("expected '") + punct + "'");
    ++i_;
  }
  std::string Ident() {
    if (Peek().kind != Tok::kIdent) Fail("expected a name");
    return t_[i_++].text;
  }

  // The child of a module instantiation, if, for, let or module definition:
  // nothing, one statement, or the statements of a `{ }` block.
  std::vector<StmtPtr> ChildStatement() {
    if (Is(";")) {
      ++i_;
      return {};
    }
    StmtPtr s = Statement();
    if (s->kind == Stmt::Kind::kBlock) return s->children;
    return {s};
  }

  StmtPtr Statement() {
    auto s = std::make_shared<Stmt>();
    s->line = Peek().line;
    if (Is(";")) {
      ++i_;
      s->kind = Stmt::Kind::kBlock;
      return s;
    }
    if (Is("{")) {
      ++i_;
      s->kind = Stmt::Kind::kBlock;
      while (!Is("}")) {
        if (Peek().kind == Tok::kEnd) Fail("unclosed '{'");
        s->children.push_back(Statement());
      }
      ++i_;
      return s;
    }
    if (Is("*")) {  // disabled: parsed, never instantiated
      ++i_;
      Statement();
      s->kind = Stmt::Kind::kDisabled;
      return s;
    }
    if (Is("#") || Is("%")) {  // highlight, background: written before the node
      const std::string modifier = Peek().text;
      ++i_;
      StmtPtr inner = Statement();
      if (inner->kind != Stmt::Kind::kCall && inner->kind != Stmt::Kind::kIf && inner->kind != Stmt::Kind::kFor &&
          inner->kind != Stmt::Kind::kLet)
        Fail("modifier '" + modifier + "' on a definition, assignment or block");
      auto copy = std::make_shared<Stmt>(*inner);
      copy->modifier = modifier;
      return copy;
    }
    if (Is("!")) Fail("modifier '!'");
    if (Peek().kind != Tok::kIdent) Fail("unexpected '" + Peek().text + "'");
    const std::string word = Peek().text;
    if (word == "include" || word == "use") Fail(word + " <...>");
    if (word == "module") {
      ++i_;
      s->kind = Stmt::Kind::kModuleDef;
      s->name = Ident();
      auto m = std::make_shared<ModuleDef>();
      m->params = Parameters();
      m->body = ChildStatement();
      s->module = m;
      return s;
    }
    if (word == "function") {
      ++i_;
      s->kind = Stmt::Kind::kFunctionDef;
      s->name = Ident();
      auto f = std::make_shared<FunctionDef>();
      f->params = Parameters();
      Expect("=");
      f->body = Expression();
      Expect(";");
      s->function = f;
      return s;
    }
    if (word == "if") {
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
    if (word == "for" || word == "let") {
      ++i_;
      s->kind = word == "for" ? Stmt::Kind::kFor : Stmt::Kind::kLet;
      s->bindings = Arguments();
      s->children = ChildStatement();
      return s;
    }
    if (word == "intersection_for") {
      ++i_;
      s->kind = Stmt::Kind::kIntersectionFor;
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

  // `(a, b = 1, ...)` of a definition.
  std::vector<Binding> Parameters() {
    std::vector<Binding> out;
    Expect("(");
    while (!Is(")")) {
      Binding b;
      b.name = Ident();
      if (Is("=")) {
        ++i_;
        b.expr = Expression();
      }
      out.push_back(std::move(b));
      if (!Is(")")) Expect(",");
    }
    ++i_;
    return out;
  }

  // `(expr, name = expr, ...)` of a call, let or for.
  std::vector<Binding> Arguments() {
    std::vector<Binding> out;
    Expect("(");
    while (!Is(")")) {
      Binding b;
      if (Peek().kind == Tok::kIdent && Is("=", 1)) {
        b.name = Ident();
        ++i_;
      }
      b.expr = Expression();
      out.push_back(std::move(b));
      if (!Is(")")) Expect(",");
    }
    ++i_;
    return out;
  }

  ExprPtr Binary(const std::string& op, ExprPtr a, ExprPtr b, int line) {
    auto e = NewExpr(Expr::Kind::kBinary, line);
    e->text = op;
    e->items = {std::move(a), std::move(b)};
    return e;
  }

  ExprPtr Expression() {
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

  // OpenSCAD's binary operators, one level per row from the loosest binding
  // to the tightest; every level is left-associative. Below the last row
  // come the unary operators and then ^ (Exponent).
  static constexpr std::size_t kBinaryLevels = 6;
  static constexpr const char* kBinaryOperators[kBinaryLevels][4] = {
      {"||"}, {"&&"}, {"==", "!="}, {"<", ">", "<=", ">="}, {"+", "-"}, {"*", "/", "%"}};

  // The operator of `level` at the cursor, or nullptr.
  const char* BinaryOperatorAt(std::size_t level) const {
    for (const char* op : kBinaryOperators[level])
      if (op && Is(op)) return op;
    return nullptr;
  }
  // An operand chain of `level`'s operators (level 0: ||, the loosest).
  ExprPtr BinaryChain(std::size_t level = 0) {
    if (level == kBinaryLevels) return Unary();
    ExprPtr a = BinaryChain(level + 1);
    while (const char* op = BinaryOperatorAt(level)) {
      const int line = Peek().line;
      ++i_;
      a = Binary(op, a, BinaryChain(level + 1), line);
    }
    return a;
  }
  ExprPtr Unary() {
    if (Is("+") || Is("-") || Is("!")) {
      auto e = NewExpr(Expr::Kind::kUnary, Peek().line);
      e->text = Peek().text;
      ++i_;
      e->items = {Unary()};
      return e;
    }
    return Exponent();
  }
  ExprPtr Exponent() {
    ExprPtr a = Postfix();
    if (!Is("^")) return a;
    const int line = Peek().line;
    ++i_;
    return Binary("^", a, Unary(), line);
  }
  ExprPtr Postfix() {
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
  ExprPtr Primary() {
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
  ExprPtr Bracket() {
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

  ExprPtr Element() {
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

  std::vector<Token> t_;
  std::size_t i_ = 0;
};

// ---------------------------------------------------------------- values

struct Value {
  // Vector values built by this thread's evaluation (reset for each model):
  // bounds the memory a model can hold (about 100 bytes a value, at most two
  // million values), which the step count does not (one concat copies a
  // whole vector).
  static thread_local std::size_t values_built;

  enum class Kind { kUndef, kBool, kNumber, kString, kVector, kRange } kind = Kind::kUndef;
  double number = 0;  // kNumber
  bool boolean = false;
  std::string text;
  std::shared_ptr<const std::vector<Value>> items;  // kVector
  double range[3] = {0, 1, 0};                      // begin, step, end

  static Value Number(double v) {
    Value x;
    x.kind = Kind::kNumber;
    x.number = v;
    return x;
  }
  static Value Bool(bool v) {
    Value x;
    x.kind = Kind::kBool;
    x.boolean = v;
    return x;
  }
  static Value String(std::string v) {
    Value x;
    x.kind = Kind::kString;
    x.text = std::move(v);
    return x;
  }
  static Value Vector(std::vector<Value> v) {
    if (v.size() > 1'000'000) throw NotNative{0, "a vector of more than 1,000,000 values"};
    if ((values_built += v.size()) > 2'000'000) throw NotNative{0, "more than 2 million vector values built"};
    Value x;
    x.kind = Kind::kVector;
    x.items = std::make_shared<const std::vector<Value>>(std::move(v));
    return x;
  }
  bool IsNumber() const { return kind == Kind::kNumber; }
  bool IsVector() const { return kind == Kind::kVector; }
  const std::vector<Value>& Items() const { return *items; }
  bool Truthy() const {
    switch (kind) {
      case Kind::kUndef: return false;
      case Kind::kBool: return boolean;
      case Kind::kNumber: return number != 0;
      case Kind::kString: return !text.empty();
      case Kind::kVector: return !items->empty();
      case Kind::kRange: return true;
    }
    return false;
  }
};

thread_local std::size_t Value::values_built = 0;

bool Equal(const Value& a, const Value& b) {
  if (a.kind != b.kind) return false;
  switch (a.kind) {
    case Value::Kind::kUndef: return true;
    case Value::Kind::kBool: return a.boolean == b.boolean;
    case Value::Kind::kNumber: return a.number == b.number;
    case Value::Kind::kString: return a.text == b.text;
    case Value::Kind::kRange:
      return a.range[0] == b.range[0] && a.range[1] == b.range[1] && a.range[2] == b.range[2];
    case Value::Kind::kVector:
      if (a.items->size() != b.items->size()) return false;
      for (std::size_t k = 0; k < a.items->size(); ++k)
        if (!Equal((*a.items)[k], (*b.items)[k])) return false;
      return true;
  }
  return false;
}

// OpenSCAD's number text in the .csg export (an ostream's default: 6
// significant digits).
std::string Num(double v) {
  if (v == 0) v = 0;  // -0 is written 0
  char buf[40];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// OpenSCAD's number text for values (vectors such as polygon points, str())
// and matrices: 6 significant digits, exact ties rounded away from zero,
// trailing zeros dropped, the exponent form (`1e+6`, `2.5e-7`) below 1e-6 and
// from 1e6.
std::string ValueNum(double v) {
  if (v == 0) return "0";
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf";
  char buf[128];
  std::snprintf(buf, sizeof buf, "%.80e", std::abs(v));  // exact decimal digits of the double
  const std::string text = buf;
  const std::size_t e_at = text.find('e');
  std::string digits = text.substr(0, 1) + text.substr(2, e_at - 2);
  int exponent = std::stoi(text.substr(e_at + 1));
  std::string six = digits.substr(0, 6);
  if (digits[6] >= '5') {
    int k = 5;
    while (k >= 0 && six[k] == '9') six[k--] = '0';
    if (k < 0) {
      six = "100000";
      ++exponent;
    } else {
      ++six[k];
    }
  }
  while (six.size() > 1 && six.back() == '0') six.pop_back();
  std::string out = v < 0 ? "-" : "";
  if (exponent < -6 || exponent >= 6) {
    out += six.substr(0, 1);
    if (six.size() > 1) out += "." + six.substr(1);
    out += (exponent < 0 ? "e-" : "e+") + std::to_string(std::abs(exponent));
  } else if (exponent < 0) {
    out += "0." + std::string(-exponent - 1, '0') + six;
  } else {
    const std::size_t whole = static_cast<std::size_t>(exponent) + 1;
    if (six.size() <= whole) {
      out += six + std::string(whole - six.size(), '0');
    } else {
      out += six.substr(0, whole) + "." + six.substr(whole);
    }
  }
  return out;
}

std::string Quote(const std::string& s, int line) {
  for (char c : s)
    if (c == '"' || c == '\\' || static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x80)
      throw NotNative{line, "a string with quotes, backslashes, control or non-ASCII characters"};
  return "\"" + s + "\"";
}

std::string Write(const Value& v, int line) {
  switch (v.kind) {
    case Value::Kind::kUndef: return "undef";
    case Value::Kind::kBool: return v.boolean ? "true" : "false";
    case Value::Kind::kNumber: return ValueNum(v.number);
    case Value::Kind::kString: return Quote(v.text, line);
    case Value::Kind::kRange: throw NotNative{line, "a range as an argument"};
    case Value::Kind::kVector: {
      std::string out = "[";
      for (std::size_t k = 0; k < v.items->size(); ++k) out += (k ? ", " : "") + Write((*v.items)[k], line);
      return out + "]";
    }
  }
  return "undef";
}

// The values a range runs through (OpenSCAD's RangeType: count by
// nextafter((end - begin) / step) + 1; `[a:b]` with a > b swapped).
std::vector<double> RangeValues(const Value& r, int line) {
  double begin = r.range[0], step = r.range[1], end = r.range[2];
  if (!std::isfinite(begin) || !std::isfinite(step) || !std::isfinite(end) || step == 0)
    throw NotNative{line, "a range with an infinite, undefined or zero part"};
  std::vector<double> out;
  if (step < 0 ? begin < end : begin > end) return out;
  const double steps = std::nextafter((end - begin) / step, std::numeric_limits<double>::max());
  if (steps >= 1e6) throw NotNative{line, "a range of more than 1,000,000 values"};
  const auto n = static_cast<std::size_t>(steps) + 1;
  for (std::size_t i = 0; i < n; ++i) out.push_back(begin + static_cast<double>(i) * step);
  return out;
}

// Degrees, exact at multiples of 30 and 45 degrees as OpenSCAD's sin_degrees
// and cos_degrees are.
double SinDegrees(double x) {
  if (!std::isfinite(x)) return std::nan("");
  x = std::fmod(x, 360.0);
  if (x < 0) x += 360.0;
  bool negate = false;
  if (x >= 180.0) {
    x -= 180.0;
    negate = true;
  }
  if (x > 90.0) x = 180.0 - x;
  double s;
  if (x == 0) s = 0;
  else if (x == 30.0) s = 0.5;
  else if (x == 45.0) s = std::sqrt(0.5);
  else if (x == 60.0) s = std::sqrt(3.0) / 2;
  else if (x == 90.0) s = 1;
  else s = std::sin(x * std::numbers::pi / 180.0);
  return negate ? -s : s;
}
double CosDegrees(double x) { return SinDegrees(x + 90.0); }

// The colour keywords OpenSCAD 2021.01 knows (SVG 1.1 / CSS3 colour keywords,
// red, green, blue of 0-255, alpha), any case, and "#rgb", "#rgba",
// "#rrggbb", "#rrggbbaa".
bool ColourByName(std::string name, double rgba[4]) {
  struct Named {
    const char* name;
    int r, g, b;
    double a;
  };
  static const Named kColours[] = {
    {"aliceblue", 240, 248, 255, 1}, {"antiquewhite", 250, 235, 215, 1}, {"aqua", 0, 255, 255, 1},
    {"aquamarine", 127, 255, 212, 1}, {"azure", 240, 255, 255, 1}, {"beige", 245, 245, 220, 1},
    {"bisque", 255, 228, 196, 1}, {"black", 0, 0, 0, 1}, {"blanchedalmond", 255, 235, 205, 1},
    {"blue", 0, 0, 255, 1}, {"blueviolet", 138, 43, 226, 1}, {"brown", 165, 42, 42, 1},
    {"burlywood", 222, 184, 135, 1}, {"cadetblue", 95, 158, 160, 1}, {"chartreuse", 127, 255, 0, 1},
    {"chocolate", 210, 105, 30, 1}, {"coral", 255, 127, 80, 1}, {"cornflowerblue", 100, 149, 237, 1},
    {"cornsilk", 255, 248, 220, 1}, {"crimson", 220, 20, 60, 1}, {"cyan", 0, 255, 255, 1},
    {"darkblue", 0, 0, 139, 1}, {"darkcyan", 0, 139, 139, 1}, {"darkgoldenrod", 184, 134, 11, 1},
    {"darkgray", 169, 169, 169, 1}, {"darkgreen", 0, 100, 0, 1}, {"darkgrey", 169, 169, 169, 1},
    {"darkkhaki", 189, 183, 107, 1}, {"darkmagenta", 139, 0, 139, 1}, {"darkolivegreen", 85, 107, 47, 1},
    {"darkorange", 255, 140, 0, 1}, {"darkorchid", 153, 50, 204, 1}, {"darkred", 139, 0, 0, 1},
    {"darksalmon", 233, 150, 122, 1}, {"darkseagreen", 143, 188, 143, 1}, {"darkslateblue", 72, 61, 139, 1},
    {"darkslategray", 47, 79, 79, 1}, {"darkslategrey", 47, 79, 79, 1}, {"darkturquoise", 0, 206, 209, 1},
    {"darkviolet", 148, 0, 211, 1}, {"deeppink", 255, 20, 147, 1}, {"deepskyblue", 0, 191, 255, 1},
    {"dimgray", 105, 105, 105, 1}, {"dimgrey", 105, 105, 105, 1}, {"dodgerblue", 30, 144, 255, 1},
    {"firebrick", 178, 34, 34, 1}, {"floralwhite", 255, 250, 240, 1}, {"forestgreen", 34, 139, 34, 1},
    {"fuchsia", 255, 0, 255, 1}, {"gainsboro", 220, 220, 220, 1}, {"ghostwhite", 248, 248, 255, 1},
    {"gold", 255, 215, 0, 1}, {"goldenrod", 218, 165, 32, 1}, {"gray", 128, 128, 128, 1}, {"green", 0, 128, 0, 1},
    {"greenyellow", 173, 255, 47, 1}, {"grey", 128, 128, 128, 1}, {"honeydew", 240, 255, 240, 1},
    {"hotpink", 255, 105, 180, 1}, {"indianred", 205, 92, 92, 1}, {"indigo", 75, 0, 130, 1},
    {"ivory", 255, 255, 240, 1}, {"khaki", 240, 230, 140, 1}, {"lavender", 230, 230, 250, 1},
    {"lavenderblush", 255, 240, 245, 1}, {"lawngreen", 124, 252, 0, 1}, {"lemonchiffon", 255, 250, 205, 1},
    {"lightblue", 173, 216, 230, 1}, {"lightcoral", 240, 128, 128, 1}, {"lightcyan", 224, 255, 255, 1},
    {"lightgoldenrodyellow", 250, 250, 210, 1}, {"lightgray", 211, 211, 211, 1}, {"lightgreen", 144, 238, 144, 1},
    {"lightgrey", 211, 211, 211, 1}, {"lightpink", 255, 182, 193, 1}, {"lightsalmon", 255, 160, 122, 1},
    {"lightseagreen", 32, 178, 170, 1}, {"lightskyblue", 135, 206, 250, 1}, {"lightslategray", 119, 136, 153, 1},
    {"lightslategrey", 119, 136, 153, 1}, {"lightsteelblue", 176, 196, 222, 1}, {"lightyellow", 255, 255, 224, 1},
    {"lime", 0, 255, 0, 1}, {"limegreen", 50, 205, 50, 1}, {"linen", 250, 240, 230, 1}, {"magenta", 255, 0, 255, 1},
    {"maroon", 128, 0, 0, 1}, {"mediumaquamarine", 102, 205, 170, 1}, {"mediumblue", 0, 0, 205, 1},
    {"mediumorchid", 186, 85, 211, 1}, {"mediumpurple", 147, 112, 219, 1}, {"mediumseagreen", 60, 179, 113, 1},
    {"mediumslateblue", 123, 104, 238, 1}, {"mediumspringgreen", 0, 250, 154, 1},
    {"mediumturquoise", 72, 209, 204, 1}, {"mediumvioletred", 199, 21, 133, 1}, {"midnightblue", 25, 25, 112, 1},
    {"mintcream", 245, 255, 250, 1}, {"mistyrose", 255, 228, 225, 1}, {"moccasin", 255, 228, 181, 1},
    {"navajowhite", 255, 222, 173, 1}, {"navy", 0, 0, 128, 1}, {"oldlace", 253, 245, 230, 1},
    {"olive", 128, 128, 0, 1}, {"olivedrab", 107, 142, 35, 1}, {"orange", 255, 165, 0, 1},
    {"orangered", 255, 69, 0, 1}, {"orchid", 218, 112, 214, 1}, {"palegoldenrod", 238, 232, 170, 1},
    {"palegreen", 152, 251, 152, 1}, {"paleturquoise", 175, 238, 238, 1}, {"palevioletred", 219, 112, 147, 1},
    {"papayawhip", 255, 239, 213, 1}, {"peachpuff", 255, 218, 185, 1}, {"peru", 205, 133, 63, 1},
    {"pink", 255, 192, 203, 1}, {"plum", 221, 160, 221, 1}, {"powderblue", 176, 224, 230, 1},
    {"purple", 128, 0, 128, 1}, {"rebeccapurple", 102, 51, 153, 1}, {"red", 255, 0, 0, 1},
    {"rosybrown", 188, 143, 143, 1}, {"royalblue", 65, 105, 225, 1}, {"saddlebrown", 139, 69, 19, 1},
    {"salmon", 250, 128, 114, 1}, {"sandybrown", 244, 164, 96, 1}, {"seagreen", 46, 139, 87, 1},
    {"seashell", 255, 245, 238, 1}, {"sienna", 160, 82, 45, 1}, {"silver", 192, 192, 192, 1},
    {"skyblue", 135, 206, 235, 1}, {"slateblue", 106, 90, 205, 1}, {"slategray", 112, 128, 144, 1},
    {"slategrey", 112, 128, 144, 1}, {"snow", 255, 250, 250, 1}, {"springgreen", 0, 255, 127, 1},
    {"steelblue", 70, 130, 180, 1}, {"tan", 210, 180, 140, 1}, {"teal", 0, 128, 128, 1},
    {"thistle", 216, 191, 216, 1}, {"tomato", 255, 99, 71, 1}, {"transparent", 0, 0, 0, 0},
    {"turquoise", 64, 224, 208, 1}, {"violet", 238, 130, 238, 1}, {"wheat", 245, 222, 179, 1},
    {"white", 255, 255, 255, 1}, {"whitesmoke", 245, 245, 245, 1}, {"yellow", 255, 255, 0, 1},
    {"yellowgreen", 154, 205, 50, 1}
  };
  for (char& ch : name) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  if (!name.empty() && name[0] == '#') {
    const std::string hex = name.substr(1);
    if (hex.find_first_not_of("0123456789abcdef") != std::string::npos) return false;
    const std::size_t n = hex.size();
    if (n != 3 && n != 4 && n != 6 && n != 8) return false;
    const std::size_t width = n <= 4 ? 1 : 2;
    for (std::size_t k = 0; k < n / width; ++k) {
      int v = std::stoi(hex.substr(k * width, width), nullptr, 16);
      if (width == 1) v *= 17;
      rgba[k] = v / 255.0;
    }
    if (n == 3 || n == 6) rgba[3] = 1;
    return true;
  }
  for (const Named& c : kColours) {
    if (name != c.name) continue;
    rgba[0] = c.r / 255.0;
    rgba[1] = c.g / 255.0;
    rgba[2] = c.b / 255.0;
    rgba[3] = c.a;
    return true;
  }
  return false;
}

// ---------------------------------------------------------------- scopes

struct Scope {
  const Scope* lexical = nullptr;  // variables, functions, modules
  const Scope* dynamic = nullptr;  // $-variables
  std::map<std::string, Value> vars;
  std::map<std::string, std::shared_ptr<const ModuleDef>> modules;
  std::map<std::string, std::shared_ptr<const FunctionDef>> functions;
  // A module body's scope: the instantiation's child statements and the
  // scope they were written in.
  bool module_body = false;
  const std::vector<StmtPtr>* children = nullptr;
  const Scope* children_scope = nullptr;

  const Value* Find(const std::string& name) const {
    const bool special = !name.empty() && name[0] == '$';
    for (const Scope* s = this; s; s = special ? s->dynamic : s->lexical) {
      auto it = s->vars.find(name);
      if (it != s->vars.end()) return &it->second;
    }
    return nullptr;
  }
  std::shared_ptr<const ModuleDef> Module(const std::string& name) const {
    for (const Scope* s = this; s; s = s->lexical) {
      auto it = s->modules.find(name);
      if (it != s->modules.end()) return it->second;
    }
    return nullptr;
  }
  std::shared_ptr<const FunctionDef> Function(const std::string& name) const {
    for (const Scope* s = this; s; s = s->lexical) {
      auto it = s->functions.find(name);
      if (it != s->functions.end()) return it->second;
    }
    return nullptr;
  }
  const Scope* Body() const {
    for (const Scope* s = this; s; s = s->lexical)
      if (s->module_body) return s;
    return nullptr;
  }
};

// A node of the CSG tree: its head (`cube(size = [1, 1, 1], center = false)`)
// and children.
struct CsgOut {
  std::string head;
  std::vector<CsgOut> children;
  std::string modifier;  // "%" or "#", written before the indentation as OpenSCAD does
};

void Print(const CsgOut& n, int depth, std::string& out) {
  out += n.modifier;
  out.append(depth, '\t');
  out += n.head;
  if (n.children.empty()) {
    out += ";\n";
    return;
  }
  out += " {\n";
  for (const CsgOut& c : n.children) Print(c, depth + 1, out);
  out.append(depth, '\t');
  out += "}\n";
}

// ---------------------------------------------------------------- evaluator

// The stack the evaluation may use: deep recursion in a model declines (and
// OpenSCAD evaluates it) well before the smallest thread stack fabatlas runs
// samples on (TBB's 4 MiB); about 2 KiB per level of a recursive function
// or module.
constexpr std::ptrdiff_t kStackBudget = 1024 * 1024;

class Evaluator {
 public:
  Evaluator() : stack_base_(reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0))) {}

  // Called at every expression and statement: bounds the stack and the work
  // (20 million steps, a second or two; exponential recursion such as
  // f(n - 1) + f(n - 1) declines instead of running for hours).
  void Guard(int line) {
    if (++steps_ > 20'000'000) throw NotNative{line, "more than 20 million evaluation steps"};
    const auto here = reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0));
    if (stack_base_ > here && static_cast<std::ptrdiff_t>(stack_base_ - here) > kStackBudget)
      throw NotNative{line, "recursion deeper than the evaluator's stack budget"};
  }

  // The statements of one scope: definitions first, then the assignments in
  // order, then the instantiations in order (OpenSCAD's rule).
  void Run(const std::vector<StmtPtr>& body, Scope& scope, std::vector<CsgOut>& out) {
    Define(body, scope);
    for (const StmtPtr& s : body) Instantiate(*s, scope, out);
  }

  void Define(const std::vector<StmtPtr>& body, Scope& scope) {
    for (const StmtPtr& s : body) {
      if (s->kind == Stmt::Kind::kModuleDef) scope.modules[s->name] = s->module;
      else if (s->kind == Stmt::Kind::kFunctionDef) scope.functions[s->name] = s->function;
    }
    for (const StmtPtr& s : body) {
      if (s->kind != Stmt::Kind::kAssign) continue;
      if (scope.vars.count(s->name)) throw NotNative{s->line, "'" + s->name + "' assigned twice in one scope"};
      scope.vars[s->name] = Eval(*s->expr, scope);
    }
  }

  Value Eval(const Expr& e, const Scope& scope) {
    Guard(e.line);
    switch (e.kind) {
      case Expr::Kind::kNumber: return Value::Number(e.number);
      case Expr::Kind::kString: return Value::String(e.text);
      case Expr::Kind::kBool: return Value::Bool(e.boolean);
      case Expr::Kind::kUndef: return Value();
      case Expr::Kind::kIdent: {
        const Value* v = scope.Find(e.text);
        if (!v) {
          if (e.text == "PI") return Value::Number(std::numbers::pi);
          throw NotNative{e.line, "unknown variable '" + e.text + "'"};
        }
        return *v;
      }
      case Expr::Kind::kRange: {
        Value r;
        r.kind = Value::Kind::kRange;
        const Value b = Eval(*e.items[0], scope), en = Eval(*e.items[2], scope);
        const Value st = e.items[1] ? Eval(*e.items[1], scope) : Value::Number(1);
        if (!b.IsNumber() || !en.IsNumber() || !st.IsNumber()) throw NotNative{e.line, "a range of non-numbers"};
        r.range[0] = b.number;
        r.range[1] = st.number;
        r.range[2] = en.number;
        if (!e.items[1] && b.number > en.number) std::swap(r.range[0], r.range[2]);  // deprecated [a:b], a > b
        return r;
      }
      case Expr::Kind::kVector: {
        std::vector<Value> items;
        for (const ExprPtr& item : e.items) Element(*item, scope, items);
        return Value::Vector(std::move(items));
      }
      case Expr::Kind::kUnary: {
        const Value a = Eval(*e.items[0], scope);
        if (e.text == "!") return Value::Bool(!a.Truthy());
        if (e.text == "+") {
          if (!a.IsNumber() && !a.IsVector()) throw NotNative{e.line, "unary + of a non-number"};
          return a;
        }
        return Negate(a, e.line);
      }
      case Expr::Kind::kBinary: return BinaryOp(e, scope);
      case Expr::Kind::kTernary:
        return Eval(*e.items[0], scope).Truthy() ? Eval(*e.items[1], scope) : Eval(*e.items[2], scope);
      case Expr::Kind::kIndex: {
        const Value a = Eval(*e.items[0], scope), i = Eval(*e.items[1], scope);
        if (!i.IsNumber()) throw NotNative{e.line, "an index that is not a number"};
        if (a.IsVector()) {
          const double k = std::floor(i.number);
          if (!(k >= 0 && k < static_cast<double>(a.Items().size()))) return Value();
          return a.Items()[static_cast<std::size_t>(k)];
        }
        if (a.kind == Value::Kind::kString) {
          const double k = std::floor(i.number);
          if (!(k >= 0 && k < static_cast<double>(a.text.size()))) return Value();
          return Value::String(std::string(1, a.text[static_cast<std::size_t>(k)]));
        }
        throw NotNative{e.line, "indexing a value that is not a vector or string"};
      }
      case Expr::Kind::kMember: {
        const Value a = Eval(*e.items[0], scope);
        const std::size_t k = e.text == "x" ? 0 : e.text == "y" ? 1 : e.text == "z" ? 2 : 3;
        if (!a.IsVector() || k == 3) throw NotNative{e.line, "member '." + e.text + "'"};
        return k < a.Items().size() ? a.Items()[k] : Value();
      }
      case Expr::Kind::kLet: {
        Scope inner;
        inner.lexical = inner.dynamic = &scope;
        Bind(e.bindings, inner);
        return Eval(*e.items[0], inner);
      }
      case Expr::Kind::kCall: return Call(e, scope);
      case Expr::Kind::kEcho: return Eval(*e.items[0], scope);
      case Expr::Kind::kAssert:
        if (e.bindings.empty() || !Eval(*e.bindings[0].expr, scope).Truthy()) throw NotNative{e.line, "a failed assert"};
        return Eval(*e.items[0], scope);
      default: throw NotNative{e.line, "a list comprehension element outside [ ]"};
    }
  }

 private:
  // let / for bindings evaluated in order, each seeing the ones before it.
  void Bind(const std::vector<Binding>& bindings, Scope& inner) {
    for (const Binding& b : bindings) {
      if (b.name.empty()) throw NotNative{b.expr->line, "a let without a name"};
      inner.vars[b.name] = Eval(*b.expr, inner);
    }
  }

  std::vector<Value> Iterate(const Value& v, int line) {
    if (v.kind == Value::Kind::kRange) {
      std::vector<Value> out;
      for (double x : RangeValues(v, line)) out.push_back(Value::Number(x));
      return out;
    }
    if (v.IsVector()) return v.Items();
    if (v.IsNumber() || v.kind == Value::Kind::kBool) return {v};
    throw NotNative{line, "a loop over a string or undef"};
  }

  // Nested loops over `bindings` (for (a = ..., b = ...)), calling `body` with
  // the scope of each combination.
  template <typename Body>
  void Loop(const std::vector<Binding>& bindings, std::size_t k, const Scope& outer, Body&& body) {
    if (k == bindings.size()) {
      body(outer);
      return;
    }
    const Binding& b = bindings[k];
    if (b.name.empty()) throw NotNative{b.expr->line, "a C-style or unnamed for"};
    for (const Value& v : Iterate(Eval(*b.expr, outer), b.expr->line)) {
      if (++iterations_ > 1000000) throw NotNative{b.expr->line, "more than 1,000,000 loop iterations"};
      Scope inner;
      inner.lexical = inner.dynamic = &outer;
      inner.vars[b.name] = v;
      Loop(bindings, k + 1, inner, body);
    }
  }

  void Element(const Expr& e, const Scope& scope, std::vector<Value>& out) {
    switch (e.kind) {
      case Expr::Kind::kCompFor:
        Loop(e.bindings, 0, scope, [&](const Scope& inner) { Element(*e.items[0], inner, out); });
        return;
      case Expr::Kind::kCompLet: {
        Scope inner;
        inner.lexical = inner.dynamic = &scope;
        Bind(e.bindings, inner);
        Element(*e.items[0], inner, out);
        return;
      }
      case Expr::Kind::kCompIf:
        if (Eval(*e.items[0], scope).Truthy()) Element(*e.items[1], scope, out);
        else if (e.items.size() > 2) Element(*e.items[2], scope, out);
        return;
      case Expr::Kind::kEach: {
        const Value v = Eval(*e.items[0], scope);
        if (v.IsVector() || v.kind == Value::Kind::kRange) {
          for (const Value& x : Iterate(v, e.line)) out.push_back(x);
        } else {
          throw NotNative{e.line, "each of a non-vector"};
        }
        return;
      }
      default: out.push_back(Eval(e, scope));
    }
  }

  Value Negate(const Value& a, int line) {
    if (a.IsNumber()) return Value::Number(-a.number);
    if (a.IsVector()) {
      std::vector<Value> out;
      for (const Value& x : a.Items()) out.push_back(Negate(x, line));
      return Value::Vector(std::move(out));
    }
    throw NotNative{line, "negation of a non-number"};
  }

  Value Arithmetic(const std::string& op, const Value& a, const Value& b, int line) {
    if (a.IsNumber() && b.IsNumber()) {
      const double x = a.number, y = b.number;
      if (op == "+") return Value::Number(x + y);
      if (op == "-") return Value::Number(x - y);
      if (op == "*") return Value::Number(x * y);
      if (op == "/") return Value::Number(x / y);
      if (op == "%") return Value::Number(std::fmod(x, y));
      if (op == "^") return Value::Number(std::pow(x, y));
    }
    if ((op == "+" || op == "-") && a.IsVector() && b.IsVector()) {
      if (a.Items().size() != b.Items().size()) throw NotNative{line, "vectors of different lengths added"};
      std::vector<Value> out;
      for (std::size_t k = 0; k < a.Items().size(); ++k) out.push_back(Arithmetic(op, a.Items()[k], b.Items()[k], line));
      return Value::Vector(std::move(out));
    }
    if ((op == "*" || op == "/") && a.IsVector() && b.IsNumber()) {
      std::vector<Value> out;
      for (const Value& x : a.Items()) out.push_back(Arithmetic(op, x, b, line));
      return Value::Vector(std::move(out));
    }
    if (op == "*" && a.IsNumber() && b.IsVector()) {
      std::vector<Value> out;
      for (const Value& x : b.Items()) out.push_back(Arithmetic(op, a, x, line));
      return Value::Vector(std::move(out));
    }
    if (op == "*" && a.IsVector() && b.IsVector()) return Product(a, b, line);
    throw NotNative{line, "operator " + op + " on these operands"};
  }

  static bool AllNumbers(const Value& v) {
    if (!v.IsVector()) return false;
    for (const Value& x : v.Items())
      if (!x.IsNumber()) return false;
    return true;
  }

  // Vector x vector (dot), matrix x vector, vector x matrix, matrix x matrix.
  Value Product(const Value& a, const Value& b, int line) {
    if (AllNumbers(a) && AllNumbers(b)) {
      if (a.Items().size() != b.Items().size()) throw NotNative{line, "dot product of different lengths"};
      double s = 0;
      for (std::size_t k = 0; k < a.Items().size(); ++k) s += a.Items()[k].number * b.Items()[k].number;
      return Value::Number(s);
    }
    if (!a.Items().empty() && AllNumbers(b)) {  // matrix x vector: rows dotted with b
      std::vector<Value> out;
      for (const Value& row : a.Items()) {
        if (!AllNumbers(row)) throw NotNative{line, "matrix product of a ragged matrix"};
        out.push_back(Product(row, b, line));
      }
      return Value::Vector(std::move(out));
    }
    if (AllNumbers(a) && !b.Items().empty()) {  // vector x matrix: a times the columns
      if (a.Items().size() != b.Items().size()) throw NotNative{line, "vector x matrix of different sizes"};
      const std::size_t cols = b.Items()[0].IsVector() ? b.Items()[0].Items().size() : 0;
      std::vector<Value> out;
      for (std::size_t c = 0; c < cols; ++c) {
        double s = 0;
        for (std::size_t r = 0; r < b.Items().size(); ++r) {
          const Value& row = b.Items()[r];
          if (!AllNumbers(row) || row.Items().size() != cols) throw NotNative{line, "ragged matrix"};
          s += a.Items()[r].number * row.Items()[c].number;
        }
        out.push_back(Value::Number(s));
      }
      return Value::Vector(std::move(out));
    }
    // matrix x matrix: each row of a times b
    std::vector<Value> out;
    for (const Value& row : a.Items()) {
      if (!AllNumbers(row)) throw NotNative{line, "matrix product of these operands"};
      out.push_back(Product(row, b, line));
    }
    return Value::Vector(std::move(out));
  }

  Value BinaryOp(const Expr& e, const Scope& scope) {
    const std::string& op = e.text;
    if (op == "&&") return Value::Bool(Eval(*e.items[0], scope).Truthy() && Eval(*e.items[1], scope).Truthy());
    if (op == "||") return Value::Bool(Eval(*e.items[0], scope).Truthy() || Eval(*e.items[1], scope).Truthy());
    const Value a = Eval(*e.items[0], scope), b = Eval(*e.items[1], scope);
    if (op == "==") return Value::Bool(Equal(a, b));
    if (op == "!=") return Value::Bool(!Equal(a, b));
    if (op == "<" || op == ">" || op == "<=" || op == ">=") {
      if (!a.IsNumber() || !b.IsNumber()) throw NotNative{e.line, "comparison of non-numbers"};
      const double x = a.number, y = b.number;
      return Value::Bool(op == "<" ? x < y : op == ">" ? x > y : op == "<=" ? x <= y : x >= y);
    }
    return Arithmetic(op, a, b, e.line);
  }

  // Arguments matched to parameter names as OpenSCAD matches them: positional
  // in order, then by name.
  std::map<std::string, Value> Match(const std::vector<Binding>& args, const std::vector<std::string>& names,
                                     const Scope& scope, int line, std::map<std::string, Value>* specials = nullptr) {
    std::map<std::string, Value> out;
    std::size_t position = 0;
    for (const Binding& a : args) {
      if (a.name.empty()) {
        if (position >= names.size()) throw NotNative{line, "too many positional arguments"};
        out[names[position++]] = Eval(*a.expr, scope);
      } else if (a.name[0] == '$' && specials) {
        (*specials)[a.name] = Eval(*a.expr, scope);
      } else {
        if (std::find(names.begin(), names.end(), a.name) == names.end())
          throw NotNative{line, "argument '" + a.name + "' not known here"};
        out[a.name] = Eval(*a.expr, scope);
      }
    }
    return out;
  }

  double NumberArg(const std::map<std::string, Value>& args, const std::string& name, int line) {
    auto it = args.find(name);
    if (it == args.end() || !it->second.IsNumber()) throw NotNative{line, "'" + name + "' is not a number"};
    return it->second.number;
  }

  // A user function or a built-in one.
  Value Call(const Expr& e, const Scope& scope) {
    if (auto f = scope.Function(e.text)) {
      if (++depth_ > 10000) throw NotNative{e.line, "recursion deeper than 10,000 calls"};
      Scope inner;
      inner.dynamic = &scope;
      inner.lexical = DefinitionScope(e.text, scope, /*module=*/false);
      BindParameters(f->params, e.bindings, scope, inner, e.line);
      Value v = Eval(*f->body, inner);
      --depth_;
      return v;
    }
    std::vector<Value> a;
    for (const Binding& b : e.bindings) {
      if (!b.name.empty()) throw NotNative{e.line, "named argument to built-in function " + e.text};
      a.push_back(Eval(*b.expr, scope));
    }
    return Builtin(e.text, a, e.line);
  }

  // The scope a function or module was defined in: the first scope along the
  // lexical chain that defines it.
  const Scope* DefinitionScope(const std::string& name, const Scope& scope, bool module) {
    for (const Scope* s = &scope; s; s = s->lexical)
      if (module ? s->modules.count(name) : s->functions.count(name)) return s;
    return nullptr;
  }

  void BindParameters(const std::vector<Binding>& params, const std::vector<Binding>& args, const Scope& caller,
                      Scope& inner, int line) {
    std::size_t position = 0;
    std::map<std::string, Value> given;
    for (const Binding& a : args) {
      if (a.name.empty()) {
        if (position >= params.size()) throw NotNative{line, "too many positional arguments"};
        given[params[position++].name] = Eval(*a.expr, caller);
      } else if (a.name[0] == '$') {
        inner.vars[a.name] = Eval(*a.expr, caller);
      } else {
        bool known = false;
        for (const Binding& p : params) known = known || p.name == a.name;
        if (!known) throw NotNative{line, "argument '" + a.name + "' not a parameter"};
        given[a.name] = Eval(*a.expr, caller);
      }
    }
    for (const Binding& p : params) {
      auto it = given.find(p.name);
      if (it != given.end()) inner.vars[p.name] = it->second;
      else if (p.expr) inner.vars[p.name] = Eval(*p.expr, inner);
      else inner.vars[p.name] = Value();
    }
  }

  static const Value& Numbers(const Value& v, int line, const char* what) {
    if (!AllNumbers(v)) throw NotNative{line, std::string(what) + " of a non-numeric vector"};
    return v;
  }

  Value Builtin(const std::string& name, const std::vector<Value>& a, int line) {
    auto num = [&](std::size_t k) {
      if (k >= a.size() || !a[k].IsNumber()) throw NotNative{line, name + "() of a non-number"};
      return a[k].number;
    };
    auto one = [&](double (*f)(double)) {
      if (a.size() != 1) throw NotNative{line, name + "() with " + std::to_string(a.size()) + " arguments"};
      return Value::Number(f(num(0)));
    };
    constexpr double kDeg = 180.0 / std::numbers::pi;
    if (name == "sin") return one([](double x) { return SinDegrees(x); });
    if (name == "cos") return one([](double x) { return CosDegrees(x); });
    if (name == "tan") return one([](double x) { return SinDegrees(x) / CosDegrees(x); });
    if (name == "asin") return one([](double x) { return std::asin(x) * kDeg; });
    if (name == "acos") return one([](double x) { return std::acos(x) * kDeg; });
    if (name == "atan") return one([](double x) { return std::atan(x) * kDeg; });
    if (name == "atan2" && a.size() == 2) return Value::Number(std::atan2(num(0), num(1)) * kDeg);
    if (name == "abs") return one([](double x) { return std::abs(x); });
    if (name == "sign") return one([](double x) { return x > 0 ? 1.0 : x < 0 ? -1.0 : 0.0; });
    if (name == "sqrt") return one([](double x) { return std::sqrt(x); });
    if (name == "exp") return one([](double x) { return std::exp(x); });
    if (name == "ln") return one([](double x) { return std::log(x); });
    if (name == "log" && a.size() == 1) return Value::Number(std::log10(num(0)));
    if (name == "log" && a.size() == 2) return Value::Number(std::log(num(1)) / std::log(num(0)));
    if (name == "floor") return one([](double x) { return std::floor(x); });
    if (name == "ceil") return one([](double x) { return std::ceil(x); });
    if (name == "round") return one([](double x) { return std::round(x); });
    if (name == "pow" && a.size() == 2) return Value::Number(std::pow(num(0), num(1)));
    if (name == "min" || name == "max") {
      const std::vector<Value>& xs = a.size() == 1 && a[0].IsVector() ? a[0].Items() : a;
      if (xs.empty()) throw NotNative{line, name + "() of nothing"};
      double m = 0;
      for (std::size_t k = 0; k < xs.size(); ++k) {
        if (!xs[k].IsNumber()) throw NotNative{line, name + "() of a non-number"};
        m = k == 0 ? xs[k].number : name == "min" ? std::min(m, xs[k].number) : std::max(m, xs[k].number);
      }
      return Value::Number(m);
    }
    if (name == "norm" && a.size() == 1) {
      double s = 0;
      for (const Value& x : Numbers(a[0], line, "norm").Items()) s += x.number * x.number;
      return Value::Number(std::sqrt(s));
    }
    if (name == "cross" && a.size() == 2) {
      const auto& u = Numbers(a[0], line, "cross").Items();
      const auto& v = Numbers(a[1], line, "cross").Items();
      if (u.size() == 2 && v.size() == 2) return Value::Number(u[0].number * v[1].number - u[1].number * v[0].number);
      if (u.size() != 3 || v.size() != 3) throw NotNative{line, "cross() of vectors not of 2 or 3 numbers"};
      return Value::Vector({Value::Number(u[1].number * v[2].number - u[2].number * v[1].number),
                            Value::Number(u[2].number * v[0].number - u[0].number * v[2].number),
                            Value::Number(u[0].number * v[1].number - u[1].number * v[0].number)});
    }
    if (name == "len" && a.size() == 1) {
      if (a[0].IsVector()) return Value::Number(static_cast<double>(a[0].Items().size()));
      if (a[0].kind == Value::Kind::kString) return Value::Number(static_cast<double>(a[0].text.size()));
      throw NotNative{line, "len() of a non-vector"};
    }
    if (name == "concat") {
      std::vector<Value> out;
      for (const Value& x : a) {
        if (x.IsVector()) out.insert(out.end(), x.Items().begin(), x.Items().end());
        else out.push_back(x);
        if (out.size() > 1'000'000) throw NotNative{line, "a vector of more than 1,000,000 values"};
      }
      return Value::Vector(std::move(out));
    }
    if (name == "str") {
      std::string out;
      for (const Value& x : a) {
        if (x.kind == Value::Kind::kString) out += x.text;
        else if (x.IsNumber() && std::isfinite(x.number)) out += ValueNum(x.number);
        else if (x.kind == Value::Kind::kBool) out += x.boolean ? "true" : "false";
        else throw NotNative{line, "str() of a vector, infinity or undef"};
        if (out.size() > 10'000'000) throw NotNative{line, "a string of more than 10,000,000 characters"};
      }
      return Value::String(out);
    }
    if (name == "chr") {
      std::string out;
      for (const Value& x : a) {
        if (!x.IsNumber() || x.number < 1 || x.number > 127) throw NotNative{line, "chr() outside ASCII"};
        out += static_cast<char>(x.number);
      }
      return Value::String(out);
    }
    if (name == "ord" && a.size() == 1 && a[0].kind == Value::Kind::kString && a[0].text.size() == 1 &&
        static_cast<unsigned char>(a[0].text[0]) < 0x80)
      return Value::Number(static_cast<unsigned char>(a[0].text[0]));
    if (name == "lookup" && a.size() == 2) {
      const double key = num(0);
      if (!a[1].IsVector() || a[1].Items().empty()) throw NotNative{line, "lookup() in a non-table"};
      std::vector<std::pair<double, double>> table;
      for (const Value& row : a[1].Items()) {
        if (!AllNumbers(row) || row.Items().size() < 2) throw NotNative{line, "lookup() in a malformed table"};
        table.push_back({row.Items()[0].number, row.Items()[1].number});
      }
      // OpenSCAD: below the first key the first value, above the last the
      // last, else linear between the neighbouring keys (table in order).
      double low_key = table[0].first, low = table[0].second, high_key = low_key, high = low;
      bool have_low = false, have_high = false;
      for (const auto& [k, v] : table) {
        if (k <= key && (!have_low || k > low_key)) low_key = k, low = v, have_low = true;
        if (k >= key && (!have_high || k < high_key)) high_key = k, high = v, have_high = true;
      }
      if (!have_low) return Value::Number(high);
      if (!have_high) return Value::Number(low);
      if (high_key == low_key) return Value::Number(low);
      return Value::Number(low + (key - low_key) / (high_key - low_key) * (high - low));
    }
    if (a.size() == 1) {
      if (name == "is_undef") return Value::Bool(a[0].kind == Value::Kind::kUndef);
      if (name == "is_num") return Value::Bool(a[0].IsNumber() && !std::isnan(a[0].number));
      if (name == "is_bool") return Value::Bool(a[0].kind == Value::Kind::kBool);
      if (name == "is_string") return Value::Bool(a[0].kind == Value::Kind::kString);
      if (name == "is_list") return Value::Bool(a[0].IsVector());
    }
    throw NotNative{line, "function " + name + "() with these arguments"};
  }

  // ------------------------------------------------------------ statements

  void Instantiate(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
    Guard(s.line);
    if (!s.modifier.empty()) {
      Stmt plain = s;
      plain.modifier.clear();
      const std::size_t before = out.size();
      Instantiate(plain, scope, out);
      if (out.size() > before + 1) throw NotNative{s.line, "modifier '" + s.modifier + "' on several nodes"};
      if (out.size() == before + 1) out.back().modifier = s.modifier;
      return;
    }
    switch (s.kind) {
      case Stmt::Kind::kAssign:
      case Stmt::Kind::kModuleDef:
      case Stmt::Kind::kFunctionDef:
      case Stmt::Kind::kDisabled: return;
      case Stmt::Kind::kBlock:
        for (const StmtPtr& c : s.children) {
          if (c->kind == Stmt::Kind::kAssign || c->kind == Stmt::Kind::kModuleDef || c->kind == Stmt::Kind::kFunctionDef)
            throw NotNative{c->line, "a definition inside a bare { } block"};
          Instantiate(*c, scope, out);
        }
        return;
      case Stmt::Kind::kIf: {
        const bool then = Eval(*s.expr, scope).Truthy();
        if (!then && s.otherwise.empty()) return;
        CsgOut group{"group()", {}};
        Scope inner;
        inner.lexical = inner.dynamic = &scope;
        Run(then ? s.children : s.otherwise, inner, group.children);
        out.push_back(std::move(group));
        return;
      }
      case Stmt::Kind::kFor: {
        CsgOut group{"group()", {}};
        Loop(s.bindings, 0, scope, [&](const Scope& bound) {
          Scope inner;
          inner.lexical = inner.dynamic = &bound;
          Run(s.children, inner, group.children);
        });
        out.push_back(std::move(group));
        return;
      }
      case Stmt::Kind::kIntersectionFor: {
        // OpenSCAD exports intersection() of every iteration's nodes side by
        // side, which is the intersection only when each iteration makes one
        // node (its render intersects each iteration's union): declined
        // otherwise.
        CsgOut both{"intersection()", {}};
        Loop(s.bindings, 0, scope, [&](const Scope& bound) {
          Scope inner;
          inner.lexical = inner.dynamic = &bound;
          const std::size_t before = both.children.size();
          Run(s.children, inner, both.children);
          if (both.children.size() != before + 1)
            throw NotNative{s.line, "intersection_for with an iteration making other than one node"};
        });
        out.push_back(std::move(both));
        return;
      }
      case Stmt::Kind::kLet: {
        CsgOut group{"group()", {}};
        Scope bound;
        bound.lexical = bound.dynamic = &scope;
        Bind(s.bindings, bound);
        Scope inner;
        inner.lexical = inner.dynamic = &bound;
        Run(s.children, inner, group.children);
        out.push_back(std::move(group));
        return;
      }
      case Stmt::Kind::kCall: CallModule(s, scope, out); return;
    }
  }

  // The child statements of a built-in module instantiation, in a scope of
  // their own under `call` (which holds the instantiation's $-arguments).
  std::vector<CsgOut> Children(const Stmt& s, const Scope& call) {
    std::vector<CsgOut> out;
    Scope inner;
    inner.lexical = inner.dynamic = &call;
    Run(s.children, inner, out);
    return out;
  }

  void CallModule(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
    if (s.name == "echo") {
      if (!s.children.empty()) {
        Scope call;
        call.lexical = call.dynamic = &scope;
        out.push_back({"group()", Children(s, call)});
      }
      return;
    }
    if (s.name == "children") {
      ChildrenCall(s, scope, out);
      return;
    }
    if (auto m = scope.Module(s.name)) {
      if (++depth_ > 10000) throw NotNative{s.line, "recursion deeper than 10,000 calls"};
      Scope body;
      body.lexical = DefinitionScope(s.name, scope, /*module=*/true);
      body.dynamic = &scope;
      body.module_body = true;
      body.children = &s.children;
      body.children_scope = &scope;
      BindParameters(m->params, s.bindings, scope, body, s.line);
      std::size_t count = 0;
      for (const StmtPtr& c : s.children) count += Instantiates(*c);
      body.vars["$children"] = Value::Number(static_cast<double>(count));
      CsgOut group{"group()", {}};
      Run(m->body, body, group.children);
      out.push_back(std::move(group));
      --depth_;
      return;
    }
    Scope call;
    call.lexical = call.dynamic = &scope;
    if (s.name == "assert") {
      std::map<std::string, Value> specials;
      auto args = Match(s.bindings, {"condition", "message"}, scope, s.line, &specials);
      if (!args["condition"].Truthy()) throw NotNative{s.line, "a failed assert"};
      if (!s.children.empty()) out.push_back({"group()", Children(s, call)});
      return;
    }
    BuiltinModule(s, scope, call, out);
  }

  // Whether a child statement counts for $children and children(i) (OpenSCAD
  // counts module instantiations, not assignments or definitions).
  static std::size_t Instantiates(const Stmt& s) {
    return s.kind == Stmt::Kind::kCall || s.kind == Stmt::Kind::kIf || s.kind == Stmt::Kind::kFor ||
                   s.kind == Stmt::Kind::kIntersectionFor || s.kind == Stmt::Kind::kLet || s.kind == Stmt::Kind::kBlock
               ? 1
               : 0;
  }

  void ChildrenCall(const Stmt& s, Scope& scope, std::vector<CsgOut>& out) {
    const Scope* body = scope.Body();
    if (!body) return;  // top level: no children
    if (!s.children.empty()) throw NotNative{s.line, "children() with children"};
    std::vector<const Stmt*> instantiations;
    for (const StmtPtr& c : *body->children) {
      if (c->kind == Stmt::Kind::kBlock) throw NotNative{c->line, "a { } block among a module's children"};
      if (Instantiates(*c)) instantiations.push_back(c.get());
    }
    // The children run where they were written, with the $-variables of the
    // place children() is called.
    Scope written;
    written.lexical = body->children_scope;
    written.dynamic = &scope;
    Define(*body->children, written);
    if (s.bindings.empty()) {
      CsgOut group{"group()", {}};
      for (const Stmt* c : instantiations) Instantiate(*c, written, group.children);
      out.push_back(std::move(group));
      return;
    }
    if (s.bindings.size() != 1 || !s.bindings[0].name.empty()) throw NotNative{s.line, "children() with these arguments"};
    const Value i = Eval(*s.bindings[0].expr, scope);
    if (!i.IsNumber()) throw NotNative{s.line, "children() of a vector or range"};
    const double k = std::floor(i.number);
    if (!(k >= 0 && k < static_cast<double>(instantiations.size()))) return;
    Instantiate(*instantiations[static_cast<std::size_t>(k)], written, out);
  }

  double Special(const Scope& scope, const char* name, double fallback) {
    const Value* v = scope.Find(name);
    if (!v) return fallback;
    if (!v->IsNumber()) throw NotNative{0, std::string(name) + " is not a number"};
    return v->number;
  }
  std::string Fragments(const Scope& scope) {
    const double fn = Special(scope, "$fn", 0), fa = std::max(Special(scope, "$fa", 12), 0.01),
                 fs = std::max(Special(scope, "$fs", 2), 0.01);
    return "$fn = " + Num(fn) + ", $fa = " + Num(fa) + ", $fs = " + Num(fs);
  }

  static std::string Matrix(const double m[4][4]) {
    std::string out = "multmatrix([";
    for (int r = 0; r < 4; ++r) {
      out += r ? ", [" : "[";
      for (int c = 0; c < 4; ++c) out += (c ? ", " : "") + ValueNum(m[r][c]);
      out += "]";
    }
    return out + "])";
  }

  // A vector of 2 or 3 numbers (z defaults to `z`), or false.
  static bool Vec3(const Value& v, double out[3], double z) {
    if (!AllNumbers(v) || v.Items().size() < 2 || v.Items().size() > 3) return false;
    out[0] = v.Items()[0].number;
    out[1] = v.Items()[1].number;
    out[2] = v.Items().size() == 3 ? v.Items()[2].number : z;
    return std::isfinite(out[0]) && std::isfinite(out[1]) && std::isfinite(out[2]);
  }

  void BuiltinModule(const Stmt& s, const Scope& scope, Scope& call, std::vector<CsgOut>& out) {
    const int line = s.line;
    std::map<std::string, Value> specials;
    auto match = [&](const std::vector<std::string>& names) {
      auto args = Match(s.bindings, names, scope, line, &specials);
      for (auto& [k, v] : specials) call.vars[k] = v;
      return args;
    };
    auto leaf = [&](std::string head) {
      if (!s.children.empty()) {
        for (const StmtPtr& c : s.children)
          if (c->kind != Stmt::Kind::kBlock || !c->children.empty())
            throw NotNative{line, s.name + "() with children"};
      }
      out.push_back({std::move(head), {}});
    };
    auto boolean = [&](const std::map<std::string, Value>& args, const char* name) {
      auto it = args.find(name);
      if (it == args.end() || it->second.kind == Value::Kind::kUndef) return false;
      if (it->second.kind != Value::Kind::kBool) throw NotNative{line, std::string("'") + name + "' not a boolean"};
      return it->second.boolean;
    };
    auto given = [&](const std::map<std::string, Value>& args, const char* name) {
      auto it = args.find(name);
      return it != args.end() && it->second.kind != Value::Kind::kUndef;
    };
    auto number = [&](const std::map<std::string, Value>& args, const char* name, double fallback) {
      auto it = args.find(name);
      if (it == args.end() || it->second.kind == Value::Kind::kUndef) return fallback;
      if (!it->second.IsNumber() || !std::isfinite(it->second.number))
        throw NotNative{line, std::string("'") + name + "' not a finite number"};
      return it->second.number;
    };
    const std::string& n = s.name;
    if (n == "cube") {
      auto args = match({"size", "center"});
      double size[3] = {1, 1, 1};
      if (given(args, "size")) {
        const Value& v = args["size"];
        if (v.IsNumber()) size[0] = size[1] = size[2] = v.number;
        else if (!AllNumbers(v) || v.Items().size() != 3) throw NotNative{line, "cube size not a number or 3 numbers"};
        else for (int k = 0; k < 3; ++k) size[k] = v.Items()[k].number;
      }
      leaf("cube(size = [" + Num(size[0]) + ", " + Num(size[1]) + ", " + Num(size[2]) + "], center = " +
           (boolean(args, "center") ? "true" : "false") + ")");
      return;
    }
    if (n == "sphere" || n == "circle") {
      auto args = match({"r", "d"});
      double r = number(args, "r", 1);
      if (given(args, "d")) r = number(args, "d", 2) / 2;
      leaf(n + "(" + Fragments(call) + ", r = " + Num(r) + ")");
      return;
    }
    if (n == "cylinder") {
      auto args = match({"h", "r1", "r2", "center", "r", "d", "d1", "d2"});
      const double h = number(args, "h", 1);
      double r1 = 1, r2 = 1;
      if (given(args, "r")) r1 = r2 = number(args, "r", 1);
      if (given(args, "d")) r1 = r2 = number(args, "d", 2) / 2;
      if (given(args, "r1")) r1 = number(args, "r1", 1);
      if (given(args, "d1")) r1 = number(args, "d1", 2) / 2;
      if (given(args, "r2")) r2 = number(args, "r2", 1);
      if (given(args, "d2")) r2 = number(args, "d2", 2) / 2;
      leaf("cylinder(" + Fragments(call) + ", h = " + Num(h) + ", r1 = " + Num(r1) + ", r2 = " + Num(r2) +
           ", center = " + (boolean(args, "center") ? "true" : "false") + ")");
      return;
    }
    if (n == "square") {
      auto args = match({"size", "center"});
      double size[2] = {1, 1};
      if (given(args, "size")) {
        const Value& v = args["size"];
        if (v.IsNumber()) size[0] = size[1] = v.number;
        else if (!AllNumbers(v) || v.Items().size() != 2) throw NotNative{line, "square size not a number or 2 numbers"};
        else for (int k = 0; k < 2; ++k) size[k] = v.Items()[k].number;
      }
      leaf("square(size = [" + Num(size[0]) + ", " + Num(size[1]) + "], center = " +
           (boolean(args, "center") ? "true" : "false") + ")");
      return;
    }
    if (n == "polygon") {
      auto args = match({"points", "paths", "convexity"});
      if (!args["points"].IsVector()) throw NotNative{line, "polygon points not a vector"};
      leaf("polygon(points = " + Write(args["points"], line) + ", paths = " + Write(args["paths"], line) +
           ", convexity = " + Num(std::trunc(number(args, "convexity", 1))) + ")");
      return;
    }
    if (n == "polyhedron") {
      auto args = match({"points", "faces", "convexity", "triangles"});
      if (given(args, "triangles") && !given(args, "faces")) args["faces"] = args["triangles"];  // deprecated name
      if (!args["points"].IsVector() || !args["faces"].IsVector()) throw NotNative{line, "polyhedron without points and faces"};
      leaf("polyhedron(points = " + Write(args["points"], line) + ", faces = " + Write(args["faces"], line) +
           ", convexity = " + Num(std::trunc(number(args, "convexity", 1))) + ")");
      return;
    }
    if (n == "text") {
      auto args = match({"text", "size", "font", "direction", "language", "script", "halign", "valign", "spacing"});
      auto text = [&](const char* name, const char* fallback) {
        auto it = args.find(name);
        if (it == args.end() || it->second.kind == Value::Kind::kUndef) return std::string(fallback);
        if (it->second.kind != Value::Kind::kString) throw NotNative{line, std::string("text '") + name + "' not a string"};
        return it->second.text;
      };
      // Direction, language and script as OpenSCAD fills them for ASCII text
      // (script "Latn" when a letter names it, none for digits and signs).
      auto Latin = [](const std::string& t) {
        return std::any_of(t.begin(), t.end(), [](char ch) { return std::isalpha(static_cast<unsigned char>(ch)) != 0; });
      };
      if (given(args, "direction") || given(args, "language") || given(args, "script"))
        throw NotNative{line, "text direction, language or script"};
      leaf("text(text = " + Quote(text("text", ""), line) + ", size = " + Num(number(args, "size", 10)) +
           ", spacing = " + Num(number(args, "spacing", 1)) + ", font = " + Quote(text("font", ""), line) +
           ", direction = \"ltr\", language = \"en\", " + (Latin(text("text", "")) ? "script = \"Latn\", " : "") +
           "halign = " + Quote(text("halign", "left"), line) +
           ", valign = " + Quote(text("valign", "baseline"), line) + ", " + Fragments(call) + ")");
      return;
    }
    double m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
    if (n == "translate") {
      auto args = match({"v"});
      double v[3];
      if (!Vec3(args["v"], v, 0)) throw NotNative{line, "translate by a non-vector"};
      for (int k = 0; k < 3; ++k) m[k][3] = v[k];
      out.push_back({Matrix(m), Children(s, call)});
      return;
    }
    if (n == "scale") {
      auto args = match({"v"});
      double v[3];
      if (args["v"].IsNumber()) v[0] = v[1] = v[2] = args["v"].number;
      else if (!Vec3(args["v"], v, 1)) throw NotNative{line, "scale by a non-vector"};
      for (int k = 0; k < 3; ++k) m[k][k] = v[k];
      out.push_back({Matrix(m), Children(s, call)});
      return;
    }
    if (n == "mirror") {
      auto args = match({"v"});
      double v[3];
      if (!Vec3(args["v"], v, 0)) throw NotNative{line, "mirror in a non-vector"};
      const double l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
      if (l2 > 0)
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) m[r][c] -= 2 * v[r] * v[c] / l2;
      out.push_back({Matrix(m), Children(s, call)});
      return;
    }
    if (n == "rotate") {
      auto args = match({"a", "v"});
      const Value& a = args["a"];
      if (a.IsVector()) {
        if (given(args, "v")) throw NotNative{line, "rotate by a vector about an axis"};
        if (!AllNumbers(a) || a.Items().empty() || a.Items().size() > 3) throw NotNative{line, "rotate by a malformed vector"};
        double ang[3] = {0, 0, 0};
        for (std::size_t k = 0; k < a.Items().size(); ++k) ang[k] = a.Items()[k].number;
        const double sx = SinDegrees(ang[0]), cx = CosDegrees(ang[0]), sy = SinDegrees(ang[1]), cy = CosDegrees(ang[1]),
                     sz = SinDegrees(ang[2]), cz = CosDegrees(ang[2]);
        const double r[3][3] = {{cy * cz, cz * sx * sy - cx * sz, cx * cz * sy + sx * sz},
                                {cy * sz, cx * cz + sx * sy * sz, -cz * sx + cx * sy * sz},
                                {-sy, cy * sx, cx * cy}};
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) m[i][j] = r[i][j];
      } else {
        if (!a.IsNumber()) throw NotNative{line, "rotate by a non-number"};
        double axis[3] = {0, 0, 1};
        if (given(args, "v") && !Vec3(args["v"], axis, 0)) throw NotNative{line, "rotate about a non-vector"};
        const double l = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        if (l == 0) {  // OpenSCAD leaves the children unrotated
          out.push_back({Matrix(m), Children(s, call)});
          return;
        }
        for (double& x : axis) x /= l;
        // Rodrigues' formula with OpenSCAD's exact degrees.
        const double c = CosDegrees(a.number), sn = SinDegrees(a.number), t = 1 - c;
        const double x = axis[0], y = axis[1], z = axis[2];
        const double r[3][3] = {{t * x * x + c, t * x * y - sn * z, t * x * z + sn * y},
                                {t * x * y + sn * z, t * y * y + c, t * y * z - sn * x},
                                {t * x * z - sn * y, t * y * z + sn * x, t * z * z + c}};
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) m[i][j] = r[i][j];
      }
      out.push_back({Matrix(m), Children(s, call)});
      return;
    }
    if (n == "multmatrix") {
      auto args = match({"m"});
      const Value& v = args["m"];
      if (!v.IsVector() || v.Items().size() < 3 || v.Items().size() > 4) throw NotNative{line, "multmatrix of a malformed matrix"};
      for (std::size_t r = 0; r < v.Items().size(); ++r) {
        const Value& row = v.Items()[r];
        if (!AllNumbers(row) || row.Items().size() != 4) throw NotNative{line, "multmatrix of a malformed matrix"};
        for (int c = 0; c < 4; ++c) m[r][c] = row.Items()[c].number;
      }
      out.push_back({Matrix(m), Children(s, call)});
      return;
    }
    if (n == "color") {
      auto args = match({"c", "alpha"});
      const Value& c = args["c"];
      double rgba[4] = {0, 0, 0, 1};
      if (c.kind == Value::Kind::kString) {
        if (!ColourByName(c.text, rgba)) throw NotNative{line, "colour '" + c.text + "'"};
      } else {
        if (!AllNumbers(c) || c.Items().size() < 3 || c.Items().size() > 4) throw NotNative{line, "colour malformed"};
        for (std::size_t k = 0; k < c.Items().size(); ++k) rgba[k] = c.Items()[k].number;
      }
      if (given(args, "alpha")) rgba[3] = number(args, "alpha", 1);
      out.push_back({"color([" + Num(rgba[0]) + ", " + Num(rgba[1]) + ", " + Num(rgba[2]) + ", " + Num(rgba[3]) + "])",
                     Children(s, call)});
      return;
    }
    if (n == "union" || n == "difference" || n == "intersection" || n == "hull" || n == "group") {
      match({});
      out.push_back({n + "()", Children(s, call)});
      return;
    }
    if (n == "offset") {
      auto args = match({"r", "delta", "chamfer"});
      std::string head;
      if (given(args, "r") && !given(args, "delta")) {
        head = "offset(r = " + Num(number(args, "r", 1));
      } else if (given(args, "delta") && !given(args, "r")) {
        head = "offset(delta = " + Num(number(args, "delta", 1)) + ", chamfer = " +
               (boolean(args, "chamfer") ? "true" : "false");
      } else {
        throw NotNative{line, "offset without exactly one of r and delta"};
      }
      out.push_back({head + ", " + Fragments(call) + ")", Children(s, call)});
      return;
    }
    if (n == "projection") {
      auto args = match({"cut", "convexity"});
      out.push_back({std::string("projection(cut = ") + (boolean(args, "cut") ? "true" : "false") +
                         ", convexity = " + Num(std::trunc(number(args, "convexity", 0))) + ")",
                     Children(s, call)});
      return;
    }
    if (n == "render") {
      auto args = match({"convexity"});
      out.push_back({"render(convexity = " + Num(std::trunc(number(args, "convexity", 1))) + ")", Children(s, call)});
      return;
    }
    if (n == "linear_extrude") {
      auto args = match({"height", "center", "convexity", "twist", "slices", "scale"});
      double height = std::max(number(args, "height", 100), 0.0);
      double convexity = std::trunc(number(args, "convexity", 0));
      if (convexity <= 0) convexity = 1;
      double scale[2] = {1, 1};
      if (given(args, "scale")) {
        const Value& v = args["scale"];
        if (v.IsNumber()) scale[0] = scale[1] = v.number;
        else if (!AllNumbers(v) || v.Items().size() != 2) throw NotNative{line, "linear_extrude scale malformed"};
        else scale[0] = v.Items()[0].number, scale[1] = v.Items()[1].number;
      }
      scale[0] = std::max(scale[0], 0.0);
      scale[1] = std::max(scale[1], 0.0);
      std::string head = "linear_extrude(height = " + Num(height) + ", center = " +
                         (boolean(args, "center") ? "true" : "false") + ", convexity = " + Num(convexity);
      const double twist = number(args, "twist", 0);
      if (twist != 0) head += ", twist = " + Num(twist);
      const bool has_slices = given(args, "slices");
      if (has_slices) head += ", slices = " + Num(std::max(std::trunc(number(args, "slices", 1)), 1.0));
      head += ", scale = [" + Num(scale[0]) + ", " + Num(scale[1]) + "]";
      if (!has_slices) head += ", " + Fragments(call);
      out.push_back({head + ")", Children(s, call)});
      return;
    }
    if (n == "rotate_extrude") {
      auto args = match({"angle", "convexity"});
      double angle = number(args, "angle", 360);
      if (angle <= -360 || angle > 360) angle = 360;
      double convexity = std::trunc(number(args, "convexity", 0));
      if (convexity <= 0) convexity = 2;
      out.push_back({"rotate_extrude(angle = " + Num(angle) + ", convexity = " + Num(convexity) + ", " +
                         Fragments(call) + ")",
                     Children(s, call)});
      return;
    }
    throw NotNative{line, "module " + n + "()"};
  }

  int depth_ = 0;
  long iterations_ = 0;
  long steps_ = 0;
  std::uintptr_t stack_base_;
};

}  // namespace

ModelEvaluation EvaluateModelText(const std::string& text, const std::string& file,
                                  const std::vector<std::pair<std::string, std::string>>& overrides) {
  const auto start = std::chrono::steady_clock::now();
  ModelEvaluation result;
  Value::values_built = 0;
  try {
    Parser parser(Lex(text));
    std::vector<StmtPtr> program = parser.Program();
    // -D name=value: the top-level assignment's value replaced (OpenSCAD
    // appends the assignment; the last value wins at the first's place), or
    // a new assignment at the end.
    for (const auto& [name, literal] : overrides) {
      ExprPtr value;
      try {
        value = Parser(Lex(literal)).OneExpression();
      } catch (NotNative& e) {
        e.line = 0;
        e.what = "the value of -D " + name + "=" + literal + ": " + e.what;
        throw;
      }
      bool replaced = false;
      for (StmtPtr& s : program) {
        if (s->kind != Stmt::Kind::kAssign || s->name != name) continue;
        auto copy = std::make_shared<Stmt>(*s);
        copy->expr = value;
        s = copy;
        replaced = true;
        break;
      }
      if (!replaced) {
        auto s = std::make_shared<Stmt>();
        s->kind = Stmt::Kind::kAssign;
        s->name = name;
        s->expr = value;
        program.push_back(s);
      }
    }
    Scope builtins;  // the special variables' defaults
    builtins.vars["$fn"] = Value::Number(0);
    builtins.vars["$fa"] = Value::Number(12);
    builtins.vars["$fs"] = Value::Number(2);
    builtins.vars["$t"] = Value::Number(0);
    builtins.vars["$preview"] = Value::Bool(false);
    builtins.vars["$children"] = Value::Number(0);
    builtins.vars["PI"] = Value::Number(std::numbers::pi);
    Scope top;
    top.lexical = top.dynamic = &builtins;
    std::vector<CsgOut> roots;
    Evaluator().Run(program, top, roots);
    for (const CsgOut& r : roots) Print(r, 0, result.csg);
    result.csg += "\n";  // OpenSCAD ends its export with an empty line
    result.evaluated = true;
  } catch (const NotNative& e) {
    result.csg.clear();
    result.declined = file + (e.line > 0 ? ":" + std::to_string(e.line) : std::string()) + ": " + e.what;
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

ModelEvaluation EvaluateModel(const std::filesystem::path& model,
                              const std::vector<std::pair<std::string, std::string>>& overrides) {
  const auto start = std::chrono::steady_clock::now();
  std::ifstream in(model, std::ios::binary);
  if (!in) {
    ModelEvaluation result;
    result.declined = model.string() + ": cannot be read";
    return result;
  }
  std::stringstream text;
  text << in.rdbuf();
  ModelEvaluation result = EvaluateModelText(text.str(), model.string(), overrides);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace fabatlas::scad

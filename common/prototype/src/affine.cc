#include "affine.h"

#include <cctype>

#include "fabatlas/error.h"

namespace fabatlas::prototype::internal {
namespace {

class Parser {
 public:
  Parser(const std::string& t, const std::function<Affine(const std::string&)>& r, const std::string& w)
      : text_(t), resolve_(r), where_(w) {}

  Affine Parse() {
    Affine f = Sum();
    Skip();
    if (pos_ != text_.size()) Fail("unexpected '" + text_.substr(pos_) + "'");
    return f;
  }

 private:
  [[noreturn]] void Fail(const std::string& m) { throw InputError(where_ + ": expression '" + text_ + "': " + m); }
  void Skip() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool Eat(char c) {
    Skip();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  Affine Sum() {
    Affine f = Product();
    while (true) {
      if (Eat('+'))
        f = f + Product();
      else if (Eat('-'))
        f = f - Product();
      else
        return f;
    }
  }
  Affine Product() {
    Affine f = Factor();
    while (true) {
      if (Eat('*')) {
        Affine g = Factor();
        if (f.IsConst())
          f = f.c * g;
        else if (g.IsConst())
          f = g.c * f;
        else
          Fail("a product of two coordinates is not linear");
      } else if (Eat('/')) {
        Affine g = Factor();
        if (!g.IsConst() || g.c == 0) Fail("division by a coordinate or by zero");
        f = (1.0 / g.c) * f;
      } else {
        return f;
      }
    }
  }
  Affine Factor() {
    Skip();
    if (Eat('-')) return (-1.0) * Factor();
    if (Eat('(')) {
      Affine f = Sum();
      if (!Eat(')')) Fail("missing ')'");
      return f;
    }
    if (pos_ >= text_.size()) Fail("unexpected end");
    char c = text_[pos_];
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      std::size_t used = 0;
      double v = std::stod(text_.substr(pos_), &used);
      pos_ += used;
      if (!std::isfinite(v)) Fail("not a finite number");
      return Affine::Const(v);
    }
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      std::size_t start = pos_;
      while (pos_ < text_.size() &&
             (std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_' || text_[pos_] == '.'))
        ++pos_;
      return resolve_(text_.substr(start, pos_ - start));
    }
    Fail(std::string("unexpected '") + c + "'");
  }

  const std::string& text_;
  const std::function<Affine(const std::string&)>& resolve_;
  const std::string& where_;
  std::size_t pos_ = 0;
};

}  // namespace

Affine ParseAffine(const std::string& text, const std::function<Affine(const std::string&)>& resolve,
                   const std::string& where) {
  return Parser(text, resolve, where).Parse();
}

}  // namespace fabatlas::prototype::internal

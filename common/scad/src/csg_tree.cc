// Parsing OpenSCAD's .csg export and running OpenSCAD (fabatlas/scad/csg_tree.h).
#include "fabatlas/scad/csg_tree.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>

#include "fabatlas/error.h"
#include "fabatlas/scad/customizer.h"
#include "fabatlas/scad/source_text.h"

extern char** environ;

namespace fabatlas::scad {
namespace {

class Parser {
 public:
  Parser(const std::string& s, const std::string& file) : s_(s), file_(file) {}

  CsgNode Root() {
    CsgNode root;
    root.name = "group";
    Skip();
    while (i_ < s_.size()) {
      CsgNode node = Node();
      if (!dropped_) root.children.push_back(std::move(node));
      Skip();
    }
    Finish(root);
    return root;
  }

 private:
  [[noreturn]] void Fail(const std::string& what) {
    throw InputError(file_ + ":" + std::to_string(line_) + ": " + what);
  }

  void Skip() {
    SourcePosition p{i_, line_};
    SkipBlank(s_, p);
    i_ = p.at;
    line_ = p.line;
  }

  bool Eat(char c) {
    Skip();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }

  void Expect(char c) {
    if (!Eat(c)) Fail(std::string("expected '") + c + "'");
  }

  std::string Ident() {
    Skip();
    std::size_t b = i_;
    while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) || s_[i_] == '_' || s_[i_] == '$')) ++i_;
    if (b == i_) Fail("expected a name");
    return s_.substr(b, i_ - b);
  }

  CsgValue Value() {
    Skip();
    CsgValue v;
    if (i_ >= s_.size()) Fail("unexpected end of file");
    char c = s_[i_];
    if (c == '[') {
      ++i_;
      v.type = CsgValue::Type::kVector;
      if (Eat(']')) return v;
      do {
        v.items.push_back(Value());
      } while (Eat(','));
      Expect(']');
      return v;
    }
    if (c == '"') {
      SourcePosition p{i_, line_};
      bool terminated = false;
      v.type = CsgValue::Type::kString;
      v.text = ReadStringLiteral(s_, p, terminated);
      i_ = p.at;
      line_ = p.line;
      if (!terminated) Fail("unterminated string");
      return v;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '-' || c == '+' || c == '.') {
      const char* start = s_.c_str() + i_;
      char* end = nullptr;
      v.number = std::strtod(start, &end);
      if (end == start) Fail("expected a number");
      i_ += static_cast<std::size_t>(end - start);
      v.type = CsgValue::Type::kNumber;
      return v;
    }
    std::string word = Ident();
    if (word == "true" || word == "false") {
      v.type = CsgValue::Type::kBoolean;
      v.boolean = word == "true";
    } else if (word == "undef") {
      v.type = CsgValue::Type::kUndef;
    } else if (word == "inf" || word == "nan") {
      v.type = CsgValue::Type::kNumber;
      v.number = word == "inf" ? HUGE_VAL : NAN;
    } else {
      Fail("unexpected '" + word + "' in an argument");
    }
    return v;
  }

  CsgNode Node() {
    Skip();
    CsgNode n;
    n.line = line_;
    // Modifiers (! # % *) may prefix a node; the .csg export keeps '%'
    // (background) nodes, which OpenSCAD does not render: the parent drops
    // them (dropped_).
    dropped_ = false;
    while (i_ < s_.size() && std::strchr("!#%*", s_[i_])) {
      if (s_[i_] == '%' || s_[i_] == '*') dropped_ = true;
      ++i_;
    }
    const bool dropped = dropped_;
    n.name = Ident();
    Expect('(');
    if (!Eat(')')) {
      do {
        Skip();
        std::size_t save = i_;
        int save_line = line_;
        bool named = false;
        if (i_ < s_.size() && (std::isalpha(static_cast<unsigned char>(s_[i_])) || s_[i_] == '$' || s_[i_] == '_')) {
          std::string key = Ident();
          if (Eat('=')) {
            n.args[key] = Value();
            named = true;
          } else {
            i_ = save;
            line_ = save_line;
          }
        }
        if (!named) n.positional.push_back(Value());
      } while (Eat(','));
      Expect(')');
    }
    if (Eat(';')) {
      dropped_ = dropped;
      return n;
    }
    Expect('{');
    while (!Eat('}')) {
      if (i_ >= s_.size()) Fail("missing '}' of " + n.name);
      CsgNode child = Node();
      if (!dropped_) n.children.push_back(std::move(child));
    }
    dropped_ = dropped;
    return n;
  }

  bool dropped_ = false;  // the node just parsed had a '%' or '*' modifier
  const std::string& s_;
  std::string file_;
  std::size_t i_ = 0;
  int line_ = 1;

 public:
  static std::string Canonical(const CsgValue& v) {
    switch (v.type) {
      case CsgValue::Type::kUndef:
        return "undef";
      case CsgValue::Type::kNumber:
        return FormatScadNumber(v.number);
      case CsgValue::Type::kString:
        return QuoteScadString(v.text);
      case CsgValue::Type::kBoolean:
        return v.boolean ? "true" : "false";
      case CsgValue::Type::kVector: {
        std::string out = "[";
        for (std::size_t k = 0; k < v.items.size(); ++k) out += (k ? "," : "") + Canonical(v.items[k]);
        return out + "]";
      }
    }
    return "undef";
  }

  static void Finish(CsgNode& n) {
    std::string out = n.name + "(";
    bool first = true;
    for (const auto& v : n.positional) {
      out += (first ? "" : ",") + Canonical(v);
      first = false;
    }
    for (const auto& [k, v] : n.args) {
      out += (first ? "" : ",") + k + "=" + Canonical(v);
      first = false;
    }
    out += ")";
    if (n.children.empty()) {
      out += ";";
    } else {
      out += "{";
      for (auto& c : n.children) {
        Finish(c);
        out += c.canonical;
      }
      out += "}";
    }
    n.canonical = std::move(out);
  }
};

}  // namespace

double CsgNode::Number(const std::string& key, double fallback) const {
  auto it = args.find(key);
  return it == args.end() || it->second.type != CsgValue::Type::kNumber ? fallback : it->second.number;
}

bool CsgNode::Boolean(const std::string& key, bool fallback) const {
  auto it = args.find(key);
  return it == args.end() || it->second.type != CsgValue::Type::kBoolean ? fallback : it->second.boolean;
}

CsgNode ParseCsg(const std::string& text, const std::string& file) { return Parser(text, file).Root(); }

bool RunOpenScad(const std::filesystem::path& model, const std::filesystem::path& out,
                 const std::vector<std::pair<std::string, std::string>>& overrides, OpenScadRun* run) {
  const auto start = std::chrono::steady_clock::now();
  const std::filesystem::path log = out.string() + ".log";
  std::vector<std::string> argv = {"timeout", "300", "openscad", "--quiet", "-o", out.string()};
  for (const auto& [name, literal] : overrides) {
    argv.push_back("-D");
    argv.push_back(name + "=" + literal);
  }
  argv.push_back(model.string());
  // posix_spawn, not fork: samples are evaluated on many threads, and only
  // async-signal-safe calls may follow a fork there.
  std::vector<char*> args;
  for (auto& s : argv) args.push_back(s.data());
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  pid_t pid = 0;
  int spawned = posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw InputError(model.string() + ": cannot start openscad: " + std::strerror(spawned));
  int status = 0;
  waitpid(pid, &status, 0);
  int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
  if (code == 127)
    throw InputError(model.string() + ": the openscad program is not installed (apt-get install openscad)");
  std::string last;
  {
    std::ifstream in(log);
    std::string line;
    while (std::getline(in, line))
      if (!line.empty()) last = line;
  }
  std::filesystem::remove(log);
  if (run) {
    run->log_tail = code == 124 ? "openscad took longer than 300 s" : last;
    run->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  std::error_code ec;
  return code == 0 && std::filesystem::exists(out, ec);
}

}  // namespace fabatlas::scad

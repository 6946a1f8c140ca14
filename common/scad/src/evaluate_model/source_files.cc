// A model's .scad files with their includes and uses (source_files.h).
#include "source_files.h"

#include <cstdlib>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <tuple>
#include <utility>

#include "fabatlas/scad/source_text.h"
#include "parser.h"

namespace fabatlas::scad::internal {
namespace {

namespace fs = std::filesystem;

bool NameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '$';
}

// `include <name>` or `use <name>` at `begin` (OpenSCAD's lexer: the word,
// then blanks or '>', then '<', the name up to '>' without tabs or line
// breaks): its end (just after '>') and name; 0 when there is none here.
std::size_t DirectiveAt(const std::string& text, std::size_t begin, const std::string& word, std::string& name,
                        int line) {
  if (text.compare(begin, word.size(), word) != 0 || (begin > 0 && NameChar(text[begin - 1]))) return 0;
  std::size_t at = begin + word.size();
  while (at < text.size() &&
         (text[at] == ' ' || text[at] == '\t' || text[at] == '\r' || text[at] == '\n' || text[at] == '>'))
    ++at;
  if (at >= text.size() || text[at] != '<') return 0;
  const std::size_t open = ++at;
  while (at < text.size() && text[at] != '>' && text[at] != '\t' && text[at] != '\r' && text[at] != '\n') ++at;
  if (at >= text.size() || text[at] != '>')
    throw NotNative{line, word + " <" + text.substr(open, at - open) + " without '>'"};
  name = text.substr(open, at - open);
  return at + 1;
}

// The tokens of a .scad file's text: the text between directives lexed as
// any (lex_source.h), each directive the symbol "include" or "use" and its
// name as a string.
std::vector<Token> LexFile(const std::string& text) {
  std::vector<Token> out;
  SourcePosition p;
  std::size_t segment = 0;  // the start of the text not yet lexed
  int segment_line = 1;
  auto lex = [&](std::size_t end) {
    std::vector<Token> tokens;
    try {
      tokens = Lex(text.substr(segment, end - segment));
    } catch (NotNative& e) {
      if (e.line > 0) e.line += segment_line - 1;
      throw;
    }
    tokens.pop_back();  // kEnd
    for (Token& t : tokens) {
      t.line += segment_line - 1;
      out.push_back(std::move(t));
    }
  };
  while (p.at < text.size()) {
    if (text[p.at] == '"') {
      bool terminated = false;
      ReadStringLiteral(text, p, terminated);
      continue;
    }
    if (SkipComment(text, p)) continue;
    bool matched = false;
    for (const char* word : {"include", "use"}) {
      std::string name;
      const std::size_t end = DirectiveAt(text, p.at, word, name, p.line);
      if (end == 0) continue;
      lex(p.at);
      out.push_back(Token{Tok::kSymbol, word, 0, p.line});
      out.push_back(Token{Tok::kString, name, 0, p.line});
      for (; p.at < end; ++p.at) p.line += text[p.at] == '\n';
      segment = end;
      segment_line = p.line;
      matched = true;
      break;
    }
    if (matched) continue;
    if (text[p.at] == '\n') ++p.line;
    ++p.at;
  }
  lex(text.size());
  out.push_back(Token{Tok::kEnd, "", 0, p.line});
  return out;
}

// The library directories after the naming file's own: OPENSCADPATH's,
// OpenSCAD's user library directory and Debian's installed one.
std::vector<fs::path> LibraryDirectories() {
  std::vector<fs::path> dirs;
  if (const char* path = std::getenv("OPENSCADPATH")) {
    std::stringstream list(path);
    std::string d;
    while (std::getline(list, d, ':'))
      if (!d.empty()) {
        std::error_code ec;
        dirs.push_back(fs::absolute(d, ec));
      }
  }
  if (const char* home = std::getenv("HOME")) dirs.push_back(fs::path(home) / ".local/share/OpenSCAD/libraries");
  dirs.push_back("/usr/share/openscad/libraries");
  return dirs;
}

bool IsFile(const fs::path& p) {
  std::error_code ec;
  return fs::exists(p, ec) && !fs::is_directory(p, ec);
}

// The files being included, outermost first, on this thread (cycles).
thread_local std::vector<std::string> including;

struct Parsed {
  std::shared_ptr<const SourceFile> file;
  bool cycle = false;  // an include was skipped as a cycle: depends on who includes it, not cached
};

Parsed Parse(const std::string& text, const std::string& path);

// The file at `path`, read and parsed; cached per process unless its parse
// met a cycle. Declines naming the file when it cannot be read.
Parsed Load(const fs::path& path) {
  static std::mutex mutex;
  static std::map<std::tuple<std::string, std::uintmax_t, fs::file_time_type>, std::shared_ptr<const SourceFile>> cache;
  std::error_code ec;
  const std::string key_path = fs::absolute(path, ec).lexically_normal().string();
  const auto key = std::make_tuple(key_path, fs::file_size(path, ec), fs::last_write_time(path, ec));
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = cache.find(key); it != cache.end()) return {it->second, false};
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw NotNative{0, "cannot be read", path.string()};
  std::stringstream text;
  text << in.rdbuf();
  Parsed parsed = Parse(text.str(), path.string());
  if (!parsed.cycle) {
    std::lock_guard<std::mutex> lock(mutex);
    cache.emplace(key, parsed.file);
  }
  return parsed;
}

Parsed Parse(const std::string& text, const std::string& path) {
  auto file = std::make_shared<SourceFile>();
  file->path = path;
  std::error_code ec;
  const fs::path dir = fs::absolute(fs::path(path), ec).parent_path();
  bool cycle = false;
  std::set<std::string> used;
  auto directive = [&](bool include, const std::string& name, int line, std::vector<StmtPtr>& out) {
    const std::string where = path + ":" + std::to_string(line) + ": " + (include ? "include <" : "use <") + name + ">";
    const fs::path found = FindSourceFile(dir, name);
    if (found.empty()) {
      file->warnings.push_back(where + ": not found (beside " + path +
                               ", in OPENSCADPATH or OpenSCAD's library directories); skipped, as OpenSCAD does");
      return;
    }
    // The file as OpenSCAD names it once found: links resolved, so a file
    // included through a link to its own directory is the same file (a
    // cycle), and what it includes is found beside the link's target.
    std::error_code unresolved;
    const fs::path real = fs::weakly_canonical(found, unresolved);
    const std::string normal = unresolved ? found.lexically_normal().string() : real.string();
    if (!include) {
      if (used.insert(normal).second) file->uses.push_back(normal);
      return;
    }
    for (const std::string& open : including)
      if (open == normal) {
        file->warnings.push_back(where + ": includes a file already being included; skipped, as OpenSCAD does");
        cycle = true;
        return;
      }
    // A chain of distinct files: bounded, as the evaluator bounds recursion.
    if (including.size() >= 64) throw NotNative{line, "includes nested more than 64 files deep"};
    including.push_back(normal);
    Parsed inner;
    try {
      inner = Load(normal);
    } catch (...) {
      including.pop_back();
      throw;
    }
    including.pop_back();
    cycle = cycle || inner.cycle;
    out.insert(out.end(), inner.file->statements.begin(), inner.file->statements.end());
    for (const std::string& u : inner.file->uses)
      if (used.insert(u).second) file->uses.push_back(u);
    file->warnings.insert(file->warnings.end(), inner.file->warnings.begin(), inner.file->warnings.end());
  };
  auto name = std::make_shared<const std::string>(path);
  try {
    Parser parser(LexFile(text), directive, name);
    file->statements = parser.Program();
  } catch (NotNative& e) {
    if (e.file.empty()) e.file = path;
    throw;
  }
  for (const StmtPtr& s : file->statements) {
    if (s->kind == Stmt::Kind::kModuleDef) file->modules[s->name] = s->module;
    if (s->kind == Stmt::Kind::kFunctionDef) file->functions[s->name] = s->function;
  }
  return {file, cycle};
}

}  // namespace

fs::path FindSourceFile(const fs::path& dir, const std::string& name) {
  if (name.empty()) return {};
  const fs::path named(name);
  if (named.is_absolute()) return IsFile(named) ? named.lexically_normal() : fs::path();
  if (IsFile(dir / named)) return (dir / named).lexically_normal();
  for (const fs::path& d : LibraryDirectories())  // this process's OPENSCADPATH now, as OpenSCAD reads it at its start
    if (IsFile(d / named)) return (d / named).lexically_normal();
  return {};
}

std::shared_ptr<const SourceFile> ParseModel(const std::string& text, const std::string& file) {
  including.clear();  // OpenSCAD lets a file include itself once: the model is not among the files being included
  try {
    Parsed parsed = Parse(text, file);
    including.clear();
    return parsed.file;
  } catch (NotNative& e) {
    including.clear();
    if (e.file == file) e.file.clear();  // the model itself
    throw;
  }
}

std::shared_ptr<const SourceFile> UsedFile(const std::string& path) {
  const std::vector<std::string> outer = std::move(including);
  including.clear();
  try {
    Parsed parsed = Load(path);
    including = outer;
    return parsed.file;
  } catch (...) {
    including = outer;
    throw;
  }
}

}  // namespace fabatlas::scad::internal

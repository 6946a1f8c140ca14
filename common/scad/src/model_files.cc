// The files an OpenSCAD model reads besides itself (fabatlas/scad/model_files.h).
#include "fabatlas/scad/model_files.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/scad/source_text.h"

namespace fabatlas::scad {
namespace {

namespace fs = std::filesystem;

// The text without comments (strings kept: file names are strings; a
// comment's line breaks kept, so offsets map to the same lines).
std::string WithoutComments(const std::string& t) {
  std::string out;
  out.reserve(t.size());
  SourcePosition p;
  while (p.at < t.size()) {
    const std::size_t start = p.at;
    const int line = p.line;
    if (t[start] == '"') {
      bool terminated = false;
      ReadStringLiteral(t, p, terminated);
      out.append(t, start, p.at - start);
    } else if (SkipComment(t, p)) {
      if (t[start + 1] == '*') out += ' ';
      out.append(static_cast<std::size_t>(p.line - line), '\n');
    } else {
      out += t[p.at++];
    }
  }
  return out;
}

bool Escapes(const fs::path& relative) {
  for (const auto& part : relative)
    if (part == "..") return true;
  return relative.is_absolute();
}

// Whether `path`, with every link resolved, lies inside directory `root`.
bool ResolvesInside(const fs::path& path, const fs::path& root) {
  std::error_code ec;
  const fs::path real = fs::canonical(path, ec);
  const fs::path real_root = fs::canonical(root, ec);
  if (real.empty() || real_root.empty()) return false;
  const fs::path rel = real.lexically_relative(real_root);
  return !rel.empty() && !Escapes(rel);
}

struct Scan {
  std::vector<fs::path> search;  // OPENSCADPATH directories
  std::vector<ModelFile> found;
  std::set<fs::path> seen;

  // `file` sits at `relative_dir` within `root`: the model's directory, or
  // the OPENSCADPATH directory a library was found in.
  void Visit(const fs::path& file, const fs::path& relative_dir, const fs::path& root) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(file.string() + ": cannot read");
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = WithoutComments(ss.str());
    static const std::regex library(R"((?:^|[^A-Za-z0-9_$])(include|use)\s*<([^>]+)>)");
    static const std::regex data(R"((?:^|[^A-Za-z0-9_$])(import|surface)\s*\(\s*(?:file\s*=\s*)?"([^"]+)\")");
    for (const auto* pattern : {&library, &data})
      for (auto it = std::sregex_iterator(text.begin(), text.end(), *pattern); it != std::sregex_iterator(); ++it) {
        const auto& m = *it;
        const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + m.position(2), '\n'));
        Add({file, line, m[1].str(), m[2].str()}, relative_dir, root, pattern == &library);
      }
  }

  // Where a file is named: the naming file, its line, the statement and the name.
  struct Named {
    fs::path file;
    int line;
    std::string statement, name;
  };

  [[noreturn]] static void Refuse(const Named& n, const std::string& why) {
    const std::string shown = n.statement == "include" || n.statement == "use" ? n.statement + " <" + n.name + ">"
                                                                               : n.statement + "(\"" + n.name + "\")";
    throw InputError(n.file.string() + ":" + std::to_string(n.line) + ": " + shown + " " + why +
                     "; a job bundle carries only the files inside the model's directory, which is all a worker "
                     "reads");
  }

  void Add(const Named& n, const fs::path& relative_dir, const fs::path& root, bool library) {
    const fs::path named = fs::path(n.name).lexically_normal();
    if (named.empty()) return;
    if (named.is_absolute()) Refuse(n, "names an absolute path");
    const fs::path relative = (relative_dir / named).lexically_normal();
    if (Escapes(relative)) Refuse(n, "leaves the model's directory");
    const fs::path dir = n.file.parent_path();
    std::vector<std::pair<fs::path, fs::path>> candidates = {{dir / named, root}};  // {file, its root}
    if (library)  // libraries are also looked up in OPENSCADPATH
      for (const auto& d : search) candidates.push_back({d / named, d});
    std::error_code ec;
    for (const auto& [c, c_root] : candidates) {
      if (!fs::is_regular_file(c, ec)) continue;
      if (!ResolvesInside(c, c_root))
        Refuse(n, "is a link to " + fs::canonical(c, ec).string() + ", outside " + c_root.string());
      if (!seen.insert(relative).second) return;
      found.push_back({relative, c});
      if (library && c.extension() == ".scad") Visit(c, relative.parent_path(), c == dir / named ? root : c_root);
      return;
    }
  }
};

}  // namespace

std::vector<ModelFile> ModelFiles(const fs::path& model, const std::string& openscadpath) {
  Scan scan;
  std::stringstream dirs(openscadpath);
  std::string d;
  while (std::getline(dirs, d, ':'))
    if (!d.empty()) scan.search.push_back(d);
  scan.seen.insert(model.filename());
  scan.Visit(model, fs::path(), model.has_parent_path() ? model.parent_path() : fs::path("."));
  return scan.found;
}

std::vector<ModelFile> ModelFiles(const fs::path& model) {
  const char* env = std::getenv("OPENSCADPATH");
  return ModelFiles(model, env ? env : "");
}

}  // namespace fabatlas::scad

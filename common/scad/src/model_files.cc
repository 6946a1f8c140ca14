// The files an OpenSCAD model reads besides itself (fabatlas/scad/model_files.h).
#include "fabatlas/scad/model_files.h"

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

// The text without comments (strings kept: file names are strings).
std::string WithoutComments(const std::string& t) {
  std::string out;
  out.reserve(t.size());
  SourcePosition p;
  while (p.at < t.size()) {
    const std::size_t start = p.at;
    if (t[start] == '"') {
      bool terminated = false;
      ReadStringLiteral(t, p, terminated);
      out.append(t, start, p.at - start);
    } else if (SkipComment(t, p)) {
      if (t[start + 1] == '*') out += ' ';
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

struct Scan {
  std::vector<fs::path> search;  // OPENSCADPATH directories
  std::vector<ModelFile> found;
  std::set<fs::path> seen;

  // `file` sits at `relative_dir` within the model's directory.
  void Visit(const fs::path& file, const fs::path& relative_dir) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(file.string() + ": cannot read");
    std::stringstream ss;
    ss << in.rdbuf();
    const std::string text = WithoutComments(ss.str());
    static const std::regex library(R"((?:^|[^A-Za-z0-9_$])(?:include|use)\s*<([^>]+)>)");
    static const std::regex data(R"((?:^|[^A-Za-z0-9_$])(?:import|surface)\s*\(\s*(?:file\s*=\s*)?"([^"]+)\")");
    for (auto it = std::sregex_iterator(text.begin(), text.end(), library); it != std::sregex_iterator(); ++it)
      Add((*it)[1].str(), file.parent_path(), relative_dir, true);
    for (auto it = std::sregex_iterator(text.begin(), text.end(), data); it != std::sregex_iterator(); ++it)
      Add((*it)[1].str(), file.parent_path(), relative_dir, false);
  }

  void Add(const std::string& name, const fs::path& dir, const fs::path& relative_dir, bool library) {
    const fs::path named = fs::path(name).lexically_normal();
    const fs::path relative = (relative_dir / named).lexically_normal();
    if (named.empty() || Escapes(relative)) return;
    std::vector<fs::path> candidates = {dir / named};
    if (library)  // libraries are also looked up in OPENSCADPATH
      for (const auto& d : search) candidates.push_back(d / named);
    std::error_code ec;
    for (const auto& c : candidates) {
      if (!fs::is_regular_file(c, ec)) continue;
      if (!seen.insert(relative).second) return;
      found.push_back({relative, c});
      if (library && c.extension() == ".scad") Visit(c, relative.parent_path());
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
  scan.Visit(model, fs::path());
  return scan.found;
}

std::vector<ModelFile> ModelFiles(const fs::path& model) {
  const char* env = std::getenv("OPENSCADPATH");
  return ModelFiles(model, env ? env : "");
}

}  // namespace fabatlas::scad

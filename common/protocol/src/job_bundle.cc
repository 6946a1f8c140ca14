// Job bundles (see job_bundle.h).
#include "fabatlas/protocol/job_bundle.h"

#include <fstream>
#include <algorithm>
#include <functional>
#include <sstream>
#include <vector>

#include "fabatlas/design/data_files.h"
#include "fabatlas/design/design.h"
#include "fabatlas/error.h"
#include "fabatlas/protocol/canonical_bytes.h"
#include "fabatlas/write_file_atomically.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/sha256.h"

namespace fabatlas::protocol {

namespace fs = std::filesystem;

namespace {

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot read");
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

// Whole or not at all (a full cache directory leaves no partial file that a
// later lease would read), one line naming the file and the reason.
void WriteFile(const fs::path& path, const std::string& bytes) {
  std::error_code ec;
  fs::create_directories(path.parent_path(), ec);
  if (ec) throw ResourceError(path.parent_path().string() + ": cannot create the directory: " + ec.message());
  WriteFileAtomically(path, bytes);
}

bool StaysInside(const fs::path& relative) {
  if (relative.empty() || relative.is_absolute()) return false;
  for (const auto& part : relative)
    if (part == "..") return false;
  return true;
}

}  // namespace

v1::JobBundle MakeJobBundle(const fs::path& job_file) {
  std::string job_text = ReadFile(job_file);
  sampling::JobFile job = sampling::ParseJobFile(job_text, job_file.string());
  fs::path design_path = job.design_path;
  design::Design design = design::LoadDesign(design_path);
  // Files named by node arguments (meshes, OpenSCAD models, prototype and
  // assembly programs) of the tree and of every object's tree, relative to
  // the design file. A file up to kMaxParentLevels directories above the
  // design (e.g. ../prototypes/x.yaml) is bundled too: the design is then
  // stored under as many of its own parent directories (designs/x.yaml), so
  // the relative reference resolves in the materialized bundle as it did here.
  constexpr int kMaxParentLevels = 2;
  // Files the nodes need without naming them (an assembly's part library
  // and meshes, design/data_files.h) come along too, read from where this
  // machine has them.
  // (A design named without a directory part, e.g. "pawn.yaml", is in ".".)
  const fs::path base = design_path.has_parent_path() ? design_path.parent_path() : fs::path(".");
  std::vector<design::DataFile> referenced;  // relative to the design; where to read it
  std::function<void(const design::Argument&)> visit_argument = [&](const design::Argument& a) {
    if (a.kind == design::Argument::Kind::kScalar) {
      const fs::path rel = fs::path(a.text).lexically_normal();
      std::error_code ec;
      if (!rel.empty() && rel.is_relative() && rel.has_extension() && fs::is_regular_file(base / rel, ec))
        referenced.push_back({rel, base / rel});
    }
    for (const auto& item : a.items) visit_argument(item);
  };
  std::function<void(const design::Node&)> visit = [&](const design::Node& node) {
    for (const auto& [name, arg] : node.args) visit_argument(arg);
    for (auto& file : design::IndirectDataFiles(node, base)) referenced.push_back(std::move(file));
    for (const auto& child : node.children) visit(child);
  };
  visit(design.tree);
  for (const auto& object : design.objects) visit(object.tree);
  int levels = 0;  // how many parent directories the references climb
  for (const auto& file : referenced) {
    int up = 0;
    for (const auto& part : file.relative) {
      if (part != "..") break;
      ++up;
    }
    if (up <= kMaxParentLevels) levels = std::max(levels, up);
  }
  fs::path prefix;  // the design's directory relative to the bundle's root
  {
    const fs::path dir = fs::absolute(base).lexically_normal();
    std::vector<fs::path> parts;
    for (const auto& part : dir.relative_path()) parts.push_back(part);
    levels = std::min<int>(levels, static_cast<int>(parts.size()));
    for (std::size_t i = parts.size() - static_cast<std::size_t>(levels); i < parts.size(); ++i) prefix /= parts[i];
  }

  v1::JobBundle bundle;
  bundle.set_job_file_name(job_file.filename().string());
  bundle.set_job_file(job_text);
  bundle.set_design_file_name((prefix / design_path.filename()).generic_string());
  bundle.set_design_file(ReadFile(design_path));
  for (const auto& file : referenced) {
    const fs::path name = (prefix / file.relative).lexically_normal();
    if (StaysInside(name)) (*bundle.mutable_files())[name.generic_string()] = ReadFile(file.source);
  }
  return bundle;
}

std::string BundleBytes(const v1::JobBundle& bundle) { return CanonicalBytes(bundle); }

std::string EvaluationDigest(const v1::JobBundle& bundle) {
  v1::JobBundle evaluation;
  evaluation.set_design_file_name(bundle.design_file_name());
  evaluation.set_design_file(bundle.design_file());
  *evaluation.mutable_files() = bundle.files();
  return Sha256Hex(BundleBytes(evaluation));
}

MaterializedBundle Materialize(const v1::JobBundle& bundle, const fs::path& dir) {
  auto check = [](const std::string& name) {
    if (!StaysInside(fs::path(name))) throw InputError("job bundle: file name '" + name + "' leaves the job directory");
  };
  check(bundle.job_file_name());
  check(bundle.design_file_name());
  MaterializedBundle m;
  m.job_file = dir / "job" / bundle.job_file_name();
  m.design_file = dir / "design" / bundle.design_file_name();
  WriteFile(m.job_file, bundle.job_file());
  WriteFile(m.design_file, bundle.design_file());
  for (const auto& [name, bytes] : bundle.files()) {
    check(name);
    WriteFile(dir / "design" / name, bytes);
  }
  return m;
}

}  // namespace fabatlas::protocol

#include "fabatlas/sampling/job_file.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "fabatlas/error.h"
#include "fabatlas/yaml_place.h"

namespace fabatlas::sampling {

namespace {

[[noreturn]] void Fail(const std::string& path, const YAML::Mark& mark, const std::string& msg) {
  FailAt(YamlPlace(path, mark), msg);
}

std::string Scalar(const std::string& path, const YAML::Node& node, const std::string& what) {
  if (!node.IsScalar()) Fail(path, node.Mark(), what + " must be a scalar");
  return node.Scalar();
}

long long Integer(const std::string& path, const YAML::Node& node, const std::string& what, long long lo,
                  long long hi) {
  const std::string s = Scalar(path, node, what);
  size_t used = 0;
  long long v = 0;
  try {
    v = std::stoll(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != s.size()) Fail(path, node.Mark(), what + " must be an integer, got '" + s + "'");
  if (v < lo || v > hi)
    Fail(path, node.Mark(), what + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + s);
  return v;
}

double Real(const std::string& path, const YAML::Node& node, const std::string& what, double lo, double hi) {
  const std::string s = Scalar(path, node, what);
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(s, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != s.size() || !std::isfinite(v))
    Fail(path, node.Mark(), what + " must be a number, got '" + s + "'");
  if (v < lo || v > hi)
    Fail(path, node.Mark(), what + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + s);
  return v;
}

// The 'sampling' mapping into job.
void ReadSampling(const std::string& path, const YAML::Node& value, JobFile& job) {
  if (!value.IsMap()) Fail(path, value.Mark(), "sampling must be a mapping");
  for (const auto& s : value) {
    const std::string skey = s.first.as<std::string>();
    const YAML::Node& sv = s.second;
    if (skey == "subdivisions")
      job.subdivisions = static_cast<int>(Integer(path, sv, "sampling.subdivisions", 1, 1000));
    else if (skey == "max_depth")
      job.sampling.max_depth = static_cast<int>(Integer(path, sv, "sampling.max_depth", 0, 4 * kDyadicBits));
    else if (skey == "dg_threshold")
      job.sampling.dg_threshold = Real(path, sv, "sampling.dg_threshold", 0.0, 1.0);
    else if (skey == "max_samples")
      job.sampling.max_samples = Integer(path, sv, "sampling.max_samples", 1, 1000000000000LL);
    else
      Fail(path, s.first.Mark(),
           "unknown key 'sampling." + skey + "' (expected subdivisions, max_depth, dg_threshold, max_samples)");
  }
}

// One entry m of the 'materials' list, a new name among job.materials.
Material ReadMaterial(const std::string& path, const YAML::Node& m, const JobFile& job) {
  if (!m.IsMap()) Fail(path, m.Mark(), "a material must be a mapping {name, density, price_per_kg}");
  Material material;
  bool have_name = false, have_density = false;
  for (const auto& f : m) {
    const std::string fkey = f.first.as<std::string>();
    if (fkey == "name") {
      material.name = Scalar(path, f.second, "materials.name");
      have_name = !material.name.empty();
    } else if (fkey == "density") {
      material.density_g_per_cm3 = Real(path, f.second, "materials.density", 1e-6, 1e6);
      have_density = true;
    } else if (fkey == "price_per_kg") {
      material.price_per_kg = Real(path, f.second, "materials.price_per_kg", 0.0, 1e12);
    } else {
      Fail(path, f.first.Mark(), "unknown key 'materials." + fkey + "' (expected name, density, price_per_kg)");
    }
  }
  if (!have_name) Fail(path, m.Mark(), "a material needs a non-empty name");
  if (!have_density) Fail(path, m.Mark(), "material '" + material.name + "' needs a density (g/cm^3)");
  for (const Material& other : job.materials)
    if (other.name == material.name) Fail(path, m.Mark(), "duplicate material '" + material.name + "'");
  return material;
}

}  // namespace

JobFile ParseJobFile(const std::string& yaml_text, const std::string& path) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    Fail(path, e.mark, e.msg);
  }
  if (!root.IsMap()) Fail(path, root.Mark(), "a job file must be a mapping with at least 'design'");
  JobFile job;
  job.path = path;
  bool have_design = false;
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    const YAML::Node& value = entry.second;
    if (key == "design") {
      const std::string design = Scalar(path, value, "design");
      if (design.empty()) Fail(path, value.Mark(), "design must name a design file");
      const std::filesystem::path p(design);
      job.design_path = p.is_absolute() ? p.lexically_normal().string()
                                        : (std::filesystem::path(path).parent_path() / p).lexically_normal().string();
      have_design = true;
    } else if (key == "sampling") {
      ReadSampling(path, value, job);
    } else if (key == "form_json") {
      const std::string v = Scalar(path, value, "form_json");
      if (v == "true")
        job.form_json = true;
      else if (v == "false")
        job.form_json = false;
      else if (v != "auto")
        Fail(path, value.Mark(), "form_json must be true, false or auto, got '" + v + "'");
    } else if (key == "threads") {
      job.threads = static_cast<int>(Integer(path, value, "threads", 1, 4096));
    } else if (key == "materials") {
      if (!value.IsSequence()) Fail(path, value.Mark(), "materials must be a list of {name, density, price_per_kg}");
      for (const auto& m : value) job.materials.push_back(ReadMaterial(path, m, job));
    } else if (key == "cluster" || key == "cache") {
      if (key == "cache" && value.IsMap() && value["min_subtree_seconds"])
        job.cache_min_subtree_seconds = Real(path, value["min_subtree_seconds"], "cache.min_subtree_seconds", 0.0, 1e9);
      YAML::Emitter out;
      out << value;
      job.reserved_sections[key] = out.c_str();
    } else {
      Fail(path, entry.first.Mark(),
           "unknown key '" + key + "' (expected design, sampling, threads, materials, cluster, cache)");
    }
  }
  if (!have_design) Fail(path, root.Mark(), "missing required key 'design'");
  return job;
}

JobFile ReadJobFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot read job file");
  std::ostringstream text;
  text << in.rdbuf();
  return ParseJobFile(text.str(), path);
}

}  // namespace fabatlas::sampling

// An OpenSCAD Customizer model as a fabatlas design (fabatlas/scad/import_design.h).
#include "fabatlas/scad/import_design.h"
#include "fabatlas/scad/model_files.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/scad/customizer.h"

namespace fabatlas::scad {
namespace {

// A YAML double-quoted scalar (JSON string syntax is valid YAML).
std::string Yaml(const std::string& s) { return nlohmann::json(s).dump(); }

std::string ReadText(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(p.string() + ": cannot read the OpenSCAD model");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

bool Whole(double v) { return v == std::floor(v) && std::abs(v) < 1e15; }

// How a parameter is exposed: kind, range, labels and OpenSCAD literals.
struct Exposure {
  const CustomizerParameter* p = nullptr;
  std::string type;                   // real, integer, enum
  double min = 0, max = 0, step = 0;  // step 0: none (noted only; the range is sampled whole)
  std::vector<std::string> labels;    // enum: what users see
  std::vector<std::string> literals;  // enum: what OpenSCAD gets
  std::vector<bool> quoted;           // enum: literal is a string
  std::size_t default_index = 0;
};

Exposure ExposureOf(const CustomizerParameter& p, const ExposeRange* range) {
  Exposure e;
  e.p = &p;
  if (range) {
    // A range from the command line: integer as a slider would be.
    const double step = range->step > 0 ? range->step : 1;
    e.type = Whole(range->lo) && Whole(step) && Whole(p.value.number) && Whole(range->hi) ? "integer" : "real";
    e.min = range->lo;
    e.max = range->hi;
    e.step = range->step;
  } else if (p.value.type == ScadValue::Type::kBoolean) {
    e.type = "enum";
    e.labels = e.literals = {"false", "true"};
    e.quoted = {false, false};
    e.default_index = p.value.text == "true";
  } else if (p.widget == CustomizerParameter::Widget::kSlider) {
    // Integer where min and step are whole (and the model's value is).
    const double step = p.step > 0 ? p.step : 1;
    e.type = Whole(p.min) && Whole(step) && Whole(p.value.number) && Whole(p.max) ? "integer" : "real";
    e.min = p.min;
    e.max = p.max;
    e.step = p.step;
  } else {
    e.type = "enum";
    std::set<std::string> seen;
    for (std::size_t i = 0; i < p.options.size(); ++i) {
      const DropdownOption& o = p.options[i];
      std::string label = o.label;
      // Labels are how users and --at name values: keep them unique.
      while (!seen.insert(label).second) label += "'";
      e.labels.push_back(label);
      e.literals.push_back(o.value.type == ScadValue::Type::kString ? o.value.text : o.value.Literal());
      e.quoted.push_back(o.value.type == ScadValue::Type::kString);
    }
    for (std::size_t i = 0; i < p.options.size(); ++i) {  // the first option equal to the model's value
      const ScadValue& v = p.options[i].value;
      if (v.type == ScadValue::Type::kNumber ? v.number == p.value.number : v.text == p.value.text) {
        e.default_index = i;
        break;
      }
    }
  }
  return e;
}

// The min_thickness check's value: a wall of two 0.4 mm FDM extrusion lines.
constexpr double kMinThickness = 0.8;

double VoxelFor(const ImportOptions& o) {
  if (o.voxel_size > 0) return o.voxel_size;
  if (o.model_size <= 0) return 0.5;
  // About 150 voxels along the largest edge, in steps of 0.05 mm, within
  // [5/8, 3/4] of the thinnest printable wall: coarser, a wall at that limit
  // no longer spans more than a voxel and the shape-diameter check calls the
  // sign's letters thin; finer, marching cubes' small faces along sharp edges
  // make a plain 12 mm cube fail it (docs/openscad.md, "Voxel size").
  const double v = std::clamp(o.model_size / 150, 0.625 * kMinThickness, 0.75 * kMinThickness);
  return std::round(v * 20) / 20;
}

std::string TypeWords(const ScadValue& v) {
  switch (v.type) {
    case ScadValue::Type::kString:
      return "a string (text box)";
    case ScadValue::Type::kVector:
      return "a vector";
    case ScadValue::Type::kBoolean:
      return "a checkbox";
    default:
      return "a number";
  }
}

std::string WidgetWords(const CustomizerParameter& p) {
  std::string w = p.widget == CustomizerParameter::Widget::kSlider
                      ? "slider [" + FormatScadNumber(p.min) + ":" +
                            (p.step > 0 ? FormatScadNumber(p.step) + ":" : "") + FormatScadNumber(p.max) + "]"
                  : p.widget == CustomizerParameter::Widget::kDropdown
                      ? "dropdown of " + std::to_string(p.options.size())
                      : TypeWords(p.value);
  return w + (p.group.empty() ? "" : " in group '" + p.group + "'");
}

// One parameter's fate: exposed or fixed, and the line saying why.
struct Choice {
  const CustomizerParameter* p = nullptr;
  bool exposed = false;
  std::string why;   // fixed: why, in words
  std::string line;  // "exposed NAME: ..." / "fixed NAME = VALUE: WHY"
};

// How each exposed parameter is exposed, in words.
using Chosen = std::map<const CustomizerParameter*, std::string>;

// The parameters `--expose` names, checked against the model.
Chosen ChosenByName(const CustomizerModel& m, const std::string& file, const ImportOptions& o) {
  std::map<std::string, const CustomizerParameter*> by_name;
  for (const auto& p : m.parameters) by_name[p.name] = &p;
  Chosen how;
  for (const auto& name : o.expose) {
    auto it = by_name.find(name);
    if (it == by_name.end())
      throw InputError(file + ": --expose " + name + ": the model has no Customizer parameter '" + name +
                       "' (a top-level literal assignment before the first '{')");
    const CustomizerParameter* p = it->second;
    const std::string at = file + ":" + std::to_string(p->line) + ": --expose " + name;
    if (name[0] == '$') throw InputError(at + ": $-variables stay fixed");
    auto range = o.ranges.find(name);
    if (range != o.ranges.end()) {
      const ExposeRange& r = range->second;
      if (p->value.type != ScadValue::Type::kNumber)
        throw InputError(at + ": the parameter is " + TypeWords(p->value) + " (" + p->value.Literal() +
                         "), a range needs a number");
      if (p->widget == CustomizerParameter::Widget::kDropdown)
        throw InputError(at + ": the parameter is a dropdown; name it without a range");
      if (p->value.number < r.lo || p->value.number > r.hi)
        throw InputError(at + ": the model's value " + FormatScadNumber(p->value.number) + " lies outside " +
                         FormatScadNumber(r.lo) + ":" + FormatScadNumber(r.hi));
      how[p] =
          "range " + FormatScadNumber(r.lo) + ":" + (r.step > 0 ? FormatScadNumber(r.step) + ":" : "") +
          FormatScadNumber(r.hi) + " from --expose" +
          (p->widget == CustomizerParameter::Widget::kSlider ? " (replaces the model's " + WidgetWords(*p) + ")" : "");
    } else {
      if (p->widget == CustomizerParameter::Widget::kNone && p->value.type != ScadValue::Type::kBoolean)
        throw InputError(
            at + ": the parameter has no slider or dropdown annotation, so it has no range (give one: --expose " +
            name + "=lo:hi)");
      how[p] = WidgetWords(*p) + ", named by --expose";
    }
  }
  if (static_cast<int>(how.size()) > o.max_dims)
    throw InputError(file + ": --expose names " + std::to_string(how.size()) + " parameters, more than --max-dims " +
                     std::to_string(o.max_dims));
  return how;
}

// The automatic choice: sliders and dropdowns outside [Hidden], Customizer
// groups (tabs) by first appearance, then file order, up to max_dims.
Chosen ChosenAutomatically(const CustomizerModel& m, const ImportOptions& o) {
  std::map<std::string, int> group_rank;
  for (const auto& p : m.parameters) group_rank.emplace(p.group, static_cast<int>(group_rank.size()));
  std::vector<const CustomizerParameter*> eligible;
  for (const auto& p : m.parameters)
    if (!p.hidden && p.widget != CustomizerParameter::Widget::kNone && p.name[0] != '$') eligible.push_back(&p);
  std::stable_sort(eligible.begin(), eligible.end(),
                   [&](auto* a, auto* b) { return group_rank.at(a->group) < group_rank.at(b->group); });
  Chosen how;
  for (std::size_t i = 0; i < eligible.size() && static_cast<int>(i) < o.max_dims; ++i)
    how[eligible[i]] = WidgetWords(*eligible[i]) + ", within --max-dims " + std::to_string(o.max_dims);
  return how;
}

// Why a parameter not exposed stays fixed, in words.
std::string WhyFixed(const CustomizerParameter& p, const ImportOptions& o) {
  const std::string in_group = p.group.empty() ? "" : " in group '" + p.group + "'";
  if (p.name[0] == '$') return "a $-variable (OpenSCAD's special variables stay fixed)";
  if (p.hidden) return "in [Hidden]";
  if (!o.expose.empty()) return "not named by --expose (" + WidgetWords(p) + ")";
  if (p.widget != CustomizerParameter::Widget::kNone)
    return "beyond --max-dims " + std::to_string(o.max_dims) + " (" + WidgetWords(p) + ")";
  if (p.value.type == ScadValue::Type::kNumber)
    return "no range: a number without a slider annotation" + in_group + " (give one: --expose " + p.name + "=lo:hi)";
  if (p.value.type == ScadValue::Type::kBoolean)
    return "a checkbox" + in_group + " (expose it: --expose " + p.name + ")";
  return TypeWords(p.value) + ": not sampled";
}

// Which parameters are exposed (import_design.h, ImportScad): in file order.
std::vector<Choice> ChooseExposed(const CustomizerModel& m, const std::string& file, const ImportOptions& o) {
  if (o.max_dims < 1 || o.max_dims > 16)
    throw InputError(file + ": --max-dims " + std::to_string(o.max_dims) +
                     " is outside 1..16 (the dimensions an artifact holds)");
  const Chosen how = o.expose.empty() ? ChosenAutomatically(m, o) : ChosenByName(m, file, o);
  std::vector<Choice> out;
  for (const auto& p : m.parameters) {
    Choice c;
    c.p = &p;
    auto it = how.find(&p);
    c.exposed = it != how.end();
    if (c.exposed) {
      c.line = "exposed " + p.name + ": " + it->second;
    } else {
      c.why = WhyFixed(p, o);
      c.line = "fixed " + p.name + " = " + p.value.Literal() + ": " + c.why;
    }
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace

void AddExposeItem(const std::string& item, ImportOptions& options) {
  const std::size_t eq = item.find('=');
  const std::string name = item.substr(0, eq);
  if (name.empty()) throw InputError("--expose '" + item + "': no parameter name (expected NAME or NAME=lo:hi[:step])");
  if (std::find(options.expose.begin(), options.expose.end(), name) == options.expose.end())
    options.expose.push_back(name);
  if (eq == std::string::npos) return;
  std::vector<double> v;
  std::stringstream ss(item.substr(eq + 1));
  std::string part;
  bool ok = true;
  while (std::getline(ss, part, ':')) {
    char* end = nullptr;
    const double x = std::strtod(part.c_str(), &end);
    ok = ok && !part.empty() && *end == 0 && std::isfinite(x);
    v.push_back(x);
  }
  const std::string text = item.substr(eq + 1);
  if (!ok || v.size() < 2 || v.size() > 3 || text.back() == ':')
    throw InputError("--expose " + item + ": malformed range '" + text +
                     "' (expected NAME=lo:hi or NAME=lo:hi:step, numbers)");
  ExposeRange r{v[0], v[1], v.size() == 3 ? v[2] : 0};
  if (!(r.lo < r.hi))
    throw InputError("--expose " + item + ": lo " + FormatScadNumber(r.lo) + " is not below hi " +
                     FormatScadNumber(r.hi));
  if (v.size() == 3 && !(r.step > 0))
    throw InputError("--expose " + item + ": step " + FormatScadNumber(r.step) + " must be positive");
  options.ranges[name] = r;
}

namespace {

// The design's head: name and voxel size (with where the size came from).
void WriteHead(std::ostream& y, const std::filesystem::path& model, const ImportOptions& options) {
  y << "# Imported from the OpenSCAD Customizer model " << model.filename().string()
    << " by `fabatlas import-scad` (docs/openscad.md).\n";
  y << "name: " << Yaml(model.stem().string()) << "\n";
  y << "voxel_size: " << FormatScadNumber(VoxelFor(options));
  if (options.voxel_size <= 0 && options.model_size > 0)
    y << "  # the model's largest edge at its defaults, " << FormatScadNumber(std::round(options.model_size * 10) / 10)
      << " mm, / 150, within [5/8, 3/4] of min_thickness";
  y << "\n";
}

// `parameters:`, the exposed ones in file order; `{}` when none.
void WriteExposed(std::ostream& y, const std::vector<Exposure>& exposures, const ImportOptions& options) {
  // No exposed parameter: the model at its own values, one sample.
  y << (exposures.empty() ? "parameters: {}  # none exposed: one sample, the model at its values\n" : "parameters:\n");
  for (const auto& e : exposures) {
    const CustomizerParameter& p = *e.p;
    y << "  " << p.name << ": {type: " << e.type;
    if (e.type == "enum") {
      y << ", values: [";
      for (std::size_t i = 0; i < e.labels.size(); ++i) y << (i ? ", " : "") << Yaml(e.labels[i]);
      y << "], default: " << Yaml(e.labels[e.default_index]);
    } else {
      y << ", min: " << FormatScadNumber(e.min) << ", max: " << FormatScadNumber(e.max)
        << ", default: " << FormatScadNumber(p.value.number);
    }
    if (!p.group.empty()) y << ", group: " << Yaml(p.group);
    if (!p.description.empty()) y << ", description: " << Yaml(p.description);
    y << "}";
    // fabatlas samples the whole range; OpenSCAD's slider step is noted only.
    if (e.step > 0 && e.type != "enum")
      y << (options.ranges.count(p.name) ? "  # --expose step " : "  # OpenSCAD slider step ")
        << FormatScadNumber(e.step);
    y << "\n";
  }
}

// `fixed:`, the rest at the model's values: shown read-only, never passed.
void WriteFixed(std::ostream& y, const std::vector<Choice>& choices) {
  bool any_fixed = false;
  for (const Choice& c : choices) {
    if (c.exposed || c.p->name[0] == '$' || c.p->hidden) continue;  // [Hidden]: the model's author hid them
    if (!any_fixed) y << "fixed:\n";
    any_fixed = true;
    y << "  " << c.p->name << ": {value: " << Yaml(c.p->value.Literal());
    if (!c.p->group.empty()) y << ", group: " << Yaml(c.p->group);
    if (!c.p->description.empty()) y << ", description: " << Yaml(c.p->description);
    y << ", why: " << Yaml(c.why) << "}\n";
  }
}

// The tree (one `openscad` node passing the exposed values), checks, properties.
void WriteTree(std::ostream& y, const std::string& reference, const std::vector<Exposure>& exposures) {
  y << "tree:\n  op: openscad\n  file: " << Yaml(reference) << "\n";
  if (!exposures.empty()) {
    y << "  set: {";
    for (std::size_t i = 0; i < exposures.size(); ++i)
      y << (i ? ", " : "") << exposures[i].p->name << ": " << exposures[i].p->name;
    y << "}\n";
  }
  bool any_enum = false;
  for (const auto& e : exposures) any_enum = any_enum || e.type == "enum";
  if (any_enum) {
    // The OpenSCAD value each enum index stands for: quoted YAML scalars are
    // passed as OpenSCAD strings, plain ones as numbers or booleans.
    y << "  choices:\n";
    for (const auto& e : exposures) {
      if (e.type != "enum") continue;
      y << "    " << e.p->name << ": [";
      for (std::size_t i = 0; i < e.literals.size(); ++i)
        y << (i ? ", " : "") << (e.quoted[i] ? Yaml(e.literals[i]) : e.literals[i]);
      y << "]\n";
    }
  }
  // Checks: the mesh OpenSCAD produces (polyhedra, subtrees it renders) must
  // be watertight; a wall of two 0.4 mm FDM extrusion lines; stands.
  y << "checks:\n  - watertight\n  - {type: min_thickness, value: " << FormatScadNumber(kMinThickness)
    << "}\n  - stands\n";
  y << "properties: [volume, bbox]\n";
}

// A parameter set's value `written` for the exposed parameter `e`, as the
// design's preset writes it; empty with `problem` saying why when it does not fit.
std::string PresetValue(const Exposure& e, const std::string& name, const std::string& written, std::string* problem) {
  if (e.type == "enum") {
    for (std::size_t i = 0; i < e.literals.size(); ++i) {
      double a = 0, b = 0;
      bool same = e.literals[i] == written || (!e.quoted[i] && std::sscanf(written.c_str(), "%lf", &a) == 1 &&
                                               std::sscanf(e.literals[i].c_str(), "%lf", &b) == 1 && a == b);
      if (same) return Yaml(e.labels[i]);
    }
    *problem = name + "=" + written + " is not one of its dropdown values";
    return "";
  }
  char* end = nullptr;
  double v = std::strtod(written.c_str(), &end);
  if (end == written.c_str() || *end != 0 || !std::isfinite(v))
    *problem = name + "=" + written + " is not a number";
  else if (v < e.min || v > e.max)
    *problem =
        name + "=" + written + " lies outside [" + FormatScadNumber(e.min) + ", " + FormatScadNumber(e.max) + "]";
  else if (e.type == "integer" && !Whole(v))
    *problem = name + "=" + written + " is not a whole number";
  else
    return FormatScadNumber(v);
  return "";
}

// One parameter set as a preset line "  NAME: {...}"; empty (and a warning
// in `s`) when a value does not fit.
std::string PresetOf(const ParameterSet& set, const std::vector<Exposure>& exposures,
                     const std::map<std::string, const CustomizerParameter*>& by_name, const std::string& json,
                     ImportSummary& s) {
  std::ostringstream values;
  std::vector<std::string> ignored;
  std::string problem;
  for (const auto& [name, written] : set.values) {
    auto e = std::find_if(exposures.begin(), exposures.end(), [&](const Exposure& x) { return x.p->name == name; });
    if (e == exposures.end()) {
      auto it = by_name.find(name);
      if (it != by_name.end()) {
        const ScadValue& v = it->second->value;
        std::string model_text = v.type == ScadValue::Type::kString ? v.text : v.Literal();
        if (model_text != written) ignored.push_back(name);
      }
      continue;
    }
    const std::string value = PresetValue(*e, name, written, &problem);
    if (!problem.empty()) break;
    values << (values.tellp() > 0 ? ", " : "") << name << ": " << value;
  }
  if (!problem.empty()) {
    s.warnings.push_back(json + ": parameter set '" + set.name + "' not kept as a preset: " + problem);
    return "";
  }
  if (!ignored.empty()) {
    std::string list;
    for (const auto& n : ignored) list += (list.empty() ? "" : ", ") + n;
    s.warnings.push_back(json + ": parameter set '" + set.name + "' also sets fixed parameters (" + list +
                         "); its preset keeps the model's values for them (expose them with --expose)");
  }
  return "  " + Yaml(set.name) + ": {" + values.str() + "}\n";
}

// OpenSCAD's parameter sets beside the model (MODEL.json) as `presets:`.
void WritePresets(std::ostream& y, const std::filesystem::path& model, const std::vector<Exposure>& exposures,
                  const CustomizerModel& m, ImportSummary& s) {
  std::filesystem::path json = model;
  json.replace_extension(".json");
  std::error_code ec;
  if (!std::filesystem::is_regular_file(json, ec)) return;
  std::map<std::string, const CustomizerParameter*> by_name;
  for (const auto& p : m.parameters) by_name[p.name] = &p;
  std::ostringstream presets;
  for (const auto& set : ReadParameterSets(ReadText(json), json.string())) {
    const std::string line = PresetOf(set, exposures, by_name, json.string(), s);
    if (line.empty()) continue;
    presets << line;
    ++s.presets;
  }
  if (s.presets > 0) y << "presets:\n" << presets.str();
}

// The job beside the design.
std::string JobYaml(const ImportOptions& options) {
  std::ostringstream job;
  job << "# A precompute job for " << options.design_file_name << " (docs/job-format.md).\n";
  job << "design: " << Yaml(options.design_file_name) << "\n";
  job << "sampling: {subdivisions: 3, max_depth: 3, dg_threshold: 0.1, max_samples: 400}\n";
  job << "threads: 2\n";
  // Fab Forms Sec. 6: plan the geometry cache (OPT-MAX, default budget), and
  // the example jobs' materials for the weight and cost readout.
  job << "cache: {strategy: opt_max}\n";
  job << "materials:\n";
  job << "  - {name: PLA, density: 1.24, price_per_kg: 20}\n";
  job << "  - {name: PETG, density: 1.27, price_per_kg: 25}\n";
  job << "  - {name: resin, density: 1.12, price_per_kg: 60}\n";
  return job.str();
}

}  // namespace

ImportSummary ImportScad(const std::filesystem::path& model, const ImportOptions& options) {
  const CustomizerModel m = ReadCustomizer(ReadText(model), model.string());
  ImportSummary s;
  s.warnings = m.warnings;
  const std::vector<Choice> choices = ChooseExposed(m, model.string(), options);
  std::vector<Exposure> exposures;
  for (const Choice& c : choices) {
    s.decisions.push_back(c.line);
    if (!c.exposed) {
      s.fixed.push_back(c.p->name);
      continue;
    }
    auto range = options.ranges.find(c.p->name);
    exposures.push_back(ExposureOf(*c.p, range == options.ranges.end() ? nullptr : &range->second));
    s.exposed.push_back(c.p->name);
  }
  const std::string reference = options.model_reference.empty() ? model.filename().string() : options.model_reference;
  std::ostringstream y;
  WriteHead(y, model, options);
  WriteExposed(y, exposures, options);
  WriteFixed(y, choices);
  WriteTree(y, reference, exposures);
  WritePresets(y, model, exposures, m, s);
  s.design_yaml = y.str();
  s.job_yaml = JobYaml(options);
  return s;
}

}  // namespace fabatlas::scad

namespace fabatlas::scad {

std::filesystem::path WriteImportedJob(const std::filesystem::path& model, const std::filesystem::path& dir,
                                       ImportOptions options, ImportSummary* summary) {
  namespace fs = std::filesystem;
  const std::string stem = model.stem().string();
  options.model_reference = stem + ".scad";
  options.design_file_name = stem + ".yaml";
  ImportSummary s = ImportScad(model, options);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir.string() + ": cannot create the directory: " + ec.message());
  auto write = [&](const fs::path& p, const std::string& text) {
    std::ofstream out(p, std::ios::binary);
    out << text;
    if (!out) throw InputError(p.string() + ": cannot write");
  };
  if (!fs::exists(dir / (stem + ".scad")) || !fs::equivalent(model, dir / (stem + ".scad")))
    write(dir / (stem + ".scad"), ReadText(model));
  fs::path json = model;
  json.replace_extension(".json");
  if (fs::is_regular_file(json, ec) &&
      (!fs::exists(dir / (stem + ".json")) || !fs::equivalent(json, dir / (stem + ".json"))))
    write(dir / (stem + ".json"), ReadText(json));
  // What the model includes, uses and imports, where OpenSCAD finds it from
  // the copy (model_files.h).
  for (const ModelFile& f : ModelFiles(model)) {
    const fs::path to = dir / f.relative;
    if (fs::exists(to, ec) && fs::equivalent(f.source, to, ec)) continue;
    fs::create_directories(to.parent_path(), ec);
    if (!fs::copy_file(f.source, to, fs::copy_options::overwrite_existing, ec))
      throw InputError(to.string() + ": cannot copy " + f.source.string() + ": " + ec.message());
  }
  write(dir / (stem + ".yaml"), s.design_yaml);
  write(dir / (stem + ".job.yaml"), s.job_yaml);
  if (summary) *summary = s;
  return dir / (stem + ".job.yaml");
}

}  // namespace fabatlas::scad

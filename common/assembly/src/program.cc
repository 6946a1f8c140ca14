#include "fabatlas/assembly/program.h"

#include <cstdlib>
#include <filesystem>
#include <algorithm>
#include <map>

#include "connector_frames.h"
#include "fabatlas/assembly/frame.h"
#include "fabatlas/yaml_place.h"

#include "yaml_errors.h"

namespace fabatlas::assembly {

std::string DefaultMeshDir() {
  if (const char* s = std::getenv("FABATLAS_SHARED_DIR")) return std::string(s) + "/data/fabhacks/meshes";
  if (const char* s = std::getenv("FABATLAS_SOURCE_DIR")) return std::string(s) + "/../shared/data/fabhacks/meshes";
  return "../shared/data/fabhacks/meshes";
}

bool IsRestingContact(const std::string& key) {
  return key == "Surface_Surface" || key == "Tube_TubeCtl" || key == "TubeCtl_Tube" || key == "TubeCtl_Rod" ||
         key == "Rod_TubeCtl";
}

Eigen::Matrix4d Program::TargetOffset() const {
  if (target_primitive < 0) return Eigen::Matrix4d::Identity();
  return ToIsometry(PartOf(target).primitives[target_primitive].frame).matrix();
}

namespace {

using internal::AsString;
using internal::Fail;

// The part library a parsed program names, relative to the program file.
std::string LibraryPathOf(const YAML::Node& root, const std::string& file) {
  if (!root.IsMap() || !root["library"]) Fail(file, root, "missing 'library:'");
  return (std::filesystem::path(file).parent_path() / AsString(file, root["library"], "library")).string();
}

using InstanceIndex = std::map<std::string, int>;  // instance name -> index in Program::instances

// Adds instance `name` of library part `part` to prog; returns its index.
int AddInstance(const std::string& file, const YAML::Node& name, const YAML::Node& part, Program& prog,
                InstanceIndex& index) {
  const std::string n = AsString(file, name, "instance name");
  const std::string p = AsString(file, part, "part");
  if (index.count(n)) Fail(file, name, "duplicate part instance '" + n + "'");
  if (!prog.library.parts.count(p)) Fail(file, part, "unknown part '" + p + "'");
  index[n] = static_cast<int>(prog.instances.size());
  prog.instances.push_back({n, p});
  return index[n];
}

// The program's target from its 'end_with' map ew: instance (added when it
// names a part), frame, optional primitive and match_rotation.
void ReadTarget(const std::string& file, const YAML::Node& root, const YAML::Node& ew, Program& prog,
                InstanceIndex& index) {
  if (!ew || !ew.IsMap() || !ew["name"] || !ew["frame"]) Fail(file, ew ? ew : root, "'end_with' needs name and frame");
  for (const auto& kv : ew)
    if (const auto k = kv.first.as<std::string>();
        k != "name" && k != "part" && k != "primitive" && k != "frame" && k != "match_rotation")
      Fail(file, kv.first, "unknown key '" + k + "' in end_with");
  const std::string n = AsString(file, ew["name"], "end_with name");
  if (ew["part"] && !index.count(n)) AddInstance(file, ew["name"], ew["part"], prog, index);
  if (!index.count(n)) Fail(file, ew["name"], "end_with names unknown instance '" + n + "'");
  prog.target = index[n];
  if (prog.target == 0) Fail(file, ew["name"], "the target cannot be the environment");
  prog.target_frame = internal::AsFrame(file, ew["frame"], "end_with frame");
  if (ew["primitive"]) {
    const std::string pn = AsString(file, ew["primitive"], "end_with primitive");
    const auto& prims = prog.PartOf(prog.target).primitives;
    for (size_t i = 0; i < prims.size(); ++i)
      if (prims[i].name == pn) prog.target_primitive = static_cast<int>(i);
    if (prog.target_primitive < 0)
      Fail(file, ew["primitive"], "part '" + prog.instances[prog.target].part + "' has no primitive '" + pn + "'");
  }
  if (ew["match_rotation"]) {
    try {
      prog.target_match_rotation = ew["match_rotation"].as<bool>();
    } catch (const YAML::Exception&) {
      Fail(file, ew["match_rotation"], "match_rotation must be true or false");
    }
  }
}

// A connector reference "instance.primitive" into inst and prim.
void ReadConnector(const std::string& file, const YAML::Node& n, const Program& prog, InstanceIndex& index, int& inst,
                   std::string& prim) {
  const std::string s = AsString(file, n, "connector reference");
  const auto dot = s.find('.');
  if (dot == std::string::npos) Fail(file, n, "connector '" + s + "' must be instance.primitive");
  const std::string in = s.substr(0, dot);
  prim = s.substr(dot + 1);
  if (!index.count(in)) Fail(file, n, "unknown part instance '" + in + "'");
  inst = index[in];
  if (!prog.PartOf(inst).Find(prim))
    Fail(file, n, "part '" + prog.instances[inst].part + "' has no primitive '" + prim + "'");
}

// PARTS.md §2.3: connections where one side takes its fixed base form, and
// the other side's parameter ranges keep the smaller part on the larger.
void ApplyBaseForms(const Primitive& pa, const Primitive& pb, Connection& con) {
  const std::string& k = con.key;
  if (k == "Surface_Surface") {
    const bool a_smaller = pa.Shape("width") < pb.Shape("width") && pa.Shape("length") < pb.Shape("length");
    const Primitive& small = a_smaller ? pa : pb;
    const Primitive& large = a_smaller ? pb : pa;
    (a_smaller ? con.params_a : con.params_b) = small.BaseFormParams();
    auto& lp = a_smaller ? con.params_b : con.params_a;
    const double fw = small.Shape("width") / (2 * large.Shape("width"));
    const double fl = small.Shape("length") / (2 * large.Shape("length"));
    lp[0].min = fw, lp[0].max = 1 - fw, lp[1].min = fl, lp[1].max = 1 - fl;
  } else if (k == "HookFlex_HookFlex") {
    con.params_a = pa.BaseFormParams();  // the placed hook
  } else if (k == "Tube_TubeCtl" || k == "TubeCtl_Tube" || k == "TubeCtl_Rod" || k == "Rod_TubeCtl") {
    const bool a_shorter = pa.Shape("length") < pb.Shape("length");
    const Primitive& small = a_shorter ? pa : pb;
    const Primitive& large = a_shorter ? pb : pa;
    (a_shorter ? con.params_a : con.params_b) = small.BaseFormParams();
    auto& lp = a_shorter ? con.params_b : con.params_a;
    const double h = 0.5 * (large.Shape("length") - small.Shape("length")) / large.Shape("length");
    lp[0].min = 0.5 - h, lp[0].max = 0.5 + h;
    if (k.find("Rod") != std::string::npos && lp.size() > 1)
      lp[1].min = lp[1].max = 90;
    else if (lp.size() > 1)
      lp[1].min = 0, lp[1].max = 360;
  }
}

// The connectors of step c ({attach, to} or {connect, with}) into con,
// marking a newly attached part in `placed`.
void ReadStepConnectors(const std::string& file, const YAML::Node& c, const Program& prog, InstanceIndex& index,
                        std::vector<bool>& placed, Connection& con) {
  if (con.closing) {
    ReadConnector(file, c["connect"], prog, index, con.part_a, con.primitive_a);
    ReadConnector(file, c["with"], prog, index, con.part_b, con.primitive_b);
    if (!placed[con.part_a] || !placed[con.part_b])
      Fail(file, c, "connect joins two parts already placed by earlier steps");
  } else {
    ReadConnector(file, c["to"], prog, index, con.part_a, con.primitive_a);      // placed
    ReadConnector(file, c["attach"], prog, index, con.part_b, con.primitive_b);  // new
    if (!placed[con.part_a]) Fail(file, c["to"], "attach: '" + prog.instances[con.part_a].name + "' is not placed yet");
    if (placed[con.part_b])
      Fail(file, c["attach"], "attach: '" + prog.instances[con.part_b].name + "' is already placed (use connect)");
    placed[con.part_b] = true;
  }
}

// One step of the program: the connection it makes, with its key,
// alignment, held flag and parameter ranges.
Connection ReadStep(const std::string& file, const YAML::Node& c, const Program& prog, InstanceIndex& index,
                    std::vector<bool>& placed) {
  if (!c.IsMap() || !((c["attach"] && c["to"]) || (c["connect"] && c["with"])))
    Fail(file, c, "a step is {attach: part.primitive, to: part.primitive} or {connect: ..., with: ...}");
  Connection con;
  con.where = YamlPlace(file, c.Mark()).str();
  con.closing = static_cast<bool>(c["connect"]);
  for (const auto& kv : c) {
    const std::string k = kv.first.as<std::string>();
    if (k != (con.closing ? "connect" : "attach") && k != (con.closing ? "with" : "to") && k != "alignment" &&
        k != "is_fixed")
      Fail(file, kv.first, "unknown key '" + k + "' in " + (con.closing ? "connect" : "attach") + " step");
  }
  ReadStepConnectors(file, c, prog, index, placed, con);
  if (con.part_a == con.part_b) Fail(file, c, "a part cannot connect to itself");
  if (c["alignment"]) {
    const std::string al = AsString(file, c["alignment"], "alignment");
    if (al != "flip" && al != "default") Fail(file, c["alignment"], "alignment must be 'flip' or 'default'");
    con.flip = al == "flip";
  }
  if (c["is_fixed"]) {
    try {
      con.is_fixed = c["is_fixed"].as<bool>();
    } catch (const YAML::Exception&) {
      Fail(file, c["is_fixed"], "is_fixed must be true or false");
    }
  }
  const Primitive& pa = prog.PrimitiveA(con);
  const Primitive& pb = prog.PrimitiveB(con);
  con.key = pa.ClassName(!con.closing) + "_" + pb.ClassName(!con.closing);
  con.align = AlignmentOffset(con.key, con.flip);
  // Held in the relaxation: fixed joints and clips (PARTS.md §1.10), and a
  // part resting on another (a surface on a surface, a roll on a rod), which
  // static friction holds in place; whether it tips over or slides off is
  // checked after the relaxation (solve.cc).
  con.held_in_relaxation = con.is_fixed || con.key.find("Clip") != std::string::npos || IsRestingContact(con.key);
  con.params_a = pa.Params();
  con.params_b = pb.Params();
  ApplyBaseForms(pa, pb, con);
  for (auto* side : {&con.params_a, &con.params_b})
    for (auto& p : *side) p.init = std::clamp(p.init, p.min, p.max);
  if (con.closing) con.symmetry_axis_a = internal::SymmetryAxis(pa.type);
  return con;
}

// PARTS.md §1: several connections on one primitive start spread evenly,
// value_i = min + (max − min)·(i+1)/(n+1), in program order.
void SpreadSharedPrimitives(Program& prog) {
  std::map<std::pair<int, std::string>, std::vector<std::vector<ParamSpec>*>> users;
  for (auto& con : prog.connections) {
    users[{con.part_a, con.primitive_a}].push_back(&con.params_a);
    users[{con.part_b, con.primitive_b}].push_back(&con.params_b);
  }
  for (auto& [key, sides] : users) {
    if (sides.size() < 2) continue;
    for (size_t i = 0; i < sides.size(); ++i)
      for (auto& p : *sides[i])
        if (!p.held)
          p.init = p.min + (p.max - p.min) * static_cast<double>(i + 1) / static_cast<double>(sides.size() + 1);
  }
}

Program Build(const YAML::Node& root, const std::string& file, std::string library_path,
              const std::string& mesh_dir_in) {
  const std::string mesh_dir = mesh_dir_in.empty() ? DefaultMeshDir() : mesh_dir_in;
  if (!root.IsMap()) Fail(file, root, "a program must be a map");
  for (const auto& kv : root) {
    const std::string k = kv.first.as<std::string>();
    if (k != "library" && k != "start_with" && k != "end_with" && k != "parts" && k != "steps" && k != "name" &&
        k != "description")
      Fail(file, kv.first, "unknown key '" + k + "'");
  }
  if (library_path.empty()) library_path = LibraryPathOf(root, file);
  Program prog;
  prog.file = file;
  prog.library = LoadPartLibrary(library_path, mesh_dir);
  InstanceIndex index;
  const YAML::Node sw = root["start_with"];
  if (!sw || !sw.IsMap() || !sw["name"] || !sw["part"] || !sw["frame"])
    Fail(file, sw ? sw : root, "'start_with' needs name, part and frame");
  AddInstance(file, sw["name"], sw["part"], prog, index);
  prog.environment_frame = internal::AsFrame(file, sw["frame"], "start_with frame");
  if (const YAML::Node parts = root["parts"]) {
    if (!parts.IsMap()) Fail(file, parts, "'parts' must be a map instance: Part");
    for (const auto& kv : parts) AddInstance(file, kv.first, kv.second, prog, index);
  }
  ReadTarget(file, root, root["end_with"], prog, index);
  const YAML::Node steps = root["steps"];
  if (!steps || !steps.IsSequence() || steps.size() == 0)
    Fail(file, steps ? steps : root, "'steps' must be a non-empty list");
  std::vector<bool> placed(prog.instances.size(), false);
  placed[0] = true;
  for (const auto& c : steps) prog.connections.push_back(ReadStep(file, c, prog, index, placed));
  for (size_t i = 0; i < placed.size(); ++i)
    if (!placed[i]) Fail(file, steps, "part '" + prog.instances[i].name + "' is never attached");
  SpreadSharedPrimitives(prog);
  return prog;
}

}  // namespace

Program LoadProgram(const std::string& path, const std::string& mesh_dir) {
  const YAML::Node root = internal::LoadYamlFile(path);
  return Build(root, path, "", mesh_dir);
}

Program ParseProgram(const std::string& text, const std::string& name, const std::string& library_path,
                     const std::string& mesh_dir) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    FailAt(YamlPlace(name, e.mark), e.msg);
  }
  return Build(root, name, library_path, mesh_dir);
}

std::string ProgramLibraryPath(const std::string& file) { return LibraryPathOf(internal::LoadYamlFile(file), file); }

}  // namespace fabatlas::assembly

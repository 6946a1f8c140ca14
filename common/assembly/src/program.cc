#include "fabatlas/assembly/program.h"

#include <cstdlib>
#include <filesystem>
#include <map>

#include "yaml_errors.h"

namespace fabatlas::assembly {

std::string DefaultMeshDir() {
  if (const char* s = std::getenv("FABATLAS_SHARED_DIR")) return std::string(s) + "/data/fabhacks/meshes";
  if (const char* s = std::getenv("FABATLAS_SOURCE_DIR")) return std::string(s) + "/../shared/data/fabhacks/meshes";
  return "../shared/data/fabhacks/meshes";
}

namespace {

using internal::AsString;
using internal::Fail;

// The part library a parsed program names, relative to the program file.
std::string LibraryPathOf(const YAML::Node& root, const std::string& file) {
  if (!root.IsMap() || !root["library"]) Fail(file, root, "missing 'library:'");
  return (std::filesystem::path(file).parent_path() / AsString(file, root["library"], "library")).string();
}

Program Build(const YAML::Node& root, const std::string& file, std::string library_path,
              const std::string& mesh_dir_in) {
  const std::string mesh_dir = mesh_dir_in.empty() ? DefaultMeshDir() : mesh_dir_in;
  if (!root.IsMap()) Fail(file, root, "a program must be a map");
  for (const auto& kv : root) {
    const std::string k = kv.first.as<std::string>();
    if (k != "library" && k != "start_with" && k != "end_with" && k != "parts" && k != "connect" &&
        k != "name" && k != "description")
      Fail(file, kv.first, "unknown key '" + k + "'");
  }
  if (library_path.empty()) library_path = LibraryPathOf(root, file);
  Program prog;
  prog.file = file;
  prog.library = LoadPartLibrary(library_path, mesh_dir);
  std::map<std::string, int> index;
  auto add_instance = [&](const YAML::Node& name, const YAML::Node& part) {
    const std::string n = AsString(file, name, "instance name");
    const std::string p = AsString(file, part, "part");
    if (index.count(n)) Fail(file, name, "duplicate part instance '" + n + "'");
    if (!prog.library.parts.count(p)) Fail(file, part, "unknown part '" + p + "'");
    index[n] = static_cast<int>(prog.instances.size());
    prog.instances.push_back({n, p});
    return index[n];
  };
  const YAML::Node sw = root["start_with"];
  if (!sw || !sw.IsMap() || !sw["name"] || !sw["part"] || !sw["frame"])
    Fail(file, sw ? sw : root, "'start_with' needs name, part and frame");
  add_instance(sw["name"], sw["part"]);
  prog.environment_frame = internal::AsFrame(file, sw["frame"], "start_with frame");
  if (const YAML::Node parts = root["parts"]) {
    if (!parts.IsMap()) Fail(file, parts, "'parts' must be a map instance: Part");
    for (const auto& kv : parts) add_instance(kv.first, kv.second);
  }
  const YAML::Node ew = root["end_with"];
  if (!ew || !ew.IsMap() || !ew["name"] || !ew["frame"]) Fail(file, ew ? ew : root, "'end_with' needs name and frame");
  {
    const std::string n = AsString(file, ew["name"], "end_with name");
    if (ew["part"] && !index.count(n)) add_instance(ew["name"], ew["part"]);
    if (!index.count(n)) Fail(file, ew["name"], "end_with names unknown instance '" + n + "'");
    prog.target = index[n];
    if (prog.target == 0) Fail(file, ew["name"], "the target cannot be the environment");
    prog.target_frame = internal::AsFrame(file, ew["frame"], "end_with frame");
    if (ew["match_rotation"]) {
      try {
        prog.target_match_rotation = ew["match_rotation"].as<bool>();
      } catch (const YAML::Exception&) {
        Fail(file, ew["match_rotation"], "match_rotation must be true or false");
      }
    }
  }
  const YAML::Node conns = root["connect"];
  if (!conns || !conns.IsSequence() || conns.size() == 0) Fail(file, conns ? conns : root, "'connect' must be a non-empty list");
  auto ref = [&](const YAML::Node& n, int& inst, std::string& prim) {
    const std::string s = AsString(file, n, "connector reference");
    const auto dot = s.find('.');
    if (dot == std::string::npos) Fail(file, n, "connector '" + s + "' must be instance.primitive");
    const std::string in = s.substr(0, dot);
    prim = s.substr(dot + 1);
    if (!index.count(in)) Fail(file, n, "unknown part instance '" + in + "'");
    inst = index[in];
    if (!prog.PartOf(inst).Find(prim))
      Fail(file, n, "part '" + prog.instances[inst].part + "' has no primitive '" + prim + "'");
  };
  for (const auto& c : conns) {
    if (!c.IsMap() || !c["a"] || !c["b"]) Fail(file, c, "connect entry needs 'a' and 'b'");
    Connection con;
    const auto m = c.Mark();
    con.where = file + ":" + std::to_string(m.line + 1) + ":" + std::to_string(m.column + 1);
    for (const auto& kv : c) {
      const std::string k = kv.first.as<std::string>();
      if (k != "a" && k != "b" && k != "alignment" && k != "is_fixed" && k != "fixed_a" && k != "fixed_b")
        Fail(file, kv.first, "unknown key '" + k + "' in connect");
    }
    ref(c["a"], con.part_a, con.primitive_a);
    ref(c["b"], con.part_b, con.primitive_b);
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
    auto values = [&](const char* key, std::vector<double>& out, const Primitive& p) {
      if (!c[key]) return;
      const YAML::Node v = c[key];
      if (!v.IsSequence() || v.size() != p.Params().size())
        Fail(file, v, std::string(key) + " needs " + std::to_string(p.Params().size()) + " values");
      for (const auto& x : v) out.push_back(internal::AsDouble(file, x, key));
    };
    values("fixed_a", con.fixed_a, prog.PrimitiveA(con));
    values("fixed_b", con.fixed_b, prog.PrimitiveB(con));
    prog.connections.push_back(con);
  }
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
    throw InputError(name + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) + ": " +
                     e.msg);
  }
  return Build(root, name, library_path, mesh_dir);
}

std::string ProgramLibraryPath(const std::string& file) {
  return LibraryPathOf(internal::LoadYamlFile(file), file);
}

}  // namespace fabatlas::assembly

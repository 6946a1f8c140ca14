// Reading prototype YAML (docs/prototype.md).
#include <algorithm>
#include <fstream>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "affine.h"
#include "fabatlas/error.h"
#include "fabatlas/yaml_place.h"
#include "fabatlas/prototype/prototype.h"

namespace fabatlas::prototype {
namespace {

using internal::Affine;

class Reader {
 public:
  Reader(const std::string& file, const std::map<std::string, double>& overrides)
      : file_(file), overrides_(overrides) {}

  std::string Where(const YAML::Node& n) const { return YamlPlace(file_, n.Mark()).str(); }
  [[noreturn]] void Fail(const YAML::Node& n, const std::string& msg) const { FailAt(YamlPlace(file_, n.Mark()), msg); }

  void Keys(const YAML::Node& n, const std::set<std::string>& allowed, const std::string& what) const {
    if (!n.IsMap()) Fail(n, what + " must be a map");
    for (const auto& kv : n) {
      std::string k = kv.first.as<std::string>();
      if (!allowed.count(k)) Fail(kv.first, "unknown key '" + k + "' in " + what);
    }
  }

  std::string Str(const YAML::Node& n, const std::string& what) const {
    if (!n || !n.IsScalar()) Fail(n, what + " must be a string");
    return n.as<std::string>();
  }

  // A number or an expression over parameters.
  double Number(const YAML::Node& n, const std::string& what) const {
    if (!n || !n.IsScalar()) Fail(n, what + " must be a number or an expression over parameters");
    std::string where = Where(n);
    Affine f = internal::ParseAffine(
        n.as<std::string>(),
        [&](const std::string& name) -> Affine {
          auto it = proto_.parameters.find(name);
          if (it == proto_.parameters.end()) throw InputError(where + ": unknown parameter '" + name + "' in " + what);
          return Affine::Const(it->second);
        },
        where);
    if (!std::isfinite(f.c)) Fail(n, what + " is not finite");
    return f.c;
  }

  int Axis(const YAML::Node& n, const std::string& what) const {
    std::string s = Str(n, what);
    if (s == "x") return 0;
    if (s == "y") return 1;
    if (s == "z") return 2;
    Fail(n, what + " must be x, y or z");
  }

  std::vector<std::string> StrList(const YAML::Node& n, const std::string& what) const {
    std::vector<std::string> out;
    if (n.IsScalar()) return {n.as<std::string>()};
    if (!n.IsSequence()) Fail(n, what + " must be a list");
    for (const auto& x : n) out.push_back(Str(x, what));
    return out;
  }

  Cuboid ReadCuboid(const YAML::Node& n, const std::string& name) const {
    Cuboid c;
    c.name = name;
    if (!n || !n.IsSequence() || n.size() != 6)
      Fail(n ? n : YAML::Node(), name + ": box must be [x0, x1, y0, y1, z0, z1]");
    for (int i = 0; i < 6; ++i) c.box[i] = Number(n[i], name + " box");
    for (int i = 0; i < 3; ++i)
      if (c.box[2 * i + 1] <= c.box[2 * i]) Fail(n, name + ": box " + "xyz"[i] + "1 must exceed " + "xyz"[i] + "0");
    return c;
  }

  Prototype Read(const YAML::Node& root) {
    proto_.file = file_;
    Keys(root,
         {"name", "description", "parameters", "fabrication", "parts", "joints", "configurations", "relationships"},
         "a prototype");
    proto_.name = root["name"] ? Str(root["name"], "name") : std::filesystem::path(file_).stem().string();
    if (const auto ps = root["parameters"]) {
      if (!ps.IsMap()) Fail(ps, "parameters must be a map name: value");
      for (const auto& kv : ps) proto_.parameters[kv.first.as<std::string>()] = Number(kv.second, "parameter");
    }
    for (const auto& [k, v] : overrides_) {
      if (!proto_.parameters.count(k)) throw InputError(file_ + ": unknown parameter '" + k + "' to set");
      if (!std::isfinite(v)) throw InputError(file_ + ": parameter '" + k + "' set to a non-finite value");
      proto_.parameters[k] = v;
    }
    if (const auto f = root["fabrication"]) {
      Keys(f, {"voxel", "gap"}, "fabrication");
      if (f["voxel"]) proto_.fabrication.voxel = Number(f["voxel"], "voxel");
      if (f["gap"]) proto_.fabrication.gap = Number(f["gap"], "gap");
      if (proto_.fabrication.voxel <= 0 || proto_.fabrication.gap < 0) Fail(f, "voxel must be > 0 and gap >= 0");
    }
    const auto parts = root["parts"];
    if (!parts || !parts.IsMap() || parts.size() == 0) Fail(parts ? parts : root, "'parts' must be a non-empty map");
    for (const auto& kv : parts) {
      Part part;
      part.name = kv.first.as<std::string>();
      part.where = Where(kv.first);
      if (proto_.PartIndex(part.name) >= 0) Fail(kv.first, "duplicate part '" + part.name + "'");
      if (part.name.find('.') != std::string::npos) Fail(kv.first, "part names cannot contain '.'");
      Keys(kv.second, {"box", "pieces", "cavities", "hold", "min_size"}, "part " + part.name);
      part.cuboid = ReadCuboid(kv.second["box"], part.name);
      if (kv.second["min_size"]) part.min_size = Number(kv.second["min_size"], "min_size");
      if (const auto h = kv.second["hold"])
        for (const std::string& s : StrList(h, "hold")) part.held.push_back(CoordIndex(h, s));
      // Piece and cavity names share the namespace of coordinates and measures.
      std::set<std::string> inner_names{"x0", "x1", "y0", "y1", "z0", "z1", "w", "d", "h", "cx", "cy", "cz"};
      if (const auto ps = kv.second["pieces"]) {
        if (!ps.IsMap()) Fail(ps, "pieces must be a map name: {box, on, align}");
        for (const auto& c : ps) {
          Keys(c.second, {"box", "on", "align", "hold"}, "piece");
          std::string n = c.first.as<std::string>();
          if (!inner_names.insert(n).second)
            Fail(c.first, "piece '" + n + "' of " + part.name + " repeats a name or is a coordinate name");
          Cuboid piece = ReadCuboid(c.second["box"], part.name + "." + n);
          piece.on = part.name;
          if (c.second["on"]) {
            std::string on = Str(c.second["on"], "on");
            bool known = on == part.name;
            for (const Cuboid& q : part.pieces) known |= q.name == part.name + "." + on;
            if (!known)
              Fail(c.second["on"], "piece " + piece.name + ": 'on' must be the part or an earlier piece of it");
            piece.on = on == part.name ? on : part.name + "." + on;
          }
          if (const auto h = c.second["hold"])
            for (const std::string& s : StrList(h, "hold")) piece.held.push_back(CoordIndex(h, s));
          if (const auto a = c.second["align"])
            for (const std::string& s : StrList(a, "align")) piece.align.push_back(CoordIndex(a, s));
          part.pieces.push_back(piece);
        }
      }
      if (const auto cs = kv.second["cavities"]) {
        if (!cs.IsMap()) Fail(cs, "cavities must be a map name: {box, open}");
        for (const auto& c : cs) {
          Keys(c.second, {"box", "open", "hold"}, "cavity");
          if (!inner_names.insert(c.first.as<std::string>()).second)
            Fail(c.first, "cavity '" + c.first.as<std::string>() + "' of " + part.name +
                              " repeats a name or is a coordinate name");
          Cuboid cav = ReadCuboid(c.second["box"], part.name + "." + c.first.as<std::string>());
          if (const auto h = c.second["hold"])
            for (const std::string& s : StrList(h, "hold")) cav.held.push_back(CoordIndex(h, s));
          if (c.second["open"]) {
            cav.open = Str(c.second["open"], "open");
            CoordIndex(c.second["open"], cav.open);
          }
          part.cavities.push_back(cav);
        }
      }
      proto_.parts.push_back(part);
    }
    if (const auto js = root["joints"]) ReadJoints(js);
    proto_.configurations.push_back({"base", {}});
    if (const auto cs = root["configurations"]) ReadConfigurations(cs);
    if (const auto rs = root["relationships"]) ReadRelationships(rs);
    return proto_;
  }

  int CoordIndex(const YAML::Node& n, const std::string& s) const {
    static const std::vector<std::string> names = {"x0", "x1", "y0", "y1", "z0", "z1"};
    for (int i = 0; i < 6; ++i)
      if (names[i] == s) return i;
    Fail(n, "'" + s + "' is not a face/coordinate (x0 x1 y0 y1 z0 z1)");
  }

  void ReadJoints(const YAML::Node& js) {
    if (!js.IsMap()) Fail(js, "joints must be a map name: joint");
    std::set<std::string> children;
    for (const auto& kv : js) {
      Joint j;
      j.name = kv.first.as<std::string>();
      j.where = Where(kv.first);
      const auto n = kv.second;
      Keys(n, {"type", "child", "parent", "axis", "at", "slide_axis", "face", "pivot_child", "pivot_parent", "on"},
           "joint " + j.name);
      std::string type = Str(n["type"], "joint type");
      if (type == "hinge")
        j.type = JointType::kHinge;
      else if (type == "slide")
        j.type = JointType::kSlide;
      else if (type == "sliding_hinge")
        j.type = JointType::kSlidingHinge;
      else if (type == "double_pivot")
        j.type = JointType::kDoublePivot;
      else
        Fail(n["type"], "joint type must be hinge, slide, sliding_hinge or double_pivot");
      j.child = Str(n["child"], "child");
      j.parent = Str(n["parent"], "parent");
      if (proto_.PartIndex(j.child) < 0) Fail(n["child"], "unknown part '" + j.child + "'");
      if (proto_.PartIndex(j.parent) < 0) Fail(n["parent"], "unknown part '" + j.parent + "'");
      if (j.child == j.parent) Fail(n, "a joint needs two different parts");
      if (!children.insert(j.child).second) {
        // Several double pivots (e.g. left and right) may carry one part; the
        // first one's values place it, the others must agree (checked below).
        auto first = std::find_if(proto_.joints.begin(), proto_.joints.end(),
                                  [&](const Joint& k) { return k.child == j.child; });
        if (first->type != JointType::kDoublePivot || j.type != JointType::kDoublePivot || first->parent != j.parent)
          Fail(n["child"],
               "part '" + j.child + "' already has a parent joint (only double pivots to one parent may share a part)");
      }
      if (j.type == JointType::kDoublePivot) {
        j.face = Str(n["face"], "face");
        int c = CoordIndex(n["face"], j.face);
        j.normal = c / 2;
        for (int k = 0; k < 2; ++k) {
          if (n["pivot_child"]) j.pivot_child[k] = Number(n["pivot_child"][k], "pivot_child");
          if (n["pivot_parent"]) j.pivot_parent[k] = Number(n["pivot_parent"][k], "pivot_parent");
        }
      } else {
        j.axis = Axis(n["axis"], "axis");
      }
      if (j.type == JointType::kHinge || j.type == JointType::kSlidingHinge) {
        const auto at = n["at"];
        if (!at || !at.IsSequence() || at.size() != 2) Fail(at ? at : n, "'at' must list the edge's two coordinates");
        for (const auto& e : at) j.at.push_back(StrList(e, "at"));
      }
      if (n["on"]) {
        if (j.type != JointType::kSlide) Fail(n["on"], "'on' (rail faces) is for slide joints");
        j.on = StrList(n["on"], "on");
        if (j.on.size() != 2) Fail(n["on"], "'on' must be [child face, parent face]");
        std::string f[2];
        for (int k = 0; k < 2; ++k) {
          auto dot = j.on[k].rfind('.');
          std::string owner = dot == std::string::npos ? "" : j.on[k].substr(0, dot);
          f[k] = dot == std::string::npos ? "" : j.on[k].substr(dot + 1);
          std::string part = owner.substr(0, owner.find('.'));
          if (part != (k ? j.parent : j.child))
            Fail(n["on"], "rail face '" + j.on[k] + "' must be a face of " + (k ? j.parent : j.child));
          CoordIndex(n["on"], f[k]);
        }
        // A part's face looks away from the part, a cavity's into the cavity.
        std::string owner = j.on[1].substr(0, j.on[1].rfind('.'));
        bool cavity = false;
        for (const Cuboid& c : proto_.parts[proto_.PartIndex(j.parent)].cavities) cavity |= c.name == owner;
        if (f[0][0] != f[1][0] || (f[0] == f[1]) != cavity)
          Fail(n["on"], "rail faces " + j.on[0] + " and " + j.on[1] + " must face each other on one axis");
        if (f[0][0] - 'x' == j.axis) Fail(n["on"], "rail faces must be parallel to the slide axis");
      }
      if (j.type == JointType::kSlidingHinge) {
        j.slide_axis = Axis(n["slide_axis"], "slide_axis");
        if (j.slide_axis == j.axis) Fail(n["slide_axis"], "slide_axis must differ from axis");
      }
      proto_.joints.push_back(j);
    }
    // No cycles: following parents must end.
    for (const Joint& j : proto_.joints) {
      std::string p = j.parent;
      for (std::size_t step = 0; step <= proto_.joints.size(); ++step) {
        auto it =
            std::find_if(proto_.joints.begin(), proto_.joints.end(), [&](const Joint& k) { return k.child == p; });
        if (it == proto_.joints.end()) break;
        if (step == proto_.joints.size()) throw InputError(j.where + ": joints form a cycle");
        p = it->parent;
      }
    }
  }

  void ReadConfigurations(const YAML::Node& cs) {
    if (!cs.IsMap()) Fail(cs, "configurations must be a map name: {joint: value}");
    for (const auto& kv : cs) {
      Configuration c;
      c.name = kv.first.as<std::string>();
      if (c.name == "base") Fail(kv.first, "'base' is the configuration with every joint at 0; it cannot be redefined");
      if (!kv.second.IsMap()) Fail(kv.second, "configuration " + c.name + " must be a map joint: value");
      for (const auto& jv : kv.second) {
        std::string jn = jv.first.as<std::string>();
        auto it =
            std::find_if(proto_.joints.begin(), proto_.joints.end(), [&](const Joint& j) { return j.name == jn; });
        if (it == proto_.joints.end()) Fail(jv.first, "unknown joint '" + jn + "'");
        c.values[jn] = ReadValue(*it, jv.second);
      }
      for (const Joint& j : proto_.joints) {
        auto first = std::find_if(proto_.joints.begin(), proto_.joints.end(),
                                  [&](const Joint& k) { return k.child == j.child; });
        if (first->name == j.name) continue;
        auto a = c.values.find(first->name), b = c.values.find(j.name);
        bool same = (a == c.values.end()) == (b == c.values.end());
        if (same && a != c.values.end())
          same = a->second.angle == b->second.angle && a->second.offset == b->second.offset &&
                 a->second.offset_free == b->second.offset_free;
        if (!same)
          Fail(kv.first, "configuration " + c.name + ": joints " + first->name + " and " + j.name +
                             " carry the same part and need the same value");
      }
      proto_.configurations.push_back(c);
    }
  }

  JointValue ReadValue(const Joint& j, const YAML::Node& n) {
    JointValue v;
    auto slide = [&](const YAML::Node& s) {
      std::string t = Str(s, "slide");
      if (t == "free")
        v.slide = "free";
      else
        v.slide = t;
    };
    switch (j.type) {
      case JointType::kHinge:
        v.angle = Number(n, "hinge angle");
        break;
      case JointType::kSlide:
        if (n.IsMap()) {
          Keys(n, {"free", "guess"}, "slide value");
          v.slide = "free";
          if (n["guess"]) v.slide_guess = Number(n["guess"], "guess");
        } else {
          slide(n);
        }
        break;
      case JointType::kSlidingHinge:
        Keys(n, {"angle", "slide", "guess"}, "sliding hinge value");
        v.angle = Number(n["angle"], "angle");
        if (n["slide"]) slide(n["slide"]);
        if (n["guess"]) v.slide_guess = Number(n["guess"], "guess");
        break;
      case JointType::kDoublePivot:
        Keys(n, {"angle", "offset", "free"}, "double pivot value");
        v.angle = Number(n["angle"], "angle");
        if (n["offset"]) {
          if (!n["offset"].IsSequence() || n["offset"].size() != 3) Fail(n["offset"], "offset must be [x, y, z]");
          for (int i = 0; i < 3; ++i) v.offset[i] = Number(n["offset"][i], "offset");
        }
        v.offset_free = n["free"] ? n["free"].as<bool>() : true;
        break;
    }
    return v;
  }

  void ReadRelationships(const YAML::Node& rs) {
    if (!rs.IsSequence()) Fail(rs, "relationships must be a list");
    int index = 0;
    for (const auto& n : rs) {
      ++index;
      Relationship r;
      r.where = Where(n);
      Keys(n,
           {"type", "name", "in", "covering", "covered", "just", "inner", "outer", "axes", "pairs", "min_overlap",
            "faces", "expression"},
           "relationship");
      std::string type = Str(n["type"], "relationship type");
      r.name = n["name"] ? Str(n["name"], "name") : type + " #" + std::to_string(index);
      if (n["in"]) {
        r.configuration = Str(n["in"], "in");
        bool known = false;
        for (const auto& c : proto_.configurations) known |= c.name == r.configuration;
        if (!known) Fail(n["in"], "unknown configuration '" + r.configuration + "'");
      }
      if (type == "cover") {
        r.type = RelationType::kCover;
        r.a = StrList(n["covering"], "covering");
        r.b = StrList(n["covered"], "covered");
        if (n["just"] && n["just"].as<bool>()) r.just = {"true"};
      } else if (type == "fit") {
        r.type = RelationType::kFit;
        r.a = StrList(n["inner"], "inner");
        r.b = {Str(n["outer"], "outer")};
        if (n["just"]) r.just = StrList(n["just"], "just");
        for (const auto& s : r.just) CoordIndex(n["just"], s);
        if (n["axes"]) {
          r.axes.clear();
          for (const auto& s : StrList(n["axes"], "axes"))
            r.axes.push_back(s == "x" ? 0 : s == "y" ? 1 : s == "z" ? 2 : -1);
          for (int a : r.axes)
            if (a < 0) Fail(n["axes"], "axes must be x, y or z");
        }
      } else if (type == "support") {
        r.type = RelationType::kSupport;
        const auto ps = n["pairs"];
        if (!ps || !ps.IsSequence()) Fail(n, "support needs pairs: [[supporting face, supported face], ...]");
        for (const auto& p : ps) {
          if (!p.IsSequence() || p.size() != 2) Fail(p, "a support pair is [supporting face, supported face]");
          r.pairs.push_back({Str(p[0], "face"), Str(p[1], "face")});
        }
        if (n["min_overlap"]) r.min_overlap = Number(n["min_overlap"], "min_overlap");
      } else if (type == "flush") {
        r.type = RelationType::kFlush;
        r.a = StrList(n["faces"], "faces");
        if (r.a.size() != 2) Fail(n["faces"], "flush needs two faces");
      } else if (type == "geometric") {
        r.type = RelationType::kGeometric;
        r.expression = Str(n["expression"], "expression");
      } else {
        Fail(n["type"], "relationship type must be cover, fit, support, flush or geometric");
      }
      proto_.relationships.push_back(r);
    }
  }

 private:
  std::string file_;
  std::map<std::string, double> overrides_;
  Prototype proto_;
};

}  // namespace

int Prototype::PartIndex(const std::string& n) const {
  for (std::size_t i = 0; i < parts.size(); ++i)
    if (parts[i].name == n) return static_cast<int>(i);
  return -1;
}

Prototype ParsePrototype(const std::string& text, const std::string& file,
                         const std::map<std::string, double>& overrides) {
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    FailAt(YamlPlace(file, e.mark), e.msg);
  }
  try {
    return Reader(file, overrides).Read(root);
  } catch (const YAML::Exception& e) {
    FailAt(YamlPlace(file, e.mark), e.msg);
  }
}

Prototype LoadPrototype(const std::filesystem::path& path, const std::map<std::string, double>& overrides) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  return ParsePrototype(ss.str(), path.string(), overrides);
}

}  // namespace fabatlas::prototype

// OpenSCAD's built-in modules as evaluate_model.h implements them
// (builtin_modules.h): primitives, transformations, colour, booleans
// and the 2-D operations and extrusions, each node's head written as
// OpenSCAD 2021.01's .csg export writes it.
#include "builtin_modules.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <string>
#include <string_view>
#include <utility>

#include "colours.h"
#include "value.h"

namespace fabatlas::scad::internal {
namespace {

using Arguments = std::map<std::string, Value>;

// The special variable `name` of scope, or fallback when unset.
double Special(const Scope& scope, const char* name, double fallback) {
  const Value* v = scope.Find(name);
  if (!v) return fallback;
  if (!v->IsNumber()) throw NotNative{0, std::string(name) + " is not a number"};
  return v->number;
}

// "$fn = .., $fa = .., $fs = .." as OpenSCAD writes them (with its lower
// bounds of $fa and $fs).
std::string Fragments(const Scope& scope) {
  const double fn = Special(scope, "$fn", 0), fa = std::max(Special(scope, "$fa", 12), 0.01),
               fs = std::max(Special(scope, "$fs", 2), 0.01);
  return "$fn = " + Num(fn) + ", $fa = " + Num(fa) + ", $fs = " + Num(fs);
}

// multmatrix([[..], [..], [..], [..]]) of a 4x4 matrix.
std::string Matrix(const double m[4][4]) {
  std::string out = "multmatrix([";
  for (int r = 0; r < 4; ++r) {
    out += r ? ", [" : "[";
    for (int c = 0; c < 4; ++c) out += (c ? ", " : "") + ValueNum(m[r][c]);
    out += "]";
  }
  return out + "])";
}

// A vector of 2 or 3 finite numbers (z defaults to `z`), or false.
bool Vec3(const Value& v, double out[3], double z) {
  if (!AllNumbers(v) || v.Items().size() < 2 || v.Items().size() > 3) return false;
  out[0] = v.Items()[0].number;
  out[1] = v.Items()[1].number;
  out[2] = v.Items().size() == 3 ? v.Items()[2].number : z;
  return std::isfinite(out[0]) && std::isfinite(out[1]) && std::isfinite(out[2]);
}

// One instantiation of a built-in module and what every module reads of it.
class ModuleCall {
 public:
  ModuleCall(Evaluator& evaluator, const Stmt& s, const Scope& scope, Scope& call, std::vector<CsgOut>& out)
      : evaluator_(evaluator), s_(s), scope_(scope), call_(call), out_(out) {}

  const std::string& Name() const { return s_.name; }
  int Line() const { return s_.line; }
  [[noreturn]] void Decline(const std::string& what) const { throw NotNative{s_.line, what}; }
  [[noreturn]] void Refuse(const std::string& what) const { throw BadModel{s_.line, what}; }

  // The arguments matched to `names`; $-arguments go to the children's scope.
  Arguments Match(const std::vector<std::string>& names) {
    auto args = evaluator_.Match(s_.bindings, names, scope_, s_.line, &specials_);
    for (auto& [k, v] : specials_) call_.vars[k] = v;
    return args;
  }
  // A node without children (empty blocks allowed, as OpenSCAD allows them).
  void Leaf(std::string head) {
    if (!s_.children.empty()) {
      for (const StmtPtr& c : s_.children)
        if (c->kind != Stmt::Kind::kBlock || !c->children.empty()) Decline(s_.name + "() with children");
    }
    out_.push_back({std::move(head), {}});
  }
  // A node over the instantiation's children.
  void Node(std::string head) { out_.push_back({std::move(head), evaluator_.Children(s_, call_)}); }
  // $fn, $fa, $fs of the children's scope, as OpenSCAD writes them.
  std::string Fragments() const { return internal::Fragments(call_); }

  // Argument `name` as a boolean: false when not given or not a boolean
  // (OpenSCAD 2021.01 takes `center`, `cut` and `chamfer` only as booleans:
  // `center = 1` or `center = [0, 0]` is false, as MCAD's nutHole passes it).
  static bool Boolean(const Arguments& args, const char* name) {
    auto it = args.find(name);
    return it != args.end() && it->second.kind == Value::Kind::kBool && it->second.boolean;
  }
  // Whether argument `name` was given (and is not undef).
  static bool Given(const Arguments& args, const char* name) {
    auto it = args.find(name);
    return it != args.end() && it->second.kind != Value::Kind::kUndef;
  }
  // Argument `name` as a finite number, fallback when not given.
  double Number(const Arguments& args, const char* name, double fallback) const {
    auto it = args.find(name);
    if (it == args.end() || it->second.kind == Value::Kind::kUndef) return fallback;
    if (!it->second.IsNumber() || !std::isfinite(it->second.number))
      Decline(std::string("'") + name + "' not a finite number");
    return it->second.number;
  }

 private:
  Evaluator& evaluator_;
  const Stmt& s_;
  const Scope& scope_;
  Scope& call_;
  std::vector<CsgOut>& out_;
  Arguments specials_;
};

using BuiltinModule = void (*)(ModuleCall&);

// ---------------------------------------------------------------- primitives

void Cube(ModuleCall& m) {
  auto args = m.Match({"size", "center"});
  double size[3] = {1, 1, 1};
  if (ModuleCall::Given(args, "size")) {
    const Value& v = args["size"];
    if (v.IsNumber())
      size[0] = size[1] = size[2] = v.number;
    else if (!AllNumbers(v) || v.Items().size() != 3)
      m.Decline("cube size not a number or 3 numbers");
    else
      for (int k = 0; k < 3; ++k) size[k] = v.Items()[k].number;
  }
  m.Leaf("cube(size = [" + Num(size[0]) + ", " + Num(size[1]) + ", " + Num(size[2]) +
         "], center = " + (m.Boolean(args, "center") ? "true" : "false") + ")");
}

// sphere() and circle().
void Round(ModuleCall& m) {
  auto args = m.Match({"r", "d"});
  double r = m.Number(args, "r", 1);
  if (ModuleCall::Given(args, "d")) r = m.Number(args, "d", 2) / 2;
  m.Leaf(m.Name() + "(" + m.Fragments() + ", r = " + Num(r) + ")");
}

void Cylinder(ModuleCall& m) {
  auto args = m.Match({"h", "r1", "r2", "center", "r", "d", "d1", "d2"});
  const double h = m.Number(args, "h", 1);
  double r1 = 1, r2 = 1;
  if (ModuleCall::Given(args, "r")) r1 = r2 = m.Number(args, "r", 1);
  if (ModuleCall::Given(args, "d")) r1 = r2 = m.Number(args, "d", 2) / 2;
  if (ModuleCall::Given(args, "r1")) r1 = m.Number(args, "r1", 1);
  if (ModuleCall::Given(args, "d1")) r1 = m.Number(args, "d1", 2) / 2;
  if (ModuleCall::Given(args, "r2")) r2 = m.Number(args, "r2", 1);
  if (ModuleCall::Given(args, "d2")) r2 = m.Number(args, "d2", 2) / 2;
  m.Leaf("cylinder(" + m.Fragments() + ", h = " + Num(h) + ", r1 = " + Num(r1) + ", r2 = " + Num(r2) +
         ", center = " + (m.Boolean(args, "center") ? "true" : "false") + ")");
}

void Square(ModuleCall& m) {
  auto args = m.Match({"size", "center"});
  double size[2] = {1, 1};
  if (ModuleCall::Given(args, "size")) {
    const Value& v = args["size"];
    if (v.IsNumber())
      size[0] = size[1] = v.number;
    else if (!AllNumbers(v) || v.Items().size() != 2)
      m.Decline("square size not a number or 2 numbers");
    else
      for (int k = 0; k < 2; ++k) size[k] = v.Items()[k].number;
  }
  m.Leaf("square(size = [" + Num(size[0]) + ", " + Num(size[1]) +
         "], center = " + (m.Boolean(args, "center") ? "true" : "false") + ")");
}

void Polygon(ModuleCall& m) {
  auto args = m.Match({"points", "paths", "convexity"});
  if (!args["points"].IsVector()) m.Decline("polygon points not a vector");
  m.Leaf("polygon(points = " + Write(args["points"], m.Line()) + ", paths = " + Write(args["paths"], m.Line()) +
         ", convexity = " + Num(std::trunc(m.Number(args, "convexity", 1))) + ")");
}

void Polyhedron(ModuleCall& m) {
  auto args = m.Match({"points", "faces", "convexity", "triangles"});
  if (ModuleCall::Given(args, "triangles") && !ModuleCall::Given(args, "faces"))
    args["faces"] = args["triangles"];  // deprecated name
  if (!args["points"].IsVector() || !args["faces"].IsVector()) m.Decline("polyhedron without points and faces");
  m.Leaf("polyhedron(points = " + Write(args["points"], m.Line()) + ", faces = " + Write(args["faces"], m.Line()) +
         ", convexity = " + Num(std::trunc(m.Number(args, "convexity", 1))) + ")");
}

// ASCII text; direction, language and script as OpenSCAD fills them for
// ASCII text (script "Latn" when a letter names it, none for digits and
// signs).
void Text(ModuleCall& m) {
  auto args = m.Match({"text", "size", "font", "direction", "language", "script", "halign", "valign", "spacing"});
  const int line = m.Line();
  auto text = [&](const char* name, const char* fallback) {
    auto it = args.find(name);
    if (it == args.end() || it->second.kind == Value::Kind::kUndef) return std::string(fallback);
    if (it->second.kind != Value::Kind::kString) m.Decline(std::string("text '") + name + "' not a string");
    return it->second.text;
  };
  auto Latin = [](const std::string& t) {
    return std::any_of(t.begin(), t.end(), [](char ch) { return std::isalpha(static_cast<unsigned char>(ch)) != 0; });
  };
  if (ModuleCall::Given(args, "direction") || ModuleCall::Given(args, "language") || ModuleCall::Given(args, "script"))
    m.Decline("text direction, language or script");
  m.Leaf("text(text = " + Quote(text("text", ""), line) + ", size = " + Num(m.Number(args, "size", 10)) +
         ", spacing = " + Num(m.Number(args, "spacing", 1)) + ", font = " + Quote(text("font", ""), line) +
         ", direction = \"ltr\", language = \"en\", " + (Latin(text("text", "")) ? "script = \"Latn\", " : "") +
         "halign = " + Quote(text("halign", "left"), line) + ", valign = " + Quote(text("valign", "baseline"), line) +
         ", " + m.Fragments() + ")");
}

// ---------------------------------------------------------------- transformations

// The identity, as each transformation starts.
struct Matrix4 {
  double m[4][4] = {{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}};
};

void Translate(ModuleCall& m) {
  auto args = m.Match({"v"});
  Matrix4 t;
  double v[3];
  if (!Vec3(args["v"], v, 0)) m.Decline("translate by a non-vector");
  for (int k = 0; k < 3; ++k) t.m[k][3] = v[k];
  m.Node(Matrix(t.m));
}

void Scale(ModuleCall& m) {
  auto args = m.Match({"v"});
  Matrix4 t;
  double v[3];
  if (args["v"].IsNumber())
    v[0] = v[1] = v[2] = args["v"].number;
  else if (!Vec3(args["v"], v, 1))
    m.Decline("scale by a non-vector");
  for (int k = 0; k < 3; ++k) t.m[k][k] = v[k];
  m.Node(Matrix(t.m));
}

void Mirror(ModuleCall& m) {
  auto args = m.Match({"v"});
  Matrix4 t;
  double v[3];
  if (!Vec3(args["v"], v, 0)) m.Decline("mirror in a non-vector");
  const double l2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  if (l2 > 0)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) t.m[r][c] -= 2 * v[r] * v[c] / l2;
  m.Node(Matrix(t.m));
}

// rotate([x, y, z]): about x, then y, then z, in OpenSCAD's exact degrees.
void EulerRotation(ModuleCall& m, const Value& a, Matrix4& t) {
  if (!AllNumbers(a) || a.Items().empty() || a.Items().size() > 3) m.Decline("rotate by a malformed vector");
  double ang[3] = {0, 0, 0};
  for (std::size_t k = 0; k < a.Items().size(); ++k) ang[k] = a.Items()[k].number;
  const double sx = SinDegrees(ang[0]), cx = CosDegrees(ang[0]), sy = SinDegrees(ang[1]), cy = CosDegrees(ang[1]),
               sz = SinDegrees(ang[2]), cz = CosDegrees(ang[2]);
  const double r[3][3] = {{cy * cz, cz * sx * sy - cx * sz, cx * cz * sy + sx * sz},
                          {cy * sz, cx * cz + sx * sy * sz, -cz * sx + cx * sy * sz},
                          {-sy, cy * sx, cx * cy}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) t.m[i][j] = r[i][j];
}

// rotate(a, v): Rodrigues' formula with OpenSCAD's exact degrees; a zero
// axis leaves the children unrotated, as OpenSCAD does.
void AxisRotation(double degrees, double axis[3], Matrix4& t) {
  const double l = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  if (l == 0) return;
  for (int k = 0; k < 3; ++k) axis[k] /= l;
  const double c = CosDegrees(degrees), sn = SinDegrees(degrees), s = 1 - c;
  const double x = axis[0], y = axis[1], z = axis[2];
  const double r[3][3] = {{s * x * x + c, s * x * y - sn * z, s * x * z + sn * y},
                          {s * x * y + sn * z, s * y * y + c, s * y * z - sn * x},
                          {s * x * z - sn * y, s * y * z + sn * x, s * z * z + c}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) t.m[i][j] = r[i][j];
}

void Rotate(ModuleCall& m) {
  auto args = m.Match({"a", "v"});
  const Value& a = args["a"];
  Matrix4 t;
  if (a.IsVector()) {
    if (ModuleCall::Given(args, "v")) m.Decline("rotate by a vector about an axis");
    EulerRotation(m, a, t);
  } else {
    if (!a.IsNumber()) m.Decline("rotate by a non-number");
    double axis[3] = {0, 0, 1};
    if (ModuleCall::Given(args, "v") && !Vec3(args["v"], axis, 0)) m.Decline("rotate about a non-vector");
    AxisRotation(a.number, axis, t);
  }
  m.Node(Matrix(t.m));
}

void Multmatrix(ModuleCall& m) {
  auto args = m.Match({"m"});
  const Value& v = args["m"];
  Matrix4 t;
  if (!v.IsVector() || v.Items().size() < 3 || v.Items().size() > 4) m.Decline("multmatrix of a malformed matrix");
  for (std::size_t r = 0; r < v.Items().size(); ++r) {
    const Value& row = v.Items()[r];
    if (!AllNumbers(row) || row.Items().size() != 4) m.Decline("multmatrix of a malformed matrix");
    for (int c = 0; c < 4; ++c) t.m[r][c] = row.Items()[c].number;
  }
  m.Node(Matrix(t.m));
}

// A colour by name (colours.h) or as 3 or 4 numbers, alpha apart.
void Color(ModuleCall& m) {
  auto args = m.Match({"c", "alpha"});
  const Value& c = args["c"];
  double rgba[4] = {0, 0, 0, 1};
  if (c.kind == Value::Kind::kString) {
    // OpenSCAD warns "Unable to parse color" and draws the default colour;
    // the designer meant a colour, so it is the model's error here.
    if (!ColourByName(c.text, rgba)) m.Refuse(UnknownColourText(c.text));
  } else {
    if (!AllNumbers(c) || c.Items().size() < 3 || c.Items().size() > 4) m.Decline("colour malformed");
    for (std::size_t k = 0; k < c.Items().size(); ++k) rgba[k] = c.Items()[k].number;
  }
  if (ModuleCall::Given(args, "alpha")) rgba[3] = m.Number(args, "alpha", 1);
  m.Node("color([" + Num(rgba[0]) + ", " + Num(rgba[1]) + ", " + Num(rgba[2]) + ", " + Num(rgba[3]) + "])");
}

// ---------------------------------------------------------------- operations

// union, difference, intersection, hull, group: no arguments.
void Operation(ModuleCall& m) {
  m.Match({});
  m.Node(m.Name() + "()");
}

void Offset(ModuleCall& m) {
  auto args = m.Match({"r", "delta", "chamfer"});
  std::string head;
  if (ModuleCall::Given(args, "r") && !ModuleCall::Given(args, "delta")) {
    head = "offset(r = " + Num(m.Number(args, "r", 1));
  } else if (ModuleCall::Given(args, "delta") && !ModuleCall::Given(args, "r")) {
    head = "offset(delta = " + Num(m.Number(args, "delta", 1)) +
           ", chamfer = " + (m.Boolean(args, "chamfer") ? "true" : "false");
  } else {
    m.Decline("offset without exactly one of r and delta");
  }
  m.Node(head + ", " + m.Fragments() + ")");
}

void Projection(ModuleCall& m) {
  auto args = m.Match({"cut", "convexity"});
  m.Node(std::string("projection(cut = ") + (m.Boolean(args, "cut") ? "true" : "false") +
         ", convexity = " + Num(std::trunc(m.Number(args, "convexity", 0))) + ")");
}

void Render(ModuleCall& m) {
  auto args = m.Match({"convexity"});
  m.Node("render(convexity = " + Num(std::trunc(m.Number(args, "convexity", 1))) + ")");
}

void LinearExtrude(ModuleCall& m) {
  auto args = m.Match({"height", "center", "convexity", "twist", "slices", "scale"});
  double height = std::max(m.Number(args, "height", 100), 0.0);
  double convexity = std::trunc(m.Number(args, "convexity", 0));
  if (convexity <= 0) convexity = 1;
  double scale[2] = {1, 1};
  if (ModuleCall::Given(args, "scale")) {
    const Value& v = args["scale"];
    if (v.IsNumber())
      scale[0] = scale[1] = v.number;
    else if (!AllNumbers(v) || v.Items().size() != 2)
      m.Decline("linear_extrude scale malformed");
    else
      scale[0] = v.Items()[0].number, scale[1] = v.Items()[1].number;
  }
  scale[0] = std::max(scale[0], 0.0);
  scale[1] = std::max(scale[1], 0.0);
  std::string head = "linear_extrude(height = " + Num(height) +
                     ", center = " + (m.Boolean(args, "center") ? "true" : "false") + ", convexity = " + Num(convexity);
  const double twist = m.Number(args, "twist", 0);
  if (twist != 0) head += ", twist = " + Num(twist);
  const bool has_slices = ModuleCall::Given(args, "slices");
  if (has_slices) head += ", slices = " + Num(std::max(std::trunc(m.Number(args, "slices", 1)), 1.0));
  head += ", scale = [" + Num(scale[0]) + ", " + Num(scale[1]) + "]";
  if (!has_slices) head += ", " + m.Fragments();
  m.Node(head + ")");
}

void RotateExtrude(ModuleCall& m) {
  auto args = m.Match({"angle", "convexity"});
  double angle = m.Number(args, "angle", 360);
  if (angle <= -360 || angle > 360) angle = 360;
  double convexity = std::trunc(m.Number(args, "convexity", 0));
  if (convexity <= 0) convexity = 2;
  m.Node("rotate_extrude(angle = " + Num(angle) + ", convexity = " + Num(convexity) + ", " + m.Fragments() + ")");
}

const std::map<std::string_view, BuiltinModule> kModules = {
    {"cube", Cube},
    {"sphere", Round},
    {"circle", Round},
    {"cylinder", Cylinder},
    {"square", Square},
    {"polygon", Polygon},
    {"polyhedron", Polyhedron},
    {"text", Text},
    {"translate", Translate},
    {"scale", Scale},
    {"mirror", Mirror},
    {"rotate", Rotate},
    {"multmatrix", Multmatrix},
    {"color", Color},
    {"union", Operation},
    {"difference", Operation},
    {"intersection", Operation},
    {"hull", Operation},
    {"group", Operation},
    {"offset", Offset},
    {"projection", Projection},
    {"render", Render},
    {"linear_extrude", LinearExtrude},
    {"rotate_extrude", RotateExtrude},
};

}  // namespace

void CallBuiltinModule(Evaluator& evaluator, const Stmt& s, const Scope& scope, Scope& call, std::vector<CsgOut>& out) {
  auto it = kModules.find(s.name);
  if (it == kModules.end()) throw NotNative{s.line, "module " + s.name + "()"};
  ModuleCall m(evaluator, s, scope, call, out);
  it->second(m);
}

}  // namespace fabatlas::scad::internal

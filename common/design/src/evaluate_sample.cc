// EvaluateSample (Fab Forms Alg. 2) and ΔG (Eq. 2).
#include "fabatlas/exact_decimal.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/design/resolve_collisions.h"
#include "fabatlas/design/state_graph.h"

#include <cmath>
#include <fstream>
#include <mutex>
#include <optional>
#include <sstream>

#include "assembly_node.h"
#include "checks.h"
#include "expression.h"
#include "fabatlas/error.h"
#include "fabatlas/stopwatch.h"
#include "fabatlas/scad/customizer.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/raw_mesh.h"
#include "fabatlas/mesh/surface_area.h"
#include "fabatlas/sha256.h"
#include "node_schema.h"
#include "openscad_node.h"
#include "operations.h"
#include "reconfigurable.h"
#include "fabatlas/swept/swept_volume.h"

namespace fabatlas::design {
namespace {

// A plain value OpenSCAD reads as a number or boolean (else it is a string).
bool IsScadNumberOrBoolean(const std::string& s) {
  if (s == "true" || s == "false") return true;
  char* end = nullptr;
  double v = std::strtod(s.c_str(), &end);
  return !s.empty() && end == s.c_str() + s.size() && std::isfinite(v) &&
         s.find_first_not_of("0123456789.-+eE") == std::string::npos;
}

// Digest of a file's bytes, remembered per path for the process lifetime.
std::string FileDigest(const std::filesystem::path& p) {
  static std::mutex mutex;
  static std::map<std::string, std::string> digests;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = digests.find(p.string());
  if (it != digests.end()) return it->second;
  std::ifstream in(p, std::ios::binary);
  if (!in) throw InputError(p.string() + ": cannot read file");
  std::stringstream ss;
  ss << in.rdbuf();
  return digests[p.string()] = Sha256Hex(ss.str());
}

// The OpenSCAD literal a `set` entry of an openscad node passes: the value
// its `choices` list holds at index `value` (quoted YAML scalars as OpenSCAD
// strings, plain ones as written), else the number.
std::string OpenScadLiteral(const Node& node, const std::string& key, double value, const SourcePlace& place) {
  auto c = node.args.find("choices");
  if (c != node.args.end()) {
    for (std::size_t i = 0; i < c->second.keys.size(); ++i) {
      if (c->second.keys[i] != key) continue;
      const auto& options = c->second.items[i].items;
      if (value != std::round(value) || value < 0 || value >= static_cast<double>(options.size()))
        throw SampleFailure(kNoGeometry, place.str() + ": '" + key + "' = " + ExactDecimal(value) +
                                             " is not an index of its " + std::to_string(options.size()) + " choices");
      const Argument& chosen = options[static_cast<std::size_t>(value)];
      return chosen.quoted || !IsScadNumberOrBoolean(chosen.text) ? scad::QuoteScadString(chosen.text) : chosen.text;
    }
  }
  return scad::FormatScadNumber(value);
}

// Evaluates the operation tree bottom-up, keying every subtree by (τ, ρ).
class TreeEvaluation {
 public:
  TreeEvaluation(const Design& d, Scope& scope, const EvaluateOptions& options, std::vector<SubtreeRecord>& records)
      : design_(d), scope_(scope), options_(options), records_(&records) {
    grid_.voxel_size = d.voxel_size;
  }

  struct Result {
    geometry::Solid solid;
    std::string key, tau;
  };

  // An object of a reconfigurable in its body frame, evaluated once per sample.
  Result EvaluateObject(const std::string& name) {
    auto it = objects_.find(name);
    if (it != objects_.end()) return it->second;
    const DesignObject* object = design_.FindObject(name);
    Result r = Evaluate(object->tree, "object:" + name);
    objects_[name] = r;
    return r;
  }

  const geometry::GridSpec& grid() const { return grid_; }

  // The design's first `assembly` node (depth first) solved at this sample.
  std::shared_ptr<const AssemblyOutcome> Assembly() {
    const Node* found = nullptr;
    std::vector<const Node*> stack{&design_.tree};
    while (!stack.empty() && !found) {
      const Node* n = stack.back();
      stack.pop_back();
      if (n->op == "assembly") found = n;
      for (auto it = n->children.rbegin(); it != n->children.rend(); ++it) stack.push_back(&*it);
    }
    if (!found) throw DesignFault(design_.file.string() + ": assembly checks need an 'assembly' node in the tree");
    return SolveAssemblyNode(Resolve(*found), *found, design_.file.parent_path());
  }

  // Meshes from outside fabatlas met while evaluating (for `watertight`).
  const std::vector<OutsideMesh>& Outside() const { return outside_; }
  const std::vector<std::string>& Warnings() const { return warnings_; }

  // Where subtree records go from now on.
  void RecordInto(std::vector<SubtreeRecord>* records) { records_ = records; }

  // The transitions' motions at this sample (resolved once).
  const std::vector<ResolvedTransition>& Transitions() {
    if (!transitions_) transitions_ = ResolveTransitions(design_, scope_);
    return *transitions_;
  }

  // The key and topology of a subtree and its children's keys, computed from the
  // resolved arguments alone (no geometry); memoised per node.
  struct Identity {
    std::string key, topology;  // topology = SHA-256 of τ, as Result::tau
    std::vector<std::string> children;
  };
  const Identity& IdentityOf(const Node& node) {
    // An object node is its object's tree (as in Evaluate).
    if (node.op == "object") return IdentityOf(design_.FindObject(node.args.at("object").text)->tree);
    auto it = identities_.find(&node);
    if (it != identities_.end()) return it->second;
    ResolvedArgs args = Resolve(node);
    std::vector<const Identity*> kids;
    for (const Node& child : node.children) kids.push_back(&IdentityOf(child));
    Identity id;
    std::string tau = node.op + "(";
    for (const auto& [name, _] : node.args) tau += name + ",";
    for (const auto* c : kids) tau += c->topology + ";";
    tau += ")";
    std::string rho = "voxel=" + ExactDecimal(design_.voxel_size) + ";" + args.Canonical();
    for (const auto* c : kids) rho += "child=" + c->key + ";";
    if (node.op == "carve_swept") {  // the same extras as Evaluate
      const Identity& moving = IdentityOf(design_.FindObject(args.Text("moving"))->tree);
      const ResolvedTransition* transition = nullptr;
      for (const auto& t : Transitions())
        if (t.name == args.Text("transition")) transition = &t;
      tau += "[moving:" + moving.topology + "]";
      rho +=
          "moving=" + moving.key + ";motion=" + transition->canonical[ObjectIndex(design_, args.Text("moving"))] + ";";
      if (!args.Text("frame").empty())
        rho += "frame_motion=" + transition->canonical[ObjectIndex(design_, args.Text("frame"))] + ";";
    }
    id.key = Sha256Hex(tau + "|" + rho);
    id.topology = Sha256Hex(tau);
    for (const auto* c : kids) id.children.push_back(c->key);
    return identities_.emplace(&node, std::move(id)).first->second;
  }

  // What a hit's trace brings (openscad_node.h, SubtreeTrace): the outside
  // meshes of its subtree and, for an `openscad` node (whose one child, its
  // CSG root, is known only once OpenSCAD has run), the child it had when
  // computed in `record` and, when `records` is not null, the records of the
  // CSG subtrees below it.
  void Recall(const Node& node, const CachedSubtree& hit, const std::string& path, SubtreeRecord& record,
              std::vector<SubtreeRecord>* records) {
    if (!hit.trace) return;
    if (node.op == "openscad" && !hit.trace->op.empty()) {
      record.children = hit.trace->children;
      if (records) AppendDescendantRecords(*hit.trace, path, records);
    }
    outside_.insert(outside_.end(), hit.trace->outside.begin(), hit.trace->outside.end());
  }

  static SubtreeRecord RecordOf(const Node& node, const Identity& id, const std::string& path) {
    SubtreeRecord record;
    record.path = path;
    record.op = node.op;
    record.topology = id.topology;
    record.key = id.key;
    record.children = id.children;
    return record;
  }

  Result Evaluate(const Node& node, const std::string& path) {
    if (node.op == "object") return EvaluateObject(node.args.at("object").text);
    // Previews look a subtree up before evaluating its children, so a cached
    // subtree costs nothing below it (Fab Forms Sec. 6.2: traversal stops at
    // nodes in H).
    // The parts are computed with the root (EvaluateOptions::parts).
    const bool parts_here = options_.parts && &node == &design_.tree && node.op == "openscad";
    if (options_.cache && options_.lookup_before_children && !parts_here) {
      const Identity& id = IdentityOf(node);
      if (auto hit = options_.cache->Find(id.key)) {
        SubtreeRecord record = RecordOf(node, id, path);
        record.from_cache = true;
        record.bytes = hit->solid.MemoryBytes();
        Recall(node, *hit, path, record, nullptr);
        records_->push_back(std::move(record));
        return {hit->solid, id.key, id.topology};
      }
    }
    ResolvedArgs args = Resolve(node);
    const std::size_t outside_before = outside_.size();  // this subtree's outside meshes follow
    std::vector<Result> children;
    for (std::size_t i = 0; i < node.children.size(); ++i)
      children.push_back(Evaluate(node.children[i], path + "/" + std::to_string(i)));

    // carve_swept also needs the moving object's geometry and the resolved
    // motions of the moving and frame objects (IdentityOf keys them too).
    Result moving;
    const ResolvedTransition* transition = nullptr;
    std::size_t moving_index = 0, frame_index = 0;
    bool has_frame = false;
    if (node.op == "carve_swept") {
      moving = EvaluateObject(args.Text("moving"));
      for (const auto& t : Transitions())
        if (t.name == args.Text("transition")) transition = &t;
      moving_index = ObjectIndex(design_, args.Text("moving"));
      has_frame = !args.Text("frame").empty();
      if (has_frame) frame_index = ObjectIndex(design_, args.Text("frame"));
    }

    SubtreeRecord record = RecordOf(node, IdentityOf(node), path);

    Result out{{}, record.key, record.topology};
    if (options_.cache && !parts_here) {
      if (auto hit = options_.cache->Find(record.key)) {
        out.solid = hit->solid;
        record.from_cache = true;
        Recall(node, *hit, path, record, records_);
      }
    }
    if (!record.from_cache) {
      // What the cache keeps beside the solid (none without a cache).
      auto trace = options_.cache ? std::make_shared<SubtreeTrace>() : nullptr;
      std::vector<geometry::Solid> inputs;
      for (auto& c : children) inputs.push_back(std::move(c.solid));
      const Stopwatch start;
      double openscad_seconds = -1;
      if (node.op == "carve_swept") {
        geometry::Solid target = inputs.size() == 1 ? inputs[0] : inputs[0];
        for (std::size_t i = 1; i < inputs.size(); ++i) target = geometry::Union(target, inputs[i]);
        const swept::RigidMotion still;
        out.solid = CarveSwept(target, moving.solid, transition->motions[moving_index],
                               has_frame ? transition->motions[frame_index] : still, args.Number("offset", 0),
                               static_cast<int>(args.Number("time_steps", 2)), grid_, node.place,
                               args.Text("exact", "true") != "false");
      } else if (node.op == "openscad") {
        // Its CSG subtrees are records (and cache entries) of their own,
        // before this one; the node's own time is OpenSCAD's export.
        OpenScadNodeContext context;
        context.grid = grid_;
        context.cache = options_.cache;
        context.records = records_;
        context.outside = &outside_;
        context.warnings = &warnings_;
        context.confine_model_files = options_.confine_model_files;
        context.path = path;
        context.parts = parts_here ? options_.parts : nullptr;
        OpenScadNodeResult scad = EvaluateOpenScadNode(node, args, design_.file.parent_path(), context);
        out.solid = std::move(scad.solid);
        if (!scad.root_key.empty()) record.children = {scad.root_key};
        if (!scad.root_key.empty() && trace) {
          trace->topology = record.topology;
          trace->op = record.op;
          trace->bytes = out.solid.MemoryBytes();
          trace->children = record.children;
          trace->child_paths = {"/csg"};
          trace->child_traces = {scad.root_trace};
        }
        openscad_seconds = scad.export_seconds;
      } else {
        out.solid = ApplyOperation(node, args, inputs, grid_, design_.file.parent_path(), &outside_);
      }
      record.seconds = openscad_seconds >= 0 ? openscad_seconds : start.Seconds();
      if (options_.cache) {
        trace->outside.assign(outside_.begin() + outside_before, outside_.end());
        options_.cache->Offer(record.key, EntryOf(out.solid, std::move(trace)), record.seconds);
      }
    }
    record.bytes = out.solid.MemoryBytes();
    records_->push_back(std::move(record));
    return out;
  }

 private:
  ResolvedArgs Resolve(const Node& node) {
    ResolvedArgs r;
    const OpSchema& schema = OperationSchemas().at(node.op);
    for (const auto& spec : schema.args) {
      auto it = node.args.find(spec.name);
      if (it == node.args.end()) continue;
      const Argument& a = it->second;
      ResolvedArgs::Value v;
      v.place = a.place;
      auto number = [&](const Argument& x) {
        double value = Expression(x.text, scope_, x.place).Evaluate();
        if (!std::isfinite(value))
          throw SampleFailure(kNoGeometry, x.place.str() + ": '" + spec.name + "' evaluates to " + ExactDecimal(value));
        return value;
      };
      switch (spec.shape) {
        case ArgShape::kNumber:
          v.numbers = {number(a)};
          break;
        case ArgShape::kVec3:
          for (const auto& x : a.items) v.numbers.push_back(number(x));
          break;
        case ArgShape::kVec2List:
        case ArgShape::kVec3List:
          for (const auto& p : a.items)
            for (const auto& x : p.items) v.numbers.push_back(number(x));
          break;
        case ArgShape::kString:
          v.text = a.text;
          if (spec.name == "file") v.digest = FileDigest(design_.file.parent_path() / a.text);
          break;
        case ArgShape::kNumberMap:
          for (std::size_t i = 0; i < a.items.size(); ++i) {
            v.keys.push_back(a.keys[i]);
            v.numbers.push_back(number(a.items[i]));
            v.literals.push_back(OpenScadLiteral(node, a.keys[i], v.numbers.back(), a.items[i].place));
          }
          break;
        case ArgShape::kChoiceMap:
          continue;  // read through `set` (OpenScadLiteral)
      }
      r.values[spec.name] = std::move(v);
    }
    return r;
  }

  const Design& design_;
  Scope& scope_;
  const EvaluateOptions& options_;
  std::vector<SubtreeRecord>* records_;
  geometry::GridSpec grid_;
  std::map<const Node*, Identity> identities_;
  std::map<std::string, Result> objects_;
  std::vector<OutsideMesh> outside_;   // meshes from outside fabatlas met in this sample
  std::vector<std::string> warnings_;  // OpenSCAD's warnings and the mesh road's fallbacks, in evaluation order
  std::optional<std::vector<ResolvedTransition>> transitions_;
};

}  // namespace

std::string ResolvedArgs::Canonical() const {
  std::string out;
  for (const auto& [name, v] : values) {
    out += name + "=";
    for (std::size_t i = 0; i < v.numbers.size(); ++i) {
      if (i < v.keys.size()) out += v.keys[i] + ":";
      out += ExactDecimal(v.numbers[i]) + ",";
      if (i < v.literals.size()) out += v.literals[i] + ",";
    }
    out += v.text + (v.digest.empty() ? "" : "@" + v.digest) + ";";
  }
  return out;
}

double ResolvedArgs::Number(const std::string& name, double fallback) const {
  auto it = values.find(name);
  return it == values.end() || it->second.numbers.empty() ? fallback : it->second.numbers[0];
}

geometry::Vec3 ResolvedArgs::Vec3(const std::string& name) const {
  const auto& n = values.at(name).numbers;
  return {n[0], n[1], n[2]};
}

std::string ResolvedArgs::Text(const std::string& name, const std::string& fallback) const {
  auto it = values.find(name);
  return it == values.end() ? fallback : it->second.text;
}

SampleResult EvaluateSample(const Design& design, const Point& u, const EvaluateOptions& options) {
  const Stopwatch start;
  SampleResult r;
  r.u = u;
  // The surface the checks extracted (null when none read it): the `area`
  // property and EvaluateOptions::keep_surface take it instead of extracting
  // it again.
  std::shared_ptr<const mesh::TriangleMesh> surface;
  auto fail = [&](const std::string& type, const std::string& reason) {
    if (r.failure.empty()) {
      r.failure = type;
      r.failure_reason = reason;
    }
  };

  // Lines 1–3: fix exposed parameters, solve constraints.
  ConstraintSolveSummary solve = SolveConstraints(design, u);
  r.values = solve.values;
  r.timings["solve"] = solve.seconds;
  CheckOutcome constraints{"constraints", solve.satisfiable, "", "", solve.seconds};
  if (!solve.satisfiable) {
    constraints.failure = kUnsatConstraints;
    std::ostringstream reason;
    reason << "constraint '" << solve.worst_constraint << "' stays violated by " << solve.max_violation;
    constraints.reason = reason.str();
    fail(kUnsatConstraints, constraints.reason);
  }
  r.checks.push_back(constraints);

  if (solve.satisfiable) {
    // Lines 7–9: set parameters, evaluate the tree (with cached subtrees).
    Scope scope(ParameterNames(design));
    for (const auto& [name, value] : solve.values) scope.Set(name, value);
    const Stopwatch tree_start;
    CheckOutcome geometry_check{"geometry", true, "", "", 0};
    std::string geometry_failure = kNoGeometry;
    // Kept for the checks: collision_free evaluates the objects (cached).
    TreeEvaluation tree(design, scope, options, r.subtrees);
    try {
      if (options.parts) options.parts->clear();
      r.solid = tree.Evaluate(design.tree, "root").solid;
      r.warnings = tree.Warnings();
      if (options.parts && options.parts->empty() && !r.solid.empty()) {
        Part whole;
        whole.name = "body1";
        whole.mesh = r.solid.ToMesh();
        options.parts->push_back(std::move(whole));
      }
      if (r.solid.empty()) {
        geometry_check.passed = false;
        geometry_check.reason = "the tree produced no material";
      }
    } catch (const SampleFailure& e) {
      geometry_check.passed = false;
      geometry_check.reason = e.what();
      geometry_failure = e.type();  // e.g. unsat_constraints from a prototype node
    } catch (const ResourceError&) {
      throw;
    } catch (const DesignFault&) {
      throw;
    } catch (const InputError& e) {
      // Out-of-range values at this point (e.g. a negative radius).
      geometry_check.passed = false;
      geometry_check.reason = e.what();
    }
    geometry_check.seconds = r.timings["tree"] = tree_start.Seconds();
    if (!geometry_check.passed) {
      geometry_check.failure = geometry_failure;
      fail(geometry_failure, geometry_check.reason);
      r.solid = geometry::Solid();
      if (options.parts) options.parts->clear();
    }
    r.checks.push_back(geometry_check);

    // Lines 10–15: every test w_i.
    if (geometry_check.passed && options.run_checks) {
      const Stopwatch checks_start;
      CheckContext context(design, r.solid, scope);
      // Objects first evaluated by a check are recorded apart: the subtree
      // records stay the tree's, root last.
      std::vector<SubtreeRecord> check_records;
      tree.RecordInto(&check_records);
      context.object_solid = [&](const std::string& name) { return tree.EvaluateObject(name).solid; };
      context.transitions = [&]() -> const std::vector<ResolvedTransition>& { return tree.Transitions(); };
      context.assembly = [&]() { return tree.Assembly(); };
      context.outside = &tree.Outside();
      context.state_graph = options.state_graph;
      double surface_seconds = 0;
      for (CheckOutcome& outcome : RunChecks(design.checks, context, &surface_seconds)) {
        if (!outcome.passed) fail(outcome.failure, outcome.reason);
        r.checks.push_back(std::move(outcome));
      }
      if (surface_seconds > 0) r.timings["surface"] = surface_seconds;
      r.timings["checks"] = checks_start.Seconds();
      surface = context.TakeMesh();
      if (options.keep_surface) r.surface = surface;
    }
    // Reconfigurables: what a collision_free check did not record (no such
    // check, or checks skipped): the objects and motions, without collisions.
    if (geometry_check.passed && options.state_graph && !design.objects.empty()) {
      StateGraph& g = *options.state_graph;
      g.object_names.clear();
      for (const auto& object : design.objects) g.object_names.push_back(object.name);
      try {
        if (g.objects.empty())
          for (const auto& object : design.objects)
            g.objects.push_back(tree.EvaluateObject(object.name).solid.ToMesh());
        {
          const auto& resolved = tree.Transitions();
          for (std::size_t k = g.transitions.size(); k < resolved.size(); ++k)
            g.transitions.push_back(
                {resolved[k].name, design.transitions[k].from, design.transitions[k].to, resolved[k].motions, {}});
        }
      } catch (const SampleFailure& e) {
        fail(e.type(), e.what());
        g = StateGraph{};
      }
    }
  }
  // Reconfigurables, Sec. 6.6: a collision the design declares repairable
  // (collision_free's `repair_with`) and automatic resolution within those
  // parameters resolves, proved by every check at the resolved point.
  if (r.failure == kCollision && options.run_checks && options.repair_collisions) {
    const std::vector<std::string> with = RepairParameters(design);
    if (!with.empty()) {
      ResolutionOptions ro;
      ro.parameters = with;
      const ResolveSummary s = ResolveCollisions(design, u, ro);
      if (s.resolved) {
        std::ostringstream reason;
        reason.precision(4);
        reason << r.failure_reason << "; repairable:";
        for (const auto& [name, d] : s.edit) reason << " " << name << (d >= 0 ? " +" : " ") << d;
        reason << " resolves it";
        r.failure = kRepairable;
        r.failure_reason = reason.str();
      }
    }
  }
  r.valid = r.failure.empty();

  // Lines 16–19: properties of valid samples.
  if (r.valid && options.run_checks) {
    const Stopwatch props_start;
    for (const std::string& name : design.properties) {
      if (name == "volume") {
        r.properties["volume"] = r.solid.Volume();
      } else if (name == "bbox") {
        geometry::Box3 box = r.solid.BoundingBox();
        r.properties["bbox_x"] = box.max[0] - box.min[0];
        r.properties["bbox_y"] = box.max[1] - box.min[1];
        r.properties["bbox_z"] = box.max[2] - box.min[2];
      } else if (name == "area") {
        r.properties["area"] = mesh::SurfaceArea(surface ? *surface : r.solid.ToMesh());
      }
    }
    for (const CheckOutcome& c : r.checks)
      for (const auto& [name, value] : c.measures) r.properties[name] = value;
    r.timings["properties"] = props_start.Seconds();
  }
  if (!options.keep_solid) r.solid = geometry::Solid();
  r.timings["total"] = start.Seconds();
  return r;
}

SweptVolumeResult ComputeSweptVolume(const Design& design, const Point& u, const std::string& node_path) {
  const std::string where = design.file.string() + ": swept volume task '" + node_path + "'";
  // Find the node: "root/i/j" or "object:NAME/i/j".
  const Node* node = nullptr;
  std::string rest;
  if (node_path.rfind("root", 0) == 0) {
    node = &design.tree;
    rest = node_path.substr(4);
  } else if (node_path.rfind("object:", 0) == 0) {
    const std::size_t slash = node_path.find('/');
    const DesignObject* object =
        design.FindObject(node_path.substr(7, slash == std::string::npos ? std::string::npos : slash - 7));
    if (object) node = &object->tree;
    rest = slash == std::string::npos ? "" : node_path.substr(slash);
  }
  while (node && !rest.empty()) {
    if (rest[0] != '/') {
      node = nullptr;
      break;
    }
    std::size_t next = rest.find('/', 1);
    const std::string index = rest.substr(1, next == std::string::npos ? std::string::npos : next - 1);
    if (index.empty() || index.find_first_not_of("0123456789") != std::string::npos || index.size() > 6 ||
        std::stoul(index) >= node->children.size()) {
      node = nullptr;
      break;
    }
    node = &node->children[std::stoul(index)];
    rest = next == std::string::npos ? "" : rest.substr(next);
  }
  if (!node || node->op != "carve_swept") throw InputError(where + ": no carve_swept node at that path");

  ConstraintSolveSummary solve = SolveConstraints(design, u);
  if (!solve.satisfiable)
    throw InputError(where + ": constraint '" + solve.worst_constraint + "' is not satisfiable here");
  Scope scope(ParameterNames(design));
  for (const auto& [name, value] : solve.values) scope.Set(name, value);
  std::vector<SubtreeRecord> records;
  EvaluateOptions options;
  TreeEvaluation tree(design, scope, options, records);
  auto text = [&](const char* key) {
    auto it = node->args.find(key);
    return it == node->args.end() ? std::string() : it->second.text;
  };
  auto number = [&](const char* key, double fallback) {
    auto it = node->args.find(key);
    return it == node->args.end() ? fallback : Expression(it->second.text, scope, it->second.place).Evaluate();
  };
  try {
    const geometry::Solid moving = tree.EvaluateObject(text("moving")).solid;
    const ResolvedTransition* transition = nullptr;
    for (const auto& t : tree.Transitions())
      if (t.name == text("transition")) transition = &t;
    const swept::RigidMotion still;
    const swept::RigidMotion& f_frame =
        text("frame").empty() ? still : transition->motions[ObjectIndex(design, text("frame"))];
    swept::SweptVolumeSummary summary;
    const mesh::TriangleMesh surface =
        SweptCutter(moving, transition->motions[ObjectIndex(design, text("moving"))], f_frame, number("offset", 0),
                    static_cast<int>(number("time_steps", 2)), tree.grid(), node->place, &summary);
    SweptVolumeResult r;
    r.volume = mesh::EnclosedVolume(surface);
    r.triangles = surface.triangles.size();
    r.time_steps = summary.time_steps;
    r.active_voxels = summary.active_voxels;
    r.surface_bytes = mesh::RawMeshBytes(surface);
    r.surface_sha256 = Sha256Hex(r.surface_bytes);
    return r;
  } catch (const SampleFailure& e) {
    throw InputError(where + ": " + e.what());
  }
}

double DeltaG(const SampleResult& a, const SampleResult& b) {
  if (!a.valid && !b.valid) return 0.0;
  if (a.valid != b.valid) return 1.0;
  return geometry::DeltaG(a.solid, b.solid);
}

}  // namespace fabatlas::design

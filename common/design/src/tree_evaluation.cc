// TreeEvaluation: a design's operation tree evaluated at one sample, every
// subtree keyed, recorded and cached (tree_evaluation.h).
#include "tree_evaluation.h"

#include <utility>

#include "fabatlas/error.h"
#include "fabatlas/exact_decimal.h"
#include "fabatlas/sha256.h"
#include "fabatlas/stopwatch.h"
#include "fabatlas/swept/swept_volume.h"

namespace fabatlas::design {

TreeEvaluation::Result TreeEvaluation::EvaluateObject(const std::string& name) {
  auto it = objects_.find(name);
  if (it != objects_.end()) return it->second;
  const DesignObject* object = design_.FindObject(name);
  Result r = Evaluate(object->tree, "object:" + name);
  objects_[name] = r;
  return r;
}

std::shared_ptr<const AssemblyOutcome> TreeEvaluation::Assembly() {
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

const TreeEvaluation::Identity& TreeEvaluation::IdentityOf(const Node& node) {
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
    rho += "moving=" + moving.key + ";motion=" + transition->canonical[ObjectIndex(design_, args.Text("moving"))] + ";";
    if (!args.Text("frame").empty())
      rho += "frame_motion=" + transition->canonical[ObjectIndex(design_, args.Text("frame"))] + ";";
  }
  id.key = Sha256Hex(tau + "|" + rho);
  id.topology = Sha256Hex(tau);
  for (const auto* c : kids) id.children.push_back(c->key);
  return identities_.emplace(&node, std::move(id)).first->second;
}

void TreeEvaluation::Recall(const Node& node, const CachedSubtree& hit, const std::string& path, SubtreeRecord& record,
                            std::vector<SubtreeRecord>* records) {
  if (!hit.trace) return;
  if (node.op == "openscad" && !hit.trace->op.empty()) {
    record.children = hit.trace->children;
    if (records) AppendDescendantRecords(*hit.trace, path, records);
  }
  outside_.insert(outside_.end(), hit.trace->outside.begin(), hit.trace->outside.end());
}

SubtreeRecord TreeEvaluation::RecordOf(const Node& node, const Identity& id, const std::string& path) {
  SubtreeRecord record;
  record.path = path;
  record.op = node.op;
  record.topology = id.topology;
  record.key = id.key;
  record.children = id.children;
  return record;
}

std::optional<TreeEvaluation::Result> TreeEvaluation::LookUpBeforeChildren(const Node& node, const std::string& path) {
  const Identity& id = IdentityOf(node);
  auto hit = options_.cache->Find(id.key);
  if (!hit) return std::nullopt;
  SubtreeRecord record = RecordOf(node, id, path);
  record.from_cache = true;
  record.bytes = hit->solid.MemoryBytes();
  Recall(node, *hit, path, record, nullptr);
  records_->push_back(std::move(record));
  return Result{hit->solid, id.key, id.topology};
}

TreeEvaluation::SweptOperands TreeEvaluation::SweptOperandsOf(const ResolvedArgs& args) {
  SweptOperands swept;
  swept.moving = EvaluateObject(args.Text("moving"));
  for (const auto& t : Transitions())
    if (t.name == args.Text("transition")) swept.transition = &t;
  swept.moving_index = ObjectIndex(design_, args.Text("moving"));
  swept.has_frame = !args.Text("frame").empty();
  if (swept.has_frame) swept.frame_index = ObjectIndex(design_, args.Text("frame"));
  return swept;
}

TreeEvaluation::Result TreeEvaluation::Evaluate(const Node& node, const std::string& path) {
  if (node.op == "object") return EvaluateObject(node.args.at("object").text);
  // The parts are computed with the root (EvaluateOptions::parts).
  const bool parts_here = options_.parts && &node == &design_.tree && node.op == "openscad";
  if (options_.cache && options_.lookup_before_children && !parts_here) {
    if (std::optional<Result> hit = LookUpBeforeChildren(node, path)) return *hit;
  }
  ResolvedArgs args = Resolve(node);
  const std::size_t outside_before = outside_.size();  // this subtree's outside meshes follow
  std::vector<Result> children;
  for (std::size_t i = 0; i < node.children.size(); ++i)
    children.push_back(Evaluate(node.children[i], path + "/" + std::to_string(i)));
  // carve_swept also needs the moving object's geometry and the resolved
  // motions of the moving and frame objects (IdentityOf keys them too).
  const SweptOperands swept = node.op == "carve_swept" ? SweptOperandsOf(args) : SweptOperands{};

  SubtreeRecord record = RecordOf(node, IdentityOf(node), path);

  Result out{{}, record.key, record.topology};
  if (options_.cache && !parts_here) {
    if (auto hit = options_.cache->Find(record.key)) {
      out.solid = hit->solid;
      record.from_cache = true;
      Recall(node, *hit, path, record, records_);
    }
  }
  if (!record.from_cache) out.solid = Compute(node, args, children, swept, parts_here, outside_before, path, record);
  record.bytes = out.solid.MemoryBytes();
  records_->push_back(std::move(record));
  return out;
}

geometry::Solid TreeEvaluation::Compute(const Node& node, const ResolvedArgs& args, std::vector<Result>& children,
                                        const SweptOperands& swept, bool parts_here, std::size_t outside_before,
                                        const std::string& path, SubtreeRecord& record) {
  // What the cache keeps beside the solid (none without a cache).
  auto trace = options_.cache ? std::make_shared<SubtreeTrace>() : nullptr;
  std::vector<geometry::Solid> inputs;
  for (auto& c : children) inputs.push_back(std::move(c.solid));
  const Stopwatch start;
  double openscad_seconds = -1;
  geometry::Solid solid;
  if (node.op == "carve_swept")
    solid = CarveSweptNode(node, args, inputs, swept);
  else if (node.op == "openscad")
    solid = EvaluateOpenScad(node, args, path, parts_here, record, trace.get(), &openscad_seconds);
  else
    solid = ApplyOperation(node, args, inputs, grid_, design_.file.parent_path(), &outside_);
  record.seconds = openscad_seconds >= 0 ? openscad_seconds : start.Seconds();
  if (options_.cache) {
    trace->outside.assign(outside_.begin() + outside_before, outside_.end());
    options_.cache->Offer(record.key, EntryOf(solid, std::move(trace)), record.seconds);
  }
  return solid;
}

geometry::Solid TreeEvaluation::CarveSweptNode(const Node& node, const ResolvedArgs& args,
                                               const std::vector<geometry::Solid>& inputs, const SweptOperands& swept) {
  geometry::Solid target = inputs.size() == 1 ? inputs[0] : inputs[0];
  for (std::size_t i = 1; i < inputs.size(); ++i) target = geometry::Union(target, inputs[i]);
  const swept::RigidMotion still;
  return CarveSwept(target, swept.moving.solid, swept.transition->motions[swept.moving_index],
                    swept.has_frame ? swept.transition->motions[swept.frame_index] : still, args.Number("offset", 0),
                    static_cast<int>(args.Number("time_steps", 2)), grid_, node.place,
                    args.Text("exact", "true") != "false");
}

geometry::Solid TreeEvaluation::EvaluateOpenScad(const Node& node, const ResolvedArgs& args, const std::string& path,
                                                 bool parts_here, SubtreeRecord& record, SubtreeTrace* trace,
                                                 double* seconds) {
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
  if (!scad.root_key.empty()) record.children = {scad.root_key};
  if (!scad.root_key.empty() && trace) {
    trace->topology = record.topology;
    trace->op = record.op;
    trace->bytes = scad.solid.MemoryBytes();
    trace->children = record.children;
    trace->child_paths = {"/csg"};
    trace->child_traces = {scad.root_trace};
  }
  *seconds = scad.export_seconds;
  return std::move(scad.solid);
}

}  // namespace fabatlas::design

#include "fabatlas/design/state_graph.h"

#include "fabatlas/error.h"

namespace fabatlas::design {

StateGraphResult EvaluateStateGraph(const Design& design, const Point& u) {
  if (design.objects.empty() || design.transitions.empty())
    throw InputError(design.file.string() + ": the design has no state graph (objects and transitions)");
  StateGraphResult out;
  EvaluateOptions options;
  options.run_checks = true;
  options.state_graph = &out.graph;
  out.sample = EvaluateSample(design, u, options);
  return out;
}

}  // namespace fabatlas::design

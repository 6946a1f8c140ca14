// fabatlas/assembly/precheck.h — verify connect() before solving (FabHacks,
// sections 4.3.1–4.3.2): connectivity table, closed primitives, critical
// dimensions, and the geometric quick reject of cycles (polygon inequality).
#pragma once

#include <string>
#include <vector>

#include "fabatlas/assembly/program.h"

namespace fabatlas::assembly {

enum class PrecheckFailure {
  kNotConnectable,     // pair not allowed by Table 1
  kBothClosed,         // two closed primitives (no motion path to connect)
  kCriticalDimension,  // available critical dimension exhausted
  kCycleCannotClose,   // polygon inequality violated for a part cycle
  kDisconnected,       // a part is not connected to the environment
};

struct PrecheckIssue {
  PrecheckFailure failure;
  std::string message;  // one line: "file:line:col: connect hook1.hook - door.rod: ..."
};

struct PrecheckOptions {
  // Samples per bounded connection parameter when bounding the distance
  // between a part's two cycle connectors (periodic ones get 2× as many).
  int samples_per_param = 7;
  // Slack (mm) added to the polygon inequality to absorb the sampling error
  // of the span bounds: we only reject cycles that miss by more than this.
  double cycle_slack_mm = 1.0;
};

struct CycleLink {
  std::string part;        // instance name
  double min_span_mm = 0;  // e_i^- : min distance between its two cycle connectors
  double max_span_mm = 0;  // e_i^+
};

struct PrecheckSummary {
  bool ok = true;
  std::vector<PrecheckIssue> issues;
  std::vector<std::vector<CycleLink>> cycles;  // one per independent cycle
};

// Runs all pre-checks on a program; never throws for a well-formed Program.
PrecheckSummary Precheck(const Program& program, const PrecheckOptions& options = {});

// Polygon inequality (FabHacks, 4.3.2, "Geometric Quick Reject"): k rigid links
// with lengths e_i in [lo_i, hi_i] can close a loop iff the linear program
//   find e: lo_i <= e_i <= hi_i,  e_k <= sum_{i != k} e_i  for all k
// is feasible. Closed form used here: feasible iff lo_k <= sum_{i != k} hi_i
// for every k (take e = hi; if one link is too long, shorten it to the sum of
// the others, which its lo allows). `slack` is added to the right-hand side.
bool PolygonInequalityFeasible(const std::vector<CycleLink>& links, double slack_mm = 0.0);

}  // namespace fabatlas::assembly

// fabatlas/protocol/tasks.h — sampling tasks as protocol messages and their
// content keys (fabatlas/v1/tasks.proto).
//
// Converts sampling::SampleTask / GeometryChangeTask to v1::TaskPayload and
// v1::TaskResult back to sampling outcomes, bit-exactly (doubles travel as
// IEEE doubles), so a form computed through the cluster is byte-identical to
// the in-process one.
#pragma once

#include <string>

#include "fabatlas/sampling/executor.h"
#include "fabatlas/v1/tasks.pb.h"

namespace fabatlas::protocol {

// Version of the task semantics, part of every task key: bump it when the
// evaluator's results change, so stored results of older code are not reused.
extern const char* const kCodeVersion;

v1::TaskPayload SamplePayload(const sampling::SampleTask& task);
v1::TaskPayload GeometryChangePayload(const sampling::GeometryChangeTask& task);
sampling::SamplePoint PointOf(const v1::SamplePoint& point);

// Task key (tasks.proto): SHA-256 hex of kind, the evaluation digest (which
// design bytes), the bootstrap subdivisions, kCodeVersion and the point keys.
// "sample", "geometry_change", "swept_volume", "cache_plan", "noop": the
// kind as log lines and metric labels name it.
std::string TaskKindName(int kind);

std::string TaskKey(const v1::TaskPayload& payload, const std::string& evaluation_digest, int subdivisions);

v1::TaskResult SampleResultOf(const sampling::SampleOutcome& outcome);
sampling::SampleOutcome SampleOutcomeOf(const v1::TaskResult& result);

// The result given to a quarantined task: an invalid sample with failure type
// "quarantined", or ΔG = 1 (samples that differ completely).
v1::TaskResult QuarantineResult(v1::TaskKind kind);

}  // namespace fabatlas::protocol

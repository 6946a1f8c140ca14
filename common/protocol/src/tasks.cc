// Sampling tasks <-> protocol messages (see tasks.h).
#include "fabatlas/protocol/tasks.h"

#include <cctype>

#include "fabatlas/sha256.h"
#include "fabatlas/sampling/point_key_text.h"

namespace fabatlas::protocol {

std::string TaskKindName(int kind) {
  std::string name = v1::TaskKind_Name(static_cast<v1::TaskKind>(kind));
  if (name.rfind("TASK_KIND_", 0) == 0) name = name.substr(10);
  for (char& c : name) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return name.empty() ? std::to_string(kind) : name;
}

const char* const kCodeVersion = "fabatlas-0.1/tasks-1";

namespace {

void Fill(const sampling::SamplePoint& from, v1::SamplePoint* to) {
  for (auto k : from.key) to->add_key(k);
  for (double u : from.u) to->add_u(u);
}

void AppendKey(std::string& text, const v1::SamplePoint& point) {
  text += sampling::PointKeyText({point.key().begin(), point.key().end()});
  text += '\n';
}

}  // namespace

v1::TaskPayload SamplePayload(const sampling::SampleTask& task) {
  v1::TaskPayload p;
  p.set_kind(v1::TASK_KIND_SAMPLE);
  Fill(task.point, p.mutable_point_a());
  return p;
}

v1::TaskPayload GeometryChangePayload(const sampling::GeometryChangeTask& task) {
  v1::TaskPayload p;
  p.set_kind(v1::TASK_KIND_GEOMETRY_CHANGE);
  Fill(task.point_a, p.mutable_point_a());
  Fill(task.point_b, p.mutable_point_b());
  return p;
}

sampling::SamplePoint PointOf(const v1::SamplePoint& point) {
  sampling::SamplePoint p;
  p.key.assign(point.key().begin(), point.key().end());
  p.u.assign(point.u().begin(), point.u().end());
  return p;
}

std::string TaskKey(const v1::TaskPayload& payload, const std::string& evaluation_digest, int subdivisions) {
  std::string text = "fabatlas.task/1\n";
  text += std::to_string(static_cast<int>(payload.kind())) + "\n";
  text += evaluation_digest + "\n" + std::to_string(subdivisions) + "\n" + kCodeVersion + "\n";
  AppendKey(text, payload.point_a());
  if (payload.kind() == v1::TASK_KIND_GEOMETRY_CHANGE) AppendKey(text, payload.point_b());
  if (payload.kind() == v1::TASK_KIND_SWEPT_VOLUME) text += payload.swept().node_path() + "\n";
  if (payload.kind() == v1::TASK_KIND_CACHE_PLAN) text += payload.cache_plan().input_digest() + "\n";
  return Sha256Hex(text);
}

v1::TaskResult SampleResultOf(const sampling::SampleOutcome& outcome) {
  v1::TaskResult r;
  auto* s = r.mutable_sample();
  s->set_valid(outcome.valid);
  s->set_failure_type(outcome.failure_type);
  for (const auto& [name, value] : outcome.properties) (*s->mutable_properties())[name] = value;
  r.set_cpu_seconds(outcome.cpu_seconds);
  return r;
}

sampling::SampleOutcome SampleOutcomeOf(const v1::TaskResult& result) {
  sampling::SampleOutcome o;
  o.valid = result.sample().valid();
  o.failure_type = result.sample().failure_type();
  for (const auto& [name, value] : result.sample().properties()) o.properties[name] = value;
  o.cpu_seconds = result.cpu_seconds();
  return o;
}

v1::TaskResult QuarantineResult(v1::TaskKind kind) {
  v1::TaskResult r;
  if (kind == v1::TASK_KIND_GEOMETRY_CHANGE) {
    r.set_geometry_change(1.0);
  } else if (kind == v1::TASK_KIND_NOOP) {
    r.set_noop(true);
  } else if (kind == v1::TASK_KIND_SWEPT_VOLUME) {
    r.mutable_swept_volume();  // empty digest: no cutter
  } else if (kind == v1::TASK_KIND_CACHE_PLAN) {
    r.mutable_cache_plan();  // empty report digest: no plan
  } else {
    r.mutable_sample()->set_valid(false);
    r.mutable_sample()->set_failure_type("quarantined");
  }
  return r;
}

}  // namespace fabatlas::protocol

// The artifact of a job whose sampling finished (see artifact_of.h).
#include "fabatlas/pipeline/artifact_of.h"

#include <cctype>

#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/protocol/tasks.h"

namespace fabatlas::pipeline {

artifact::JobBundle PlainBundle(const v1::JobBundle& bundle) {
  artifact::JobBundle b;
  b.job_file_name = bundle.job_file_name();
  b.job_file = bundle.job_file();
  b.design_file_name = bundle.design_file_name();
  b.design_file = bundle.design_file();
  for (const auto& [name, bytes] : bundle.files()) b.files[name] = bytes;
  return b;
}

v1::JobBundle ProtoBundle(const artifact::JobBundle& b) {
  v1::JobBundle bundle;
  bundle.set_job_file_name(b.job_file_name);
  bundle.set_job_file(b.job_file);
  bundle.set_design_file_name(b.design_file_name);
  bundle.set_design_file(b.design_file);
  for (const auto& [name, bytes] : b.files) (*bundle.mutable_files())[name] = bytes;
  return bundle;
}

artifact::Artifact ArtifactOf(const v1::JobBundle& bundle, const std::string& design_name, const sampling::JobFile& job,
                              const sampling::Form& form) {
  artifact::Artifact a;
  a.form = form;
  artifact::Manifest& m = a.manifest;
  m.design_name = design_name;
  m.design_hash = protocol::EvaluationDigest(bundle);
  m.code_version = protocol::kCodeVersion;
  m.subdivisions = form.subdivisions;
  m.max_depth = job.sampling.max_depth;
  m.dg_threshold = job.sampling.dg_threshold;
  m.max_samples = job.sampling.max_samples;
  m.statistics = artifact::StatisticsOf(form);
  a.bundle = PlainBundle(bundle);
  AddStartingPoints(a);
  return a;
}

void AddStartingPoints(artifact::Artifact& artifact, const cache::StartingPointOptions& options) {
  artifact.starting_points.clear();
  for (const auto& p : cache::ChooseStartingPoints(artifact.form, options))
    artifact.starting_points.push_back({p.sample_id, p.component, p.u});
}

std::string ArtifactFileName(const std::string& design_name) {
  std::string name = design_name.empty() ? "design" : design_name;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != '-') c = '_';
  return name + ".fabatlas";
}

}  // namespace fabatlas::pipeline

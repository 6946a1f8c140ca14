// fabatlas/sampling/job_file.h — the precompute job file (YAML), documented
// in docs/job-format.md:
//
//   design: designs/vase.yaml      # required, relative to the job file
//   sampling:                      # optional, defaults as SamplingOptions
//     subdivisions: 5              #   bootstrap cells per dimension
//     max_depth: 6
//     dg_threshold: 0.1
//     max_samples: 100000
//   threads: 2                     # optional, local executor threads
//   form_json: auto                # optional: true | false | auto (see below)
//   materials:                     # optional, for the viewer's cost/weight
//     - {name: PLA, density: 1.24, price_per_kg: 20}
//   cluster: {...}                 # reserved, kept as YAML text
//   cache:                         # kept as YAML text too
//     min_subtree_seconds: 0.1     # cluster workers upload subtrees this slow
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "fabatlas/sampling/adaptive_sampler.h"

namespace fabatlas::sampling {

// A fabrication material for the viewer's cost and weight readout (Fab Forms
// Sec. 7.2: "live updates on the model cost and weight in different
// materials"): weight = volume * density, cost = weight * price_per_kg.
struct Material {
  std::string name;
  double density_g_per_cm3 = 0.0;  // > 0
  double price_per_kg = 0.0;       // >= 0, in the job's currency
};

struct JobFile {
  std::string path;         // the job file as given
  std::string design_path;  // resolved against the job file's directory
  int subdivisions = 5;
  SamplingOptions sampling;
  int threads = 1;
  // form_json: true | false | auto (unset): whether the run also writes
  // form.json beside the artifact (precompute::WritesFormJson; auto = only
  // forms of at most precompute::kFormJsonMaxSamples samples).
  std::optional<bool> form_json;
  // cache.min_subtree_seconds: cluster workers upload the geometry of every
  // subtree whose root took at least this long to compute (wall seconds) as
  // a blob for the geometry cache artifact (Fab Forms Sec. 6).
  double cache_min_subtree_seconds = 0.1;
  std::vector<Material> materials;  // in file order; names unique
  // Reserved sections ("cluster", "cache") as YAML text, for later readers.
  std::map<std::string, std::string> reserved_sections;
};

// Parses YAML text; `path` names the file in messages and anchors
// design_path. Every problem throws fabatlas::InputError with a one-line
// "path:line:col: message" (1-based line and column): syntax errors, unknown
// keys, missing design, wrong types, values out of range.
JobFile ParseJobFile(const std::string& yaml_text, const std::string& path);
// Reads and parses a file; an unreadable file is an InputError too.
JobFile ReadJobFile(const std::string& path);

}  // namespace fabatlas::sampling

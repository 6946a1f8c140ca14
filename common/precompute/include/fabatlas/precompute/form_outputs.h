// fabatlas/precompute/form_outputs.h — what a finished sampling run leaves on
// disk and prints: the Form, its Fab Forms Table 3 statistics and 2-D validity
// maps. Used by the local run and by the coordinator alike.
#pragma once

#include <filesystem>
#include <string>

#include "fabatlas/design/design.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/write_file_atomically.h"

namespace fabatlas::precompute {

// The artifact (<design>.fabatlas) is a run's primary result; form.json is
// the same form as JSON, ~750 bytes per sample (75 MB at 10^5 samples, built
// in memory). With `form_json: auto` (the default) it is written for forms
// of at most this many samples.
inline constexpr std::size_t kFormJsonMaxSamples = 10000;
// Whether a run of `job` whose form has `samples` samples writes form.json.
bool WritesFormJson(const sampling::JobFile& job, std::size_t samples);

// Writes into out_dir (created if missing; every file written to a temporary
// name and renamed):
//   form.json        the sampled form (sampling::FormToJson), when form_json
//                    is true (else a form.json left there is removed)
//   statistics.json  samples, CPU time, valid-volume %, failure shares, ...
//   map_<a>_<b>.png  validity map over exposed parameters a and b (every
//                    consecutive pair; the others at their defaults)
// Throws InputError naming the path on I/O failure (e.g. a full disk).
void WriteFormOutputs(const design::Design& design, const sampling::SamplingSummary& summary,
                      const std::filesystem::path& out_dir, bool form_json);

// One line in the manner of Fab Forms Table 3:
//   "vase  |U|=3  samples 1,234  CPU 0.52 h  valid 6.5%  failures: 77% unsat_constraints, 23% not_watertight"
std::string Table3Row(const design::Design& design, const sampling::SamplingStatistics& statistics);

// Whole files or none (fabatlas/write_file_atomically.h), for the outputs.
using fabatlas::WriteFileAtomically;

}  // namespace fabatlas::precompute

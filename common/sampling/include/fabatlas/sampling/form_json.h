// fabatlas/sampling/form_json.h — the sampled form as JSON (format
// "fabatlas.form/1", documented in docs/sampling.md), for the artifact.
//
// The text is canonical: keys sorted, samples in id order, nodes in index
// order, ΔG values in (a, b) order, doubles printed round-trip exact, so two
// equal forms give byte-identical text. Timings (per-sample cpu_seconds) are
// written only when include_timings is true, because they vary between runs.
#pragma once

#include <string>

#include "fabatlas/sampling/form.h"

namespace fabatlas::sampling {

std::string FormToJson(const Form& form, bool include_timings = false);

// Reads text written by FormToJson. Throws fabatlas::InputError
// ("<source>: message") for malformed text or a form that is inconsistent
// (a leaf corner without a sample, a child index out of range, ...).
Form FormFromJson(const std::string& text, const std::string& source = "form.json");

}  // namespace fabatlas::sampling

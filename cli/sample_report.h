// Reports of an evaluated sample: JSON for tools, text for people.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "fabatlas/design/evaluate_sample.h"

namespace fabatlas::cli {

nlohmann::json SampleJson(const design::Design& design, const design::SampleResult& r);
std::string SampleText(const design::Design& design, const design::SampleResult& r);

}  // namespace fabatlas::cli

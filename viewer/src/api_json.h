// The JSON documents of the customiser's API (docs/viewer.md, "API"), built
// from a Customiser; http_api.cc routes requests to them. Internal.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fabatlas/viewer/customiser.h"

namespace fabatlas::viewer {

// A request the API refuses: 400 with `reason` as its body.
struct BadRequest {
  std::string reason;
};

// form_json.cc: the form, its parameters and samples.
nlohmann::json SampleJson(const Customiser& c, std::int64_t id);
nlohmann::json FixedJson(const Customiser& c);
nlohmann::json ParamsJson(const Customiser& c);
nlohmann::json FormJson(const Customiser& c);
nlohmann::json StretchesJson(const std::vector<Stretch>& stretches);

// state_graph_json.cc: a reconfigurable design played and resolved. Throw
// BadRequest for a form without a state graph.
nlohmann::json StateGraphJson(const Customiser& c, const std::vector<double>& u, int frames);
nlohmann::json ResolveJson(const Customiser& c, const std::vector<double>& u);

}  // namespace fabatlas::viewer

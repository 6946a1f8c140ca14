// The job file's cache section (see cache_options.h).
#include "fabatlas/pipeline/cache_options.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

#include "fabatlas/error.h"

namespace fabatlas::pipeline {

cache::CacheOptions CacheOptionsOf(const sampling::JobFile& job) {
  cache::CacheOptions o;
  o.budget_bytes = kDefaultCacheBudgetMb << 20;
  auto it = job.reserved_sections.find("cache");
  if (it == job.reserved_sections.end()) return o;
  const std::string where = job.path + ": cache: ";
  YAML::Node node;
  try {
    node = YAML::Load(it->second);
  } catch (const YAML::Exception& e) {
    throw InputError(where + e.msg);
  }
  if (!node || node.IsNull()) return o;
  if (!node.IsMap()) throw InputError(where + "expected a mapping");
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    try {
      if (key == "strategy") {
        const std::string v = kv.second.as<std::string>();
        if (v == "naive")
          o.strategy = cache::Strategy::kNaive;
        else if (v == "opt_ave")
          o.strategy = cache::Strategy::kOptAve;
        else if (v == "opt_max")
          o.strategy = cache::Strategy::kOptMax;
        else
          throw InputError(where + "strategy '" + v + "' is not naive, opt_ave or opt_max");
      } else if (key == "budget_mb") {
        const double v = kv.second.as<double>();
        if (!(v > 0) || !std::isfinite(v)) throw InputError(where + "budget_mb must be a positive number");
        o.budget_bytes = static_cast<std::uint64_t>(v * 1024 * 1024);
      } else if (key == "min_subtree_seconds") {
        const double v = kv.second.as<double>();
        if (!(v >= 0) || !std::isfinite(v)) throw InputError(where + "min_subtree_seconds must be >= 0");
        o.min_seconds = v;
      } else if (key == "store_rfree") {
        kv.second.as<bool>();  // read by StoresRfree
      } else {
        throw InputError(where + "unknown key '" + key + "' (strategy, budget_mb, min_subtree_seconds, store_rfree)");
      }
    } catch (const YAML::Exception&) {
      throw InputError(where + "'" + key + "' has the wrong type");
    }
  }
  return o;
}

bool StoresRfree(const sampling::JobFile& job) {
  CacheOptionsOf(job);  // the section's errors, once
  auto it = job.reserved_sections.find("cache");
  if (it == job.reserved_sections.end()) return false;
  const YAML::Node node = YAML::Load(it->second);
  return node.IsMap() && node["store_rfree"] && node["store_rfree"].as<bool>();
}

bool WantsCache(const sampling::JobFile& job) {
  auto it = job.reserved_sections.find("cache");
  if (it == job.reserved_sections.end()) return false;
  return it->second.find("strategy") != std::string::npos || it->second.find("budget_mb") != std::string::npos;
}

}  // namespace fabatlas::pipeline

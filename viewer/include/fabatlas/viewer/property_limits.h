// fabatlas/viewer/property_limits.h — runtime thresholds on stored
// properties (Fab Forms Sec. 7.2): the user bounds weight, cost, volume or a
// bounding-box side, and the valid region shrinks to the samples meeting
// the bounds. A sample outside a bound counts as invalid, so valid
// stretches, the validity map and snapping keep their interval semantics
// (valid_region.h, snap.h) on the limited form.
#pragma once

#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "fabatlas/sampling/form.h"
#include "fabatlas/sampling/job_file.h"

namespace fabatlas::viewer {

// The failure type of a sample outside a limit: "limit:" + property.
inline constexpr const char* kLimitFailurePrefix = "limit:";

struct PropertyLimit {
  // A recorded property ("volume", "bbox_z", ...), or "weight:MATERIAL" (g)
  // / "cost:MATERIAL" derived from "volume" with the job's material table
  // (MaterialReadouts in customiser.h).
  std::string property;
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
};

// "volume<=9000,weight:PLA<=10,bbox_z>=20" (the API's limits= value; empty:
// none). Throws InputError naming the item for anything else, a non-finite
// number, or a material not in `materials`.
std::vector<PropertyLimit> ParseLimits(const std::string& text, const std::vector<sampling::Material>& materials);

// The value of a limit's property for a sample's properties; nullopt when
// the sample does not record it (then the limit does not apply).
std::optional<double> LimitedValue(const PropertyLimit& limit, const std::map<std::string, double>& properties,
                                   const std::vector<sampling::Material>& materials);

// The names queries can use (limits, objectives, trade-offs): every
// property a sample of `form` records (valid or not: a form under limits
// may have no valid sample left), sorted, then weight:M and cost:M for
// each material M when some sample records "volume".
// O(samples x properties).
std::vector<std::string> PropertyNames(const sampling::Form& form, const std::vector<sampling::Material>& materials);

// The canonical name of a property as a query names it: a property some
// sample records, or weight:M / cost:M for a material M of the job
// (also spelled weight_M / cost_M, as on a command line, unless a sample
// records that name itself). Throws InputError naming the property and
// listing PropertyNames otherwise. Stops at the first sample recording the
// name, so a known name costs little.
std::string ResolvePropertyName(const std::string& name, const sampling::Form& form,
                                const std::vector<sampling::Material>& materials);

// What objectives and trade-offs compare (optimise.h, pareto_front.h): one
// of the form's parameters, whose value at a sample is its coordinate, or
// else a property (ResolvePropertyName). A parameter's name comes first, so
// it is found without scanning the samples.
struct Quantity {
  std::string name;    // canonical: weight:PLA, volume, radius, ...
  int dimension = -1;  // >= 0: a parameter
  // weight:M / cost:M: the material, looked up once (else empty).
  std::vector<sampling::Material> material{};
  bool cost = false;  // with a material: cost, else weight (g)
};
// Throws InputError naming the quantity and listing the properties and
// parameters when it is neither.
Quantity ResolveQuantity(const std::string& name, const sampling::Form& form,
                         const std::vector<sampling::Material>& materials);
// The quantity at a sample; nullopt when the sample does not record it.
// A recorded property or a parameter costs one look-up, no allocation.
std::optional<double> QuantityValue(const Quantity& q, const sampling::FormSample& sample,
                                    const std::vector<sampling::Material>& materials);

// A copy of `form` in which every valid sample breaking a limit is invalid
// with failure type "limit:<property>" (the first limit broken, in order).
// O(samples x limits).
sampling::Form ApplyLimits(const sampling::Form& form, const std::vector<PropertyLimit>& limits,
                           const std::vector<sampling::Material>& materials);

// The first limit the properties break, in words, e.g. "volume 9520 above
// your limit 9000"; empty if none.
std::string LimitReason(const std::map<std::string, double>& properties, const std::vector<PropertyLimit>& limits,
                        const std::vector<sampling::Material>& materials);

}  // namespace fabatlas::viewer

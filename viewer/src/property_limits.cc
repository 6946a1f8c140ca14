#include "fabatlas/viewer/property_limits.h"

#include <charconv>
#include <cmath>
#include <set>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/viewer/customiser.h"

namespace fabatlas::viewer {

namespace {

const sampling::Material* FindMaterial(const std::vector<sampling::Material>& materials, const std::string& name) {
  for (const auto& m : materials)
    if (m.name == name) return &m;
  return nullptr;
}

std::string Number(double v) {
  std::ostringstream out;
  out.precision(6);
  out << v;
  return out.str();
}

}  // namespace

std::vector<PropertyLimit> ParseLimits(const std::string& text, const std::vector<sampling::Material>& materials) {
  std::vector<PropertyLimit> limits;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    const auto le = item.find("<="), ge = item.find(">=");
    const auto at = le != std::string::npos ? le : ge;
    if (at == std::string::npos || at == 0)
      throw InputError("limit '" + item + "': expected PROPERTY<=NUMBER or PROPERTY>=NUMBER");
    const std::string property = item.substr(0, at), number = item.substr(at + 2);
    double v = 0;
    const auto [end, ec] = std::from_chars(number.data(), number.data() + number.size(), v);
    if (number.empty() || ec != std::errc() || end != number.data() + number.size() || !std::isfinite(v))
      throw InputError("limit '" + item + "': '" + number + "' is not a finite number");
    for (const char* prefix : {"weight:", "cost:"})
      if (property.rfind(prefix, 0) == 0 && !FindMaterial(materials, property.substr(std::string(prefix).size())))
        throw InputError("limit '" + item + "': no material '" + property.substr(std::string(prefix).size()) +
                         "' in the job's materials");
    PropertyLimit* limit = nullptr;
    for (auto& l : limits)
      if (l.property == property) limit = &l;
    if (!limit) limit = &limits.emplace_back(PropertyLimit{property});
    (le != std::string::npos ? limit->max : limit->min) = v;
  }
  return limits;
}

std::optional<double> LimitedValue(const PropertyLimit& limit, const std::map<std::string, double>& properties,
                                   const std::vector<sampling::Material>& materials) {
  const auto derived = [&](const std::string& prefix) -> std::optional<double> {
    const auto volume = properties.find("volume");
    const auto* m = FindMaterial(materials, limit.property.substr(prefix.size()));
    if (volume == properties.end() || !m) return std::nullopt;
    const MaterialReadout r = MaterialReadouts(volume->second, {*m}).front();
    return prefix == "weight:" ? r.weight_g : r.cost;
  };
  if (limit.property.rfind("weight:", 0) == 0) return derived("weight:");
  if (limit.property.rfind("cost:", 0) == 0) return derived("cost:");
  const auto it = properties.find(limit.property);
  if (it == properties.end()) return std::nullopt;
  return it->second;
}

std::vector<std::string> PropertyNames(const sampling::Form& form, const std::vector<sampling::Material>& materials) {
  std::set<std::string> recorded;
  for (const auto& s : form.samples)
    for (const auto& [name, value] : s.outcome.properties) recorded.insert(name);
  std::vector<std::string> names(recorded.begin(), recorded.end());
  if (recorded.count("volume"))
    for (const char* prefix : {"weight:", "cost:"})
      for (const auto& m : materials) names.push_back(prefix + m.name);
  return names;
}

std::string ResolvePropertyName(const std::string& name, const sampling::Form& form,
                                const std::vector<sampling::Material>& materials) {
  const auto recorded = [&](const std::string& property) {
    for (const auto& s : form.samples)
      if (s.outcome.properties.count(property)) return true;
    return false;
  };
  if (!name.empty() && recorded(name)) return name;
  for (const std::string prefix : {"weight", "cost"}) {
    if (name.size() <= prefix.size() + 1 || name.compare(0, prefix.size(), prefix) != 0) continue;
    const char sep = name[prefix.size()];
    if (sep != ':' && sep != '_') continue;
    const std::string material = name.substr(prefix.size() + 1);
    if (FindMaterial(materials, material) && recorded("volume")) return prefix + ":" + material;
  }
  std::string known;
  for (const auto& n : PropertyNames(form, materials)) known += (known.empty() ? "" : ", ") + n;
  throw InputError("unknown property '" + name + "' (known: " + (known.empty() ? "none" : known) + ")");
}

Quantity ResolveQuantity(const std::string& name, const sampling::Form& form,
                         const std::vector<sampling::Material>& materials) {
  std::string parameters;
  for (std::size_t d = 0; d < form.dimensions.size(); ++d) {
    if (form.dimensions[d].name == name) return {name, static_cast<int>(d)};
    parameters += (parameters.empty() ? "" : ", ") + form.dimensions[d].name;
  }
  try {
    Quantity q{ResolvePropertyName(name, form, materials)};
    for (const char* prefix : {"weight:", "cost:"}) {
      const std::string p = prefix;
      if (q.name.rfind(p, 0) == 0) {
        q.material = {*FindMaterial(materials, q.name.substr(p.size()))};
        q.cost = p == "cost:";
      }
    }
    return q;
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + "; nor a parameter (" + parameters + ")");
  }
}

std::optional<double> QuantityValue(const Quantity& q, const sampling::FormSample& sample,
                                    const std::vector<sampling::Material>& materials) {
  (void)materials;  // resolved into q by ResolveQuantity
  if (q.dimension >= 0) return sample.u.at(static_cast<std::size_t>(q.dimension));
  const auto& properties = sample.outcome.properties;
  if (q.material.empty()) {
    const auto it = properties.find(q.name);
    if (it == properties.end()) return std::nullopt;
    return it->second;
  }
  const auto volume = properties.find("volume");
  if (volume == properties.end()) return std::nullopt;
  const MaterialReadout r = MaterialReadouts(volume->second, q.material).front();
  return q.cost ? r.cost : r.weight_g;
}

sampling::Form ApplyLimits(const sampling::Form& form, const std::vector<PropertyLimit>& limits,
                           const std::vector<sampling::Material>& materials) {
  sampling::Form out = form;
  if (limits.empty()) return out;
  for (auto& s : out.samples) {
    if (!s.outcome.valid) continue;
    for (const auto& limit : limits) {
      const auto v = LimitedValue(limit, s.outcome.properties, materials);
      if (v && (*v < limit.min || *v > limit.max)) {
        s.outcome.valid = false;
        s.outcome.failure_type = kLimitFailurePrefix + limit.property;
        break;
      }
    }
  }
  return out;
}

std::string LimitReason(const std::map<std::string, double>& properties, const std::vector<PropertyLimit>& limits,
                        const std::vector<sampling::Material>& materials) {
  for (const auto& limit : limits) {
    const auto v = LimitedValue(limit, properties, materials);
    if (!v) continue;
    // "weight in PLA 11.6 g", "volume 9322.85 mm^3", "bbox_z 45 mm".
    const std::string& p = limit.property;
    std::string label = p, unit;
    if (p.rfind("weight:", 0) == 0)
      label = "weight in " + p.substr(7), unit = " g";
    else if (p.rfind("cost:", 0) == 0)
      label = "cost in " + p.substr(5);
    else if (p == "volume")
      unit = " mm³";
    else if (p.rfind("bbox", 0) == 0)
      unit = " mm";
    if (*v > limit.max) return label + " " + Number(*v) + unit + " above your limit " + Number(limit.max) + unit;
    if (*v < limit.min) return label + " " + Number(*v) + unit + " below your limit " + Number(limit.min) + unit;
  }
  return {};
}

}  // namespace fabatlas::viewer

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fabatlas/design/design.h"
#include "fabatlas/error.h"

namespace fabatlas::design {

Point DefaultPoint(const Design& design) {
  Point u;
  for (const auto& p : design.exposed) u[p.name] = p.default_value;
  return u;
}

Point ParsePoint(const Design& design, const std::string& text, const std::string& what) {
  Point u = DefaultPoint(design);
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item.empty()) continue;
    auto eq = item.find('=');
    if (eq == std::string::npos) throw InputError(what + ": '" + item + "' is not name=value");
    std::string name = item.substr(0, eq), value = item.substr(eq + 1);
    const ExposedParameter* p = design.FindExposed(name);
    if (!p) throw InputError(what + ": '" + name + "' is not an exposed parameter of " + design.file.string());
    double v = 0;
    if (p->kind == ParameterKind::kEnumerated) {
      auto f = std::find(p->labels.begin(), p->labels.end(), value);
      if (f != p->labels.end()) {
        u[name] = static_cast<double>(f - p->labels.begin());
        continue;
      }
    }
    std::size_t used = 0;
    try {
      v = std::stod(value, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != value.size())
      throw InputError(what + ": value of '" + name + "' is not a number: '" + value + "'");
    if (!std::isfinite(v)) throw InputError(what + ": value of '" + name + "' is not finite");
    if (v < p->min || v > p->max) {
      std::ostringstream msg;
      msg << what << ": " << name << "=" << value << " is outside [" << p->min << ", " << p->max << "]";
      throw InputError(msg.str());
    }
    if (p->kind != ParameterKind::kReal && v != std::round(v))
      throw InputError(what + ": '" + name + "' takes whole numbers, got " + value);
    u[name] = v;
  }
  return u;
}

}  // namespace fabatlas::design

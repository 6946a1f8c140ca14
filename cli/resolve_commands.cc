// fabatlas resolve — collision resolution of a reconfigurable design at a
// point (Reconfigurables, Secs. 6.4–6.6): per collision interval the
// spacetime contact normal, per colliding pair the hint in the design's
// parameters, then automatic resolution proved by the design's own checks.
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"
#include "fabatlas/design/design_at_point.h"
#include "fabatlas/design/resolution_hint.h"
#include "fabatlas/design/resolve_collisions.h"
#include "fabatlas/error.h"

namespace fabatlas::cli {
namespace {

struct ResolveArgs {
  std::string design, at, parameters, out;
};

std::string VecText(const Vec3& v) {
  std::ostringstream s;
  s.precision(3);
  s << std::fixed << "[" << v[0] << ", " << v[1] << ", " << v[2] << "]";
  return s.str();
}

std::string EditText(const std::map<std::string, double>& edit) {
  if (edit.empty()) return "none";
  std::ostringstream s;
  s.precision(4);
  bool first = true;
  for (const auto& [name, v] : edit) {
    s << (first ? "" : ", ") << name << " " << (v >= 0 ? "+" : "") << v;
    first = false;
  }
  return s.str();
}

std::string PointText(const design::Point& u) {
  std::ostringstream s;
  s.precision(6);
  bool first = true;
  for (const auto& [name, v] : u) {
    s << (first ? "" : ",") << name << "=" << v;
    first = false;
  }
  return s.str();
}

void Resolve(const ResolveArgs& args, int& exit_code) {
  const design::Design d = LoadDesignOrModel(args.design);
  const design::Point u = design::ParsePoint(d, args.at, "--at");
  design::ResolutionOptions options;
  std::stringstream names(args.parameters);
  for (std::string name; std::getline(names, name, ',');)
    if (!name.empty()) options.parameters.push_back(name);
  const design::HintSummary hints = design::ResolutionHints(d, u, options);
  std::cout << d.name << " at " << PointText(u) << ": "
            << (hints.sample.valid ? "valid" : "INVALID (" + hints.sample.failure + "): " + hints.sample.failure_reason)
            << "\n";
  std::cout.precision(4);
  for (const auto& i : hints.intervals) {
    const auto& n = i.normal;
    std::cout << "interval: transition " << i.transition << " t in [" << i.t_begin << ", " << i.t_end << "]: '"
              << i.object_a << "' and '" << i.object_b << "'\n";
    std::cout << "  spacetime normal of '" << i.object_b << "': " << VecText(n.spacetime_normal) << " (energy "
              << n.energy << " mm, " << n.contour_samples << " samples with a contour)\n";
    if (n.has_first_contact)
      std::cout << "  spatial normal at first contact (t = " << n.first_contact_t
                << "): " << VecText(n.first_contact_normal) << "\n";
    else
      std::cout << "  spatial normal at first contact: none (in contact from the start)\n";
    std::cout << "  keyframe hint, translation control points of '" << i.object_b << "':";
    for (const auto& p : n.control_point_gradient) std::cout << " " << VecText(p);
    std::cout << "\n";
  }
  for (const auto& h : hints.pairs) {
    std::cout << "pair '" << h.object_a << "' and '" << h.object_b << "': energy " << h.energy << " mm\n";
    std::cout << "  hint (-dE/du): " << EditText(h.descent) << "\n";
    std::cout << "  step: " << EditText(h.step) << " (energy after " << h.energy_after << " mm)\n";
  }
  if (hints.sample.valid) {
    std::cout << "resolved: nothing to resolve\n";
    return;
  }
  const design::ResolveSummary r = design::ResolveCollisions(d, u, options);
  std::cout << "resolved: " << (r.resolved ? "yes" : "no") << " at " << PointText(r.after) << "\n";
  std::cout << "  edit: " << EditText(r.edit) << " (size " << r.edit_size << " of the ranges)\n";
  std::cout << "  energy " << r.energy_before << " -> " << r.energy_after << " mm; " << r.steps.size() << " steps, "
            << r.evaluations << " evaluations, " << r.seconds << " s\n";
  std::cout << "  checks: " << (r.resolved ? "pass" : r.failure_after + ": " + r.reason_after) << "\n";
  if (!args.out.empty()) {
    if (!r.resolved) {
      std::cout << "  not written: " << args.out << " (not resolved)\n";
    } else {
      const std::string text = design::DesignTextAt(d, r.after);
      std::ofstream out(args.out, std::ios::binary);
      out << text;
      if (!out) throw InputError("-o " + args.out + ": cannot write");
      std::cout << "  written: " << args.out << "\n";
    }
  }
  if (!r.resolved) exit_code = 3;
}

}  // namespace

void AddResolveCommands(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ResolveArgs>();
  auto* resolve =
      app.add_subcommand("resolve",
                         "a reconfigurable's collisions at a point: contact normals, hints, automatic resolution "
                         "(exit 3 when the design stays invalid)");
  resolve->add_option("design", args->design, "design YAML with objects and transitions")->required();
  resolve->add_option("--at", args->at, "name=value,... (others take their defaults)");
  resolve->add_option("--parameters", args->parameters,
                      "the degrees of freedom, name,... (default: every real parameter)");
  resolve->add_option("-o,--out", args->out, "write the resolved design (YAML, defaults at the resolved point)");
  resolve->callback([args, &exit_code] { Resolve(*args, exit_code); });
}

}  // namespace fabatlas::cli

#include "fabatlas/viewer/export_design.h"

#include <chrono>
#include <cctype>
#include <cmath>
#include <limits>
#include <sstream>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/encode_3mf.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/mesh/write_mesh.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/artifact/glb.h"
#include "fabatlas/scad/part_trees.h"

namespace fabatlas::viewer {

double FabricationVoxelSize(double design_voxel_size_mm) { return design_voxel_size_mm / 2; }

std::string PointText(const Customiser& c, const std::vector<double>& u) {
  std::ostringstream out;
  out.precision(6);
  for (int d = 0; d < c.dimension_count() && d < static_cast<int>(u.size()); ++d) {
    const auto& dim = c.space().dimension(d);
    if (d) out << ',';
    out << dim.name << '=';
    const auto i = static_cast<std::size_t>(std::llround(u[d]));
    if (dim.kind == sampling::DimensionKind::kEnumerated && i < dim.values.size())
      out << dim.values[i];
    else
      out << u[d];
  }
  return out.str();
}

std::int64_t NearestValidSample(const Customiser& c, const std::vector<double>& u) {
  std::int64_t best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  const auto& samples = c.form().samples;
  for (std::size_t id = 0; id < samples.size(); ++id) {
    if (!samples[id].outcome.valid) continue;
    double d2 = 0;
    for (int d = 0; d < c.dimension_count(); ++d) {
      const auto& dim = c.space().dimension(d);
      const double range = dim.hi > dim.lo ? dim.hi - dim.lo : 1.0;
      const double t = (samples[id].u[d] - u[d]) / range;
      d2 += t * t;
    }
    if (d2 < best_d) {
      best_d = d2;
      best = static_cast<std::int64_t>(id);
    }
  }
  return best;
}

namespace {

// Throws an InputError naming why u cannot be exported: an unknown format,
// no design, a point of the wrong size, or one outside the valid region (with
// the failures there and the nearest valid point).
void RequireExportable(const Customiser& c, const std::vector<double>& u, const std::string& f) {
  if (f != "stl" && f != "3mf" && f != "glb" && f != "obj")
    throw InputError("format '" + f + "' is not one of stl, 3mf, glb, obj");
  if (!c.source().design) throw InputError("this form has no design to export");
  if (static_cast<int>(u.size()) != c.dimension_count())
    throw InputError("the point has " + std::to_string(u.size()) + " values, the form has " +
                     std::to_string(c.dimension_count()) + " parameters");
  if (c.IsValid(u)) return;
  std::string why;
  for (const auto& failure : FailuresAt(c.form(), c.space(), c.corners(), u))
    why += (why.empty() ? "" : ", ") + failure;
  const std::int64_t nearest = NearestValidSample(c, u);
  throw InputError(PointText(c, u) + " is outside the valid region" + (why.empty() ? "" : " (" + why + ")") +
                   (nearest < 0 ? std::string("; the form has no valid point")
                                : "; nearest valid point: " + PointText(c, c.form().samples[nearest].u)));
}

// Throws an InputError naming the check the design fails at exactly u
// (though the samples around it pass), with the nearest valid point.
void RequireChecksPass(const Customiser& c, const std::vector<double>& u, const design::SampleResult& r) {
  if (r.valid) return;
  const design::CheckOutcome* failed = nullptr;
  for (const auto& check : r.checks)
    if (!check.passed) {
      failed = &check;
      break;
    }
  const std::int64_t nearest = NearestValidSample(c, u);
  throw InputError(
      PointText(c, u) + " fails check '" + (failed ? failed->name : r.failure) + "' at exactly this point (" +
      r.failure + ": " + (r.failure_reason.empty() && failed ? failed->reason : r.failure_reason) +
      "), though the samples around it pass" +
      (nearest < 0 ? std::string() : "; nearest valid point: " + PointText(c, c.form().samples[nearest].u)));
}

// The part `part=` asks for among the design's parts (every part's name goes
// to out.parts): nullptr for the whole design.
struct PartChoice {
  const design::Part* chosen = nullptr;
  bool coloured = false;  // some part has a colour
};

PartChoice ChoosePart(const Customiser& c, const std::vector<double>& u, const ExportOptions& options,
                      const std::vector<design::Part>& parts, ExportResult& out) {
  PartChoice choice;
  std::string names;
  for (const auto& p : parts) {
    std::string shown = p.name;  // "name" or "name #rrggbb"
    if (p.coloured) {
      shown += ' ';
      shown += scad::HexColour(p.rgba);
    }
    out.parts.push_back(shown);
    names += (names.empty() ? "" : ", ") + p.name;
    if (p.name == options.part) choice.chosen = &p;
    choice.coloured = choice.coloured || p.coloured;
  }
  if (parts.empty()) {
    out.parts = {"body1"};
    names = "body1";
  }
  const bool whole = options.part.empty() || (parts.empty() && options.part == "body1");
  if (!whole && !choice.chosen)
    throw InputError("part '" + options.part + "' is not one of the design's parts at " + PointText(c, u) + ": " +
                     names);
  if (!whole && options.format != "stl" && options.format != "obj")
    throw InputError("part= selects one part of an stl or obj file; a " + options.format + " file holds every part");
  return choice;
}

// The file's bytes: the parts as objects of their own (3mf, glb) when there
// are several or coloured ones, else the one mesh m. Every part written so
// must be closed (a ResourceError otherwise).
std::string EncodeExport(const Customiser& c, const std::vector<double>& u, const std::string& f,
                         const std::vector<design::Part>& parts, bool several, const mesh::TriangleMesh& m,
                         bool exact_boundary, const mesh::InspectOptions& inspect) {
  if (several && (f == "3mf" || f == "glb")) {
    for (const auto& p : parts) {
      const mesh::MeshReport part_report = mesh::InspectMesh(p.mesh, inspect);
      if (!part_report.closed)
        throw ResourceError(PointText(c, u) + ": part " + p.name + " is not closed (" + part_report.closed_reason +
                            ")");
    }
  }
  if (several && f == "3mf") {
    std::vector<mesh::Object3mf> objects;
    for (const auto& p : parts) objects.push_back({p.name, &p.mesh, p.coloured, p.rgba});
    return mesh::Encode3mfObjects(objects);
  }
  if (several && f == "glb") {
    std::vector<artifact::GlbPart> glb;
    for (const auto& p : parts) glb.push_back({p.name, &p.mesh, p.coloured, p.rgba});
    return artifact::PartsToGlb(glb, exact_boundary);
  }
  return f == "glb" ? artifact::SolidPreviewGlb(m, exact_boundary) : mesh::EncodeMesh(m, "." + f);
}

// "<design>-<point>[-<part>].<format>", every character but letters, digits,
// '-', '.' and '=' replaced by '_'.
std::string ExportFileName(const Customiser& c, const std::vector<double>& u, const design::Part* chosen,
                           const std::string& f) {
  std::string name = c.source().name + "-" + PointText(c, u) + (chosen ? "-" + chosen->name : "");
  for (char& ch : name)
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '-' && ch != '.' && ch != '=') ch = '_';
  return name + "." + f;
}

}  // namespace

ExportResult ExportDesign(const Customiser& c, const std::vector<double>& u, const ExportOptions& options) {
  const std::string& f = options.format;
  RequireExportable(c, u, f);
  design::Design design = *c.source().design;
  design.voxel_size = options.voxel_size > 0 ? options.voxel_size : FabricationVoxelSize(design.voxel_size);
  // The valid region between samples is an interpolation (IsValidPoint);
  // the file is the design at exactly u, so its checks run again there, on
  // the geometry written (at the fabrication voxel size), before anything
  // is encoded.
  design::EvaluateOptions evaluate;
  evaluate.run_checks = true;
  // Parts: an OpenSCAD model's bodies and colours; any other design is one
  // part, the solid (not meshed twice).
  std::vector<design::Part> parts;
  if (design.tree.op == "openscad") evaluate.parts = &parts;
  const auto start = std::chrono::steady_clock::now();
  const design::SampleResult r = design::EvaluateSample(design, precompute::DesignPointOf(design, u), evaluate);
  RequireChecksPass(c, u, r);
  ExportResult out;
  const PartChoice choice = ChoosePart(c, u, options, parts, out);
  const mesh::TriangleMesh m = choice.chosen ? choice.chosen->mesh : r.solid.ToMesh();
  mesh::InspectOptions inspect;
  inspect.check_self_intersection = false;
  const mesh::MeshReport report = mesh::InspectMesh(m, inspect);
  if (!report.closed)
    throw ResourceError(PointText(c, u) + ": the mesh at voxel size " + std::to_string(design.voxel_size) +
                        " mm is not closed (" + report.closed_reason + ")");
  const bool several = parts.size() > 1 || choice.coloured;
  out.bytes = EncodeExport(c, u, f, parts, several, m, r.solid.boundary() != nullptr, inspect);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.u = u;
  out.voxel_size = design.voxel_size;
  out.triangles = static_cast<std::int64_t>(m.triangles.size());
  out.volume_mm3 = report.volume;
  for (const auto& check : r.checks) out.checks.push_back(check.name);
  out.file_name = ExportFileName(c, u, choice.chosen, f);
  return out;
}

}  // namespace fabatlas::viewer

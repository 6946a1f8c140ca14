// fabatlas/viewer/pareto_front.h — the trade-off between two properties over
// the valid samples of a form (Schulz et al. 2018, "Interactive exploration
// of design trade-offs": the Pareto front over precomputed designs), found by
// one sort and one sweep (Kung, Luccio and Preparata 1975, the maxima of a
// set of vectors in the plane); citations in docs/references.md.
//
// Each axis is a property or parameter as ResolveQuantity accepts it
// (recorded, weight / cost in a material, or a parameter's value) to
// minimise or maximise, e.g. volume (min) against radius (max). A valid sample is
// on the front when no other valid sample is at least as good on both axes
// and better on one. Samples with equal values on both axes count once (the
// lowest id). Only samples are compared, not points inside leaves: there
// the runtime knows properties by multilinear interpolation of the leaf's
// corners, whose values lie in the convex hull of the corners' values, so
// they can fall between front points (the front of samples is a staircase)
// but never beyond its ends; the samples are what the page previews. Limits: pass the limited form
// (Customiser::LimitedForm). Cost: O(valid samples log valid samples), single-threaded, thread-safe.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "fabatlas/sampling/form.h"
#include "fabatlas/sampling/job_file.h"

namespace fabatlas::viewer {

struct ParetoAxis {
  std::string property;
  bool maximise = false;  // default: minimise
};

struct ParetoOptions {
  ParetoAxis a, b;
  bool keep_dominated = false;  // also return the dominated candidates (for a plot)
};

struct ParetoPoint {
  std::int64_t sample = -1;
  double a = 0, b = 0;  // the properties' values (not negated for maximised axes)
};

struct ParetoFront {
  std::string a, b;                    // canonical property names of the axes
  std::vector<ParetoPoint> points;     // best on axis a first (so worst on b first)
  std::int64_t candidates = 0;         // valid samples recording both properties
  std::vector<ParetoPoint> dominated;  // with keep_dominated: the other candidates, best on a first
};

// Throws InputError for an unknown property (ResolveQuantity) or the
// same property on both axes with the same sense.
ParetoFront ParetoFrontOf(const sampling::Form& form, const std::vector<sampling::Material>& materials,
                          const ParetoOptions& options);

// "volume,max:radius": two axes, each "PROPERTY", "min:PROPERTY" or
// "max:PROPERTY" (minimise by default). Throws InputError otherwise.
ParetoOptions ParseParetoAxes(const std::string& text);

// The front as CSV: a header `sample,<a>,<b>,<parameter>...` and one row per
// point in the front's order, numbers with 17 significant digits.
std::string ParetoCsv(const sampling::Form& form, const ParetoFront& front);

struct ParetoPlotOptions {
  int width = 900, height = 600;  // pixels
  std::string title;              // e.g. the design name
};
// The dominated candidates (grey dots, when kept) and the front (blue
// squares joined as a staircase in order) with axes, ticks and names, as
// PNG through picture::Canvas; x is axis a, y axis b. Written atomically;
// InputError when the front is empty or the file cannot be written.
void WriteParetoPng(const ParetoFront& front, const std::filesystem::path& path, const ParetoPlotOptions& options = {});

}  // namespace fabatlas::viewer

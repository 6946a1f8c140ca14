// solve/resting_contacts.h (internal to fabatlas_assembly) — whether parts
// resting on others stay after the relaxation.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fabatlas/assembly/program.h"

namespace fabatlas::assembly::internal {

// Resting contacts (IsRestingContact: a surface standing on a surface, a
// roll on a rod; the side in its base form rests on the other). The
// reference glues them; a real part on a support slides off when the support
// tilts beyond the friction angle (a surface's normal from the vertical, a
// rod's axis from the horizontal), and a part standing on a surface tips over
// when the vertical through the centre of mass of it and everything it
// carries leaves its footprint (the small surface's W × L rectangle; the
// stands-on-a-flat-surface test of Fab Forms). Each is reported.
std::vector<std::string> RestingFailures(const Program& prog, const std::vector<Eigen::Isometry3d>& poses,
                                         double friction_angle_deg);

}  // namespace fabatlas::assembly::internal

#include "node_schema.h"

namespace fabatlas::design {

const std::map<std::string, OpSchema>& OperationSchemas() {
  using S = ArgShape;
  static const std::map<std::string, OpSchema> schemas = {
      // Primitives (leaves).
      {"sphere", {{{"radius", S::kNumber}}, 0, 0}},
      {"box", {{{"size", S::kVec3}}, 0, 0}},
      {"cylinder", {{{"radius", S::kNumber}, {"height", S::kNumber}}, 0, 0}},
      {"cone", {{{"bottom_radius", S::kNumber}, {"top_radius", S::kNumber}, {"height", S::kNumber}}, 0, 0}},
      {"torus", {{{"major_radius", S::kNumber}, {"minor_radius", S::kNumber}}, 0, 0}},
      {"capsule", {{{"a", S::kVec3}, {"b", S::kVec3}, {"radius", S::kNumber}}, 0, 0}},
      {"extrude", {{{"polygon", S::kVec2List}, {"height", S::kNumber}}, 0, 0}},
      {"revolve", {{{"profile", S::kVec2List}, {"sides", S::kNumber, false}}, 0, 0}},
      {"spheres", {{{"centers", S::kVec3List}, {"radius", S::kNumber}}, 0, 0}},
      {"tentacle",
       {{{"length", S::kNumber},
         {"base_radius", S::kNumber},
         {"tip_radius", S::kNumber},
         {"curvature", S::kNumber},
         {"heading", S::kNumber, false},
         {"spacing", S::kNumber, false}},
        0,
        0}},
      {"mesh", {{{"file", S::kString}}, 0, 0}},
      // An OpenSCAD model (docs/openscad.md): `set` passes -D overrides,
      // `choices` the OpenSCAD value each index of an enum in `set` stands
      // for; `render: native` (default) evaluates OpenSCAD's CSG tree with
      // level sets, `render: openscad` imports OpenSCAD's own STL.
      {"openscad",
       {{{"file", S::kString},
         {"set", S::kNumberMap, false},
         {"choices", S::kChoiceMap, false},
         {"render", S::kString, false}},
        0,
        0}},
      // A works-like prototype (Koo et al., docs/prototype.md): solved, then
      // its printable geometry; unsatisfiable constraints fail the sample.
      {"prototype", {{{"file", S::kString}, {"set", S::kNumberMap, false}}, 0, 0}},
      // A FabHacks assembly (docs/assembly.md): a program file, or a
      // generated family (`family`, its part library as `file`, parameters in
      // `set`), solved; its parts placed at the solved poses.
      {"assembly",
       {{{"file", S::kString},
         {"family", S::kString, false},
         {"set", S::kNumberMap, false},
         {"meshes", S::kString, false}},
        0,
        0}},
      // Transforms: several children are unioned first.
      {"translate", {{{"by", S::kVec3}}, 1, -1}},
      {"rotate", {{{"degrees", S::kVec3}}, 1, -1}},
      {"scale", {{{"factor", S::kNumber}}, 1, -1}},
      // CSG: difference subtracts every later child from the first.
      {"union", {{{"exact", S::kString, false}}, 2, -1}},
      {"difference", {{{"exact", S::kString, false}}, 2, -1}},
      {"intersection", {{{"exact", S::kString, false}}, 2, -1}},
      {"offset", {{{"distance", S::kNumber}}, 1, -1}},
      {"shell", {{{"thickness", S::kNumber}}, 1, -1}},
      {"linear_array", {{{"count", S::kNumber}, {"step", S::kVec3}}, 1, -1}},
      {"polar_array", {{{"count", S::kNumber}, {"angle", S::kNumber, false}}, 1, -1}},
      // Reconfigurables: an object of the design, in its body
      // frame; and the children minus the eps-offset swept volume of object
      // `moving` along `transition`, observed in object `frame`'s body frame
      // (the world if no frame is given).
      {"object", {{{"object", S::kString}}, 0, 0}},
      {"carve_swept",
       {{{"moving", S::kString},
         {"transition", S::kString},
         {"frame", S::kString, false},
         {"offset", S::kNumber, false},
         {"time_steps", S::kNumber, false},
         {"exact", S::kString, false}},
        1,
        -1}},
  };
  return schemas;
}

const std::map<std::string, OpSchema>& CheckSchemas() {
  using S = ArgShape;
  static const std::map<std::string, OpSchema> schemas = {
      {"watertight", {{}, 0, 0}},
      {"min_thickness",
       {{{"value", S::kNumber}, {"method", S::kString, false}, {"max_thin_fraction", S::kNumber, false}}, 0, 0}},
      {"stands", {{{"margin", S::kNumber, false}}, 0, 0}},
      {"max_volume", {{{"value", S::kNumber}}, 0, 0}},
      {"fem",
       {{{"voxel", S::kNumber},
         {"youngs_modulus", S::kNumber},
         {"poisson", S::kNumber, false},
         {"fixed", S::kVec3List},
         {"loaded", S::kVec3List},
         {"force", S::kVec3},
         {"max_displacement", S::kNumber},
         {"max_strain", S::kNumber, false},
         {"element", S::kString, false}},
        0,
        0}},
      {"collision_free",
       {{{"time_steps", S::kNumber, false}, {"clearance", S::kNumber, false}, {"repair_with", S::kString, false}},
        0,
        0}},
      // Assemblies (FabHacks): the design's `assembly` node solved at the sample.
      {"assembly_feasible", {{}, 0, 0}},
      {"assembly_stable", {{}, 0, 0}},
      {"target_reached", {{{"tolerance", S::kNumber, false}, {"tolerance_deg", S::kNumber, false}}, 0, 0}},
  };
  return schemas;
}

const std::vector<std::string>& PropertyNames() {
  static const std::vector<std::string> names = {"volume", "area", "bbox"};
  return names;
}

}  // namespace fabatlas::design

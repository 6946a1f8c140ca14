// A spur gear: MCAD's involute gear (Debian openscad-mcad,
// MCAD/involute_gears.scad, module gear) with a hub around its bore.
// Customizer annotations name what a person chooses. Not every choice
// prints: a bore close to the gear's root circle leaves a rim thinner
// than a nozzle, and a wider one cuts the teeth off the gear.
use <MCAD/involute_gears.scad>

/* [Gear] */
// Number of teeth
teeth = 17; // [8:40]
// Thickness of the gear (mm)
thickness = 5; // [2:12]

/* [Shaft] */
// Diameter of the hole for the shaft (mm)
bore = 6; // [2:24]

/* [Hidden] */
// Tooth size: MCAD's circular pitch (pitch circle length per tooth x 180 / pi, in mm)
pitch = 240;

gear(number_of_teeth = teeth, circular_pitch = pitch, gear_thickness = thickness,
     rim_thickness = thickness, rim_width = 2, hub_thickness = thickness + 4,
     hub_diameter = bore + 6, bore_diameter = bore);

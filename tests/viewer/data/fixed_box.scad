// The parameters of tests/scad/data/organiser.scad (18, written to the
// OpenSCAD Customizer rules) on a plain box, so the page test's run takes
// seconds: tests/viewer/browser_fixed_test.mjs checks the page, not the shape.

/* [Size] */
// Outer width (mm)
width = 80; // [40:5:160]
// Outer depth (mm)
depth = 60; // [40:5:160]
// Height (mm)
height = 25; // [10:60]

/* [Compartments] */
// Compartments along the width
columns = 3; // [1:6]
// Compartments along the depth
rows = 2; // [1:6]
// Divider thickness (mm)
divider = 1.6; // [0.8:0.2:4]
// Divider height as a fraction of the height
divider_ratio = 0.8; // [0.4:0.05:1]

/* [Walls] */
// Outer wall (mm)
wall = 2; // [1:0.5:5]
// Floor (mm)
floor_thickness = 1.5; // [0.6:0.1:4]
// Corner radius (mm)
corner = 3; // [0:10]

/* [Finish] */
// Finger notch in every divider
notches = true;
// Label recess on the front
label = 0; // [0:none, 1:shallow, 2:deep]
// Stacking lip height (mm)
lip = 1.5; // .5
// Lip inset (mm)
lip_inset = 1;
// Text on the label
label_text = "tools";

/* [Hidden] */
$fn = 40;
eps = 0.01;
tag = 7; // [1:9]

cube([width, depth, height]);

// A drawer organiser with 17 Customizer parameters, written to the rules of
// the OpenSCAD User Manual ("Customizer"): groups (tabs), sliders with and
// without steps, a labelled dropdown, a checkbox, spin boxes with only a step
// comment, a text box and a [Hidden] group. Test data for `fabatlas
// import-scad` (tests/scad/scad_import_test.cc, scad_cli_test.cc).

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

inner_w = width - 2 * wall;
inner_d = depth - 2 * wall;
cell_w = (inner_w - (columns - 1) * divider) / columns;
cell_d = (inner_d - (rows - 1) * divider) / rows;
divider_h = floor_thickness + divider_ratio * (height - floor_thickness);

module rounded(w, d, h, r) {
  if (r > 0)
    hull() for (x = [r, w - r]) for (y = [r, d - r]) translate([x, y, 0]) cylinder(r = r, h = h);
  else
    cube([w, d, h]);
}

module divider_x(x) {
  difference() {
    translate([x, wall - eps, 0]) cube([divider, inner_d + 2 * eps, divider_h]);
    if (notches) translate([x - eps, depth / 2, divider_h]) rotate([0, 90, 0]) cylinder(r = 6, h = divider + 2 * eps);
  }
}

module divider_y(y) {
  difference() {
    translate([wall - eps, y, 0]) cube([inner_w + 2 * eps, divider, divider_h]);
    if (notches) translate([width / 2, y - eps, divider_h]) rotate([-90, 0, 0]) cylinder(r = 6, h = divider + 2 * eps);
  }
}

union() {
  difference() {
    rounded(width, depth, height, corner);
    translate([wall, wall, floor_thickness]) cube([inner_w, inner_d, height]);
    if (label > 0) translate([width / 4, -eps, height - 8]) cube([width / 2, label * 0.5 + eps, 6]);
  }
  for (i = [1 : columns - 1]) divider_x(wall + i * cell_w + (i - 1) * divider);
  for (j = [1 : rows - 1]) divider_y(wall + j * cell_d + (j - 1) * divider);
  if (lip > 0)
    translate([lip_inset, lip_inset, height])
      difference() {
        cube([width - 2 * lip_inset, depth - 2 * lip_inset, lip]);
        translate([wall, wall, -eps]) cube([width - 2 * lip_inset - 2 * wall, depth - 2 * lip_inset - 2 * wall, lip + 2 * eps]);
      }
}

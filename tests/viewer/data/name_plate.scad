// A name plate on a stand in three colours and three bodies (the plate, the
// stand, the knob), for the customiser's parts and colours (issue 32).

/* [Plate] */
// Width of the plate
width = 60; // [40:100]
// Height of the plate
height = 20; // [12:30]

/* [Hidden] */
stand_depth = 24;

color("steelblue") cube([width, 3, height]);
color("orange") translate([0, 1.5 - stand_depth / 2, 0]) cube([width, stand_depth, 2]);
color("crimson") translate([width / 2, 1.5, height]) rotate([90, 0, 0]) cylinder(h = 3, r = 5, center = true, $fn = 40);

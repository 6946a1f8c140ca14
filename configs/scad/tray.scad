// A small parametric tray: a walled box with a row of holes in its floor.
// OpenSCAD Customizer annotations (OpenSCAD User Manual, "Customizer").

/* [Size] */
// Outer width of the tray (mm)
width = 60; // [30:120]

// Outer depth of the tray (mm)
depth = 40;

// Wall and floor thickness (mm)
wall = 2; // [0.4:0.2:6]

/* [Holes] */
// Number of drain holes in the floor
holes = 3; // [0:8]

// Shape of the holes
shape = "round"; // [round, square]

/* [Hidden] */
height = 15;
hole_size = 6;
$fn = 32;

difference() {
    cube([width, depth, height]);
    translate([wall, wall, wall]) cube([width - 2 * wall, depth - 2 * wall, height]);
    for (i = [0 : holes - 1]) {
        translate([(i + 1) * width / (holes + 1), depth / 2, -1])
            if (shape == "round") cylinder(d = hole_size, h = wall + 2);
            else translate([-hole_size / 2, -hole_size / 2, 0]) cube([hole_size, hole_size, wall + 2]);
    }
}

// The holes of the holey vase (Fab Forms Table 2): a ring of `count`
// round holes of radius `radius` drilled radially outward from the z axis
// in the plane z = 0, the first along +x. The vase (a surface of revolution
// in the design) subtracts this cutter at the ring's height.
// OpenSCAD Customizer annotations (OpenSCAD User Manual, "Customizer").

/* [Holes] */
// Number of holes around the vase
count = 8; // [3:16]

// Radius of each hole (mm)
radius = 3; // [1:10]

// How far the drills reach from the axis (mm)
reach = 60; // [10:100]

/* [Hidden] */
$fn = 24;

for (i = [0 : count - 1])
    rotate([0, 0, i * 360 / count])
        rotate([0, 90, 0])
            cylinder(r = radius, h = reach);

// The wheel of the toy car (Fab Forms Table 2: its wheel is an OpenSCAD
// model): a tyre of round section on a rim disc with `spokes` openings
// between the spokes and a hub. Axis z, centred at the origin.
// OpenSCAD Customizer annotations (OpenSCAD User Manual, "Customizer").

/* [Wheel] */
// Outer radius of the tyre (mm)
radius = 14; // [5:30]

// Width of the tyre (mm)
width = 5.7; // [3:16]

// Number of spokes
spokes = 5; // [3:8]

/* [Hidden] */
// Radius of the hub (mm)
hub = 4;
// Thickness of the rim disc (mm)
disc = 2;
$fn = 32;

tyre = width / 2;           // radius of the tyre's section
rim = radius - 2 * tyre;   // the disc reaches the tyre's inner edge
opening = (rim + hub) / 2;  // centre radius of the openings

union() {
    // the tyre: a ring of round section
    rotate_extrude() translate([radius - tyre, 0]) circle(r = tyre);
    // the rim disc with one opening between each pair of spokes
    difference() {
        cylinder(r = rim + tyre / 2, h = disc, center = true);
        for (i = [0 : spokes - 1])
            rotate([0, 0, (i + 0.5) * 360 / spokes])
                translate([opening, 0, 0])
                    cylinder(r = 0.45 * (rim - hub), h = disc + 2, center = true);
    }
    // the hub
    cylinder(r = hub, h = width, center = true);
}

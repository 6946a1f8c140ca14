// The handle of Yin Yang Cup 2 (Fab Forms Table 2: its handle is an
// OpenSCAD model). The handle is the outline of one half of a yin-yang
// disc standing in the xz-plane: the disc's outer half circle (radius
// `reach`, bulging to +x) and the S curve that divides the disc (two half
// circles of radius reach / 2), both swept by a round section of radius
// `thick`. The ends sit on the z axis at z = +-reach; the cup's wall
// passes through them, and the cup cuts away what reaches into its cavity.
// OpenSCAD Customizer annotations (OpenSCAD User Manual, "Customizer").

/* [Handle] */
// Radius of the yin-yang disc the handle outlines (mm)
reach = 16; // [4:40]

// Radius of the handle's round section (mm)
thick = 3.5; // [1:15]

/* [Hidden] */
$fn = 24;

// A half circle of radius r swept by the section, in the xz-plane, centred
// at (0, 0, z0), bulging to +x (side = 1) or -x (side = -1).
module arc(r, z0, side) {
    translate([0, 0, z0]) rotate([90, 0, 0]) rotate([0, 0, side > 0 ? -90 : 90])
        rotate_extrude(angle = 180) translate([r, 0]) circle(r = thick);
}

union() {
    arc(reach, 0, 1);             // the disc's outer half
    arc(reach / 2, reach / 2, 1); // the S curve: upper half bulges outward
    arc(reach / 2, -reach / 2, -1); //            lower half bulges inward
}

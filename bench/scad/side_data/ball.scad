// The outside mesh of the side-data run (job.yaml): OpenSCAD's 300-fragment
// sphere of radius 10 mm (45,000 vertices, 89,402 faces, about 2.2 MB in
// fabatlas's memory). Make it once:
//   openscad -o bench/scad/side_data/ball.off bench/scad/side_data/ball.scad
sphere(r = 10, $fn = 300);

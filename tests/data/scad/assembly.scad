// Imports resolve relative to this file's directory.
union() {
  import("parts/tetra.off");
  translate([2, 0, 0]) import(file = "cube.off", convexity = 3);
}

// fuzz-csg: seed 0xf58732324b4ec43f family tilted touching yes provenance no; 9 leaves
union() {
  multmatrix([[4, 8, -1, 39], [-4, 1, -8, 15], [-7, 4, 4, -21], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 1, r2 = 1, center = true, $fn = 12);
  union() {
    union() {
      multmatrix([[4, -1, 8, 19], [-4, -8, 1, 26], [-7, 4, 4, -4], [0, 0, 0, 1]]) cube([2, 3, 2], center = false);
      multmatrix([[8, -1, 4, 32], [1, -8, -4, 31], [4, 4, -7, -11], [0, 0, 0, 1]]) cylinder(h = 1, r1 = 1.5, r2 = 1.5, center = false, $fn = 4);
    }
    multmatrix([[8, 1, 4, 11], [1, 8, -4, 25], [4, -4, -7, -8], [0, 0, 0, 1]]) cube([2, 2, 3], center = false);
  }
  difference() {
    multmatrix([[-8, -1, -4, 51], [-1, -8, 4, 12], [-4, 4, 7, -24], [0, 0, 0, 1]]) cube([3, 2, 2], center = false);
    intersection() {
      multmatrix([[-8, -4, -1, 44], [-4, 7, 4, -5], [1, -4, 8, 8], [0, 0, 0, 1]]) cube([3, 1, 3], center = false);
      intersection() {
        multmatrix([[4, -1, 8, 31], [-4, -8, 1, 23], [-7, 4, 4, -7], [0, 0, 0, 1]]) sphere(r = 2, $fn = 8);
        multmatrix([[-1, 4, 8, 43], [-8, -4, 1, 11], [4, -7, 4, -28], [0, 0, 0, 1]]) sphere(r = 2, $fn = 8);
      }
    }
    multmatrix([[1, -4, 8, 24], [8, 4, 1, 30], [-4, 7, 4, -15], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 2, r2 = 2, center = false, $fn = 3);
  }
}
// Shrunk to 9 leaves; it failed with: invalid output (334 triangles): 0 boundary, 4 non-manifold, 0 inconsistent, 0 unbalanced edges; 0 degenerate, 1 duplicate triangles; 0 non-finite vertices

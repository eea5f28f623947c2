// fuzz-csg: seed 0x64be0023e0c7136b family tilted touching yes provenance no; 5 leaves
// A cube of volume 54 touching one of 108 along an edge where rounding folded a thin
// triangle of each onto the other: the smaller shell was removed as a folded sliver.
union() {
  union() {
    multmatrix([[2, -2, -1, 6], [-1, -2, 2, 9], [2, 1, 2, 3], [0, 0, 0, 1]]) cube([2, 1, 1], center = false);
    intersection() {
      multmatrix([[-2, -1, -2, 5], [1, 2, -2, 5], [-2, 2, 1, 2], [0, 0, 0, 1]]) cylinder(h = 1, r1 = 2, r2 = 2, center = false, $fn = 12);
      multmatrix([[-2, -1, -2, 8], [-2, 2, 1, 2], [1, 2, -2, 2], [0, 0, 0, 1]]) cube([1, 2, 2], center = false);
    }
  }
  intersection() {
    multmatrix([[-2, -1, -2, 8], [-2, 2, 1, 2], [1, 2, -2, 2], [0, 0, 0, 1]]) cube([1, 2, 2], center = false);
    multmatrix([[1, -2, 2, 3], [-2, -2, -1, 12], [-2, 1, 2, 3], [0, 0, 0, 1]]) cube([3, 1, 2], center = false);
  }
}
// Shrunk to 5 leaves; it failed with: at (5.424452747776952, 7.134691921702129, 6.8999397637829034) the result's winding number is 0.000000 but the point is inside the tree's solid

// fuzz_csg seed 0x612d3b4f107e4ce5 (grid family), shrunk to 4 leaves. Rounding puts a
// ridge of the sphere onto a face of a box (8 crossing pairs); evaluated again, its
// parts touch along an edge where the exact result does not touch: their vertex copies
// are moved apart inside the round.
difference() {
  union() {
    intersection() {
      multmatrix([[0, 1, 0, 3], [-1, 0, 0, 3], [0, 0, 1, 1], [0, 0, 0, 1]]) sphere(r = 2, $fn = 8);
      multmatrix([[1, 0, 0, 3], [0, 1, 0, 2], [0, 0, 1, 2], [0, 0, 0, 1]]) cube([2, 3, 2], center = false);
    }
    multmatrix([[0, 0, 1, 1], [0, 1, 0, 1], [1, 0, 0, 0], [0, 0, 0, 1]]) cube([2, 2, 3], center = false);
  }
  multmatrix([[1, 0, 0, 2], [0, 0, -1, 2], [0, 1, 0, 1], [0, 0, 0, 1]]) cylinder(h = 1, r1 = 2, r2 = 2, center = false, $fn = 3);
}

// fuzz_csg seed 0x3e46cc6a3545eac9 (grid family), shrunk to 2 leaves. Rounding puts a
// vertex of the cut onto the box's face x = 0, inside a triangle of it (4 pairs of
// triangles touching there); the rounds evaluate it again to the same mesh (a touch
// changes no winding number). Moving that corner by one unit in the last place, off
// the face, mends it.
difference() {
  multmatrix([[0, 1, 0, 0], [-1, 0, 0, 2], [0, 0, -1, 6], [0, 0, 0, 1]]) cube([1, 2, 3], center = false);
  multmatrix([[1, 0, 0, 1], [0, -1, 0, 3], [0, 0, -1, 4], [0, 0, 0, 1]]) cylinder(h = 3, r1 = 2, r2 = 0, center = false, $fn = 3);
}

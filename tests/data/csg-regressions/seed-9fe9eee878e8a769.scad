// fuzz-csg: seed 0x9fe9eee878e8a769 family tilted touching yes provenance no; 2 leaves
// Caught: a sliver of the exact result rounded to a closed shell that is flat or inside out
// (the whole output); such shells are now removed (void_shells.c).
intersection() {
  multmatrix([[1, -4, -8, 3], [8, 4, -1, 6], [4, -7, 4, 48], [0, 0, 0, 1]]) cylinder(h = 1, r1 = 2, r2 = 2, center = false, $fn = 3);
  multmatrix([[4, 1, 8, -29], [-4, 8, 1, 11], [7, 4, -4, 46], [0, 0, 0, 1]]) cube([2, 1, 2], center = false);
}
// Shrunk to 2 leaves; it failed with: output is inverted (volume 0)

// fuzz-csg: seed 0x5803ca1a87ccda41 family tilted touching yes provenance no; 2 leaves
// Caught: a sliver of the exact result rounded to a closed shell that is flat or inside out
// (the whole output); such shells are now removed (void_shells.c).
intersection() {
  multmatrix([[-8, 1, 4, 18], [-1, 8, -4, 18], [-4, -4, -7, 0], [0, 0, 0, 1]]) cube([1, 2, 3], center = false);
  multmatrix([[-1, -8, -4, 36], [-8, -1, 4, 18], [4, -4, 7, -36], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 1, r2 = 1, center = true, $fn = 12);
}
// Shrunk to 2 leaves; it failed with: output is inverted (volume -1.51582e-13)

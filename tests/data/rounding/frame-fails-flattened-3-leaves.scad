// Shrunk from fuzz seed 0x3ef8374711511995 (export family, its turn written around the
// tree; 70 leaves, 6 digits): the turned group's result has slivers folded onto each
// other that the evaluation around it cannot take as a leaf (the winding number of a
// region below the resolution of doubles is not decided), so the tree is evaluated
// again with each leaf turned on its own, and that result is clean.
multmatrix([[-0.5, -0.866025, 0, 0], [0.866025, -0.5, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) {
  difference() {
    union() {
      multmatrix([[1, 0, 0, 0], [0, 0.707107, -0.707107, 40], [0, 0.707107, 0.707107, 0], [0, 0, 0, 1]]) cube([50, 50, 45], center = true);
      multmatrix([[1, 0, 0, 0], [0, 0.707107, -0.707107, 40], [0, 0.707107, 0.707107, 0], [0, 0, 0, 1]]) cube([45, 45, 45], center = true);
    }
    multmatrix([[0.707107, -0.707107, 0, 40], [0.707107, 0.707107, 0, 40], [0, 0, 1, 0], [0, 0, 0, 1]]) cube([50, 50, 50], center = true);
  }
}

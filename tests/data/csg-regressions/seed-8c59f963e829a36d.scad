// fuzz-csg: seed 0x8c59f963e829a36d family grid touching yes provenance yes; 21 leaves
// Caught: folded or flattened triangles after rounding to doubles.
intersection() {
  union() {
    union() {
      intersection() {
        union() {
          intersection() {
            difference() {
              union() {
                union() {
                  difference() {
                    intersection() {
                      difference() {
                        multmatrix([[1, 0, 0, 3], [0, 0, -1, 3], [0, -1, 0, 4], [0, 0, 0, 1]]) cube([3, 2, 2], center = false);
                        multmatrix([[0, 0, 1, 0], [-1, 0, 0, 5], [0, -1, 0, 4], [0, 0, 0, 1]]) cube([2, 1, 1], center = false);
                      }
                      multmatrix([[0, -1, 0, 3], [0, 0, 1, 3], [-1, 0, 0, 4], [0, 0, 0, 1]]) cube([1, 2, 1], center = false);
                      multmatrix([[-1, 0, 0, 2], [0, -1, 0, 4], [0, 0, 1, 3], [0, 0, 0, 1]]) sphere(r = 2, $fn = 4);
                      multmatrix([[1, 0, 0, 3], [0, 0, 1, 3], [0, -1, 0, 4], [0, 0, 0, 1]]) cube([2, 2, 1], center = false);
                    }
                    multmatrix([[-1, 0, 0, 1], [0, 1, 0, 0], [0, 0, -1, 5], [0, 0, 0, 1]]) cube([1, 1, 2], center = false);
                    multmatrix([[-1, 0, 0, 3], [0, 0, 1, 1], [0, 1, 0, 1], [0, 0, 0, 1]]) cube([2, 3, 3], center = false);
                  }
                  multmatrix([[0, 0, 1, 4], [1, 0, 0, 2], [0, -1, 0, 2], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 2, r2 = 2, center = true, $fn = 4);
                  multmatrix([[0, 0, -1, 3], [-1, 0, 0, 1], [0, -1, 0, 6], [0, 0, 0, 1]]) cube([1, 3, 3], center = false);
                }
                multmatrix([[0, -1, 0, 5], [0, 0, -1, 4], [1, 0, 0, 3], [0, 0, 0, 1]]) cube([3, 2, 1], center = false);
              }
              multmatrix([[0, -1, 0, 4], [1, 0, 0, 0], [0, 0, -1, 3], [0, 0, 0, 1]]) cube([2, 3, 2], center = false);
            }
            multmatrix([[0, 0, 1, 4], [1, 0, 0, 1], [0, 1, 0, 1], [0, 0, 0, 1]]) cylinder(h = 3, r1 = 0.5, r2 = 0, center = false, $fn = 12);
          }
          multmatrix([[0, -1, 0, 3], [1, 0, 0, 1], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([1, 2, 1], center = false);
        }
        multmatrix([[0, 0, -1, 5], [1, 0, 0, 3], [0, 1, 0, 0], [0, 0, 0, 1]]) cube([3, 2, 2], center = false);
      }
      multmatrix([[1, 0, 0, 2], [0, 1, 0, 1], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([2, 3, 2], center = false);
      multmatrix([[-1, 0, 0, 1], [0, 1, 0, 0], [0, 0, -1, 5], [0, 0, 0, 1]]) cube([1, 1, 2], center = false);
      multmatrix([[0, -1, 0, 4], [0, 0, -1, 1], [1, 0, 0, 0], [0, 0, 0, 1]]) cube([2, 3, 1], center = false);
    }
    multmatrix([[-1, 0, 0, 6], [0, 0, -1, 4], [0, -1, 0, 4], [0, 0, 0, 1]]) cube([3, 2, 2], center = false);
    multmatrix([[0, -1, 0, 4], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) cube([3, 3, 2], center = false);
    multmatrix([[1, 0, 0, 1], [0, -1, 0, 2], [0, 0, -1, 3], [0, 0, 0, 1]]) sphere(r = 1, $fn = 8);
  }
  multmatrix([[0, -1, 0, 5], [0, 0, -1, 2], [-1, 0, 0, 1], [0, 0, 0, 1]]) cube([1, 2, 2], center = false);
}

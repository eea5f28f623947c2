// fuzz-csg: seed 0x71c8f971b26c7794 family grid touching yes provenance no; 23 leaves
// Caught: folded or flattened triangles after rounding to doubles.
difference() {
  union() {
    multmatrix([[0, 0, -1, 2], [0, -1, 0, 4], [1, 0, 0, 1], [0, 0, 0, 1]]) cube([3, 3, 2], center = false);
    difference() {
      multmatrix([[0, 1, 0, 2], [0, 0, 1, 2], [-1, 0, 0, 4], [0, 0, 0, 1]]) cube([2, 3, 2], center = false);
      multmatrix([[0, -1, 0, 4], [0, 0, -1, 2], [-1, 0, 0, 3], [0, 0, 0, 1]]) cube([1, 1, 2], center = false);
    }
    multmatrix([[0, 0, 1, 3], [-1, 0, 0, 4], [0, 1, 0, 4], [0, 0, 0, 1]]) cylinder(h = 1, r1 = 2, r2 = 2, center = true, $fn = 8);
  }
  union() {
    intersection() {
      multmatrix([[-1, 0, 0, 4], [0, 0, 1, 2], [0, 1, 0, 3], [0, 0, 0, 1]]) cube([2, 1, 2], center = false);
      multmatrix([[0, 0, 1, 0], [-1, 0, 0, 5], [0, 1, 0, 0], [0, 0, 0, 1]]) cube([2, 2, 3], center = false);
      multmatrix([[0, -1, 0, 4], [0, 0, -1, 2], [-1, 0, 0, 3], [0, 0, 0, 1]]) cube([1, 1, 2], center = false);
      multmatrix([[0, -1, 0, 4], [0, 0, -1, 5], [-1, 0, 0, 6], [0, 0, 0, 1]]) cube([3, 3, 2], center = false);
    }
    union() {
      union() {
        multmatrix([[0, 0, -1, 1], [0, 1, 0, 1], [-1, 0, 0, 4], [0, 0, 0, 1]]) sphere(r = 2, $fn = 4);
        intersection() {
          difference() {
            multmatrix([[0, -1, 0, 4], [1, 0, 0, 3], [0, 0, 1, 2], [0, 0, 0, 1]]) cube([3, 2, 3], center = false);
            multmatrix([[-1, 0, 0, 5], [0, 0, 1, 1], [0, -1, 0, 6], [0, 0, 0, 1]]) cube([2, 3, 3], center = false);
          }
          intersection() {
            multmatrix([[-1, 0, 0, 3], [0, 0, -1, 1], [0, -1, 0, 1], [0, 0, 0, 1]]) sphere(r = 1.5, $fn = 4);
            multmatrix([[0, 0, 1, 2], [0, -1, 0, 2], [-1, 0, 0, 2], [0, 0, 0, 1]]) cube([2, 2, 1], center = false);
          }
          multmatrix([[0, 1, 0, 1], [0, 0, -1, 4], [1, 0, 0, 0], [0, 0, 0, 1]]) cube([3, 1, 3], center = false);
        }
        union() {
          union() {
            multmatrix([[0, 0, 1, 3], [0, 1, 0, 0], [1, 0, 0, 3], [0, 0, 0, 1]]) cube([2, 2, 1], center = false);
            multmatrix([[0, 1, 0, 3], [0, 0, 1, 0], [-1, 0, 0, 3], [0, 0, 0, 1]]) cube([1, 1, 2], center = false);
          }
          multmatrix([[0, 0, -1, 3], [1, 0, 0, 1], [0, 1, 0, 0], [0, 0, 0, 1]]) cube([1, 1, 3], center = false);
        }
        multmatrix([[-1, 0, 0, 4], [0, 1, 0, 0], [0, 0, -1, 3], [0, 0, 0, 1]]) cube([1, 3, 1], center = false);
      }
      union() {
        intersection() {
          multmatrix([[0, 1, 0, 1], [1, 0, 0, 4], [0, 0, -1, 4], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 2, r2 = 2, center = false, $fn = 8);
          multmatrix([[0, 0, 1, 4], [0, -1, 0, 3], [1, 0, 0, 4], [0, 0, 0, 1]]) sphere(r = 1, $fn = 6);
        }
        union() {
          multmatrix([[0, 0, 1, 0], [0, -1, 0, 5], [-1, 0, 0, 5], [0, 0, 0, 1]]) cube([2, 3, 1], center = false);
          multmatrix([[0, 0, 1, 0], [1, 0, 0, 0], [0, -1, 0, 3], [0, 0, 0, 1]]) cube([3, 1, 1], center = false);
        }
      }
    }
    multmatrix([[0, -1, 0, 2], [1, 0, 0, 2], [0, 0, 1, 1], [0, 0, 0, 1]]) cube([2, 1, 3], center = false);
  }
}

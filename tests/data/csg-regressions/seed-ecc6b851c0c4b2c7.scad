// fuzz-csg: seed 0xecc6b851c0c4b2c7 family grid touching yes provenance yes; 30 leaves
// Caught: output changed from run to run (point definitions ordered by address).
intersection() {
  union() {
    union() {
      multmatrix([[0, 0, -1, 4], [1, 0, 0, 2], [0, 1, 0, 1], [0, 0, 0, 1]]) cube([3, 1, 1], center = false);
      union() {
        multmatrix([[-1, 0, 0, 3], [0, -1, 0, 4], [0, 0, -1, 3], [0, 0, 0, 1]]) sphere(r = 1.5, $fn = 4);
        multmatrix([[0, -1, 0, 4], [-1, 0, 0, 1], [0, 0, -1, 1], [0, 0, 0, 1]]) sphere(r = 1.5, $fn = 8);
      }
    }
    union() {
      difference() {
        multmatrix([[0, 0, 1, 1], [0, -1, 0, 2], [-1, 0, 0, 3], [0, 0, 0, 1]]) cube([3, 2, 2], center = false);
        multmatrix([[1, 0, 0, 2], [0, 1, 0, 4], [0, 0, 1, 1], [0, 0, 0, 1]]) sphere(r = 1, $fn = 6);
      }
      multmatrix([[0, -1, 0, 2], [-1, 0, 0, 4], [0, 0, -1, 3], [0, 0, 0, 1]]) cylinder(h = 3, r1 = 2, r2 = 2, center = false, $fn = 3);
    }
  }
  union() {
    multmatrix([[0, 0, -1, 3], [1, 0, 0, 2], [0, -1, 0, 3], [0, 0, 0, 1]]) sphere(r = 2, $fn = 6);
    union() {
      union() {
        union() {
          multmatrix([[0, 1, 0, 3], [-1, 0, 0, 5], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([2, 2, 2], center = false);
          union() {
            multmatrix([[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 2], [0, 0, 0, 1]]) cube([3, 3, 1], center = false);
            multmatrix([[0, -1, 0, 6], [1, 0, 0, 1], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([2, 3, 3], center = false);
          }
          union() {
            multmatrix([[0, 1, 0, 2], [1, 0, 0, 2], [0, 0, 1, 2], [0, 0, 0, 1]]) cube([3, 3, 2], center = false);
            multmatrix([[1, 0, 0, 2], [0, -1, 0, 3], [0, 0, -1, 4], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 2, r2 = 0, center = true, $fn = 8);
          }
        }
        multmatrix([[0, 0, 1, 0], [1, 0, 0, 1], [0, -1, 0, 3], [0, 0, 0, 1]]) cube([2, 1, 2], center = false);
        multmatrix([[0, 1, 0, 1], [0, 0, -1, 4], [1, 0, 0, 3], [0, 0, 0, 1]]) cube([2, 2, 1], center = false);
      }
      difference() {
        multmatrix([[0, 0, -1, 2], [0, -1, 0, 4], [1, 0, 0, 1], [0, 0, 0, 1]]) cube([3, 3, 1], center = false);
        multmatrix([[-1, 0, 0, 2], [0, -1, 0, 3], [0, 0, -1, 2], [0, 0, 0, 1]]) sphere(r = 1.5, $fn = 4);
      }
      multmatrix([[0, -1, 0, 3], [0, 0, 1, 1], [-1, 0, 0, 2], [0, 0, 0, 1]]) cube([1, 1, 2], center = false);
    }
    union() {
      union() {
        difference() {
          multmatrix([[0, 0, -1, 4], [1, 0, 0, 0], [0, 1, 0, 1], [0, 0, 0, 1]]) cube([1, 1, 2], center = false);
          multmatrix([[0, 1, 0, 3], [-1, 0, 0, 5], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([2, 2, 2], center = false);
        }
        multmatrix([[-1, 0, 0, 4], [0, 1, 0, 1], [0, 0, 1, 1], [0, 0, 0, 1]]) cube([3, 2, 3], center = false);
        multmatrix([[1, 0, 0, 2], [0, 0, -1, 2], [0, -1, 0, 4], [0, 0, 0, 1]]) cube([3, 1, 1], center = false);
      }
      difference() {
        union() {
          multmatrix([[1, 0, 0, 1], [0, 1, 0, 0], [0, 0, -1, 5], [0, 0, 0, 1]]) cube([3, 1, 3], center = false);
          union() {
            multmatrix([[0, -1, 0, 4], [0, 0, 1, 2], [1, 0, 0, 3], [0, 0, 0, 1]]) cube([3, 3, 3], center = false);
            multmatrix([[0, 1, 0, 3], [0, 0, -1, 3], [1, 0, 0, 3], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 1, r2 = 1, center = false, $fn = 4);
          }
          multmatrix([[0, 0, 1, 4], [0, -1, 0, 2], [1, 0, 0, 2], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 0.5, r2 = 0, center = false, $fn = 3);
        }
        multmatrix([[-1, 0, 0, 6], [0, 0, -1, 4], [0, 1, 0, 2], [0, 0, 0, 1]]) cube([3, 1, 2], center = false);
      }
      union() {
        multmatrix([[-1, 0, 0, 6], [0, 0, -1, 5], [0, -1, 0, 4], [0, 0, 0, 1]]) cube([3, 2, 2], center = false);
        multmatrix([[0, -1, 0, 5], [1, 0, 0, 0], [0, 0, -1, 2], [0, 0, 0, 1]]) cube([1, 2, 1], center = false);
        multmatrix([[0, 0, 1, 2], [-1, 0, 0, 1], [0, -1, 0, 4], [0, 0, 0, 1]]) cube([1, 1, 3], center = false);
        multmatrix([[0, 0, -1, 5], [0, 1, 0, 1], [1, 0, 0, 0], [0, 0, 0, 1]]) cube([3, 1, 2], center = false);
      }
    }
  }
}

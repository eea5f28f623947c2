// fuzz-csg: seed 0xee029dc935e28966 family grid touching yes provenance yes; 10 leaves
// Caught: folded or flattened triangles after rounding to doubles.
difference() {
  intersection() {
    difference() {
      union() {
        union() {
          multmatrix([[0, -1, 0, 2], [1, 0, 0, 4], [0, 0, 1, 1], [0, 0, 0, 1]]) sphere(r = 1.5, $fn = 6);
          multmatrix([[-1, 0, 0, 1], [0, 0, -1, 1], [0, -1, 0, 1], [0, 0, 0, 1]]) cylinder(h = 3, r1 = 0.5, r2 = 0.5, center = false, $fn = 6);
        }
        multmatrix([[0, 0, -1, 2], [0, -1, 0, 2], [1, 0, 0, 1], [0, 0, 0, 1]]) sphere(r = 2, $fn = 6);
      }
      difference() {
        multmatrix([[-1, 0, 0, 6], [0, 0, 1, 2], [0, -1, 0, 1], [0, 0, 0, 1]]) cube([3, 1, 2], center = false);
        difference() {
          multmatrix([[0, 0, 1, 3], [0, -1, 0, 4], [-1, 0, 0, 5], [0, 0, 0, 1]]) cube([3, 3, 3], center = false);
          multmatrix([[1, 0, 0, 1], [0, -1, 0, 1], [0, 0, -1, 4], [0, 0, 0, 1]]) sphere(r = 1, $fn = 8);
        }
      }
    }
    difference() {
      multmatrix([[0, -1, 0, 1], [-1, 0, 0, 2], [0, 0, -1, 2], [0, 0, 0, 1]]) sphere(r = 2, $fn = 6);
      union() {
        multmatrix([[0, 0, -1, 4], [0, 1, 0, 1], [-1, 0, 0, 4], [0, 0, 0, 1]]) cube([2, 3, 1], center = false);
        multmatrix([[0, 0, 1, 1], [1, 0, 0, 0], [0, -1, 0, 3], [0, 0, 0, 1]]) cube([1, 2, 3], center = false);
      }
    }
  }
  multmatrix([[-1, 0, 0, 1], [0, 0, -1, 5], [0, 1, 0, 1], [0, 0, 0, 1]]) cube([1, 2, 3], center = false);
}

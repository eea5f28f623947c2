// fuzz-csg: seed 0xc90ecd7a33bc97bf family grid touching yes provenance no; 30 leaves
// Caught: "a region's label could not be decided" (faces coplanar with another leaf).
union() {
  union() {
    union() {
      multmatrix([[0, 0, 1, 2], [0, 1, 0, 3], [-1, 0, 0, 4], [0, 0, 0, 1]]) cylinder(h = 3, r1 = 1.5, r2 = 1.5, center = true, $fn = 12);
      multmatrix([[0, 0, 1, 1], [1, 0, 0, 1], [0, -1, 0, 3], [0, 0, 0, 1]]) sphere(r = 1.5, $fn = 8);
    }
    multmatrix([[0, 0, -1, 4], [0, 1, 0, 2], [1, 0, 0, 3], [0, 0, 0, 1]]) cube([2, 2, 1], center = false);
    difference() {
      multmatrix([[0, -1, 0, 3], [1, 0, 0, 1], [0, 0, -1, 5], [0, 0, 0, 1]]) cube([3, 3, 2], center = false);
      difference() {
        union() {
          multmatrix([[0, 0, -1, 4], [0, 1, 0, 2], [1, 0, 0, 3], [0, 0, 0, 1]]) cube([2, 2, 1], center = false);
          multmatrix([[0, 0, 1, 2], [0, 1, 0, 3], [-1, 0, 0, 4], [0, 0, 0, 1]]) cylinder(h = 3, r1 = 1.5, r2 = 1.5, center = true, $fn = 12);
        }
        difference() {
          multmatrix([[0, 1, 0, 2], [-1, 0, 0, 5], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([3, 3, 2], center = false);
          multmatrix([[0, 0, 1, 4], [1, 0, 0, 4], [0, 1, 0, 4], [0, 0, 0, 1]]) sphere(r = 2, $fn = 4);
        }
      }
    }
    union() {
      intersection() {
        multmatrix([[0, 1, 0, 2], [1, 0, 0, 1], [0, 0, -1, 2], [0, 0, 0, 1]]) cube([3, 2, 2], center = false);
        union() {
          multmatrix([[-1, 0, 0, 4], [0, -1, 0, 2], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([3, 1, 2], center = false);
          multmatrix([[0, -1, 0, 1], [-1, 0, 0, 3], [0, 0, -1, 2], [0, 0, 0, 1]]) cube([1, 1, 1], center = false);
        }
      }
      difference() {
        union() {
          multmatrix([[-1, 0, 0, 4], [0, 0, 1, 1], [0, 1, 0, 1], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 2, r2 = 2, center = false, $fn = 8);
          multmatrix([[-1, 0, 0, 1], [0, 0, -1, 2], [0, 1, 0, 1], [0, 0, 0, 1]]) cube([1, 3, 1], center = false);
          multmatrix([[0, -1, 0, 1], [-1, 0, 0, 3], [0, 0, -1, 2], [0, 0, 0, 1]]) cube([1, 1, 1], center = false);
        }
        union() {
          union() {
            multmatrix([[0, 0, 1, 2], [0, -1, 0, 3], [-1, 0, 0, 4], [0, 0, 0, 1]]) sphere(r = 2, $fn = 8);
            multmatrix([[1, 0, 0, 0], [0, 1, 0, 3], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([2, 1, 2], center = false);
            multmatrix([[0, 0, -1, 6], [0, -1, 0, 2], [-1, 0, 0, 5], [0, 0, 0, 1]]) cube([3, 2, 3], center = false);
          }
          multmatrix([[-1, 0, 0, 4], [0, 0, 1, 1], [0, 1, 0, 1], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 2, r2 = 2, center = false, $fn = 8);
          multmatrix([[0, 1, 0, 3], [-1, 0, 0, 2], [0, 0, 1, 2], [0, 0, 0, 1]]) cube([1, 1, 3], center = false);
        }
      }
      difference() {
        intersection() {
          multmatrix([[1, 0, 0, 1], [0, 1, 0, 3], [0, 0, -1, 3], [0, 0, 0, 1]]) cylinder(h = 1, r1 = 1, r2 = 1, center = false, $fn = 4);
          multmatrix([[0, 1, 0, 3], [1, 0, 0, 3], [0, 0, -1, 3], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 0.5, r2 = 0, center = true, $fn = 4);
        }
        union() {
          multmatrix([[1, 0, 0, 1], [0, 0, 1, 1], [0, -1, 0, 4], [0, 0, 0, 1]]) cube([3, 3, 3], center = false);
          multmatrix([[0, -1, 0, 6], [-1, 0, 0, 3], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([2, 3, 2], center = false);
        }
        multmatrix([[-1, 0, 0, 3], [0, -1, 0, 4], [0, 0, 1, 1], [0, 0, 0, 1]]) cube([1, 1, 3], center = false);
      }
    }
  }
  union() {
    multmatrix([[0, -1, 0, 6], [-1, 0, 0, 3], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([2, 3, 2], center = false);
    union() {
      multmatrix([[0, 1, 0, 3], [-1, 0, 0, 3], [0, 0, 1, 0], [0, 0, 0, 1]]) cube([3, 2, 1], center = false);
      multmatrix([[0, 0, 1, 3], [1, 0, 0, 2], [0, 1, 0, 3], [0, 0, 0, 1]]) cube([2, 3, 1], center = false);
      multmatrix([[-1, 0, 0, 4], [0, 1, 0, 0], [0, 0, -1, 6], [0, 0, 0, 1]]) cube([1, 2, 3], center = false);
      multmatrix([[0, 0, 1, 3], [0, 1, 0, 4], [1, 0, 0, 1], [0, 0, 0, 1]]) cylinder(h = 1, r1 = 2, r2 = 2, center = false, $fn = 4);
    }
    multmatrix([[1, 0, 0, 0], [0, 1, 0, 3], [0, 0, 1, 3], [0, 0, 0, 1]]) cube([2, 1, 2], center = false);
  }
}

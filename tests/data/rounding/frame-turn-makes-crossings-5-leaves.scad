// Shrunk by removing leaves from fuzz seed 0x933f38573a86f08f (export family, its turn
// written around the tree): turning the group's result makes 12 pairs of its triangles
// cross; moving 2 corners by a unit in the last place mends them.
multmatrix([[0.25881900000000002, 0.96592599999999995, 0, 1000], [-5.9145899999999996e-17, 1.5848100000000001e-17, -1, -2000], [-0.96592599999999995, 0.25881900000000002, 6.1232300000000004e-17, 500], [0, 0, 0, 1]]) {
  union() {
    union() {
      union() {
        union() {
          union() {
            intersection() {
              union() {
                intersection() {
                  union() {
                    intersection() {
                      union() {
                        union() {
                          difference() {
                          }
                        }
                      }
                    }
                  }
                }
              }
            }
          }
        }
        union() {
        }
      }
      multmatrix([[-0.25881900000000002, -0.96592599999999995, 0, 0], [0.96592599999999995, -0.25881900000000002, 0, 40], [0, 0, 1, 0], [0, 0, 0, 1]]) cube([45, 50, 45], center = true);
    }
    union() {
      intersection() {
        multmatrix([[0.96592599999999995, -0.25881900000000002, 0, 0], [0.25881900000000002, 0.96592599999999995, 0, 40], [0, 0, 1, 0], [0, 0, 0, 1]]) cube([50, 50, 45], center = true);
      }
      union() {
        intersection() {
          difference() {
            union() {
              union() {
                multmatrix([[1, 0, 0, 40], [0, 0.5, -0.86602500000000004, 40], [0, 0.86602500000000004, 0.5, 0], [0, 0, 0, 1]]) cube([50, 45, 45], center = true);
              }
            }
            intersection() {
              multmatrix([[1, 0, 0, 40], [0, -0.25881900000000002, -0.96592599999999995, 40], [0, 0.96592599999999995, -0.25881900000000002, 0], [0, 0, 0, 1]]) cube([50, 50, 45], center = true);
            }
          }
          difference() {
            intersection() {
              intersection() {
              }
              union() {
              }
            }
          }
          difference() {
            union() {
            }
          }
        }
        union() {
          multmatrix([[1, 0, 0, 0], [0, -0.96592599999999995, -0.25881900000000002, 80], [0, 0.25881900000000002, -0.96592599999999995, 0], [0, 0, 0, 1]]) cube([45, 50, 50], center = true);
        }
        union() {
        }
      }
    }
  }
}

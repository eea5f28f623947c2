// fuzz-csg: seed 0x7e0c761b43f114a7 family export touching yes provenance yes; 72 leaves
// Fuzz seed 0x7e0c761b43f114a7 (run 44), shrunk to 12 leaves by removing leaves (its
// empty groups matter). The turned group's result crosses itself; evaluated as a leaf by
// its winding number it lost a part of the solid: a fold flat onto itself there (a crack
// of no width between coincident sheets facing opposite ways) was joined into one region
// with the faces beside it, and the ray from a piece of the fold gave them all the
// numbers beyond the whole stack (tests/data/rounding/flat-fold-crack.off).
multmatrix([[0.70710700000000004, 0.70710700000000004, 0, 0], [-4.3297799999999998e-17, 4.3297799999999998e-17, -1, 0], [-0.70710700000000004, 0.70710700000000004, 6.1232300000000004e-17, 0], [0, 0, 0, 1]]) {
  union() {
    intersection() {
      union() {
        intersection() {
          union() {
            union() {
            }
            intersection() {
            }
          }
        }
        difference() {
          union() {
            intersection() {
              intersection() {
              }
            }
            union() {
              union() {
                difference() {
                  union() {
                  }
                }
              }
            }
          }
          difference() {
            difference() {
              union() {
                difference() {
                }
                intersection() {
                }
              }
              union() {
              }
            }
            union() {
              union() {
              }
              intersection() {
              }
              difference() {
                difference() {
                  intersection() {
                  }
                }
              }
            }
            union() {
              union() {
                multmatrix([[1, 0, 0, 80], [0, -0.96592599999999995, -0.25881900000000002, 40], [0, 0.25881900000000002, -0.96592599999999995, 0], [0, 0, 0, 1]]) cube([45, 50, 50], center = true);
                difference() {
                  difference() {
                  }
                }
              }
              multmatrix([[6.1232300000000004e-17, -1, 0, 120], [1, 6.1232300000000004e-17, 0, 40], [0, 0, 1, 0], [0, 0, 0, 1]]) cube([50, 45, 50], center = true);
            }
            difference() {
              multmatrix([[-0.25881900000000002, 0, 0.96592599999999995, 120], [0, 1, 0, 40], [-0.96592599999999995, 0, -0.25881900000000002, 0], [0, 0, 0, 1]]) cube([50, 50, 50], center = true);
            }
          }
        }
      }
      intersection() {
        intersection() {
        }
        union() {
          intersection() {
          }
          difference() {
            union() {
              difference() {
              }
            }
            intersection() {
              multmatrix([[1, 0, 0, 40], [0, 0.86602500000000004, -0.5, 80], [0, 0.5, 0.86602500000000004, 0], [0, 0, 0, 1]]) cube([45, 50, 45], center = true);
              multmatrix([[1, 0, 0, 40], [0, -0.70710700000000004, -0.70710700000000004, 80], [0, 0.70710700000000004, -0.70710700000000004, 0], [0, 0, 0, 1]]) cube([50, 45, 50], center = true);
            }
          }
          difference() {
            union() {
              multmatrix([[0.96592599999999995, 0, 0.25881900000000002, 40], [0, 1, 0, 80], [-0.25881900000000002, 0, 0.96592599999999995, 0], [0, 0, 0, 1]]) cube([50, 45, 50], center = true);
              difference() {
                multmatrix([[0.25881900000000002, 0, 0.96592599999999995, 80], [0, 1, 0, 80], [-0.96592599999999995, 0, 0.25881900000000002, 0], [0, 0, 0, 1]]) cube([50, 50, 50], center = true);
              }
            }
            union() {
              intersection() {
              }
            }
          }
        }
      }
    }
    union() {
      union() {
        union() {
          multmatrix([[-0.25881900000000002, 0, 0.96592599999999995, 120], [0, 1, 0, 80], [-0.96592599999999995, 0, -0.25881900000000002, 0], [0, 0, 0, 1]]) cube([50, 50, 45], center = true);
        }
        difference() {
        }
      }
      union() {
        multmatrix([[0.86602500000000004, 0, 0.5, 0], [0, 1, 0, 120], [-0.5, 0, 0.86602500000000004, 0], [0, 0, 0, 1]]) cube([50, 45, 45], center = true);
        union() {
          multmatrix([[0.70710700000000004, -0.70710700000000004, 0, 0], [0.70710700000000004, 0.70710700000000004, 0, 120], [0, 0, 1, 0], [0, 0, 0, 1]]) cube([50, 45, 50], center = true);
          union() {
            multmatrix([[-0.5, 0, 0.86602500000000004, 0], [0, 1, 0, 120], [-0.86602500000000004, 0, -0.5, 0], [0, 0, 0, 1]]) cube([50, 50, 50], center = true);
          }
        }
      }
      intersection() {
        intersection() {
        }
        multmatrix([[-0.96592599999999995, -0.25881900000000002, 0, 40], [0.25881900000000002, -0.96592599999999995, 0, 120], [0, 0, 1, 0], [0, 0, 0, 1]]) cube([45, 45, 50], center = true);
      }
    }
  }
}
// Shrunk to 72 leaves; it failed with: at (89.669425949890282, 20.26087120974038, 99.395590676839419) the result's winding number is 0.000000 but the point is inside the tree's solid

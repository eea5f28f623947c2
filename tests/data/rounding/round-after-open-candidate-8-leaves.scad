// fuzz_csg seed 0x1b0e262942045b62 (grid family), shrunk to 8 leaves (the empty
// operations are as the shrinking left them; removing them changes the case). The first
// round's evaluation of the rounded result is open (1 open edge): no start for the next
// round, which starts from the snapped mesh's evaluation instead and settles it.
union() {
  union() {
    union() {
      intersection() {
        intersection() {
        }
        intersection() {
        }
      }
      intersection() {
      }
      union() {
      }
      union() {
        difference() {
          union() {
          }
        }
        difference() {
          intersection() {
          }
        }
        multmatrix([[0, 0, 1, 3], [-1, 0, 0, 4], [0, 1, 0, 3], [0, 0, 0, 1]]) cube([2, 3, 2], center = false);
      }
    }
    intersection() {
      union() {
        union() {
          difference() {
          }
          difference() {
            multmatrix([[0, 1, 0, 3], [0, 0, -1, 3], [-1, 0, 0, 4], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 0.5, r2 = 0.5, center = true, $fn = 4);
            intersection() {
            }
          }
          multmatrix([[-1, 0, 0, 3], [0, 0, -1, 2], [0, -1, 0, 4], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 0.5, r2 = 0, center = true, $fn = 12);
        }
        difference() {
          union() {
            union() {
              union() {
              }
            }
          }
          difference() {
          }
        }
      }
      difference() {
      }
    }
    union() {
      difference() {
        difference() {
        }
      }
      difference() {
        multmatrix([[0, 0, -1, 3], [0, 1, 0, 2], [-1, 0, 0, 4], [0, 0, 0, 1]]) cube([2, 2, 1], center = false);
      }
    }
  }
  union() {
    union() {
      intersection() {
        intersection() {
        }
      }
      intersection() {
        union() {
        }
      }
      difference() {
        intersection() {
          intersection() {
            intersection() {
              intersection() {
              }
            }
          }
          intersection() {
            union() {
            }
          }
        }
        intersection() {
        }
      }
    }
    intersection() {
      union() {
        difference() {
          union() {
          }
        }
      }
    }
    union() {
      multmatrix([[1, 0, 0, 2], [0, 0, 1, 3], [0, -1, 0, 3], [0, 0, 0, 1]]) sphere(r = 2, $fn = 6);
      intersection() {
        intersection() {
          union() {
            difference() {
            }
          }
        }
        difference() {
          intersection() {
            intersection() {
              union() {
                multmatrix([[0, -1, 0, 4], [0, 0, -1, 3], [1, 0, 0, 3], [0, 0, 0, 1]]) sphere(r = 2, $fn = 6);
              }
            }
            union() {
              union() {
              }
            }
          }
          intersection() {
            multmatrix([[0, -1, 0, 5], [0, 0, 1, 0], [1, 0, 0, 3], [0, 0, 0, 1]]) cube([2, 3, 2], center = false);
          }
        }
      }
    }
  }
  union() {
    union() {
    }
    union() {
      difference() {
        difference() {
        }
      }
      multmatrix([[-1, 0, 0, 2], [0, 0, -1, 2], [0, 1, 0, 4], [0, 0, 0, 1]]) cylinder(h = 2, r1 = 1, r2 = 1, center = false, $fn = 6);
    }
  }
}

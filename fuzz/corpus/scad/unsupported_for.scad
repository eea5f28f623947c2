for (i = [0:3]) translate([i, 0, 0]) cube(1);

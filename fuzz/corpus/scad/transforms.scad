$fn = 12;
translate([1, 2, 3]) rotate([30, 45, 60]) scale([1, 2, 0.5]) cylinder(h = 4, r1 = 2, r2 = 1);
mirror([1, 1, 0]) multmatrix([[1, 0.5, 0, 1], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) cube(2);
rotate(a = 45, v = [1, 1, 1]) cube([1, 2, 3]);

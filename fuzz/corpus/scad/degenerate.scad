scale([1, 0, 1]) cube(1); cube(0); sphere(1e300, $fn = 1e9);

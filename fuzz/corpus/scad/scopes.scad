sphere(2);
$fn = 5;
translate([5, 0, 0], $fn = 7) { $fa = 3; sphere(2); { sphere(3, $fs = 0.5); } }
$fn = 6;

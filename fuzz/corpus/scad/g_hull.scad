hull(){circle(1,$fn=4);translate([3,0])square(1);}
hull(){cube(1);translate([2,2,2])sphere(1,$fn=4);}

minkowski(){square(2);circle(0.5,$fn=4);}
minkowski(){cube([2,1,1]);rotate([0,0,45])cube(0.5);}

linear_extrude(1)offset(r=0.2,$fn=4)projection()hull(){cube(1);translate([1,1,1])cube(1);}

projection(cut=true)rotate([30,40,0])cube(2,center=true);
projection()union(){rotate([45,0,0])cube(1);translate([0.5,0,0])cube([1,2,0.5]);}

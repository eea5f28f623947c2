rotate_extrude(angle=90,$fn=6)translate([2,0])square(1);
rotate_extrude($fn=5)polygon([[0,0],[2,0],[0,2]]);

linear_extrude(height=3,twist=90,slices=3,scale=0.5,center=true)square(2,center=true);
linear_extrude(2,scale=0)circle(1,$fn=5);
linear_extrude(2,scale=[0,1])translate([1,0])square(1);

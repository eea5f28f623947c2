resize([3,0,2],auto=true)sphere(1,$fn=5);
resize([4,1])circle(1,$fn=6);

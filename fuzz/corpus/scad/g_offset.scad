offset(r=0.5,$fn=6)square(2);
offset(delta=-0.3)polygon([[0,0],[3,0],[3,3],[2,1]]);
offset(delta=1,chamfer=true)square(1);

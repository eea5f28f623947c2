circle(r=2,$fn=7); translate([5,0]) square([2,3],center=true);
polygon([[0,0],[4,0],[4,4],[0,4],[1,1],[3,1],[2,3]],[[0,1,2,3],[4,5,6]]);

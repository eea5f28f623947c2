difference(){square(4);translate([1,1])circle(1,$fn=6);}
intersection(){square(3);rotate(30)square(3);}

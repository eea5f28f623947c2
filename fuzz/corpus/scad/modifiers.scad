// background, disabled and highlighted objects
difference() {
  %cube(100);
  #sphere(5);
  *cylinder(h = "never evaluated");
  /* a block
     comment */ cube(3);
}

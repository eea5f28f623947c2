union() {
  cube(1);

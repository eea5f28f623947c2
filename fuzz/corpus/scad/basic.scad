difference() {
  cube(10, center = true);
  sphere(r = 6, $fn = 24);
}

// OpenSCAD's example018 (four cubes, three turned 45 degrees) as its .csg export writes
// it, moved to (150, 150, 0): rounding the exact result to doubles makes 4 edges of more
// than two triangles once vertices are welded by coordinates (at the origin it comes out
// clean).
multmatrix([[1, 0, 0, 150], [0, 1, 0, 150], [0, 0, 1, 0], [0, 0, 0, 1]]) {
  union() {
    cube(size = [45, 45, 45], center = true);
    multmatrix([[1, 0, 0, 0], [0, 0.707107, -0.707107, 0], [0, 0.707107, 0.707107, 0], [0, 0, 0, 1]])
      cube(size = [50, 50, 50], center = true);
    multmatrix([[0.707107, 0, 0.707107, 0], [0, 1, 0, 0], [-0.707107, 0, 0.707107, 0], [0, 0, 0, 1]])
      cube(size = [50, 50, 50], center = true);
    multmatrix([[0.707107, -0.707107, 0, 0], [0.707107, 0.707107, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
      cube(size = [50, 50, 50], center = true);
  }
}

"""The Python interface (python/meshcsg) against known answers. Run by `make test`
(ctest python_api) with MESHCSG_LIBRARY naming the built shared library."""

import logging
import os

import numpy as np
import pytest

import meshcsg

# A unit cube as a user would type it: 8 corners, 12 triangles facing outward.
CUBE_V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                   [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], dtype=np.float64)
CUBE_T = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                   [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])


def unit_cube(scale=1.0, offset=(0, 0, 0)):
    return meshcsg.Mesh(CUBE_V * scale + np.asarray(offset, dtype=np.float64), CUBE_T)


def test_mesh_from_numpy_arrays():
    m = meshcsg.Mesh(CUBE_V, CUBE_T)
    assert m.vertices.shape == (8, 3) and m.vertices.dtype == np.float64
    assert m.triangles.shape == (12, 3) and m.triangles.dtype == np.uint32
    assert m.volume == 1.0
    assert m.area == pytest.approx(6.0, abs=1e-12)
    assert m.is_closed
    assert np.array_equal(m.bounds, [[0, 0, 0], [1, 1, 1]])
    # float64 C-contiguous vertices are used as given, not copied, and left writable
    assert np.shares_memory(m.vertices, CUBE_V)
    assert CUBE_V.flags.writeable and not m.vertices.flags.writeable


def test_mesh_rejects_bad_arrays():
    with pytest.raises(ValueError, match=r"\(n, 3\)"):
        meshcsg.Mesh(np.zeros((4, 2)), CUBE_T)
    with pytest.raises(ValueError, match="outside 0..7"):
        meshcsg.Mesh(CUBE_V, CUBE_T + 1)
    with pytest.raises(ValueError, match="integers"):
        meshcsg.Mesh(CUBE_V, CUBE_T.astype(float))


def test_open_mesh_is_not_closed_and_cannot_be_evaluated():
    open_box = meshcsg.Mesh(CUBE_V, CUBE_T[:-1])
    assert not open_box.is_closed
    with pytest.raises(meshcsg.Error) as raised:
        meshcsg.union(open_box, unit_cube(offset=(5, 0, 0)))
    assert raised.value.status == 7  # MCSG_ERR_INVALID_MESH
    assert "boundary" in str(raised.value) or "closed" in str(raised.value)


def test_results_are_views_of_the_library_memory():
    r = meshcsg.cube(2)
    assert r.vertices.base is not None and not r.vertices.flags.owndata
    assert not r.vertices.flags.writeable
    assert r.volume == 8.0


def test_primitives_follow_openscad():
    assert meshcsg.cube([1, 2, 3]).volume == 6.0
    assert np.array_equal(meshcsg.cube(2, center=True).bounds, [[-1, -1, -1], [1, 1, 1]])
    s = meshcsg.sphere(5, segments=16)
    assert s.vertices.shape == (16 * 8, 3)  # n points on (n + 1) / 2 rings
    c = meshcsg.cylinder(10, r=2, segments=12)
    assert c.vertices.shape == (24, 3) and c.triangles.shape == (2 * 12 + 2 * 10, 3)
    cone = meshcsg.cylinder(10, r1=2, r2=0, segments=12)
    assert cone.vertices.shape == (13, 3)
    # OpenSCAD's default resolution ($fa = 12, $fs = 2): 30 fragments for r = 10
    assert meshcsg.cylinder(1, r=10).vertices.shape == (60, 3)
    with pytest.raises(ValueError):
        meshcsg.cylinder(1, r=1, r1=2)


def test_transforms():
    m = unit_cube()
    assert np.array_equal(m.translate((1, 2, 3)).bounds, [[1, 2, 3], [2, 3, 4]])
    turned = meshcsg.rotate(m, 90)  # about z, exactly
    assert np.array_equal(turned.bounds, [[-1, 0, 0], [0, 1, 1]])
    assert np.array_equal(m.rotate([90, 0, 0]).bounds, [[0, -1, 0], [1, 0, 1]])
    assert m.rotate(30).volume == pytest.approx(1.0, rel=1e-15)
    mirrored = m.scale([-1, 1, 1])
    assert mirrored.volume == 1.0 and mirrored.is_closed  # turned to face outward
    assert meshcsg.scale(m, 2).volume == 8.0
    matrix = np.eye(4)
    matrix[:3, 3] = (5, 0, 0)
    assert np.array_equal(meshcsg.transform(m, matrix).bounds, [[5, 0, 0], [6, 1, 1]])
    with pytest.raises(ValueError):
        m.transform(np.eye(3))


def test_rotation_matches_the_csg_language():
    scad = meshcsg.evaluate_scad("union() { rotate([10, 20, 33]) cube(1); }",
                                 keep_all_vertices=True)
    here = meshcsg.rotate(meshcsg.cube(1), [10, 20, 33])
    assert np.array_equal(np.unique(scad.vertices, axis=0), np.unique(here.vertices, axis=0))
    scad = meshcsg.evaluate_scad("rotate(a = 50, v = [1, 2, 3]) cube(1);")
    here = meshcsg.rotate(meshcsg.cube(1), 50, [1, 2, 3])
    assert np.array_equal(np.unique(scad.vertices, axis=0), np.unique(here.vertices, axis=0))


def test_difference_of_cube_and_sphere_given_as_arrays():
    ball = meshcsg.sphere(0.4, segments=24).translate((0.5, 0.5, 0.5))
    ball_arrays = meshcsg.Mesh(np.array(ball.vertices), np.array(ball.triangles))
    result = meshcsg.difference(unit_cube(), ball_arrays)
    assert result.is_closed
    # the ball lies inside: the cube minus its exact (polyhedral) volume
    assert result.volume == pytest.approx(1.0 - ball.volume, rel=1e-12)


def test_union_and_intersection_volumes():
    a, b = unit_cube(2), unit_cube(2, offset=(1, 0, 0))
    assert meshcsg.union(a, b).volume == 12.0
    assert meshcsg.intersection(a, b).volume == 4.0
    assert meshcsg.difference(a, b).volume == 4.0
    assert meshcsg.union().triangles.shape == (0, 3)
    far = unit_cube(offset=(10, 0, 0))
    assert meshcsg.intersection(a, far).triangles.shape == (0, 3)


def test_difference_of_several_is_one_evaluation():
    steps = []
    a = unit_cube(4)
    cutters = [unit_cube().scale([1, 1, 6]).translate((x, 1.5, -1)) for x in (0.5, 2.5)]
    result = meshcsg.difference(a, *cutters, progress=lambda step, done: steps.append(
        (step, done)))
    assert steps.count(("classify", False)) == 1
    assert result.volume == pytest.approx(64 - 2 * 4, rel=1e-15)


def test_tree_builder_nested():
    t = meshcsg.Tree()
    a, b = t.leaf(unit_cube(2)), t.leaf(unit_cube(2, offset=(1, 0, 0)))
    c = t.leaf(unit_cube(4, offset=(-1, -1, 1)))
    u = t.union(a, b)
    result = t.evaluate(t.difference(u, c))
    assert result.volume == 6.0
    _, leaf, face = t.evaluate(u, provenance=True)
    assert set(np.unique(leaf)) == {a, b}
    assert face.max() < 12


def test_provenance_names_operand_and_face():
    a, b = unit_cube(2), unit_cube(2, offset=(1, 1, 1))
    mesh, operand, face = meshcsg.union(a, b, provenance=True)
    assert operand.shape == (len(mesh.triangles),) and face.shape == operand.shape
    assert set(np.unique(operand)) == {0, 1}
    # each output triangle lies on its source face: same normal direction
    for t in range(len(mesh.triangles)):
        src = (a, b)[operand[t]]
        p = mesh.vertices[mesh.triangles[t]]
        q = src.vertices[src.triangles[face[t]]]
        n1 = np.cross(p[1] - p[0], p[2] - p[0])
        n2 = np.cross(q[1] - q[0], q[2] - q[0])
        assert np.allclose(n1 / np.linalg.norm(n1), n2 / np.linalg.norm(n2))


def test_threads_do_not_change_the_result():
    scene = [meshcsg.sphere(1, segments=20).translate((x * 0.7, 0, 0)) for x in range(5)]
    one = meshcsg.union(*scene, threads=1)
    two = meshcsg.union(*scene, threads=2)
    assert np.array_equal(one.vertices, two.vertices)
    assert np.array_equal(one.triangles, two.triangles)
    with pytest.raises(ValueError):
        meshcsg.union(*scene, threads=-1)


def test_progress_can_stop_and_exceptions_propagate():
    a, b = unit_cube(2), unit_cube(2, offset=(1, 1, 1))
    with pytest.raises(meshcsg.CancelledError) as raised:
        meshcsg.union(a, b, progress=lambda step, done: step == "classify")
    assert raised.value.status == 10

    def broken(step, done):
        raise KeyError("from the callback")
    with pytest.raises(KeyError, match="from the callback"):
        meshcsg.union(a, b, progress=broken)


def test_keep_all_vertices():
    text = ("difference() { cube(10, center=true); "
            "cylinder(h=20, r=3, center=true, $fn=64); }")
    assert meshcsg.evaluate_scad(text).triangles.shape == (272, 3)
    assert meshcsg.evaluate_scad(text, keep_all_vertices=True).triangles.shape == (528, 3)


def test_evaluate_scad_path_and_errors(tmp_path):
    path = tmp_path / "part.scad"
    path.write_text("difference() { cube(2); translate([1, 1, 1]) cube(2); }\n")
    assert meshcsg.evaluate_scad(path).volume == 7.0
    assert meshcsg.evaluate_scad(str(path)).volume == 7.0
    with pytest.raises(meshcsg.Error) as raised:
        meshcsg.evaluate_scad("cube(;")
    assert raised.value.status == 3 and "<text>:1:6" in str(raised.value)
    assert raised.value.status_name == "malformed input"


def test_read_write_round_trip(tmp_path):
    m = meshcsg.difference(unit_cube(2), unit_cube(1, offset=(0.5, 0.5, 0.5)))
    for name in ("r.off", "r.obj", "r.stl", "r.ply", "r.3mf"):
        m.write(tmp_path / name)
        back = meshcsg.read(tmp_path / name)
        assert back.volume == m.volume and back.is_closed
    m.write(tmp_path / "r.txt", format="stl-ascii")
    assert (tmp_path / "r.txt").read_text().startswith("solid")
    with pytest.raises(ValueError):
        m.write(tmp_path / "r.off", format="gltf")
    with pytest.raises(meshcsg.Error) as raised:
        meshcsg.read(tmp_path / "missing.off")
    assert raised.value.status == 2 and "missing.off" in str(raised.value)


def test_library_messages_go_to_logging(caplog):
    # a pair of zero-area triangles (0, 8 and 1 lie on a line) is removed with a warning
    v = np.vstack([CUBE_V, [[0.5, 0, 0]]])
    with caplog.at_level(logging.WARNING, logger="meshcsg"):
        meshcsg.union(meshcsg.Mesh(v, np.vstack([CUBE_T, [[0, 8, 1], [0, 1, 8]]])))
    assert any(r.name == "meshcsg" and r.levelno == logging.WARNING for r in caplog.records)


def test_version():
    assert meshcsg.__version__ == meshcsg.library_version()
    assert meshcsg.__version__.count(".") == 2
    assert os.path.basename(meshcsg._capi.__file__) == "_capi.py"

"""meshcsg: exact constructive solid geometry on closed triangle meshes.

The Python interface to libmeshcsg (through ctypes: importing it needs no compiler).
Meshes hold numpy arrays: vertices as an (n, 3) float64 array, triangles as an (m, 3)
uint32 array, counter-clockwise seen from outside. Each of union(), difference() and
intersection() is one exact evaluation of all its operands; Tree builds deeper trees,
and evaluate_scad() runs OpenSCAD-language text or files. Failures raise meshcsg.Error
carrying the library's status and one-line message. The library's warnings and
informational messages go to the logger "meshcsg".

    import numpy as np, meshcsg
    box = meshcsg.cube(10, center=True)
    ball = meshcsg.sphere(6, segments=48)
    part = meshcsg.difference(box, ball)
    print(part.volume, part.is_closed)
    part.write("part.stl")
"""

import ctypes
import logging
import os

import numpy as np

from . import _capi, _trig
from ._capi import CancelledError, Error

__all__ = ["Mesh", "Tree", "Error", "CancelledError", "read", "cube", "sphere", "cylinder",
           "translate", "rotate", "scale", "transform", "union", "difference",
           "intersection", "evaluate_scad", "library_version"]

_LOG = logging.getLogger("meshcsg")
_LEVELS = {0: logging.DEBUG, 1: logging.INFO, 2: logging.WARNING}
_FORMATS = {None: 0, "off": 1, "obj": 2, "stl-ascii": 3, "stl": 4, "stl-binary": 4,
            "ply-ascii": 5, "ply": 6, "ply-binary": 6, "ply-binary-be": 7, "3mf": 8}
_UNION, _INTERSECTION, _DIFFERENCE = 1, 2, 3


def library_version():
    """The version of the loaded libmeshcsg, "MAJOR.MINOR.PATCH"."""
    return _capi.lib.mcsg_version().decode()


__version__ = library_version()


# ---- options and callbacks -------------------------------------------------------------

@_capi.LOG_FN
def _log_callback(user, level, message):
    _LOG.log(_LEVELS.get(level, logging.WARNING), "%s", message.decode(errors="replace"))


class _Call:
    """The options of one call: threads, keep_all_vertices, and a progress callable
    progress(step, done) (step a str, done a bool; return True to stop, which raises
    CancelledError). An exception in the callable stops the call and is raised again."""

    def __init__(self, threads=0, progress=None, keep_all_vertices=False):
        if not isinstance(threads, int) or not 0 <= threads <= 1024:
            raise ValueError("threads must be an integer from 0 (all cores) to 1024")
        self.options = _capi.Options()
        self.options.log = _log_callback
        self.options.threads = threads
        self.options.keep_all_vertices = 1 if keep_all_vertices else 0
        self.raised = None
        if progress is not None:
            self._progress = _capi.PROGRESS_FN(self._report(progress))
            self.options.progress = self._progress

    def _report(self, progress):
        def report(user, step, done):
            try:
                return 1 if progress(step.decode(), bool(done)) else 0
            except BaseException as e:  # raised again after the library has unwound
                self.raised = e
                return 1
        return report

    def check(self, status, err):
        if self.raised is not None:
            raised, self.raised = self.raised, None
            raise raised
        _capi.check(status, err)


# ---- meshes ----------------------------------------------------------------------------

class _Owned:
    """A mesh whose arrays the library allocated; freed when no array uses them."""

    def __init__(self):
        self.mesh = _capi.Mesh()

    def __del__(self):
        _capi.lib.mcsg_mesh_free(ctypes.byref(self.mesh), None)


class _Provenance:
    def __init__(self):
        self.pointer = ctypes.POINTER(_capi.Provenance)()

    def __del__(self):
        if self.pointer:
            _capi.lib.mcsg_free(self.pointer, None)


def _library_array(pointer, ctype, length, dtype, owner):
    """A flat numpy array over `length` ctype elements the library owns at `pointer` (no
    copy); `owner`, which frees them, lives as long as the array."""
    if length == 0:
        return np.zeros(0, dtype)
    buffer_type = type("buffer", (ctype * length,), {})  # a subclass takes attributes
    buffer = buffer_type.from_address(ctypes.cast(pointer, ctypes.c_void_p).value)
    buffer.owner = owner
    return np.frombuffer(buffer, dtype=dtype)


def _read_only(array):
    view = array.view()
    view.flags.writeable = False
    return view


class Mesh:
    """A triangle mesh: `vertices` (n x 3 float64) and `triangles` (m x 3 uint32, indices
    into vertices, counter-clockwise seen from outside). The arrays are read-only views:
    given ones are not copied when they already have that type and layout."""

    def __init__(self, vertices, triangles):
        v = np.ascontiguousarray(vertices, dtype=np.float64)
        t = np.asarray(triangles)
        if v.size == 0:
            v = v.reshape(0, 3)
        if t.size == 0:
            t = np.zeros((0, 3), np.uint32)
        if v.ndim != 2 or v.shape[1] != 3:
            raise ValueError("vertices must be an (n, 3) array, not %s" % (v.shape,))
        if t.ndim != 2 or t.shape[1] != 3:
            raise ValueError("triangles must be an (m, 3) array, not %s" % (t.shape,))
        if t.dtype != np.uint32:
            if t.dtype.kind not in "iu":
                raise ValueError("triangles must hold integers, not %s" % t.dtype)
            if t.size and (t.min() < 0 or t.max() >= len(v)):
                raise ValueError("a triangle index is outside 0..%d" % (len(v) - 1))
        self._vertices = _read_only(v)
        self._triangles = _read_only(np.ascontiguousarray(t, dtype=np.uint32))
        self._report = None

    @classmethod
    def _from_library(cls, owned):
        m = owned.mesh
        v = _library_array(m.vertices, ctypes.c_double, 3 * m.vertex_count, np.float64, owned)
        t = _library_array(m.triangles, ctypes.c_uint32, 3 * m.triangle_count, np.uint32, owned)
        return cls(v.reshape(-1, 3), t.reshape(-1, 3))

    def _c_mesh(self):
        m = _capi.Mesh()
        m.vertices = self._vertices.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
        m.triangles = self._triangles.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32))
        m.vertex_count = len(self._vertices)
        m.triangle_count = len(self._triangles)
        return m

    @property
    def vertices(self):
        """The vertices, an (n, 3) float64 array (read-only)."""
        return self._vertices

    @property
    def triangles(self):
        """The triangles, an (m, 3) uint32 array of vertex indices (read-only)."""
        return self._triangles

    def _check(self):
        if self._report is None:
            report, err = _capi.CheckReport(), _capi.ErrorInfo()
            m = self._c_mesh()
            _capi.check(_capi.lib.mcsg_mesh_check(ctypes.byref(m), None,
                                                  ctypes.byref(report), ctypes.byref(err)),
                        err)
            self._report = report
        return self._report

    @property
    def volume(self):
        """The signed volume (meaningful when the mesh is closed)."""
        return self._check().volume

    @property
    def area(self):
        """The surface area."""
        p = self._vertices[self._triangles]
        return float(np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]),
                                    axis=1).sum() / 2)

    @property
    def is_closed(self):
        """Whether every edge (vertices identified by coordinates) is used as often in one
        direction as in the other: what evaluation requires of an operand."""
        r = self._check()
        return (r.boundary_edges == 0 and r.inconsistent_edges == 0 and
                r.unbalanced_edges == 0 and r.out_of_range_indices == 0 and
                r.nonfinite_vertices == 0)

    @property
    def bounds(self):
        """[[xmin, ymin, zmin], [xmax, ymax, zmax]] of the vertices used by triangles."""
        if len(self._triangles) == 0:
            return np.zeros((2, 3))
        used = self._vertices[np.unique(self._triangles)]
        return np.array([used.min(axis=0), used.max(axis=0)])

    def __repr__(self):
        return "meshcsg.Mesh(%d vertices, %d triangles)" % (len(self._vertices),
                                                             len(self._triangles))

    def write(self, path, format=None):
        """Write the mesh to `path`; the format comes from the extension (.off .obj .stl
        .ply .3mf) unless `format` names one: off, obj, stl (binary), stl-ascii, ply
        (binary little-endian), ply-ascii, ply-binary-be, 3mf."""
        if format not in _FORMATS:
            raise ValueError("unknown format %r; known: %s" %
                             (format, ", ".join(f for f in _FORMATS if f)))
        err, m = _capi.ErrorInfo(), self._c_mesh()
        _capi.check(_capi.lib.mcsg_mesh_write(os.fsencode(path), _FORMATS[format],
                                              ctypes.byref(m), None, ctypes.byref(err)), err)

    def transform(self, matrix):
        """The mesh mapped by an affine matrix, 3 x 4 or 4 x 4 (last row 0, 0, 0, 1):
        p' = M[:3, :3] p + M[:3, 3]. A mirror turns the triangles so that they keep
        facing outward. Coordinates are rounded to doubles."""
        m = np.asarray(matrix, dtype=np.float64)
        if m.shape == (4, 4):
            if not np.array_equal(m[3], [0, 0, 0, 1]):
                raise ValueError("a 4 x 4 matrix must end with the row 0, 0, 0, 1")
            m = m[:3]
        if m.shape != (3, 4):
            raise ValueError("the matrix must be 3 x 4 or 4 x 4, not %s" % (m.shape,))
        c = _capi.Mesh()
        vertices, triangles = np.array(self._vertices), np.array(self._triangles)
        c.vertices = vertices.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
        c.triangles = triangles.ctypes.data_as(ctypes.POINTER(ctypes.c_uint32))
        c.vertex_count, c.triangle_count = len(vertices), len(triangles)
        flat = np.ascontiguousarray(m.reshape(12))
        _capi.lib.mcsg_mesh_transform(ctypes.byref(c),
                                      flat.ctypes.data_as(ctypes.POINTER(ctypes.c_double)))
        return Mesh(vertices, triangles)

    def translate(self, offset):
        """The mesh moved by `offset` (x, y, z)."""
        return translate(self, offset)

    def rotate(self, a, v=None):
        """The mesh rotated as OpenSCAD's rotate(a, v) (see meshcsg.rotate)."""
        return rotate(self, a, v)

    def scale(self, factor):
        """The mesh scaled by a number or by (x, y, z)."""
        return scale(self, factor)


def _linear(mesh, l, offset=(0.0, 0.0, 0.0)):
    return mesh.transform([[l[0], l[1], l[2], offset[0]], [l[3], l[4], l[5], offset[1]],
                           [l[6], l[7], l[8], offset[2]]])


def translate(mesh, offset):
    """`mesh` moved by `offset` (x, y, z)."""
    x, y, z = (float(c) for c in offset)
    return _linear(mesh, [1, 0, 0, 0, 1, 0, 0, 0, 1], (x, y, z))


def rotate(mesh, a, v=None):
    """`mesh` rotated as OpenSCAD's rotate(): `a` a vector of up to three angles in
    degrees (about x, then y, then z), or one angle about the axis `v` (default z).
    Multiples of 30 and 45 degrees are exact, as in a .scad file."""
    if np.ndim(a) == 1:
        if len(a) > 3:
            raise ValueError("rotate: a vector of up to three angles")
        return _linear(mesh, _trig.euler(list(a)))
    return _linear(mesh, _trig.angle_axis(a, (0, 0, 1) if v is None else v))


def scale(mesh, factor):
    """`mesh` scaled by a number or by (x, y, z) (a negative factor mirrors it)."""
    f = [float(factor)] * 3 if np.ndim(factor) == 0 else [float(c) for c in factor]
    if len(f) != 3:
        raise ValueError("scale: a number or three factors")
    return _linear(mesh, [f[0], 0, 0, 0, f[1], 0, 0, 0, f[2]])


def transform(mesh, matrix):
    """`mesh` mapped by an affine matrix (Mesh.transform)."""
    return mesh.transform(matrix)


def read(path):
    """Read a mesh file (.off .obj .stl .ply .3mf .amf, detected from the content and the
    name); a 3MF file's build items, or an AMF file's objects, come as one mesh, their
    shells side by side."""
    owned, err = _Owned(), _capi.ErrorInfo()
    _capi.check(_capi.lib.mcsg_mesh_read(os.fsencode(path), 0, None, ctypes.byref(owned.mesh),
                                         ctypes.byref(err)), err)
    return Mesh._from_library(owned)


# ---- primitives, as OpenSCAD tessellates them ------------------------------------------

def _resolution(segments):
    if segments is not None and (not isinstance(segments, (int, np.integer)) or segments < 0):
        raise ValueError("segments must be a positive integer (OpenSCAD's $fn)")
    return _capi.Resolution(float(segments or 0), 0.0, 0.0)


def cube(size, center=False):
    """OpenSCAD's cube(size, center): size a number or (x, y, z)."""
    s = [float(size)] * 3 if np.ndim(size) == 0 else [float(c) for c in size]
    if len(s) != 3:
        raise ValueError("cube: a size or three sizes")
    owned, err = _Owned(), _capi.ErrorInfo()
    _capi.check(_capi.lib.mcsg_make_cube((ctypes.c_double * 3)(*s), 1 if center else 0, None,
                                         ctypes.byref(owned.mesh), ctypes.byref(err)), err)
    return Mesh._from_library(owned)


def sphere(r, segments=None):
    """OpenSCAD's sphere(r); `segments` is $fn (default: OpenSCAD's $fa = 12, $fs = 2)."""
    owned, err = _Owned(), _capi.ErrorInfo()
    _capi.check(_capi.lib.mcsg_make_sphere(float(r), _resolution(segments), None,
                                           ctypes.byref(owned.mesh), ctypes.byref(err)), err)
    return Mesh._from_library(owned)


def cylinder(h, r=None, r1=None, r2=None, center=False, segments=None):
    """OpenSCAD's cylinder(h, r | r1, r2, center); `segments` is $fn."""
    if r is not None and (r1 is not None or r2 is not None):
        raise ValueError("cylinder: give r, or r1 and r2")
    r1 = r if r is not None else (1.0 if r1 is None else r1)
    r2 = r if r is not None else (1.0 if r2 is None else r2)
    owned, err = _Owned(), _capi.ErrorInfo()
    _capi.check(_capi.lib.mcsg_make_cylinder(float(h), float(r1), float(r2),
                                             1 if center else 0, _resolution(segments), None,
                                             ctypes.byref(owned.mesh), ctypes.byref(err)), err)
    return Mesh._from_library(owned)


# ---- trees and evaluation --------------------------------------------------------------

class Tree:
    """A CSG tree evaluated exactly in one pass. Leaves and operations return node ids:

        t = meshcsg.Tree()
        a, b, c = t.leaf(box), t.leaf(ball), t.leaf(rod)
        result = t.evaluate(t.difference(t.union(a, b), c))
    """

    def __init__(self):
        self._tree = ctypes.c_void_p()
        err = _capi.ErrorInfo()
        _capi.check(_capi.lib.mcsg_tree_create(None, ctypes.byref(self._tree),
                                               ctypes.byref(err)), err)

    def __del__(self):
        if getattr(self, "_tree", None):
            _capi.lib.mcsg_tree_free(self._tree)
            self._tree = None

    def leaf(self, mesh, label=None):
        """Add a leaf holding a copy of `mesh`; returns its node id."""
        if not isinstance(mesh, Mesh):
            raise TypeError("a leaf is a meshcsg.Mesh, not %s" % type(mesh).__name__)
        node, err, m = ctypes.c_uint32(), _capi.ErrorInfo(), mesh._c_mesh()
        _capi.check(_capi.lib.mcsg_tree_add_leaf(self._tree, ctypes.byref(m), None,
                                                 None if label is None else label.encode(),
                                                 ctypes.byref(node), ctypes.byref(err)), err)
        return node.value

    def _op(self, kind, children):
        ids = (ctypes.c_uint32 * max(len(children), 1))(*children)
        node, err = ctypes.c_uint32(), _capi.ErrorInfo()
        _capi.check(_capi.lib.mcsg_tree_add_op(self._tree, kind, ids, len(children), None,
                                               ctypes.byref(node), ctypes.byref(err)), err)
        return node.value

    def union(self, *nodes):
        """A union node of the given nodes (none: the empty set)."""
        return self._op(_UNION, nodes)

    def intersection(self, *nodes):
        """An intersection node of the given nodes."""
        return self._op(_INTERSECTION, nodes)

    def difference(self, first, *others):
        """The first node minus all the others."""
        return self._op(_DIFFERENCE, (first,) + others)

    def evaluate(self, root=None, threads=0, progress=None, keep_all_vertices=False,
                 provenance=False):
        """The exact result of the tree at `root` (default: the last node added), as a
        Mesh. With provenance=True: (mesh, leaf, face), two uint32 arrays with, per
        output triangle, the node id of the leaf and the index of the leaf's triangle
        it lies on."""
        if root is not None:
            err = _capi.ErrorInfo()
            _capi.check(_capi.lib.mcsg_tree_set_root(self._tree, root, ctypes.byref(err)), err)
        return _evaluate(self._tree, _Call(threads, progress, keep_all_vertices), provenance)


def _evaluate(tree, call, provenance):
    owned, err = _Owned(), _capi.ErrorInfo()
    origin = _Provenance() if provenance else None
    status = _capi.lib.mcsg_eval(tree, ctypes.byref(call.options), ctypes.byref(owned.mesh),
                                 ctypes.byref(origin.pointer) if origin else None, None,
                                 ctypes.byref(err))
    call.check(status, err)
    mesh = Mesh._from_library(owned)
    if not provenance:
        return mesh
    pairs = _library_array(origin.pointer, _capi.Provenance, owned.mesh.triangle_count,
                           np.dtype([("leaf", np.uint32), ("face", np.uint32)]), origin)
    return mesh, pairs["leaf"], pairs["face"]


def _operation(kind, meshes, threads, progress, keep_all_vertices, provenance):
    tree = Tree()
    leaves = [tree.leaf(m) for m in meshes]
    root = tree._op(kind, leaves)
    result = tree.evaluate(root, threads, progress, keep_all_vertices, provenance)
    if not provenance:
        return result
    mesh, leaf, face = result
    operand = np.zeros(max(leaves, default=0) + 1, np.uint32)
    operand[leaves] = np.arange(len(leaves), dtype=np.uint32)
    return mesh, operand[leaf], face


def union(*meshes, threads=0, progress=None, keep_all_vertices=False, provenance=False):
    """The union of the meshes, one exact evaluation. With provenance=True: (mesh,
    operand, face), per output triangle the index of the operand it comes from and of
    the operand's triangle it lies on. threads: 0 for all cores; progress: a callable
    progress(step, done) that returns True to stop; keep_all_vertices: keep the
    vertices that carry no shape."""
    return _operation(_UNION, meshes, threads, progress, keep_all_vertices, provenance)


def intersection(*meshes, threads=0, progress=None, keep_all_vertices=False,
                 provenance=False):
    """The intersection of the meshes, one exact evaluation (options as union's)."""
    return _operation(_INTERSECTION, meshes, threads, progress, keep_all_vertices, provenance)


def difference(first, *others, threads=0, progress=None, keep_all_vertices=False,
               provenance=False):
    """`first` minus all the others, one exact evaluation (options as union's)."""
    return _operation(_DIFFERENCE, (first,) + others, threads, progress, keep_all_vertices,
                      provenance)


def evaluate_scad(source, threads=0, progress=None, keep_all_vertices=False,
                  provenance=False):
    """Evaluate a .scad or .csg file, given as a path (str or os.PathLike naming an
    existing file) or as the text itself. Provenance as Tree.evaluate."""
    tree, err = ctypes.c_void_p(), _capi.ErrorInfo()
    call = _Call(threads, progress, keep_all_vertices)
    is_path = isinstance(source, os.PathLike) or (
        isinstance(source, str) and "\n" not in source and os.path.isfile(source))
    if is_path:
        status = _capi.lib.mcsg_scad_read(os.fsencode(source), ctypes.byref(call.options),
                                          ctypes.byref(tree), ctypes.byref(err))
    else:
        text = source.encode() if isinstance(source, str) else bytes(source)
        status = _capi.lib.mcsg_scad_read_memory(text, len(text), b"<text>", None,
                                                 ctypes.byref(call.options),
                                                 ctypes.byref(tree), ctypes.byref(err))
    call.check(status, err)
    try:
        return _evaluate(tree, call, provenance)
    finally:
        _capi.lib.mcsg_tree_free(tree)

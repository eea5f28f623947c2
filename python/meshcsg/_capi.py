"""The C interface of libmeshcsg (include/meshcsg.h) through ctypes: the structures the
Python layer passes, and the library found at import time.

The library is looked for, in order: the path in the environment variable
MESHCSG_LIBRARY; the installed layout (this package in PREFIX/lib/python3/dist-packages,
the library in PREFIX/lib); the loader's search path (libmeshcsg.so.MAJOR)."""

import ctypes
import os

MAJOR = 0  # the soname's version, MCSG_VERSION_MAJOR of the header


class Error(Exception):
    """A failed call: `status` is the library's status code, `status_name` its short
    description, and str(error) the library's one-line message."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status
        self.status_name = _status_name(status)


class CancelledError(Error):
    """The progress callback asked to stop (status MCSG_ERR_CANCELLED)."""


STATUS_CANCELLED = 10


class Mesh(ctypes.Structure):
    _fields_ = [("vertices", ctypes.POINTER(ctypes.c_double)),
                ("triangles", ctypes.POINTER(ctypes.c_uint32)),
                ("vertex_count", ctypes.c_size_t),
                ("triangle_count", ctypes.c_size_t)]


class ErrorInfo(ctypes.Structure):
    _fields_ = [("status", ctypes.c_int), ("message", ctypes.c_char * 512)]


class Allocator(ctypes.Structure):
    _fields_ = [("malloc_fn", ctypes.c_void_p), ("realloc_fn", ctypes.c_void_p),
                ("free_fn", ctypes.c_void_p), ("user", ctypes.c_void_p)]


LOG_FN = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int, ctypes.c_char_p)
PROGRESS_FN = ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int)


class Options(ctypes.Structure):
    _fields_ = [("allocator", Allocator), ("log", LOG_FN), ("log_user", ctypes.c_void_p),
                ("threads", ctypes.c_int), ("progress", PROGRESS_FN),
                ("progress_user", ctypes.c_void_p),
                ("check_self_intersections", ctypes.c_int),
                ("check_output_crossings", ctypes.c_int),
                ("keep_all_vertices", ctypes.c_int), ("pool", ctypes.c_void_p)]


class Resolution(ctypes.Structure):
    _fields_ = [("fn", ctypes.c_double), ("fa", ctypes.c_double), ("fs", ctypes.c_double)]


class Provenance(ctypes.Structure):
    _fields_ = [("leaf", ctypes.c_uint32), ("face", ctypes.c_uint32)]


_size = ctypes.c_size_t
_u32 = ctypes.c_uint32
_CHECK_COUNTS = ["vertex_count", "triangle_count", "out_of_range_indices",
                 "nonfinite_vertices", "degenerate_triangles", "duplicate_triangles",
                 "boundary_edges", "nonmanifold_edges", "inconsistent_edges",
                 "duplicate_vertices", "unused_vertices", "components"]


class CheckReport(ctypes.Structure):
    _fields_ = ([(name, _size) for name in _CHECK_COUNTS] +
                [("volume", ctypes.c_double), ("inverted", ctypes.c_int),
                 ("volume_sign", ctypes.c_int),
                 ("example_out_of_range_triangle", _u32), ("example_nonfinite_vertex", _u32),
                 ("example_degenerate_triangle", _u32), ("example_duplicate_triangle", _u32),
                 ("example_boundary_edge", _u32 * 2), ("example_nonmanifold_edge", _u32 * 2),
                 ("example_inconsistent_edge", _u32 * 2),
                 ("unbalanced_edges", _size), ("example_unbalanced_edge", _u32 * 2),
                 ("self_touching_edges", _size), ("example_self_touching_edge", _u32 * 2)])


def _load():
    names = []
    if os.environ.get("MESHCSG_LIBRARY"):
        names.append(os.environ["MESHCSG_LIBRARY"])
    here = os.path.dirname(os.path.abspath(__file__))
    names.append(os.path.join(here, "..", "..", "..", "libmeshcsg.so.%d" % MAJOR))
    names.append("libmeshcsg.so.%d" % MAJOR)
    tried = []
    for name in names:
        if os.sep in name and not os.path.exists(name):
            tried.append(name + " (no such file)")
            continue
        try:
            return ctypes.CDLL(name)
        except OSError as e:
            tried.append("%s (%s)" % (name, e))
    raise ImportError("meshcsg: cannot load the shared library libmeshcsg.so.%d; tried: %s. "
                      "Set MESHCSG_LIBRARY to its path." % (MAJOR, "; ".join(tried)))


lib = _load()

_P = ctypes.POINTER
_status = ctypes.c_int
_SIGNATURES = {
    "mcsg_version": (ctypes.c_char_p, []),
    "mcsg_status_string": (ctypes.c_char_p, [_status]),
    "mcsg_free": (None, [ctypes.c_void_p, _P(Options)]),
    "mcsg_mesh_free": (None, [_P(Mesh), _P(Options)]),
    "mcsg_mesh_transform": (None, [_P(Mesh), _P(ctypes.c_double)]),
    "mcsg_mesh_read": (_status, [ctypes.c_char_p, ctypes.c_int, _P(Options), _P(Mesh),
                                 _P(ErrorInfo)]),
    "mcsg_mesh_write": (_status, [ctypes.c_char_p, ctypes.c_int, _P(Mesh), _P(Options),
                                  _P(ErrorInfo)]),
    "mcsg_mesh_check": (_status, [_P(Mesh), _P(Options), _P(CheckReport), _P(ErrorInfo)]),
    "mcsg_make_cube": (_status, [_P(ctypes.c_double), ctypes.c_int, _P(Options), _P(Mesh),
                                 _P(ErrorInfo)]),
    "mcsg_make_sphere": (_status, [ctypes.c_double, Resolution, _P(Options), _P(Mesh),
                                   _P(ErrorInfo)]),
    "mcsg_make_cylinder": (_status, [ctypes.c_double, ctypes.c_double, ctypes.c_double,
                                     ctypes.c_int, Resolution, _P(Options), _P(Mesh),
                                     _P(ErrorInfo)]),
    "mcsg_tree_create": (_status, [_P(Options), _P(ctypes.c_void_p), _P(ErrorInfo)]),
    "mcsg_tree_free": (None, [ctypes.c_void_p]),
    "mcsg_tree_add_leaf": (_status, [ctypes.c_void_p, _P(Mesh), _P(ctypes.c_double),
                                     ctypes.c_char_p, _P(_u32), _P(ErrorInfo)]),
    "mcsg_tree_add_op": (_status, [ctypes.c_void_p, ctypes.c_int, _P(_u32), _size,
                                   ctypes.c_char_p, _P(_u32), _P(ErrorInfo)]),
    "mcsg_tree_set_root": (_status, [ctypes.c_void_p, _u32, _P(ErrorInfo)]),
    "mcsg_tree_node_count": (_size, [ctypes.c_void_p]),
    "mcsg_tree_leaf_count": (_size, [ctypes.c_void_p]),
    "mcsg_scad_read": (_status, [ctypes.c_char_p, _P(Options), _P(ctypes.c_void_p),
                                 _P(ErrorInfo)]),
    "mcsg_scad_read_memory": (_status, [ctypes.c_char_p, _size, ctypes.c_char_p,
                                        ctypes.c_char_p, _P(Options), _P(ctypes.c_void_p),
                                        _P(ErrorInfo)]),
    "mcsg_eval": (_status, [ctypes.c_void_p, _P(Options), _P(Mesh), _P(_P(Provenance)),
                            ctypes.c_void_p, _P(ErrorInfo)]),
}
for _name, (_restype, _argtypes) in _SIGNATURES.items():
    _function = getattr(lib, _name)
    _function.restype = _restype
    _function.argtypes = _argtypes


def _status_name(status):
    return lib.mcsg_status_string(status).decode()


def check(status, err):
    """Raises the library's error for a failed call."""
    if status != 0:
        message = err.message.decode(errors="replace")
        cls = CancelledError if status == STATUS_CANCELLED else Error
        raise cls(status, message)

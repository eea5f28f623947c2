#!/usr/bin/env python3
"""End-to-end benchmark of `meshcsg eval`: the paper's Table 1 / Table 2 scenes and ours.

Each scene is a folder of OFF leaves and a tree.scad (the layout of
../shared/scenes/make_scenes.py, whose generators are reused so that the reference
volumes apply). Scenes are generated once into a cache folder. Every scene is then run as
a whole process (parse + evaluate + write an OFF file), RUNS times on one thread and RUNS
times on two, and the medians go into a Markdown table written between the markers
<!-- eval-bench:begin --> and <!-- eval-bench:end --> of docs/benchmarks.md.

usage: eval_bench.py MESHCSG SHARED_DIR CACHE_DIR DOC.md [--runs N] [--only a,b]
"""
import math
import os
import platform
import random
import re
import statistics
import subprocess
import sys
import time

BEGIN, END = '<!-- eval-bench:begin -->', '<!-- eval-bench:end -->'
GENERATOR_VERSION = '1'

# Time targets: whole process, one thread, seconds.
TARGETS = {
    'ring_spheres_800': 0.5, 'spheres_overlap_700': 0.5, 'cow100K_minus_shifted': 0.4,
    'armadillo_union_6bunnies': 0.6, 'cylinder_28_holes': 0.1, 'bunny_and_bunny_same': 0.1,
    'box_grid_8': 0.02,
}
MEMORY_TARGET = 250  # bytes per input face
# The fewest output triangles known for a scene: the minimum where it is proven (a
# closed mesh of genus g with V vertices has 2 V + 4 g - 4 triangles: the cube minus the
# cylinder has its 8 corners and the circles' 128 points), else a peer's count as issue
# 34 measured it (Manifold, not packaged in Debian).
LEANEST = {
    'cube_minus_cylinder_64': (272, 'minimum'),
    'cylinder_28_holes': (36112, 'Manifold'),
    'ring_spheres_800': (100750, 'Manifold'),
    'box_grid_8': (1428, 'Manifold'),
}
CUBE_MINUS_CYLINDER = ('difference() { cube(10, center = true); '
                       'cylinder(h = 20, r = 3, center = true, $fn = 64); }\n')


def icosphere(centre, radius, rot):
    """A level-2 icosphere (320 faces), rotated by the matrix rot, outward oriented."""
    t = (1 + 5 ** 0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t),
         (0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    unit = lambda p: tuple(c / math.sqrt(sum(x * x for x in p)) for c in p)
    v = [unit(p) for p in v]
    for _ in range(2):
        v, f = subdivide((v, f), unit)
    out = []
    for p in v:
        q = [sum(rot[i][j] * p[j] for j in range(3)) for i in range(3)]
        out.append(tuple(centre[i] + radius * q[i] for i in range(3)))
    return out, f


def subdivide(mesh, project=lambda p: p):
    """Split every triangle into four at its edge midpoints (shared between neighbours)."""
    v, f = mesh
    v = list(v)
    mid = {}

    def midpoint(a, b):
        key = (a, b) if a < b else (b, a)
        if key not in mid:
            mid[key] = len(v)
            v.append(project(tuple((v[a][i] + v[b][i]) / 2 for i in range(3))))
        return mid[key]

    out = []
    for a, b, c in f:
        ab, bc, ca = midpoint(a, b), midpoint(b, c), midpoint(c, a)
        out += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
    return v, out


def random_rotation(rnd):
    """A rotation matrix from a random unit quaternion."""
    q = [rnd.gauss(0, 1) for _ in range(4)]
    n = math.sqrt(sum(x * x for x in q))
    w, x, y, z = (c / n for c in q)
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]


def spheres_overlap(count=700, seed=7):
    """`count` icospheres of radius 1 on a jittered grid of spacing 1.5: every sphere
    crosses its (up to six) axis neighbours."""
    rnd = random.Random(seed)
    nx, ny = 10, 10
    meshes = []
    for k in range(count):
        i, j, l = k % nx, (k // nx) % ny, k // (nx * ny)
        c = tuple(1.5 * g + rnd.uniform(-0.15, 0.15) for g in (i, j, l))
        meshes.append(icosphere(c, rnd.uniform(0.95, 1.05), random_rotation(rnd)))
    return meshes, ['union'] + list(range(count))


def model_minus_shifted(ms, models, name, levels=0):
    m = ms.normalize(ms.read_obj(os.path.join(models, name)))
    for _ in range(levels):
        m = subdivide(m)
    return [m, ms.transform(m, 1.0, (0.7, 0.4, 0.3), 0.05)], ['difference', 0, 1]


def ring_spheres_constant_density(ms, n, seed=1):
    """The ring series under the paper's condition for Table 2 (k/n about constant): the
    ring's length grows with n (major radius 10 n / 100, 40 n / 100 segments around), so
    the spheres keep ring_spheres_100's spacing and each meets as many neighbours at 800
    spheres as at 100. Spheres are placed as make_scenes.ring_spheres places them; the
    tree is the same alternating chain, n levels deep."""
    rnd = random.Random(seed)
    R, r = 10.0 * n / 100, 2.5
    meshes = [ms.torus(R, r, nu=40 * n // 100)]
    for k in range(n):
        u = 2 * math.pi * (k + rnd.random() * 0.5) / n
        w = rnd.uniform(0, 2 * math.pi)
        rr = r * rnd.uniform(0.85, 1.15)
        c = ((R + rr * math.cos(w)) * math.cos(u), (R + rr * math.cos(w)) * math.sin(u),
             rr * math.sin(w))
        meshes.append(ms.sphere(c, rnd.uniform(0.6, 1.1), rot=rnd.uniform(0, 1)))
    tree = 0
    for k in range(1, n + 1):
        tree = ['union' if k % 2 else 'difference', tree, k]
    return meshes, tree


def drill_plate(ms, n, radius=0.3, segments=24):
    """A CAD/CAM part: an n x n plate, 1 thick, drilled through by an n x n grid of
    round holes (24-sided cylinders), all in one difference. Volume (volume_of below):
    the plate minus the holes' polygons."""
    meshes = [ms.box((0, 0, 0), (n, n, 1))]
    for i in range(n):
        for j in range(n):
            meshes.append(ms.cylinder((i + 0.5, j + 0.5, 0.5), radius, 2.0, segments))
    return meshes, ['difference'] + list(range(len(meshes)))


# Exact volumes and shells of the generated scenes that reference.tsv does not list.
def menger_sponge(level, digits=None, leaf_matrices=False):
    """OpenSCAD's example024 (a Menger sponge of side 100 at `level`, turned to stand on a
    corner, its lower half cut away) as the CSG text OpenSCAD's .csg export writes:
    numbers with `digits` significant digits (6: the export, where faces meant to be
    coplanar are ~1e-5 apart), or every double exactly (None). With `leaf_matrices` each
    cube carries the product of the matrices above it (as meshcsg's reader composes them,
    written exactly), so nothing groups the turned cubes: each is turned and rounded on
    its own, as in a tree whose leaves were transformed one by one."""
    fmt = (lambda x: '%.*g' % (digits, x)) if digits else (lambda x: repr(float(x)))
    side = 100.0
    a, b = math.radians(45), math.atan(1 / math.sqrt(2))
    rot = [[math.cos(b), math.sin(b) * math.sin(a), math.sin(b) * math.cos(a)],
           [0.0, math.cos(a), -math.sin(a)],
           [-math.sin(b), math.cos(b) * math.sin(a), math.cos(b) * math.cos(a)]]
    turns = [[[1, 0, 0], [0, 1, 0], [0, 0, 1]],   # rotate([0, 0, 0]), [0, 0, 90], [0, 90, 0]
             [[0, -1, 0], [1, 0, 0], [0, 0, 1]],
             [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]]
    out = []

    def as_rows(m, t=(0, 0, 0), f=fmt):
        return [[float(f(m[i][j])) for j in range(3)] + [float(f(t[i]))] for i in range(3)]

    def compose(p, o):  # p after o, in the order of modules.c compose()
        return [[p[r][0] * o[0][c] + p[r][1] * o[1][c] + p[r][2] * o[2][c] +
                 (p[r][3] if c == 3 else 0.0) for c in range(4)] for r in range(3)]

    def multmatrix(rows, f=fmt):
        text = ['[%s, %s, %s, %s]' % tuple(f(x) for x in rows[i]) for i in range(3)]
        return 'multmatrix([%s, [0, 0, 0, 1]])' % ', '.join(text)

    def open_block(indent, rows, above):
        if leaf_matrices:
            return compose(above, rows)
        out.append('%s%s {' % (indent, multmatrix(rows)))
        return above

    def close_block(indent):
        if not leaf_matrices:
            out.append('%s}' % indent)

    def cube(indent, size, above):
        text = 'cube(size = [%s, %s, %s], center = true);' % tuple(fmt(x) for x in size)
        prefix = multmatrix(above, repr) + ' ' if leaf_matrices else ''
        out.append(indent + prefix + text)

    def negative(size, level_left, indent, above):
        l = size / 3
        cube(indent, (side * 1.1, l, l), above)
        if level_left > 1:
            for i in (-1, 0, 1):
                for j in (-1, 0, 1):
                    if i or j:
                        inner = open_block(indent, as_rows(turns[0], (0, i * l, j * l)), above)
                        negative(l, level_left - 1, indent + '  ', inner)
                        close_block(indent)

    identity = as_rows(turns[0])
    out.append('difference() {')
    turned = open_block('  ', as_rows(rot), identity)
    out.append('    difference() {')
    cube('      ', (side,) * 3, turned)
    for t in turns:
        inner = open_block('      ', as_rows(t), turned)
        negative(side, level, '        ', inner)
        close_block('      ')
    out.append('    }')
    close_block('  ')
    out.append('  translate([0, 0, %s]) cube(size = [%s, %s, %s], center = true);' % (
        fmt(-side), fmt(2 * side), fmt(2 * side), fmt(2 * side)))
    out.append('}')
    return '\n'.join(out) + '\n'


def fan_plate_polygon(n, length=9000.0, width=100.0):
    """The outline of a CAD-like plate: its near edge on x = 0 with a vertex at its middle
    (the apex), its far end at x = -length an arc of n segments bulging by width / 4."""
    poly = [(0.0, -width / 2), (0.0, 0.0), (0.0, width / 2)]
    for i in range(n + 1):
        t = math.pi / 2 - math.pi * i / n
        poly.append((-(length + width / 4 * math.cos(t)), width / 2 * math.sin(t)))
    return poly


def fan_plate(poly, z0, height):
    """The plate extruded from z0, its flat faces fan-triangulated from the apex as CAD
    exporters triangulate a polygon: slivers as long as the plate and 0.08 wide."""
    m = len(poly)  # counter-clockwise seen from +z, the apex at index 1
    v = [(x, y, z0) for x, y in poly] + [(x, y, z0 + height) for x, y in poly]
    f = []
    for k in range(2, m):
        a, b = k, (k + 1) % m
        f.append((1, b, a))
        f.append((1 + m, a + m, b + m))
    for i in range(m):
        j = (i + 1) % m
        f.append((i, j, j + m))
        f.append((i, j + m, i + m))
    return v, f


def polygon_area(poly):
    return abs(sum(x0 * y1 - x1 * y0 for (x0, y0), (x1, y1) in
                   zip(poly, poly[1:] + poly[:1]))) / 2


def cad_fans(layout, n=3900):
    """Two fan-triangulated plates (31K faces in all), 'crossing' at right angles (the
    second turned about z and raised by half the thickness), 'stacked' (the second on
    the first, mirrored: their touching fans share the apex) or 'gap' (stacked 1e-7
    apart: no face meets the other plate, but their float boxes overlap)."""
    poly = fan_plate_polygon(n)
    a = fan_plate(poly, 0.0, 10.0)
    if layout == 'crossing':
        b = ([(-y - 4500.0, x + 4500.0, z + 5.0) for x, y, z in a[0]], a[1])
    else:
        mirrored = [(x, 0.0 - y) for x, y in poly][::-1]
        b = fan_plate(mirrored[-3:] + mirrored[:-3], 10.0 + (1e-7 if layout == 'gap' else 0),
                      10.0)
    return [a, b], ['union', 0, 1]


def analytic_references():
    ref = {}
    for n in (2, 3, 4):  # half a Menger sponge of side 100; one shell
        ref['menger_%d_exact' % n] = (0.5 * 100.0 ** 3 * (20 / 27) ** n, 1)
    ref['cube_minus_cylinder_64'] = (1000 - 10 * 32 * 9 * math.sin(2 * math.pi / 64), 1)
    plate = polygon_area(fan_plate_polygon(3900)) * 10.0
    ref['cad_fans_crossing'] = (2 * plate - 100.0 * 100.0 * 5.0, 1)
    ref['cad_fans_stacked'] = (2 * plate, 1)
    ref['cad_fans_gap'] = (2 * plate, 2)
    for n in (32, 64):
        ref['box_grid_%d' % n] = (0.875 * n * n, 1)  # plate - holes (n^2 / 4) + bars (n^2 / 8)
        hole = 0.5 * 24 * 0.3 ** 2 * math.sin(2 * math.pi / 24)
        ref['drill_plate_%d' % n] = (n * n * (1 - hole), 1)
    return ref


def scene_builders(ms, models):
    """(name, builder, note) in table order."""
    out = []
    for n in range(100, 900, 100):
        out.append(('ring_spheres_%d' % n, lambda n=n: ms.ring_spheres(n), 'Table 2'))
    for n in (100, 200, 400, 800):
        out.append(('ring_constant_density_%d' % n,
                    lambda n=n: ring_spheres_constant_density(ms, n), 'Table 2, k/n constant'))
    out.append(('cube_minus_cylinder_64', lambda: CUBE_MINUS_CYLINDER, 'issue 34'))
    out.append(('cylinder_28_holes', ms.cylinder_holes, 'Table 1 no. 5'))
    out.append(('box_grid_8', ms.box_grid, 'plate - holes + bars'))
    for n in (32, 64):
        out.append(('box_grid_%d' % n, lambda n=n: ms.box_grid(n), 'CAD plate, %d holes' % (n * n)))
    for n in (32, 64):
        out.append(('drill_plate_%d' % n, lambda n=n: drill_plate(ms, n),
                    'CAD plate, %d round holes' % (n * n)))
    model = {}

    def from_models(name):
        if not model:
            for scene, meshes, tree in ms.model_scenes(models):
                model[scene] = (meshes, tree)
        return model[name]
    for name in ('armadillo_union_6bunnies', 'cow100K_minus_shifted', 'bunny100k_minus_shifted',
                 'bunny_and_bunny_same'):
        out.append((name, lambda name=name: from_models(name), 'model'))
    out.append(('spheres_overlap_700', spheres_overlap, '700 x 320 faces'))
    for n in (2, 3, 4):
        out.append(('menger_%d_6digits' % n, lambda n=n: menger_sponge(n, 6),
                    'OpenSCAD example024 export, level %d' % n))
        out.append(('menger_%d_exact' % n, lambda n=n: menger_sponge(n),
                    'the same, exact numbers'))
    for layout in ('crossing', 'stacked', 'gap'):
        out.append(('cad_fans_%s' % layout, lambda l=layout: cad_fans(l),
                    'CAD fans, 31K faces, %s' % layout))
    for faces in ('25k', '50k'):
        out.append(('bunny%s_minus_shifted' % faces,
                    lambda f=faces: model_minus_shifted(ms, models, 'bunny%s.obj' % f),
                    'scaling'))
    out.append(('bunny400k_minus_shifted',
                lambda: model_minus_shifted(ms, models, 'bunny100k.obj', 1), 'scaling'))
    out.append(('bunny1600k_minus_shifted',
                lambda: model_minus_shifted(ms, models, 'bunny100k.obj', 2), 'scaling, 3.2M'))
    return out


def ensure_scene(ms, cache, name, build):
    d = os.path.join(cache, name)
    stamp = os.path.join(d, 'generator-version')
    if os.path.exists(stamp) and open(stamp).read() == GENERATOR_VERSION:
        return d
    sys.stderr.write('generating %s\n' % name)
    built = build()
    if isinstance(built, str):  # a CSG text of primitives: no leaf files
        os.makedirs(d, exist_ok=True)
        open(os.path.join(d, 'tree.scad'), 'w').write(built)
    else:
        ms.emit(cache, name, *built)
    open(stamp, 'w').write(GENERATOR_VERSION)
    return d


STEP_LINE = re.compile(r'^\s+([a-z ]+?)\s{2,}([0-9.]+) s')
HEAD_LINE = re.compile(r'primitives (\d+), faces (\d+) \(min (\d+), max (\d+)')


BROKEN_STATUS = 3  # meshcsg eval: result written, but it breaks a guarantee (the warning says)


def run_once(meshcsg, scene_dir, out, threads):
    """One whole-process run: (wall seconds, peak RSS bytes, stats dict); the stats hold
    'broken', the warning, when the result breaks a guarantee after rounding."""
    cmd = [meshcsg, 'eval', os.path.join(scene_dir, 'tree.scad'), '-o', out, '--stats',
           '--threads', str(threads)]
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    stdout, stderr = proc.communicate()
    wall = time.perf_counter() - start
    if proc.returncode not in (0, BROKEN_STATUS):
        sys.exit('%s failed: %s' % (' '.join(cmd), stderr.decode().strip()))
    rss = 0
    stats = {}
    if proc.returncode == BROKEN_STATUS:
        warning = [l.split('to doubles: ', 1)[-1] for l in stderr.decode().splitlines()
                   if 'breaks its guarantees' in l]
        stats['broken'] = warning[0] if warning else 'see its warning'
    for line in stdout.decode().splitlines():
        m = STEP_LINE.match(line)
        if m:
            stats[m.group(1)] = float(m.group(2))
        m = HEAD_LINE.search(line)
        if m:
            stats['primitives'], stats['faces'], stats['min'], stats['max'] = map(
                int, m.groups())
        m = re.search(r'\((\d+) vertices, (\d+) triangles[;)]', line)
        if m and line.strip().startswith('assemble'):
            stats['out_triangles'] = int(m.group(2))
        m = re.search(r'peak memory\s+([0-9.]+) MiB', line)
        if m:
            rss = float(m.group(1)) * 1048576
    return wall, rss, stats


def check_output(meshcsg, out):
    """(volume, shells, message) of the result, by `meshcsg check`."""
    res = subprocess.run([meshcsg, 'check', out], capture_output=True, text=True)
    m = re.search(r'ok: .* (\d+) components?, volume ([-0-9.e+]+)', res.stdout)
    if res.returncode != 0 or not m:
        return None, None, (res.stdout + res.stderr).strip()
    return float(m.group(2)), int(m.group(1)), 'ok'


def references(shared):
    ref = {}
    path = os.path.join(shared, 'scenes', 'reference.tsv')
    for line in open(path).read().splitlines()[1:]:
        name, faces, volume, shells = line.split('\t')
        ref[name] = (float(volume), int(shells))
    return ref


STEPS = {  # the paper's steps: 1 octree, 2 intersection, 3 classification
    1: ('octree',),
    2: ('candidate pairs', 'intersect', 'arrange faces', 'number points'),
    3: ('whole faces', 'triangulate', 'classify', 'assemble'),
}


def measure(meshcsg, scene_dir, runs, tmp):
    out = os.path.join(tmp, 'result.off')
    one = [run_once(meshcsg, scene_dir, out, 1) for _ in range(runs)]
    two = [run_once(meshcsg, scene_dir, out, 2) for _ in range(runs)]
    volume, shells, message = check_output(meshcsg, out)
    med = lambda xs: statistics.median(xs)
    stats = one[0][2]
    row = {
        'faces': stats['faces'], 'min': stats['min'], 'max': stats['max'],
        'primitives': stats['primitives'], 'out': stats.get('out_triangles', 0),
        'total': med([w for w, _, _ in one]), 'total2': med([w for w, _, _ in two]),
        'memory': med([r for _, r, _ in one]),
        'volume': volume, 'shells': shells, 'check': message, 'broken': stats.get('broken'),
    }
    for step, names in STEPS.items():
        row['step%d' % step] = med([sum(s.get(n, 0) for n in names) for _, _, s in one])
    row['io'] = med([w - s.get('total', 0) for w, _, s in one])
    row['check_inputs'] = med([s.get('input check', 0) + s.get('positive tree', 0)
                               for _, _, s in one])
    return row


def fmt_faces(n):
    return '%.1fK' % (n / 1000) if n < 1e6 else '%.2fM' % (n / 1e6)


def machine():
    cpu = 'unknown CPU'
    for line in open('/proc/cpuinfo'):
        if line.startswith('model name'):
            cpu = line.split(':', 1)[1].strip()
            break
    mem = 0
    for line in open('/proc/meminfo'):
        if line.startswith('MemTotal'):
            mem = int(line.split()[1]) / 1048576
    cc = subprocess.run(['cc', '--version'], capture_output=True, text=True).stdout
    return '%s, %d cores visible, %.0f GiB; %s; %s' % (
        cpu, os.cpu_count(), mem, cc.splitlines()[0] if cc else 'cc ?', platform.platform())


def table(rows, refs):
    lines = [
        '| scene | faces total | min | max | primitives | total (1 thread) | step 1 | step 2 '
        '| step 3 | check + I/O | peak memory | bytes/face | output faces | leanest known '
        '| 2 threads | speed-up | target | result |',
        '|' + '---|' * 18,
    ]
    for name, note, r in rows:
        target = TARGETS.get(name)
        ref = refs.get(name)
        if r['check'] != 'ok':
            result = 'INVALID: ' + r['check']
        elif ref:
            same = abs(r['volume'] - ref[0]) <= 1e-9 * abs(ref[0]) and r['shells'] == ref[1]
            result = ('matches reference' if same else
                      'MISMATCH: volume %.12g shells %d' % (r['volume'], r['shells']))
        else:
            result = 'closed, volume %.10g, %d shells' % (r['volume'], r['shells'])
        if r['broken']:  # `meshcsg check` reports the same breakage, welded
            result = 'BROKEN by rounding (exit %d): %s' % (BROKEN_STATUS, r['broken'])
        per_face = r['memory'] / r['faces']
        target_text = '-' if target is None else '%s %g s' % (
            'met' if r['total'] <= target else 'MISSED', target)
        lean = LEANEST.get(name)
        lean_text = '-' if lean is None else '%d (%s): %.2fx' % (lean[0], lean[1],
                                                                r['out'] / lean[0])
        lines.append(
            '| %s (%s) | %s | %d | %d | %d | %.3f s | %.3f | %.3f | %.3f | %.3f | %.0f MiB | '
            '%.0f%s | %d | %s | %.3f s | %.2fx | %s | %s |' % (
                name, note, fmt_faces(r['faces']), r['min'], r['max'], r['primitives'],
                r['total'], r['step1'], r['step2'], r['step3'],
                r['check_inputs'] + r['io'], r['memory'] / 1048576, per_face,
                '' if per_face <= MEMORY_TARGET else ' (over)', r['out'], lean_text, r['total2'],
                r['total'] / r['total2'], target_text, result))
    return '\n'.join(lines)


def ring_growth(rows):
    t = {name: r['total'] for name, _, r in rows}
    lines = []
    if 'ring_spheres_100' in t and 'ring_spheres_800' in t:
        ratio = t['ring_spheres_800'] / t['ring_spheres_100']
        lines.append('Ring series growth: t(800) / t(100) = %.2f (target <= 9; the paper: 12.8 / '
                     '1.38 = 9.3).' % ratio)
    if 'ring_constant_density_100' in t and 'ring_constant_density_800' in t:
        ratio = t['ring_constant_density_800'] / t['ring_constant_density_100']
        lines.append('Constant-density ring series (the paper\'s condition, k/n constant): '
                     't(800) / t(100) = %.2f.' % ratio)
    return '\n'.join(lines)


def write_doc(doc, text, begin=BEGIN, end=END):
    """Replaces the block between the markers begin and end (appends it if absent)."""
    old = open(doc).read() if os.path.exists(doc) else ''
    block = begin + '\n' + text + '\n' + end
    if begin in old and end in old:
        new = old[:old.index(begin)] + block + old[old.index(end) + len(end):]
    else:
        new = old.rstrip('\n') + '\n\n' + block + '\n'
    open(doc, 'w').write(new)


def main():
    args = sys.argv[1:]
    if len(args) < 4:
        sys.exit(__doc__)
    meshcsg, shared, cache, doc = (os.path.abspath(a) for a in args[:4])
    runs = int(args[args.index('--runs') + 1]) if '--runs' in args else 5
    only = set(args[args.index('--only') + 1].split(',')) if '--only' in args else None
    sys.path.insert(0, os.path.join(shared, 'scenes'))
    import make_scenes as ms
    os.makedirs(cache, exist_ok=True)
    tmp = os.path.join(cache, 'out')
    os.makedirs(tmp, exist_ok=True)
    refs = analytic_references()
    refs.update(references(shared))
    rows = []
    for name, build, note in scene_builders(ms, os.path.join(shared, 'models')):
        if only and name not in only:
            continue
        d = ensure_scene(ms, cache, name, build)
        r = measure(meshcsg, d, runs, tmp)
        sys.stderr.write('%-28s %7.3f s (2 threads %.3f s) %6.0f MiB  %s\n' % (
            name, r['total'], r['total2'], r['memory'] / 1048576, r['check']))
        rows.append((name, note, r))
    text = '\n'.join([
        'Generated by `make bench` (bench/eval_bench.py) on %s.' % time.strftime('%Y-%m-%d'),
        'Machine: %s.' % machine(),
        'Whole process (`meshcsg eval tree.scad -o result.off --stats`: parse the leaves, '
        'evaluate, write OFF), median of %d runs; steps as in the paper\'s Table 1: step 1 '
        'octree, step 2 candidate pairs + intersection + per-face arrangement + point '
        'numbering, step 3 whole-face decisions + triangulation + classification + assembly; "check + I/O" is the '
        'rest (input contract check, parsing, writing). Peak memory is the process\'s peak '
        'RSS on one thread. "Leanest known": the fewest output triangles known for the scene '
        '(the minimum, or a peer\'s count) and the ratio of meshcsg\'s to it.' % runs,
        '',
        table(rows, refs),
        '',
        ring_growth(rows),
    ])
    write_doc(doc, text)


if __name__ == '__main__':
    main()

#!/usr/bin/env python3
"""Peer comparison for `make bench`: meshcsg against CGAL's corefinement (bench/cgal).

CGAL evaluates a tree one boolean operation at a time (bench/cgal/cgal_csg.cpp), with the
exact-predicates kernel that rounds constructed points (EPICK, CGAL's fast choice) and,
once per scene, with the exact-constructions kernel (EPECK, the exact peer). Both tools
run as whole processes (parse + evaluate + write an OFF file) on one thread, alternated
RUNS times per scene in the same period of machine load, so the ratios are fairer than
comparing two tables measured at different times. CGAL's result is checked with
`meshcsg check` against the reference volume and shell count of ../shared/scenes.

The table goes between <!-- cgal-bench:begin --> and <!-- cgal-bench:end --> of
docs/benchmarks.md.

usage: cgal_bench.py MESHCSG CGAL_CSG SHARED_DIR CACHE_DIR DOC.md [--runs N] [--only a,b]
"""
import json
import os
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import eval_bench as eb  # noqa: E402  (scene generation, checks, document writing)

BEGIN, END = '<!-- cgal-bench:begin -->', '<!-- cgal-bench:end -->'
SCENES = ['ring_spheres_100', 'ring_spheres_200', 'ring_spheres_400', 'ring_spheres_800',
          'cylinder_28_holes', 'box_grid_8', 'armadillo_union_6bunnies',
          'cow100K_minus_shifted', 'bunny100k_minus_shifted', 'bunny_and_bunny_same',
          'spheres_overlap_700', 'bunny25k_minus_shifted', 'bunny50k_minus_shifted',
          'bunny400k_minus_shifted']
SLOW = 30.0      # a CGAL run slower than this is not repeated
TIMEOUT = 900.0  # a CGAL run is stopped after this (reported as such)


def timed(cmd, cwd=None):
    """(wall seconds, return code, stderr text) of one whole-process run."""
    start = time.perf_counter()
    try:
        proc = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        return time.perf_counter() - start, 'timeout', 'stopped after %.0f s' % TIMEOUT
    wall = time.perf_counter() - start
    return wall, proc.returncode, proc.stderr.strip()


def describe_failure(code, message):
    if code == 'timeout':
        return message
    if isinstance(code, int) and code < 0:
        return 'crashed (signal %d)' % -code
    return 'failed: ' + (message.splitlines()[-1] if message else 'exit %s' % code)


def check_result(meshcsg, out, ref, ours):
    """CGAL's result against the reference, or (scenes without one) against meshcsg's
    result ours = (volume, shells)."""
    volume, shells, message = eb.check_output(meshcsg, out)
    if message != 'ok':
        return 'INVALID: ' + message
    against, what = (ref, 'reference') if ref is not None else (ours, 'meshcsg')
    if abs(volume - against[0]) <= 1e-9 * abs(against[0]) and shells == against[1]:
        return 'matches ' + what
    return 'MISMATCH with %s: volume %.12g, %d shells' % (what, volume, shells)


def measure(meshcsg, cgal, scene_dir, runs, tmp, ref):
    tree_scad, tree_sexp = (os.path.join(scene_dir, t) for t in ('tree.scad', 'tree.sexp'))
    ours_out, peer_out = os.path.join(tmp, 'ours.off'), os.path.join(tmp, 'cgal.off')
    ours, peer, peer_state = [], [], None
    for i in range(runs):
        wall, code, message = timed([meshcsg, 'eval', tree_scad, '-o', ours_out,
                                     '--threads', '1'])
        if code != 0:
            sys.exit('meshcsg failed on %s: %s' % (scene_dir, message))
        ours.append(wall)
        if peer_state is not None and (peer_state != 'ok' or peer[-1] > SLOW):
            continue
        wall, code, message = timed([cgal, tree_sexp, '-o', peer_out])
        if code != 0:
            peer_state = describe_failure(code, message)
            continue
        peer.append(wall)
        peer_state = 'ok'
    volume, shells, _ = eb.check_output(meshcsg, ours_out)
    ours_result = (volume, shells)
    row = {'ours': statistics.median(ours), 'epick': None, 'epick_check': peer_state}
    if peer_state == 'ok':
        row['epick'] = statistics.median(peer)
        row['epick_check'] = check_result(meshcsg, peer_out, ref, ours_result)
    # EPECK is slower than EPICK: not run where EPICK already took over SLOW seconds or
    # was stopped at TIMEOUT (it would only spend another TIMEOUT); run where EPICK
    # crashed or failed, since the exact kernel may succeed there.
    row['epeck'], row['epeck_check'] = None, 'not run (EPICK over %.0f s)' % SLOW
    epick_timed_out = peer_state is not None and peer_state.startswith('stopped after')
    if not epick_timed_out and (row['epick'] is None or row['epick'] <= SLOW):
        wall, code, message = timed([cgal, tree_sexp, '-o', peer_out, '--exact'])
        row['epeck'] = wall if code == 0 else None
        row['epeck_check'] = (check_result(meshcsg, peer_out, ref, ours_result) if code == 0
                              else describe_failure(code, message))
    return row


def ratio(peer, ours):
    return '%.1fx' % (peer / ours) if peer is not None else '-'


def seconds(value, state):
    return '%.3f s' % value if value is not None else state


def table(rows):
    lines = [
        '| scene | faces | CGAL operations | meshcsg | CGAL (EPICK) | ratio | EPICK result '
        '| CGAL (EPECK, 1 run) | ratio | EPECK result |',
        '|' + '---|' * 10,
    ]
    for name, r in rows:
        lines.append('| %s | %s | %d | %.3f s | %s | %s | %s | %s | %s | %s |' % (
            name, eb.fmt_faces(r['faces']), r['operations'], r['ours'],
            seconds(r['epick'], '-'), ratio(r['epick'], r['ours']), r['epick_check'],
            seconds(r['epeck'], '-'), ratio(r['epeck'], r['ours']), r['epeck_check']))
    return '\n'.join(lines)


def main():
    args = sys.argv[1:]
    if len(args) < 5:
        sys.exit(__doc__)
    meshcsg, cgal, shared, cache, doc = (os.path.abspath(a) for a in args[:5])
    runs = int(args[args.index('--runs') + 1]) if '--runs' in args else 3
    only = set(args[args.index('--only') + 1].split(',')) if '--only' in args else None
    sys.path.insert(0, os.path.join(shared, 'scenes'))
    import make_scenes as ms
    tmp = os.path.join(cache, 'out')
    os.makedirs(tmp, exist_ok=True)
    refs = eb.references(shared)
    rows = []
    for name, build, _ in eb.scene_builders(ms, os.path.join(shared, 'models')):
        if name not in SCENES or (only and name not in only):
            continue
        d = eb.ensure_scene(ms, cache, name, build)
        r = measure(meshcsg, cgal, d, runs, tmp, refs.get(name))
        scene = json.load(open(os.path.join(d, 'scene.json')))
        r['faces'], r['operations'] = scene['faces'], scene['leaves'] - 1
        sys.stderr.write('%-28s meshcsg %.3f s  CGAL %s (%s)  EPECK %s (%s)\n' % (
            name, r['ours'], seconds(r['epick'], '-'), r['epick_check'],
            seconds(r['epeck'], '-'), r['epeck_check']))
        rows.append((name, r))
    text = '\n'.join([
        'Generated by `make bench` (bench/cgal_bench.py, CGAL %s) on %s.' % (
            cgal_version(), time.strftime('%Y-%m-%d')),
        'Machine: %s.' % eb.machine(),
        'Whole process on one thread (parse, evaluate, write OFF) for both tools; CGAL '
        'evaluates the tree one corefinement at a time (bench/cgal/cgal_csg.cpp). meshcsg '
        'and CGAL with EPICK alternate, median of %d runs each (CGAL runs over %.0f s are '
        'not repeated); EPECK runs once, where EPICK takes under %.0f s. Ratio = CGAL time / '
        'meshcsg time.' % (runs, SLOW, SLOW),
        '',
        table(rows),
    ])
    eb.write_doc(doc, text, BEGIN, END)


def cgal_version():
    path = '/usr/include/CGAL/version.h'
    if os.path.exists(path):
        for line in open(path):
            if line.startswith('#define CGAL_VERSION '):
                return line.split()[2]
    return '?'


if __name__ == '__main__':
    main()

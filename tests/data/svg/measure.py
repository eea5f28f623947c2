#!/usr/bin/env python3
"""OpenSCAD 2021.01's result for import() of each SVG here: loops, points, exact area.

Run in this folder with `openscad` on the PATH: python3 measure.py [FILE[:center:dpi]...].
For each case, OpenSCAD exports the 2D import as SVG (its loops, six-digit coordinates)
and the import extruded by 1 and united with a far cube as NEF3 (exact rational
vertices). Each SVG vertex is matched to the nearest exact vertex at z = 0, and the area
is summed exactly (fractions) from the loops so recovered. Prints one C table row per
case: file, center, dpi, loops, points, area (test_svg.c's known answers).
"""
import os
import re
import subprocess
import sys
import tempfile
from fractions import Fraction

CASES = [
    ("spec-paths-arcs01.svg", False, 72), ("spec-paths-arcs02.svg", False, 72),
    ("spec-paths-cubic01.svg", False, 72), ("spec-paths-cubic02.svg", False, 72),
    ("spec-paths-quad01.svg", False, 72), ("spec-paths-triangle01.svg", False, 72),
    ("spec-shapes-circle01.svg", False, 72), ("spec-shapes-ellipse01.svg", False, 72),
    ("spec-shapes-line01.svg", False, 72), ("spec-shapes-polygon01.svg", False, 72),
    ("spec-shapes-polyline01.svg", False, 72), ("spec-shapes-rect01.svg", False, 72),
    ("spec-shapes-rect02.svg", False, 72), ("box-w-holes.svg", True, 72),
    ("simple.svg", True, 72), ("simple.svg", False, 96), ("line-cap-line-join.svg", False, 72),
] + [(f, False, 72) for f in sorted(os.listdir(os.path.dirname(os.path.abspath(__file__))))
     if f.startswith("viewbox_")]


def run(scad, out):
    subprocess.run(["openscad", "-o", out, scad], check=True, capture_output=True)


def measure(name, center, dpi):
    here = os.path.dirname(os.path.abspath(__file__))
    call = 'import("%s", center=%s, dpi=%s)' % (os.path.join(here, name),
                                                   "true" if center else "false", dpi)
    with tempfile.TemporaryDirectory() as tmp:
        s2 = os.path.join(tmp, "a.scad")
        s3 = os.path.join(tmp, "b.scad")
        open(s2, "w").write(call + ";\n")
        open(s3, "w").write("linear_extrude(1) %s;\ntranslate([1e6, 1e6, 0]) cube(1);\n" % call)
        run(s2, os.path.join(tmp, "a.svg"))
        run(s3, os.path.join(tmp, "b.nef3"))
        svg = open(os.path.join(tmp, "a.svg")).read()
        nef = open(os.path.join(tmp, "b.nef3")).read()
    exact = []
    count = int(re.search(r"^vertices\s+(\d+)", nef, re.M).group(1))
    lines = [l for l in nef.splitlines() if re.match(r"^\d+ \{", l)][:count]
    for m in (re.search(r"\|\s*(-?\d+) (-?\d+) (-?\d+) (-?\d+) \}", l) for l in lines):
        x, y, z, w = (int(v) for v in m.groups())
        if z == 0 and abs(Fraction(x, w)) < 500000:
            exact.append((Fraction(x, w), Fraction(y, w)))
    loops = []
    for d in re.findall(r'd="([^"]*)"', svg):
        for sub in re.split(r"(?=M)", d):
            pts = re.findall(r"(-?[\d.e+-]+),(-?[\d.e+-]+)", sub)
            if pts:
                loops.append([(float(a), -float(b)) for a, b in pts])
    area = Fraction(0)
    points = 0
    for loop in loops:
        snapped = [min(exact, key=lambda e: (float(e[0]) - x) ** 2 + (float(e[1]) - y) ** 2)
                   for x, y in loop]
        points += len(snapped)
        for i, a in enumerate(snapped):
            b = snapped[(i + 1) % len(snapped)]
            area += (a[0] * b[1] - b[0] * a[1]) / 2
    return len(loops), points, len(exact), abs(area)


def main():
    cases = CASES
    if len(sys.argv) > 1:
        cases = []
        for arg in sys.argv[1:]:
            f, *rest = arg.split(":")
            cases.append((f, rest[0] == "true" if rest else False,
                          float(rest[1]) if len(rest) > 1 else 72))
    for name, center, dpi in cases:
        loops, points, vertices, area = measure(name, center, dpi)
        print('    {"%s", %s, %g, %d, %d, %.17g}, /* %d exact vertices */'
              % (name, "true" if center else "false", dpi, loops, points, float(area),
                 vertices))


if __name__ == "__main__":
    main()

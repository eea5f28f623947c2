"""Rotation matrices as meshcsg's CSG language computes them (src/scad/degree_trig.c):
the angle reduced to [0, 360), folded into [0, 90], 30, 45, 60 and 90 degrees exact,
so that rotate() here gives the very same doubles as rotate() in a .scad file."""

import math

_SQRT3_4 = 0.86602540378443859659
_SQRT1_2 = 0.70710678118654752440
_DEG2RAD = 0.017453292519943295769
_HUGE = float(1 << 26) * 360.0 * float(1 << 26)


def _reduce(x):
    if 0.0 <= x < 360.0:
        return x
    if -_HUGE < x < _HUGE:
        return x - 360.0 * math.floor(x / 360.0)
    return math.nan


def _half_turn(x):
    """x reduced to [0, 180), and whether half a turn was taken off."""
    x = _reduce(x)
    oppose = x >= 180.0
    return (x - 180.0 if oppose else x), oppose


def sin_degrees(x):
    x, oppose = _half_turn(x)
    if math.isnan(x):
        return x
    if x > 90.0:
        x = 180.0 - x
    if x < 45.0:
        x = 0.5 if x == 30.0 else math.sin(x * _DEG2RAD)
    elif x == 45.0:
        x = _SQRT1_2
    elif x == 60.0:
        x = _SQRT3_4
    else:
        x = math.cos((90.0 - x) * _DEG2RAD)
    return -x if oppose else x


def cos_degrees(x):
    x, oppose = _half_turn(x)
    if math.isnan(x):
        return x
    if x > 90.0:
        x = 180.0 - x
        oppose = not oppose
    if x > 45.0:
        x = 0.5 if x == 60.0 else math.sin((90.0 - x) * _DEG2RAD)
    elif x == 45.0:
        x = _SQRT1_2
    elif x == 30.0:
        x = _SQRT3_4
    else:
        x = math.cos(x * _DEG2RAD)
    return -x if oppose else x


def euler(angles):
    """rotate([x, y, z]): Rz * Ry * Rx, as a row-major 3x3 list."""
    s = [sin_degrees(float(a)) for a in angles] + [0.0] * (3 - len(angles))
    c = [cos_degrees(float(a)) for a in angles] + [1.0] * (3 - len(angles))
    return [c[1] * c[2], c[2] * s[0] * s[1] - c[0] * s[2], c[0] * c[2] * s[1] + s[0] * s[2],
            c[1] * s[2], c[0] * c[2] + s[0] * s[1] * s[2], -c[2] * s[0] + c[0] * s[1] * s[2],
            -s[1], c[1] * s[0], c[0] * c[1]]


def angle_axis(a, v):
    """rotate(a, v): a degrees about the axis v (identity for a zero axis)."""
    s, c = sin_degrees(float(a)), cos_degrees(float(a))
    v = [float(x) for x in v]
    norm2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    if not norm2 > 0:
        return [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    k = (1 - c) / norm2
    length = math.sqrt(norm2)
    cv = [x * k for x in v]
    us = [(x / length) * s for x in v]
    return [cv[0] * v[0] + c, cv[1] * v[0] - us[2], cv[2] * v[0] + us[1],
            cv[0] * v[1] + us[2], cv[1] * v[1] + c, cv[2] * v[1] - us[0],
            cv[0] * v[2] - us[1], cv[1] * v[2] + us[0], cv[2] * v[2] + c]

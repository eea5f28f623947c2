/*
 * Trigonometry in degrees, following OpenSCAD's src/utils/degree_trig.cc operation for
 * operation (same reduction, same constants, same special cases), so that primitives and
 * rotations get the very same doubles OpenSCAD computes:
 *  - the angle is reduced to [0, 360) by x -= 360 * floor(x / 360); beyond
 *    +-360 * 2^52 the result would be meaningless and NaN is returned;
 *  - the reduced angle is folded into [0, 90] by symmetry, and 30, 45 and 60 degrees
 *    give the correctly rounded constants, 0 and 90 the exact values 0 and 1;
 *  - other angles use the C library's sin/cos/tan of x * (pi / 180), always on the
 *    smaller of the angle and its complement (sin of [0, 45), cos of [45, 90]).
 */
#include "base/degree_trig.h"

#include <math.h>

/* The same literals as OpenSCAD's degree_trig.h (each rounds to the nearest double). */
#define SQRT3 1.73205080756887719318
#define SQRT3_4 0.86602540378443859659 /* sqrt(3)/2 */
#define SQRT1_3 0.57735026918962573106 /* sqrt(3)/3 */
#define SQRT1_2 0.70710678118654752440 /* sqrt(2)/2 */
#define RAD2DEG 57.2957795130823208767
#define DEG2RAD 0.017453292519943295769

/* 360 * 2^52: beyond this, reducing the angle would lose every bit of accuracy. */
#define TRIG_HUGE_VAL ((double)(1L << 26) * 360.0 * (double)(1L << 26))

/* Reduce x to [0, 360); false (leaving x alone) when x is NaN or too large. Finite
 * values in [0, 360) are kept as they are. */
static int reduce_degrees(double *x, double period)
{
    double v = *x;
    if (v < period && v >= 0.0)
        return 1;
    if (v < TRIG_HUGE_VAL && v > -TRIG_HUGE_VAL) {
        double revolutions = floor(v / period);
        *x = v - period * revolutions;
        return 1;
    }
    return 0; /* infinite, NaN or huge */
}

double mci_sin_degrees(double x)
{
    int oppose;
    if (!reduce_degrees(&x, 360.0))
        return NAN;
    oppose = x >= 180.0;
    if (oppose)
        x -= 180.0;
    if (x > 90.0)
        x = 180.0 - x;
    if (x < 45.0)
        x = (x == 30.0) ? 0.5 : sin(x * DEG2RAD);
    else if (x == 45.0)
        x = SQRT1_2;
    else if (x == 60.0)
        x = SQRT3_4;
    else
        x = cos((90.0 - x) * DEG2RAD);
    return oppose ? -x : x;
}

double mci_cos_degrees(double x)
{
    int oppose;
    if (!reduce_degrees(&x, 360.0))
        return NAN;
    oppose = x >= 180.0;
    if (oppose)
        x -= 180.0;
    if (x > 90.0) {
        x = 180.0 - x;
        oppose = !oppose;
    }
    if (x > 45.0)
        x = (x == 60.0) ? 0.5 : sin((90.0 - x) * DEG2RAD);
    else if (x == 45.0)
        x = SQRT1_2;
    else if (x == 30.0)
        x = SQRT3_4;
    else
        x = cos(x * DEG2RAD);
    return oppose ? -x : x;
}

double mci_tan_degrees(double x)
{
    double cycles_d = floor(x / 180.0);
    int odd_cycle, oppose;
    if (!reduce_degrees(&x, 180.0))
        return NAN;
    /* OpenSCAD keeps the cycle count in an int; only its parity matters here. */
    odd_cycle = fmod(cycles_d, 2.0) != 0.0;
    oppose = x > 90.0;
    if (oppose)
        x = 180.0 - x;
    if (x == 0.0)
        x = odd_cycle ? -0.0 : 0.0;
    else if (x == 30.0)
        x = SQRT1_3;
    else if (x == 45.0)
        x = 1.0;
    else if (x == 60.0)
        x = SQRT3;
    else if (x == 90.0)
        x = odd_cycle ? -INFINITY : INFINITY;
    else
        x = tan(x * DEG2RAD);
    return oppose ? -x : x;
}

/* The inverse functions return a whole number of degrees when that number's forward
 * function gives back exactly x (so asin(0.5) is exactly 30). */
double mci_asin_degrees(double x)
{
    double degs = asin(x) * RAD2DEG, whole = round(degs);
    return mci_sin_degrees(whole) == x ? whole : degs;
}

double mci_acos_degrees(double x)
{
    double degs = acos(x) * RAD2DEG, whole = round(degs);
    return mci_cos_degrees(whole) == x ? whole : degs;
}

double mci_atan_degrees(double x)
{
    double degs = atan(x) * RAD2DEG, whole = round(degs);
    return mci_tan_degrees(whole) == x ? whole : degs;
}

double mci_atan2_degrees(double y, double x)
{
    double degs = atan2(y, x) * RAD2DEG, whole = round(degs);
    return fabs(degs - whole) < 3.0E-14 ? whole : degs;
}

void mci_angle_axis_degrees(double a, const double v[3], double m[9])
{
    double s = mci_sin_degrees(a), c = mci_cos_degrees(a);
    double norm2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    double k, len, cv[3], us[3];
    for (int i = 0; i < 9; i++)
        m[i] = (i % 4 == 0) ? 1.0 : 0.0;
    if (!(norm2 > 0))
        return;
    /* Like OpenSCAD (Wikipedia's axis-angle formula), divide by |v|^2 rather than
     * normalising v twice: fewer roundings. */
    k = (1 - c) / norm2;
    len = sqrt(norm2);
    for (int i = 0; i < 3; i++) {
        cv[i] = v[i] * k;
        us[i] = (v[i] / len) * s;
    }
    m[0] = cv[0] * v[0] + c;
    m[1] = cv[1] * v[0] - us[2];
    m[2] = cv[2] * v[0] + us[1];
    m[3] = cv[0] * v[1] + us[2];
    m[4] = cv[1] * v[1] + c;
    m[5] = cv[2] * v[1] - us[0];
    m[6] = cv[0] * v[2] - us[1];
    m[7] = cv[1] * v[2] + us[0];
    m[8] = cv[2] * v[2] + c;
}

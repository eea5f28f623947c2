/*
 * Trigonometry in degrees, exactly as OpenSCAD computes it (src/utils/degree_trig.cc):
 * arguments are reduced to [0, 360) first, and multiples of 30 and 45 degrees give exact
 * (correctly rounded) results, so that e.g. cos(90) is 0 and sin(30) is 0.5. Used by
 * the primitive tessellation, by rotate() and by the CSG language's sin/cos/tan.
 */
#ifndef MESHCSG_BASE_DEGREE_TRIG_H
#define MESHCSG_BASE_DEGREE_TRIG_H

double mci_sin_degrees(double x);
double mci_cos_degrees(double x);
double mci_tan_degrees(double x);
double mci_asin_degrees(double x);
double mci_acos_degrees(double x);
double mci_atan_degrees(double x);
double mci_atan2_degrees(double y, double x);

/* OpenSCAD's angle_axis_degrees: the row-major 3x3 rotation by `a` degrees about the
 * axis v (which need not be unit length); the identity when v is zero. */
void mci_angle_axis_degrees(double a, const double v[3], double m[9]);

#endif

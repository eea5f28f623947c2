/*
 * Locale-independent, exact conversions between decimal text and doubles.
 * Parsing is correctly rounded (round-to-nearest-even, like a conforming strtod in the
 * "C" locale) whatever the host program's locale; formatting writes the shortest decimal
 * that parses back to the identical double.
 */
#ifndef MESHCSG_BASE_NUMPARSE_H
#define MESHCSG_BASE_NUMPARSE_H

#include <stdbool.h>
#include <stddef.h>

/* Parse one number at `s` (no leading whitespace skipped), reading no byte at or beyond
 * `end`. Accepts an optional sign, decimal digits with an optional '.', an optional
 * exponent (e/E, optional sign, digits), and case-insensitive "inf", "infinity", "nan".
 * On success stores the value in *out, sets *next to the first byte not consumed and
 * returns true. Returns false (leaving *out and *next untouched) when no number starts
 * at s. Values beyond the double range give +-inf; tiny ones round to subnormals or 0. */
bool mci_parse_double(const char *s, const char *end, double *out, const char **next);

/* "00", "01", ... "99": the two digits of k at 2 k. */
extern const char mci_digit_pairs[201];

/* The room mci_format_double needs at buf: its text (at most 24 characters and the
 * terminating NUL) is laid out in place, with fixed-size copies of digits that may reach
 * past the text's end. */
#define MCI_DOUBLE_TEXT_MAX 48

/* Write the shortest decimal (%.15g, %.16g or %.17g style) that mci_parse_double reads
 * back to exactly `value`, with '.' as decimal point whatever the locale. "inf", "-inf"
 * and "nan" for non-finite values. Returns the number of characters written. */
size_t mci_format_double(char buf[MCI_DOUBLE_TEXT_MAX], double value);

#endif

/*
 * Tests of src/base/numparse.c: mci_parse_double must agree bit for bit with glibc's strtod
 * in the "C" locale (which is correctly rounded) on random doubles printed in several
 * ways, random digit strings, exact midpoints between adjacent doubles (computed with
 * GMP), subnormals and the overflow threshold; it must respect the `end` bound and
 * ignore the locale. mci_format_double must write the shortest of %.15g/%.16g/%.17g
 * that reads back exactly. (Independence of the process locale: test_numparse_locale.c.)
 */
#define _POSIX_C_SOURCE 200809L

#include "base/numparse.h"
#include "testlib.h"

#include <float.h>
#include <gmp.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Iteration counts, chosen to keep the whole test well under 20 s with ASan. */
#define RANDOM_BIT_PATTERNS 1000000
#define RANDOM_DIGIT_STRINGS 300000
#define HALFWAY_CASES 12000
#define SHORT_NUMBERS 400000

static uint64_t rng_state = 0x9e3779b97f4a7c15ull;

static uint64_t next_random(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double double_from_bits(uint64_t bits)
{
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
}

static uint64_t bits_of(double d)
{
    uint64_t bits;
    memcpy(&bits, &d, sizeof bits);
    return bits;
}

/* Parse `text` with both parsers from an exactly-sized heap copy (no terminator, so
 * ASan catches any read past `end`) and compare value and end position. */
static void compare_with_strtod(const char *text)
{
    size_t len = strlen(text);
    char *copy = malloc(len ? len : 1);
    char *ref_end;
    const char *next = NULL;
    double ours = 0, ref = strtod(text, &ref_end);
    bool ok;
    memcpy(copy, text, len);
    ok = mci_parse_double(copy, copy + len, &ours, &next);
    test_checks++;
    if (ref_end == text) {
        if (ok)
            test_fail(__FILE__, __LINE__, "\"%s\": parsed but strtod rejects it", text);
    } else if (!ok) {
        test_fail(__FILE__, __LINE__, "\"%s\": rejected, strtod gives %.17g", text, ref);
    } else if (!test_same_double(ours, ref) || next - copy != ref_end - text) {
        test_fail(__FILE__, __LINE__, "\"%s\": got %a (%td chars), strtod %a (%td chars)",
                  text, ours, next - copy, ref, ref_end - text);
    }
    free(copy);
}

/* Same check without the heap copy, for the bulk random loops (faster under ASan). */
static void quick_compare(const char *text)
{
    size_t len = strlen(text);
    char *ref_end;
    const char *next = NULL;
    double ours = 0, ref = strtod(text, &ref_end);
    bool ok = mci_parse_double(text, text + len, &ours, &next);
    test_checks++;
    if (!ok || !test_same_double(ours, ref) || next != ref_end)
        test_fail(__FILE__, __LINE__, "\"%s\": got %a, strtod %a", text, ours, ref);
}

/* mci_parse_double over the first n characters of text. */
static bool parse_prefix(const char *text, size_t n, double *v, const char **next)
{
    return mci_parse_double(text, text + n, v, next);
}

TEST(fixed_strings)
{
    static const char *const cases[] = {
        "0", "-0", "+0", "0.0", "-0.0e10", "1", "-1", "1.", ".5", "-.5", "00000.0001",
        "1e", "1e+", "1e-", "1ex", "1.5e3", "1.5E-3", "1e+308", "1e309", "-1e309",
        "1e-323", "1e-324", "3e-324", "2.4703282292062327e-324",
        "2.4703282292062328e-324", "4.9406564584124654e-324", "2.2250738585072011e-308",
        "2.2250738585072014e-308", "2.2250738585072012e-308",
        "1.7976931348623157e308", "1.7976931348623158e308", "1.7976931348623159e308",
        "1e999999999999", "1e-999999999999", "-1e999999999999999999999999",
        "0e999999999999", "123456789012345678901234567890", "0.1", "0.2", "0.3",
        "9007199254740993", "9007199254740992.5", "9007199254740993.0000000000000000001",
        "18446744073709551615", "18446744073709551616", "1e22", "1e23", "8.5e-20",
        "inf", "-inf", "INF", "Infinity", "-INFINITY", "infinit", "nan", "-NaN",
        "nan(123abc)", "nan(", "nan()", "in", "na", "", "-", "+", ".", "-.", ".e5", "e5",
        "1.2.3", "1..2", "12 34", "3.4e38", "3.4028234663852886e38", "1e-300",
        "0.000000000000000000000000000000000000000000000000000000000000000001e64",
        "100000000000000000000000000000000000000000000000000000000000000000e-64",
        "7.0064923216240854e-46", "4.4501477170144023e-308",
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        compare_with_strtod(cases[i]);
}

TEST(end_bound_is_respected)
{
    const char text[] = "1.5e3";
    double v = 0;
    const char *next = NULL;
    CHECK(mci_parse_double(text, text + 2, &v, &next) && v == 1.0 && next == text + 2);
    CHECK(mci_parse_double(text, text + 4, &v, &next) && v == 1.5 && next == text + 3);
    CHECK(!mci_parse_double(text, text, &v, &next));
    CHECK(parse_prefix("infinity", 5, &v, &next) && isinf(v));
    CHECK(parse_prefix("0x10", 4, &v, &next) && v == 0.0);
}

TEST(long_mantissas)
{
    /* Thousands of digits: only the first 800 are exact, the rest is a sticky bit. */
    size_t n = 3000;
    char *text = malloc(n + 16);
    memset(text, '0', n);
    text[0] = '1';
    strcpy(text + n, "e-3000");
    compare_with_strtod(text);
    text[n - 1] = '1';
    compare_with_strtod(text);
    memcpy(text, "0.", 2);
    text[2] = '5';
    strcpy(text + n, "e-2");
    compare_with_strtod(text);
    free(text);
}

TEST(random_bit_patterns)
{
    static const char *const formats[] = {"%.17g", "%.16g", "%.15g", "%.25e", "%.40e"};
    char text[128];
    int before = test_failures;
    for (int i = 0; i < RANDOM_BIT_PATTERNS && test_failures - before < 10; i++) {
        double d = double_from_bits(next_random());
        if (isnan(d))
            continue;
        for (size_t f = 0; f < sizeof formats / sizeof formats[0]; f++) {
            if (f >= 3 && i % 8 != 0)
                continue; /* the long forms are slower: sample them */
            snprintf(text, sizeof text, formats[f], d);
            quick_compare(text);
        }
    }
}

/* A random decimal: 1..40 digits, a point somewhere, exponent -400..400, a sign. */
static void random_digit_string(char *text)
{
    int digits = 1 + (int)(next_random() % 40);
    int point = (int)(next_random() % (uint64_t)(digits + 1));
    char *p = text;
    if (next_random() & 1)
        *p++ = '-';
    for (int i = 0; i < digits; i++) {
        if (i == point)
            *p++ = '.';
        /* Bias towards runs of 0 and 9, which sit near powers of ten and midpoints. */
        uint64_t r = next_random() % 16;
        *p++ = (char)('0' + (r < 3 ? 0 : r < 6 ? 9 : (int)(r % 10)));
    }
    sprintf(p, "e%d", (int)(next_random() % 801) - 400);
}

TEST(random_digit_strings)
{
    char text[128];
    int before = test_failures;
    for (int i = 0; i < RANDOM_DIGIT_STRINGS && test_failures - before < 10; i++) {
        random_digit_string(text);
        quick_compare(text);
    }
}

/* Numbers as mesh files write them, for the one-pass path (scan_short): 1 to 21
 * significant digits (over 19 goes to the general scanner), leading zeros, a point
 * anywhere or none, trailing zeros, and often an exponent near the edges of the 64- and
 * 128-bit paths (-21 and 38 after the point's shift). */
static void random_short_number(char *text)
{
    int digits = 1 + (int)(next_random() % 21);
    int leading = (int)(next_random() % 4), trailing = (int)(next_random() % 3);
    int total = leading + digits + trailing;
    int point = (int)(next_random() % (uint64_t)(total + 2)) - 1; /* -1: no point */
    char *p = text;
    if (next_random() % 3 == 0)
        *p++ = next_random() & 1 ? '-' : '+';
    for (int i = 0; i < total; i++) {
        if (i == point)
            *p++ = '.';
        if (i < leading || i >= leading + digits)
            *p++ = '0';
        else
            *p++ = (char)('0' + (i == leading ? 1 + next_random() % 9 : next_random() % 10));
    }
    if (point == total)
        *p++ = '.';
    if (next_random() & 1)
        sprintf(p, "e%d", (int)(next_random() % 81) - 40);
    else
        *p = '\0';
}

TEST(short_numbers)
{
    char text[128];
    int before = test_failures;
    for (int i = 0; i < SHORT_NUMBERS && test_failures - before < 10; i++) {
        random_short_number(text);
        quick_compare(text);
    }
}

/* The exact value of a finite positive double as an integer multiple of 2^-1074. */
static void units_of(mpz_t out, double d)
{
    uint64_t bits = bits_of(d);
    uint64_t exponent = (bits >> 52) & 0x7ff, fraction = bits & ((1ull << 52) - 1);
    mpz_set_ui(out, (unsigned long)fraction);
    if (exponent) {
        mpz_setbit(out, 52);
        mpz_mul_2exp(out, out, (mp_bitcnt_t)(exponent - 1));
    }
}

/* Decimal text of x * 2^-1075 (exact), with trailing zeros removed if `trim`, then
 * `suffix` digits appended. Returns a malloc'd string. */
static char *exact_decimal(const mpz_t x, bool trim, const char *suffix)
{
    mpz_t scaled;
    char *digits, *text;
    long exponent = -1075;
    size_t len;
    mpz_init(scaled);
    mpz_ui_pow_ui(scaled, 5, 1075);
    mpz_mul(scaled, scaled, x);
    digits = mpz_get_str(NULL, 10, scaled);
    len = strlen(digits);
    while (trim && len > 1 && digits[len - 1] == '0') {
        digits[--len] = '\0';
        exponent++;
    }
    text = malloc(len + strlen(suffix) + 32);
    sprintf(text, "%s%se%ld", digits, suffix, exponent - (long)strlen(suffix));
    free(digits);
    mpz_clear(scaled);
    return text;
}

/* Check the midpoint between d and its upper neighbour (units `lo` and `hi`), and that
 * midpoint plus or minus a tiny amount. */
static void check_midpoint(const mpz_t lo, const mpz_t hi)
{
    static const char *const suffixes[] = {"", "1", "0000000000000000000000001"};
    mpz_t mid, below;
    char *text;
    mpz_inits(mid, below, NULL);
    mpz_add(mid, lo, hi); /* (lo + hi) * 2^-1075 */
    for (size_t s = 0; s < 3; s++) {
        text = exact_decimal(mid, s != 2, suffixes[s]);
        compare_with_strtod(text);
        free(text);
    }
    /* 10 * mid - 1, read with one more decimal place: the midpoint minus 2^-1075 / 10. */
    mpz_mul_ui(below, mid, 10);
    mpz_sub_ui(below, below, 1);
    text = exact_decimal(below, true, "");
    sprintf(strrchr(text, 'e'), "e%ld", strtol(strrchr(text, 'e') + 1, NULL, 10) - 1);
    compare_with_strtod(text);
    free(text);
    mpz_clears(mid, below, NULL);
}

TEST(halfway_cases)
{
    mpz_t lo, hi;
    int before = test_failures;
    mpz_inits(lo, hi, NULL);
    for (int i = 0; i < HALFWAY_CASES && test_failures - before < 10; i++) {
        uint64_t bits = next_random() & ~(1ull << 63);
        double d = double_from_bits(bits);
        if (i % 4 == 0)
            d = double_from_bits(bits & ((1ull << 52) - 1)); /* subnormal */
        if (!isfinite(d) || d == DBL_MAX)
            continue;
        units_of(lo, d);
        units_of(hi, nextafter(d, INFINITY));
        check_midpoint(lo, hi);
    }
    /* Around zero, the smallest subnormal and DBL_MAX (whose upper "neighbour" is
     * 2^1024: the midpoint must round to infinity, anything below it to DBL_MAX). */
    mpz_set_ui(lo, 0);
    mpz_set_ui(hi, 1);
    check_midpoint(lo, hi);
    units_of(lo, DBL_MAX);
    mpz_set_ui(hi, 0);
    mpz_setbit(hi, 1024 + 1074);
    check_midpoint(lo, hi);
    mpz_clears(lo, hi, NULL);
}

TEST(special_values)
{
    double v = 0;
    const char *next = NULL;
    CHECK(parse_prefix("4.9406564584124654e-324", 23, &v, &next) && v == ldexp(1.0, -1074));
    compare_with_strtod("1.7976931348623158079372897140530341507993413271003782693617377898"
                        "044496829276475094664736817664e308"); /* just below the threshold */
    compare_with_strtod("179769313486231580793728971405303415079934132710037826936173778980"
                        "44496829276475094664736817664.0000000001e279");
}

static bool shortest_is_right(double d, const char *out)
{
    char text[64];
    for (int precision = 15; precision <= 17; precision++) {
        snprintf(text, sizeof text, "%.*g", precision, d);
        if (strtod(text, NULL) == d || precision == 17)
            return strcmp(text, out) == 0;
    }
    return false;
}

/* The one-product path for up to 19 digits times 10^-1 .. 10^-21 (times_inverse_five)
 * must give up exactly where its product cannot decide: at values half way between two
 * doubles, (2 j + 1) 2^-(s + 1) written as (2 j + 1) 5^s 10^-s with a 53-bit j, and at
 * their decimal neighbours; and 17-digit fractions like a mesh file's. */
TEST(halfway_fractions)
{
    char text[64];
    int before = test_failures;
    for (int i = 0; i < 100000 && test_failures - before < 10; i++) {
        uint64_t j = (next_random() >> 11) | (UINT64_C(1) << 52), v = 2 * j + 1;
        int s = 1 + (int)(next_random() % 2); /* 5^s v stays below 2^64 */
        for (int k = 0; k < s; k++)
            v *= 5;
        for (int d = -1; d <= 1; d++) {
            snprintf(text, sizeof text, "%llue-%d", (unsigned long long)(v + (uint64_t)d), s);
            quick_compare(text);
        }
        snprintf(text, sizeof text, "%d.%016llu", (int)(next_random() % 10),
                 (unsigned long long)(next_random() % UINT64_C(10000000000000000)));
        quick_compare(text);
    }
}

TEST(format_round_trip)
{
    char out[MCI_DOUBLE_TEXT_MAX];
    int before = test_failures;
    static const double fixed[] = {0.0, -0.0, 0.1, 1e-300, 3.4e38, DBL_MAX, DBL_MIN, 1e22,
                                   4.9406564584124654e-324, -1.5, 123456789.0, 1.0 / 3};
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++) {
        mci_format_double(out, fixed[i]);
        CHECK_MSG(shortest_is_right(fixed[i], out), "%a formatted as %s", fixed[i], out);
    }
    for (int i = 0; i < RANDOM_BIT_PATTERNS / 4 && test_failures - before < 10; i++) {
        double d = double_from_bits(next_random()), back = 0;
        const char *next;
        size_t len;
        if (isnan(d))
            continue;
        len = mci_format_double(out, d);
        CHECK_MSG(len == strlen(out) && len < MCI_DOUBLE_TEXT_MAX, "length of %s", out);
        CHECK_MSG(mci_parse_double(out, out + len, &back, &next) && test_same_double(back, d) &&
                      next == out + len,
                  "%a -> %s -> %a", d, out, back);
        CHECK_MSG(isinf(d) || shortest_is_right(d, out), "%a formatted as %s", d, out);
    }
    CHECK(mci_format_double(out, INFINITY) == 3 && strcmp(out, "inf") == 0);
    CHECK(mci_format_double(out, -INFINITY) == 4 && strcmp(out, "-inf") == 0);
    CHECK(mci_format_double(out, NAN) == 3 && strcmp(out, "nan") == 0);
}

/* Input coordinates are short decimals: the formatter's printf-free path for them must
 * give printf's text, at every digit count and scale, near the fixed-notation limits
 * (1e-4, 1e15) and where 15 digits do not suffice. */
TEST(format_short_decimals)
{
    char out[MCI_DOUBLE_TEXT_MAX], text[64];
    int before = test_failures;
    static const double edges[] = {1e-4, 1e15, 999999999999999.0, 999999999999999.875,
                                   0.000099999999999999, 0.000100000000000001,
                                   123456789012345.6, 0.30000000000000004, 1e-5, 5e-324};
    for (size_t i = 0; i < sizeof edges / sizeof edges[0]; i++) {
        for (int sign = -1; sign <= 1; sign += 2) {
            mci_format_double(out, sign * edges[i]);
            CHECK_MSG(shortest_is_right(sign * edges[i], out), "%a formatted as %s",
                      sign * edges[i], out);
        }
    }
    for (int i = 0; i < 200000 && test_failures - before < 10; i++) {
        int digits = 1 + (int)(next_random() % 17), exponent = (int)(next_random() % 40) - 22;
        uint64_t scale = 1, mantissa;
        double d;
        for (int k = 0; k < digits; k++)
            scale *= 10;
        mantissa = next_random() % scale;
        snprintf(text, sizeof text, "%s%llue%d", next_random() % 2 ? "-" : "",
                 (unsigned long long)mantissa, exponent);
        d = strtod(text, NULL);
        mci_format_double(out, d);
        CHECK_MSG(shortest_is_right(d, out), "%s = %a formatted as %s", text, d, out);
    }
}

/* Computed coordinates need 16 or 17 digits, which the formatter derives exactly
 * without printf for decimal exponents in about [-16, 16]: random doubles there, and the
 * neighbours of powers of ten (where the exponent estimate and rounding can be one off),
 * must give printf's text. */
TEST(format_typical_range)
{
    char out[MCI_DOUBLE_TEXT_MAX];
    int before = test_failures;
    for (int i = 0; i < 300000 && test_failures - before < 10; i++) {
        double d = ldexp(1.0 + (double)(next_random() >> 12) * 0x1p-52,
                         (int)(next_random() % 140) - 70);
        d = next_random() % 2 ? -d : d;
        mci_format_double(out, d);
        CHECK_MSG(shortest_is_right(d, out), "%a formatted as %s", d, out);
    }
    /* Powers of two, all of them: the gap to the next double down is half the gap up,
     * which the exact read-back test must take into account; and 16 digits failing does
     * not mean 15 fail there (2^149 reads back from 15 digits, not from 16: an earlier
     * formatter wrote 17 for it and seven other powers). */
    for (int k = -1074; k <= 1023; k++) {
        double p = ldexp(1.0, k), near[3] = {p, nextafter(p, 0), nextafter(p, INFINITY)};
        for (int j = 0; j < 3; j++) {
            mci_format_double(out, near[j]);
            CHECK_MSG(shortest_is_right(near[j], out), "%a formatted as %s", near[j], out);
        }
    }
    for (int k = -25; k <= 25; k++) {
        double p = pow(10, k), near[5] = {p, nextafter(p, 0), nextafter(p, INFINITY),
                                          nextafter(nextafter(p, 0), 0),
                                          nextafter(nextafter(p, INFINITY), INFINITY)};
        for (int j = 0; j < 5; j++) {
            mci_format_double(out, near[j]);
            CHECK_MSG(shortest_is_right(near[j], out), "%a formatted as %s", near[j], out);
        }
    }
}

/* The formatter decides whether 15 or 16 digits read back from one 18-digit product and
 * a bound on the half gap, and defers to the exact test within a unit of it: the doubles
 * next to a short decimal sit on both sides of that boundary; integers exercise the
 * digit blocks (eight digits at a time by fixed-point multiplication) at every length. */
TEST(format_read_back_boundaries)
{
    char out[MCI_DOUBLE_TEXT_MAX], text[64];
    int before = test_failures;
    for (int i = 0; i < 100000 && test_failures - before < 10; i++) {
        int digits = 15 + (int)(next_random() % 2), exponent = (int)(next_random() % 34) - 17;
        uint64_t low = digits == 15 ? UINT64_C(100000000000000) : UINT64_C(1000000000000000);
        double d, near;
        snprintf(text, sizeof text, "%llue%d",
                 (unsigned long long)(low + next_random() % (9 * low)), exponent - digits + 1);
        d = strtod(text, NULL);
        near = d;
        for (int step = 0; step < 3; step++, near = nextafter(near, 0)) {
            mci_format_double(out, near);
            CHECK_MSG(shortest_is_right(near, out), "%a formatted as %s", near, out);
        }
        near = nextafter(d, INFINITY);
        for (int step = 0; step < 2; step++, near = nextafter(near, INFINITY)) {
            mci_format_double(out, near);
            CHECK_MSG(shortest_is_right(near, out), "%a formatted as %s", near, out);
        }
    }
    for (int i = 0; i < 200000 && test_failures - before < 10; i++) {
        uint64_t n = next_random() % (UINT64_C(1) << (1 + next_random() % 53));
        mci_format_double(out, (double)n);
        snprintf(text, sizeof text, "%llu", (unsigned long long)n);
        CHECK_MSG((n >= UINT64_C(1000000000000000) && shortest_is_right((double)n, out)) ||
                      strcmp(out, text) == 0,
                  "%llu formatted as %s", (unsigned long long)n, out);
    }
}

int main(void)
{
    RUN(fixed_strings);
    RUN(end_bound_is_respected);
    RUN(long_mantissas);
    RUN(special_values);
    RUN(random_bit_patterns);
    RUN(random_digit_strings);
    RUN(short_numbers);
    RUN(halfway_cases);
    RUN(halfway_fractions);
    RUN(format_round_trip);
    RUN(format_short_decimals);
    RUN(format_typical_range);
    RUN(format_read_back_boundaries);
    return test_summary();
}

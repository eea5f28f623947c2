/*
 * Exact, locale-independent conversion between decimal text and doubles.
 *
 * Parsing follows the decimal floating-point syntax of C11 7.22.1.3 (strtod) without hex
 * floats, and rounds correctly (IEEE 754 round-to-nearest-even) by three exact paths:
 *
 *  1. Clinger's fast path: at most 15-16 digits (mantissa < 2^53) and |exponent| <= 22,
 *     where one IEEE multiply or divide of two exact doubles rounds once, correctly.
 *  2. A 128-bit integer path for up to 19 significant digits: the value is an exact
 *     integer product m * 10^e, or the quotient (m * 2^s) / 10^k with a sticky bit for
 *     the remainder, rounded to 53 bits by round_to_double. Numbers for these two paths
 *     are read in one pass (scan_short), the others through the digit array below.
 *  3. A GMP mpn path for everything else, on fixed-size stack arrays so that it never
 *     allocates (mpn functions leave memory management to the caller). Only the first
 *     MAX_SIG_DIGITS digits are kept, plus a sticky digit: a double or a midpoint
 *     between two doubles has at most 767 significant digits, so digits beyond 800 can
 *     only tell "a little above" from "exactly", which the sticky digit preserves.
 *
 * Formatting writes the text printf's %.15g, %.16g or %.17g would (17 digits always
 * round-trip), the first that parses back to the same double, with '.' whatever the
 * locale. printf itself is the fallback only: the 15, 16 or 17 digits come from an exact
 * 128-bit product m 5^k 2^j, correctly rounded, and whether they read back is decided from
 * the same product and a bound on the gap between doubles, or on exact integers where the
 * bound cannot tell (printf's multi-precision path cost thousands of instructions per
 * number, most of the time of writing a mesh). Digits are written eight at a time by
 * fixed-point multiplication, without divisions.
 */
#include "base/numparse.h"

#include <float.h>
#include <gmp.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#if GMP_NAIL_BITS != 0
#error "numparse.c assumes GMP limbs without nail bits"
#endif

__extension__ typedef unsigned __int128 u128;

/* Significant digits kept for the exact path (see the file comment). */
#define MAX_SIG_DIGITS 800
/* Explicit exponents saturate here: far beyond any double, far from int64 overflow. */
#define EXPONENT_CAP 100000000
/* Decimal digits that fit one limb as a power of ten, for building big integers. */
#if GMP_NUMB_BITS >= 64
#define LIMB_DIGITS 19
#else
#define LIMB_DIGITS 9
#endif
/* A big integer holds at most D * 2^s with D < 10^801 and 2^s <= 2^66 * 10^1125 (see
 * parse_big_fraction), i.e. below 2^3805 bits; round up generously. */
#define BIG_BITS 3900
#define BIG_LIMBS (BIG_BITS / GMP_NUMB_BITS + 2)

/* The decimal value digits[0..count) * 10^exp10, digits being values 0..9 without
 * leading or trailing zeros (count == 0 means zero). */
typedef struct decimal {
    unsigned char digits[MAX_SIG_DIGITS + 1];
    size_t count;
    int64_t exp10;
} decimal;

typedef struct bignum {
    mp_limb_t limb[BIG_LIMBS];
    mp_size_t size; /* limbs in use; the top one is non-zero unless size == 0 */
} bignum;

static const double exact_pow10[23] = {
    1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
};

static bool is_digit(char c) { return c >= '0' && c <= '9'; }

static char lower(char c) { return (c >= 'A' && c <= 'Z') ? (char)(c - 'A' + 'a') : c; }

/* Case-insensitive match of the lower-case word at s, bounded by end. */
static bool match_word(const char *s, const char *end, const char *word)
{
    size_t n = strlen(word);
    if ((size_t)(end - s) < n)
        return false;
    for (size_t i = 0; i < n; i++)
        if (lower(s[i]) != word[i])
            return false;
    return true;
}

/* The number of bits of x (0 for 0), from the exponent of x converted to double: the
 * conversion can round up to the next power of two, which one shift corrects. */
static int bit_length64(uint64_t x)
{
    double d = (double)x;
    uint64_t bits;
    int n;
    if (x == 0)
        return 0;
    memcpy(&bits, &d, sizeof bits);
    n = (int)((bits >> 52) & 0x7ff) - 1022; /* 2^(n-1) <= d < 2^n */
    if (n > 64)
        n = 64;
    return (x >> (n - 1)) ? n : n - 1;
}

static int bit_length128(u128 x)
{
    uint64_t hi = (uint64_t)(x >> 64);
    return hi ? 64 + bit_length64(hi) : bit_length64((uint64_t)x);
}

static const uint64_t pow10_u64[20] = {
    1ull, 10ull, 100ull, 1000ull, 10000ull, 100000ull, 1000000ull, 10000000ull,
    100000000ull, 1000000000ull, 10000000000ull, 100000000000ull, 1000000000000ull,
    10000000000000ull, 100000000000000ull, 1000000000000000ull, 10000000000000000ull,
    100000000000000000ull, 1000000000000000000ull, 10000000000000000000ull,
};

/* 10^k for 0 <= k <= 38 (10^38 < 2^128). */
static u128 pow10_u128(int k)
{
    return k <= 19 ? (u128)pow10_u64[k] : (u128)pow10_u64[19] * pow10_u64[k - 19];
}

/* ---------------------------------------------------------------------------------- */
/* Rounding an exact binary value to a double                                          */

/* Round (top + epsilon) * 2^e2 to the nearest double, ties to even, where top has its
 * bit 63 set and `sticky` says whether epsilon (below one unit of top) is non-zero.
 * Handles subnormals (fewer mantissa bits kept) and overflow to infinity. */
static double round_to_double(uint64_t top, int64_t e2, bool sticky)
{
    int64_t leading = e2 + 63; /* binary exponent of the leading bit */
    int64_t drop = 11;         /* 64 - 53 bits dropped for a normal double */
    u128 kept, rest, half;
    /* Normal, below overflow, and 2^(e2 + 11) itself normal: in 64 bits. */
    if (leading >= -1022 + 52 && leading < 1023) {
        uint64_t k = top >> 11, r = top & 0x7FF, bits = (uint64_t)(e2 + 11 + 1023) << 52;
        double scale;
        k += r > 0x400 || (r == 0x400 && (sticky || (k & 1)));
        memcpy(&scale, &bits, sizeof scale); /* 2^(e2 + 11): k <= 2^53, so exact */
        return (double)k * scale;
    }
    if (leading > 1023)
        return INFINITY;
    if (leading < -1022)
        drop += -1022 - leading; /* subnormal: fewer bits above 2^-1074 */
    if (drop > 64)
        return 0.0; /* below half of the smallest subnormal */
    kept = (u128)top >> drop;
    rest = (u128)top & ((((u128)1) << drop) - 1);
    half = ((u128)1) << (drop - 1);
    if (rest > half || (rest == half && (sticky || (kept & 1))))
        kept++;
    /* kept <= 2^53 is exact as a double, and so is the scaled result unless it
     * overflows, where the product (or ldexp) gives the correctly rounded infinity. A
     * power of two in the normal range is built from its bits (ldexp is a library call). */
    if (e2 + drop >= -1022 && e2 + drop <= 1023) {
        uint64_t bits = (uint64_t)(e2 + drop + 1023) << 52;
        double scale;
        memcpy(&scale, &bits, sizeof scale);
        return (double)(uint64_t)kept * scale;
    }
    return ldexp((double)(uint64_t)kept, (int)(e2 + drop));
}

/* Round (x + epsilon) * 2^e2, x != 0, with the same meaning of sticky. */
static double round_u128(u128 x, int64_t e2, bool sticky)
{
    int bits = bit_length128(x);
    if (bits > 64) {
        int shift = bits - 64;
        sticky = sticky || (x & ((((u128)1) << shift) - 1)) != 0;
        return round_to_double((uint64_t)(x >> shift), e2 + shift, sticky);
    }
    return round_to_double((uint64_t)x << (64 - bits), e2 - (64 - bits), sticky);
}

/* ---------------------------------------------------------------------------------- */
/* Big integers on the stack (GMP mpn)                                                 */

static int64_t big_bit_length(const bignum *x)
{
    if (x->size == 0)
        return 0;
    return (int64_t)(x->size - 1) * GMP_NUMB_BITS +
           bit_length64((uint64_t)x->limb[x->size - 1]);
}

/* x = x * mul + add, with mul, add < 2^GMP_NUMB_BITS. The caller guarantees room. */
static void big_mul_add(bignum *x, mp_limb_t mul, mp_limb_t add)
{
    mp_limb_t carry;
    if (x->size == 0) {
        x->limb[0] = add;
        x->size = add != 0;
        return;
    }
    carry = mpn_mul_1(x->limb, x->limb, x->size, mul);
    carry += mpn_add_1(x->limb, x->limb, x->size, add); /* cannot overflow the limb */
    if (carry)
        x->limb[x->size++] = carry;
}

/* 10^k for 0 <= k <= LIMB_DIGITS. */
static mp_limb_t limb_pow10(int k) { return (mp_limb_t)pow10_u64[k]; }

/* x = x * 10^k. */
static void big_mul_pow10(bignum *x, int64_t k)
{
    for (; k >= LIMB_DIGITS; k -= LIMB_DIGITS)
        big_mul_add(x, limb_pow10(LIMB_DIGITS), 0);
    if (k > 0)
        big_mul_add(x, limb_pow10((int)k), 0);
}

static void big_from_digits(bignum *x, const decimal *d)
{
    x->size = 0;
    for (size_t i = 0; i < d->count; i += LIMB_DIGITS) {
        size_t n = d->count - i < LIMB_DIGITS ? d->count - i : LIMB_DIGITS;
        mp_limb_t chunk = 0;
        for (size_t j = 0; j < n; j++)
            chunk = chunk * 10 + d->digits[i + j];
        big_mul_add(x, limb_pow10((int)n), chunk);
    }
}

/* x = x * 2^s. */
static void big_shift_left(bignum *x, int64_t s)
{
    mp_size_t limbs = (mp_size_t)(s / GMP_NUMB_BITS);
    unsigned bits = (unsigned)(s % GMP_NUMB_BITS);
    mp_limb_t carry = 0;
    if (x->size == 0)
        return;
    if (bits)
        carry = mpn_lshift(x->limb, x->limb, x->size, bits);
    if (carry)
        x->limb[x->size++] = carry;
    if (limbs) {
        memmove(x->limb + limbs, x->limb, (size_t)x->size * sizeof(mp_limb_t));
        memset(x->limb, 0, (size_t)limbs * sizeof(mp_limb_t));
        x->size += limbs;
    }
}

/* Round (x + sticky epsilon) * 2^e2 to a double, x != 0. */
static double round_big(const bignum *x, int64_t e2, bool sticky)
{
    int64_t bits = big_bit_length(x);
    u128 acc = 0;
    int64_t acc_bits = 0;
    mp_size_t i = x->size;
    /* Gather limbs from the top until they hold at least 64 significant bits. */
    while (i > 0 && acc_bits < 64) {
        i--;
        acc = (acc << GMP_NUMB_BITS) | x->limb[i];
        acc_bits = bits - (int64_t)i * GMP_NUMB_BITS;
    }
    if (i > 0 && !mpn_zero_p(x->limb, i))
        sticky = true;
    return round_u128(acc, e2 + (int64_t)i * GMP_NUMB_BITS, sticky);
}

/* d * 10^exp10 with exp10 >= 0: an exact integer. */
static double parse_big_integer(const decimal *d)
{
    bignum x;
    big_from_digits(&x, d);
    big_mul_pow10(&x, d->exp10);
    return round_big(&x, 0, false);
}

/* d / 10^k with k = -exp10 > 0: scale d by 2^s so that the quotient has at least 66
 * bits (53 + round bit + margin), divide exactly and keep the remainder as sticky. */
static double parse_big_fraction(const decimal *d)
{
    bignum num, den, quot, rem;
    int64_t shift;
    den.limb[0] = 1;
    den.size = 1;
    big_mul_pow10(&den, -d->exp10);
    big_from_digits(&num, d);
    shift = big_bit_length(&den) + 66 - big_bit_length(&num);
    if (shift < 0)
        shift = 0;
    big_shift_left(&num, shift);
    mpn_tdiv_qr(quot.limb, rem.limb, 0, num.limb, num.size, den.limb, den.size);
    quot.size = num.size - den.size + 1;
    while (quot.size > 0 && quot.limb[quot.size - 1] == 0)
        quot.size--;
    return round_big(&quot, -shift, !mpn_zero_p(rem.limb, den.size));
}

/* ---------------------------------------------------------------------------------- */
/* Choosing the path                                                                   */

/* m * 10^e, m != 0, by paths 1 and 2 of the file comment; false when neither applies
 * (the exponent is out of their range). */
/* floor(2^b / 5^k) for k = 1 .. 21, each in [2^127, 2^128) (b = 127 + the bit length of
 * 5^k), as high and low words: m 10^-k = m 5^-k 2^-k is then a 192-bit product. */
static const struct {
    uint64_t hi, lo;
    int b;
} inverse_five[22] = {
    {0, 0, 0}, /* k = 0 is not used */
    {UINT64_C(0xcccccccccccccccc), UINT64_C(0xcccccccccccccccc), 130}, /* 5^-1 */
    {UINT64_C(0xa3d70a3d70a3d70a), UINT64_C(0x3d70a3d70a3d70a3), 132}, /* 5^-2 */
    {UINT64_C(0x83126e978d4fdf3b), UINT64_C(0x645a1cac083126e9), 134}, /* 5^-3 */
    {UINT64_C(0xd1b71758e219652b), UINT64_C(0xd3c36113404ea4a8), 137}, /* 5^-4 */
    {UINT64_C(0xa7c5ac471b478423), UINT64_C(0x0fcf80dc33721d53), 139}, /* 5^-5 */
    {UINT64_C(0x8637bd05af6c69b5), UINT64_C(0xa63f9a49c2c1b10f), 141}, /* 5^-6 */
    {UINT64_C(0xd6bf94d5e57a42bc), UINT64_C(0x3d32907604691b4c), 144}, /* 5^-7 */
    {UINT64_C(0xabcc77118461cefc), UINT64_C(0xfdc20d2b36ba7c3d), 146}, /* 5^-8 */
    {UINT64_C(0x89705f4136b4a597), UINT64_C(0x31680a88f8953030), 148}, /* 5^-9 */
    {UINT64_C(0xdbe6fecebdedd5be), UINT64_C(0xb573440e5a884d1b), 151}, /* 5^-10 */
    {UINT64_C(0xafebff0bcb24aafe), UINT64_C(0xf78f69a51539d748), 153}, /* 5^-11 */
    {UINT64_C(0x8cbccc096f5088cb), UINT64_C(0xf93f87b7442e45d3), 155}, /* 5^-12 */
    {UINT64_C(0xe12e13424bb40e13), UINT64_C(0x2865a5f206b06fb9), 158}, /* 5^-13 */
    {UINT64_C(0xb424dc35095cd80f), UINT64_C(0x538484c19ef38c94), 160}, /* 5^-14 */
    {UINT64_C(0x901d7cf73ab0acd9), UINT64_C(0x0f9d37014bf60a10), 162}, /* 5^-15 */
    {UINT64_C(0xe69594bec44de15b), UINT64_C(0x4c2ebe687989a9b3), 165}, /* 5^-16 */
    {UINT64_C(0xb877aa3236a4b449), UINT64_C(0x09befeb9fad487c2), 167}, /* 5^-17 */
    {UINT64_C(0x9392ee8e921d5d07), UINT64_C(0x3aff322e62439fcf), 169}, /* 5^-18 */
    {UINT64_C(0xec1e4a7db69561a5), UINT64_C(0x2b31e9e3d06c32e5), 172}, /* 5^-19 */
    {UINT64_C(0xbce5086492111aea), UINT64_C(0x88f4bb1ca6bcf584), 174}, /* 5^-20 */
    {UINT64_C(0x971da05074da7bee), UINT64_C(0xd3f6fc16ebca5e03), 176}, /* 5^-21 */
};

/* m 10^-k correctly rounded, for m != 0 and 1 <= k <= 21, by one 64 x 128-bit product
 * with the truncated 5^-k above (Eisel and Lemire's method). The product P is below the
 * exact m 2^b / 5^k by less than m < 2^64, so its top word is exact unless the middle
 * word is all ones (then a carry may reach it), and the bits below the top word can only
 * be larger than they look: they decide the rounding unless the kept bits end exactly
 * half way with nothing visible below. False in those two rare cases (the caller then
 * divides exactly). */
static bool times_inverse_five(uint64_t m, int k, double *out)
{
    int lz = 64 - bit_length64(m);
    uint64_t w = m << lz, top, middle, low;
    u128 high = (u128)w * inverse_five[k].hi, lower = (u128)w * inverse_five[k].lo;
    int64_t e2 = 128 - lz - inverse_five[k].b - k;
    low = (uint64_t)lower;
    high += lower >> 64; /* < 2^128: w * hi <= (2^64 - 1)^2 */
    top = (uint64_t)(high >> 64);
    middle = (uint64_t)high;
    if (!(top >> 63)) { /* the product has 191 bits: move one up */
        if ((middle | (UINT64_C(1) << 63)) == UINT64_MAX)
            return false;
        top = top << 1 | middle >> 63;
        middle = middle << 1 | low >> 63;
        low <<= 1;
        e2--;
    } else if (middle == UINT64_MAX) {
        return false;
    }
    if ((top & 0x7FF) == 0x400 && (middle | low) == 0)
        return false;
    *out = round_to_double(top, e2, (middle | low) != 0);
    return true;
}

static bool small_to_double(uint64_t m, int64_t e, double *out)
{
#if FLT_EVAL_METHOD == 0 /* one rounding per operation (not x87 extended precision) */
    if (m < ((uint64_t)1 << 53) && e >= -22 && e <= 22) {
        *out = e >= 0 ? (double)m * exact_pow10[e] : (double)m / exact_pow10[-e];
        return true;
    }
#endif
    if (e >= 0 && e <= 38) {
        u128 p = pow10_u128((int)e);
        if ((u128)m <= ~(u128)0 / p) {
            *out = round_u128((u128)m * p, 0, false);
            return true;
        }
    }
    if (e < 0 && e >= -21) {
        if (times_inverse_five(m, (int)-e, out))
            return true;
        /* 10^21 < 2^70 and the numerator has 127 bits: the quotient has >= 57. */
        int shift = 127 - bit_length64(m);
        u128 num = (u128)m << shift, den = pow10_u128((int)-e);
        *out = round_u128(num / den, -shift, num % den != 0);
        return true;
    }
    return false;
}

/* Exact value of d for at most 19 digits. */
static double parse_small(const decimal *d)
{
    uint64_t m = 0;
    double value;
    for (size_t i = 0; i < d->count; i++)
        m = m * 10 + d->digits[i];
    if (small_to_double(m, d->exp10, &value))
        return value;
    return d->exp10 >= 0 ? parse_big_integer(d) : parse_big_fraction(d);
}

static double decimal_to_double(const decimal *d)
{
    int64_t magnitude = (int64_t)d->count + d->exp10; /* value < 10^magnitude */
    if (d->count == 0)
        return 0.0;
    if (magnitude - 1 >= 309) /* value >= 1e309 > DBL_MAX */
        return INFINITY;
    if (magnitude < -324) /* value < 1e-325, below half of 2^-1074 */
        return 0.0;
    if (d->count <= 19)
        return parse_small(d);
    return d->exp10 >= 0 ? parse_big_integer(d) : parse_big_fraction(d);
}

/* ---------------------------------------------------------------------------------- */
/* Scanning the text                                                                   */

/* Append one mantissa digit: leading zeros are dropped, digits beyond MAX_SIG_DIGITS
 * only count (their position raises the exponent) and set *dropped_nonzero. */
static void add_digit(decimal *d, char c, int64_t *dropped, bool *dropped_nonzero)
{
    if (d->count == 0 && c == '0')
        return;
    if (d->count < MAX_SIG_DIGITS) {
        d->digits[d->count++] = (unsigned char)(c - '0');
        return;
    }
    (*dropped)++;
    if (c != '0')
        *dropped_nonzero = true;
}

/* Parse "e[+-]digits" at *p; leave *p alone (exponent 0) if no digit follows. */
static int64_t scan_exponent(const char **p, const char *end)
{
    const char *s = *p;
    bool negative = false;
    int64_t value = 0;
    if (s >= end || (*s != 'e' && *s != 'E'))
        return 0;
    s++;
    if (s < end && (*s == '+' || *s == '-'))
        negative = *s++ == '-';
    if (s >= end || !is_digit(*s))
        return 0;
    for (; s < end && is_digit(*s); s++)
        if (value < EXPONENT_CAP)
            value = value * 10 + (*s - '0');
    *p = s;
    return negative ? -value : value;
}

/* Scan digits, an optional '.', digits and an exponent into *d. Returns the first byte
 * after the number, or NULL when there is no digit at all. */
static const char *scan_decimal(const char *s, const char *end, decimal *d)
{
    int64_t dropped = 0, fraction_digits = 0;
    bool dropped_nonzero = false, any_digit = false;
    d->count = 0;
    for (; s < end && is_digit(*s); s++, any_digit = true)
        add_digit(d, *s, &dropped, &dropped_nonzero);
    if (s < end && *s == '.') {
        for (s++; s < end && is_digit(*s); s++, fraction_digits++, any_digit = true)
            add_digit(d, *s, &dropped, &dropped_nonzero);
    }
    if (!any_digit)
        return NULL;
    d->exp10 = scan_exponent(&s, end) - fraction_digits + dropped;
    while (d->count > 0 && d->digits[d->count - 1] == 0 && !dropped_nonzero) {
        d->count--;
        d->exp10++;
    }
    if (dropped_nonzero) { /* a sticky digit just below the kept ones */
        d->digits[d->count++] = 1;
        d->exp10--;
    }
    return s;
}

/* The n-char-sequence of "nan(...)": digits, letters and '_' (C11 7.22.1.3). */
static bool is_nan_char(char c)
{
    return is_digit(c) || c == '_' || (lower(c) >= 'a' && lower(c) <= 'z');
}

/* "inf", "infinity" or "nan" (optionally "nan(chars)"), case-insensitive. */
static const char *scan_special(const char *s, const char *end, double *value)
{
    if (match_word(s, end, "infinity")) {
        *value = INFINITY;
        return s + 8;
    }
    if (match_word(s, end, "inf")) {
        *value = INFINITY;
        return s + 3;
    }
    if (match_word(s, end, "nan")) {
        const char *p = s + 3;
        *value = NAN;
        if (p < end && *p == '(') {
            const char *q = p + 1;
            while (q < end && is_nan_char(*q))
                q++;
            if (q < end && *q == ')')
                p = q + 1;
        }
        return p;
    }
    return NULL;
}

/* The value of the eight ASCII digits at p, or false (nothing written) when one of them
 * is not a digit: eight at once in a 64-bit word, read in little-endian order whatever
 * the machine's (compilers turn the byte assembly into one load where they can). */
static bool eight_digits(const char *p, uint64_t *out)
{
    const unsigned char *b = (const unsigned char *)p;
    uint64_t x = (uint64_t)b[0] | (uint64_t)b[1] << 8 | (uint64_t)b[2] << 16 |
                 (uint64_t)b[3] << 24 | (uint64_t)b[4] << 32 | (uint64_t)b[5] << 40 |
                 (uint64_t)b[6] << 48 | (uint64_t)b[7] << 56;
    /* every byte in '0'..'9': high nibble 3, and adding 6 keeps the high nibble at 3 */
    if (((x & UINT64_C(0xF0F0F0F0F0F0F0F0)) |
         (((x + UINT64_C(0x0606060606060606)) & UINT64_C(0xF0F0F0F0F0F0F0F0)) >> 4)) !=
        UINT64_C(0x3333333333333333))
        return false;
    x -= UINT64_C(0x3030303030303030);
    x = x * 10 + (x >> 8); /* byte pairs: 10 d0 + d1 in every other byte */
    x = ((x & UINT64_C(0x000000FF000000FF)) * (100 + (UINT64_C(1000000) << 32)) +
         ((x >> 16) & UINT64_C(0x000000FF000000FF)) * (1 + (UINT64_C(10000) << 32))) >> 32;
    *out = (uint32_t)x;
    return true;
}

/* Digits from p on, accumulated into *m (which wraps past 19 digits); returns the end of
 * the run. Eight at a time while they last: mesh files are mostly 17-digit numbers. */
static inline const char *accumulate_digits(const char *p, const char *end, uint64_t *m)
{
    uint64_t eight;
    while (end - p >= 8 && eight_digits(p, &eight)) {
        *m = *m * 100000000 + eight;
        p += 8;
    }
    for (; p < end && is_digit(*p); p++)
        *m = *m * 10 + (uint64_t)(*p - '0');
    return p;
}

/* The common case in one pass: at most 19 significant digits (leading zeros do not
 * count, trailing ones do), accumulated as they are read, and an exponent within the
 * 64- and 128-bit paths. Returns the first byte after the number, or NULL when the
 * general scanner must decide (more digits, no digit, a far exponent). Mesh files are
 * mostly 17-digit numbers: storing each digit and converting afterwards cost hundreds
 * of instructions per number. */
static const char *scan_short(const char *s, const char *end, double *value)
{
    uint64_t m = 0; /* wraps past 19 digits, and is then not used */
    const char *p = s, *first;
    size_t significant, fraction = 0;
    int64_t e;
    while (p < end && *p == '0')
        p++;
    first = p;
    p = accumulate_digits(p, end, &m);
    significant = (size_t)(p - first);
    if (p < end && *p == '.') {
        const char *point = p++;
        if (significant == 0)
            while (p < end && *p == '0')
                p++;
        first = p;
        p = accumulate_digits(p, end, &m);
        significant += (size_t)(p - first);
        fraction = (size_t)(p - point - 1);
        if (p - s == 1)
            return NULL; /* "." alone */
    }
    if (p == s || significant > 19)
        return NULL;
    e = scan_exponent(&p, end) - (int64_t)fraction;
    if (m == 0) {
        *value = 0.0;
        return p;
    }
    return small_to_double(m, e, value) ? p : NULL;
}

bool mci_parse_double(const char *s, const char *end, double *out, const char **next)
{
    bool negative = false;
    const char *after;
    double value = 0.0;
    decimal d;
    if (s < end && (*s == '+' || *s == '-'))
        negative = *s++ == '-';
    if (s < end && (is_digit(*s) || *s == '.')) {
        after = scan_short(s, end, &value);
        if (!after && (after = scan_decimal(s, end, &d)) != NULL)
            value = decimal_to_double(&d);
    } else {
        after = scan_special(s, end, &value);
    }
    if (!after)
        return false;
    *out = negative ? -value : value;
    *next = after;
    return true;
}

/* ---------------------------------------------------------------------------------- */
/* Formatting                                                                          */

/* Replace each run of characters that cannot be part of a C-locale number (the
 * locale's decimal point, possibly multi-byte) with '.'. Returns the new length. */
static size_t normalise_decimal_point(char *text, size_t len)
{
    size_t out = 0;
    for (size_t i = 0; i < len;) {
        char c = text[i];
        if (is_digit(c) || c == 'e' || c == 'E' || c == '+' || c == '-') {
            text[out++] = c;
            i++;
            continue;
        }
        while (i < len && !(is_digit(text[i]) || text[i] == 'e' || text[i] == 'E' ||
                            text[i] == '+' || text[i] == '-'))
            i++;
        text[out++] = '.';
    }
    text[out] = '\0';
    return out;
}

/* |value| = m 2^(e - 53) with m in [2^52, 2^53) (e is frexp's exponent), for a nonzero
 * finite value. Normal values are read from their bits (frexp and ldexp are library
 * calls, and this runs several times for every number written). */
static void split_double(double value, uint64_t *m, int *e)
{
    uint64_t bits;
    int biased;
    memcpy(&bits, &value, sizeof bits);
    biased = (int)((bits >> 52) & 0x7ff);
    if (biased == 0) { /* subnormal: normalise through frexp */
        double fraction = frexp(fabs(value), e);
        *m = (uint64_t)ldexp(fraction, 53);
        return;
    }
    *m = (bits & ((UINT64_C(1) << 52) - 1)) | (UINT64_C(1) << 52);
    *e = biased - 1022;
}

/* |value| 10^scale, for |value| = mantissa 2^(e - 53), as m 2^shift with m = mantissa
 * 5^scale, 0 <= scale <= 32 (so m < 2^53 5^32 < 2^128). */
static u128 times_power_of_five(uint64_t mantissa, int e, int scale, int *shift)
{
    /* 5^k for k < 28 (below 2^64) */
    static const uint64_t five[28] = {
        1u, 5u, 25u, 125u, 625u, 3125u, 15625u, 78125u, 390625u, 1953125u, 9765625u,
        48828125u, 244140625u, 1220703125u, 6103515625u, 30517578125u, 152587890625u,
        762939453125u, 3814697265625u, 19073486328125u, 95367431640625u, 476837158203125u,
        2384185791015625u, 11920928955078125u, 59604644775390625u, 298023223876953125u,
        1490116119384765625u, 7450580596923828125u};
    *shift = e - 53 + scale;
    if (scale < 28)
        return (u128)mantissa * five[scale];
    return (u128)mantissa * (pow10_u128(scale) >> scale); /* 5^scale: 10^scale / 2^scale */
}

/* The same from the double. */
static u128 times_power_of_ten(double value, int scale, int *shift)
{
    int e;
    uint64_t mantissa;
    split_double(value, &mantissa, &e);
    return times_power_of_five(mantissa, e, scale, shift);
}

/* round_half_even(|value| * 10^scale) for 0 <= scale <= 32, exactly: |value| = m 2^e,
 * and m 5^scale < 2^53 * 5^32 < 2^128. Returns false when the product cannot be held. */
static bool scaled_decimal(double value, int scale, u128 *out)
{
    u128 m, q, rest, half;
    int shift;
    if (scale < 0 || scale > 32)
        return false;
    m = times_power_of_ten(value, scale, &shift);
    if (shift >= 0) {
        if (bit_length128(m) + shift > 127)
            return false;
        *out = m << shift;
        return true;
    }
    if (-shift >= 128) {
        *out = 0;
        return true;
    }
    q = m >> -shift;
    rest = m & ((((u128)1) << -shift) - 1);
    half = ((u128)1) << (-shift - 1);
    *out = q + (rest > half || (rest == half && (q & 1)));
    return true;
}

const char mci_digit_pairs[201] = /* "00" "01" ... "99" */
    "00010203040506070809101112131415161718192021222324"
    "25262728293031323334353637383940414243444546474849"
    "50515253545556575859606162636465666768697071727374"
    "75767778798081828384858687888990919293949596979899";

/* The eight decimal digits of x < 10^8, leading zeros kept. t = x 2^57 / 10^6 in fixed
 * point, rounded up: its excess, under 0.15 x units, stays below the 2^57 / 10^6 units
 * between the fractions k / 10^6 that x / 10^6 can have, and both scale alike with every
 * multiplication by 100, so each pair read from the top bits is exact (it was checked
 * for every x; test_numparse compares integers of every length with printf). A pair
 * costs a mask, a multiplication and a shift instead of a 64-bit division. */
static void write_eight(char *out, uint32_t x)
{
    const uint64_t fraction = (UINT64_C(1) << 57) - 1;
    uint64_t t = (uint64_t)x * UINT64_C(144115188076); /* ceil(2^57 / 10^6) */
    memcpy(out, mci_digit_pairs + 2 * (t >> 57), 2);
    t = (t & fraction) * 100;
    memcpy(out + 2, mci_digit_pairs + 2 * (t >> 57), 2);
    t = (t & fraction) * 100;
    memcpy(out + 4, mci_digit_pairs + 2 * (t >> 57), 2);
    t = (t & fraction) * 100;
    memcpy(out + 6, mci_digit_pairs + 2 * (t >> 57), 2);
}

/* Room for the digits of a 64-bit number in blocks of eight, and for copies of a fixed
 * DIGIT_COPY bytes from any digit (the text buffers have room for those too): fixed-size
 * copies are a few moves, variable ones a library call. */
enum { DIGIT_BLOCKS = 24, DIGIT_COPY = 24 };

/* The `count` (1..20) decimal digits of n < 10^count, leading zeros kept: they end at
 * block + DIGIT_BLOCKS, and the start is returned. block has DIGIT_BLOCKS + DIGIT_COPY
 * bytes. */
static const char *write_digits(char block[DIGIT_BLOCKS + DIGIT_COPY], uint64_t n, int count)
{
    uint64_t high = n / 100000000;
    write_eight(block + 16, (uint32_t)(n - high * 100000000));
    if (count > 8) {
        uint64_t top = high / 100000000;
        write_eight(block + 8, (uint32_t)(high - top * 100000000));
        if (count > 16)
            write_eight(block, (uint32_t)top);
    }
    memset(block + DIGIT_BLOCKS, '0', DIGIT_COPY);
    return block + DIGIT_BLOCKS - count;
}

/* Whether the decimal digits * 10^-scale reads back as the nonzero double value
 * (nearest double, ties to even), decided on integers: with |value| = m 2^(e-53),
 * m in [2^52, 2^53), one ulp times 10^scale is 5^scale 2^shift (shift = e - 53 + scale),
 * and everything is scaled by 2^(2 - shift) to stay integral: the value is 4 m 5^scale,
 * the half gap above 2 * 5^scale, below the same or half of it when m = 2^52 (the next
 * double down is in the binade below). A decimal exactly halfway would read back as value
 * when m is even (a midpoint between doubles needs 17 or more significant digits where
 * this test applies, so this stays a statement of the rule). Returns -1 when the
 * integers would not fit (the caller then parses). */
static int reads_back(double value, u128 digits, int scale)
{
    int e, shift;
    uint64_t m;
    u128 five, exact, text_value, diff, gap;
    split_double(value, &m, &e);
    shift = e - 53 + scale;
    if (scale < 0 || scale > 27 || shift > 0 || shift < -60 || e < -1000 ||
        digits >= ((u128)1 << 57))
        return -1;
    five = pow10_u128(scale) >> scale; /* 5^scale < 2^63 */
    exact = (u128)m * five * 4;        /* < 2^118 */
    text_value = digits << (2 - shift); /* < 2^119 */
    if (text_value >= exact) {
        diff = text_value - exact;
        gap = five * 2;
    } else {
        diff = exact - text_value;
        gap = m == ((uint64_t)1 << 52) ? five : five * 2;
    }
    return diff < gap || (diff == gap && m % 2 == 0);
}

/* floor(log10(|value|)) or one less, from the binary exponent alone: |value| is in
 * [2^(e-1), 2^e), and 78913 / 2^18 is log10(2) to 7 digits (floor division by hand: a
 * right shift of a negative number is implementation-defined). */
static int decimal_exponent_from_binary(int e)
{
    long t = (long)(e - 1) * 78913;
    return (int)(t >= 0 ? t / 262144 : -((-t + 262143) / 262144));
}

static int decimal_exponent_estimate(double value)
{
    uint64_t m;
    int e;
    split_double(value, &m, &e);
    return decimal_exponent_from_binary(e);
}

/* The `precision` significant digits of a nonzero finite value, correctly rounded as
 * printf's %.*g gives them, and the decimal exponent of the first: |value| ~ digits *
 * 10^(exponent - precision + 1). False when the value's decimal exponent is outside the
 * range of these integers (then printf is used). */
static bool exact_digits(double value, int precision, u128 *digits_out, int *exponent_out)
{
    int exponent = decimal_exponent_estimate(value), tries = 0;
    u128 digits, low = pow10_u128(precision - 1), high = pow10_u128(precision);
    for (;;) { /* the estimate can be one off (and rounding can carry into a new digit) */
        if (++tries > 4 || !scaled_decimal(value, precision - 1 - exponent, &digits))
            return false;
        if (digits >= high)
            exponent++;
        else if (digits < low)
            exponent--;
        else
            break;
    }
    if (digits == low) { /* 10^(p-1) may be a value just below 10^exponent rounded up */
        u128 below;
        if (!scaled_decimal(value, precision - exponent, &below))
            return false;
        if (below < high) {
            exponent--;
            digits = below;
        }
    }
    *digits_out = digits;
    *exponent_out = exponent;
    return true;
}

/* "e+dd", "e-dd" or with three digits, as printf writes a %g exponent. */
static size_t put_exponent(char *text, int exponent)
{
    int magnitude = exponent < 0 ? -exponent : exponent;
    size_t len = 2;
    text[0] = 'e';
    text[1] = exponent < 0 ? '-' : '+';
    if (magnitude >= 100) {
        text[len++] = (char)('0' + magnitude / 100);
        magnitude %= 100;
    }
    memcpy(text + len, mci_digit_pairs + 2 * magnitude, 2);
    return len + 2;
}

/* printf's "%.*g" text of value from its exact digits (exact_digits). The digits are
 * moved DIGIT_COPY bytes at a time, so up to 42 bytes of text are written (a sign, 16
 * digits and the point before the last copy): text has MCI_DOUBLE_TEXT_MAX. */
static size_t layout_g(char text[MCI_DOUBLE_TEXT_MAX], double value, u128 digits, int precision,
                       int exponent)
{
    /* digits < 10^precision <= 10^17: exactly `precision` digits, no leading zero */
    char block[DIGIT_BLOCKS + DIGIT_COPY];
    const char *d = write_digits(block, (uint64_t)digits, precision);
    int count = precision, point;
    size_t len = 0;
    while (count > 1 && d[count - 1] == '0') /* %g drops trailing zeros */
        count--;
    if (value < 0)
        text[len++] = '-';
    if (exponent < -4 || exponent >= precision) { /* d.ddde+xx */
        text[len++] = d[0];
        if (count > 1) {
            text[len++] = '.';
            memcpy(text + len, d + 1, DIGIT_COPY);
            len += (size_t)count - 1;
        }
        len += put_exponent(text + len, exponent);
    } else if (exponent < 0) { /* 0.000ddd */
        memcpy(text + len, "0.0000", 6);
        len += (size_t)(1 - exponent);
        memcpy(text + len, d, DIGIT_COPY);
        len += (size_t)count;
    } else if (count <= exponent + 1) { /* ddd000: an integer (the block's padding is '0') */
        memcpy(text + len, d, DIGIT_COPY);
        len += (size_t)exponent + 1;
    } else { /* ddd.ddd */
        point = exponent + 1;
        memcpy(text + len, d, DIGIT_COPY);
        text[len + (size_t)point] = '.';
        memcpy(text + len + (size_t)point + 1, d + point, DIGIT_COPY);
        len += (size_t)count + 1;
    }
    text[len] = '\0';
    return len;
}

/* text = value with `precision` significant digits, written only when it reads back as
 * value (17 digits always do, and are not checked); whether it did. */
static bool format_round_trips(double value, int precision, char text[64], size_t *len)
{
    double back;
    const char *next;
    u128 digits;
    int exponent, exact = 1, n;
    if (value != 0 && exact_digits(value, precision, &digits, &exponent)) {
        if (precision < 17 && (exact = reads_back(value, digits, precision - 1 - exponent)) == 0)
            return false;
        *len = layout_g(text, value, digits, precision, exponent);
        return exact == 1 ||
               (mci_parse_double(text, text + *len, &back, &next) && back == value);
    }
    n = snprintf(text, 64, "%.*g", precision, value);
    if (n < 0 || n >= 64) { /* cannot happen for a finite double */
        memcpy(text, "0", 2);
        *len = 1;
        return false;
    }
    /* Only printf's text can hold the locale's decimal point. */
    *len = normalise_decimal_point(text, (size_t)n);
    return precision == 17 ||
           (mci_parse_double(text, text + *len, &back, &next) && back == value);
}

/* floor(|value| * 10^scale) and whether anything was cut off, for 0 <= scale <= 32.
 * False when that does not fit 64 bits. */
static bool scaled_floor(uint64_t mantissa, int e, int scale, uint64_t *floor_out,
                         bool *sticky)
{
    int shift;
    u128 m = times_power_of_five(mantissa, e, scale, &shift);
    if (shift >= 0) {
        if (bit_length128(m) + shift > 63)
            return false;
        *floor_out = (uint64_t)(m << shift);
        *sticky = false;
        return true;
    }
    if (-shift >= 128 || bit_length128(m) + shift > 63)
        return false;
    *floor_out = (uint64_t)(m >> -shift);
    *sticky = (m & ((((u128)1) << -shift) - 1)) != 0;
    return true;
}

/* F = floor(|value| 10^(17 - E)) in [10^17, 10^18), E the decimal exponent of |value|
 * (10^E <= |value| < 10^(E + 1)), and whether the floor cut anything off. False outside
 * E in -15..17 (the caller then takes the general path). */
static bool eighteen_digits(uint64_t m, int e, uint64_t *f, bool *sticky, int *exponent)
{
    int estimate = decimal_exponent_from_binary(e);
    for (*exponent = estimate; *exponent <= estimate + 1; ++*exponent) {
        if (17 - *exponent < 0 || 17 - *exponent > 32 ||
            !scaled_floor(m, e, 17 - *exponent, f, sticky))
            return false;
        if (*f < 100000000000000000u)
            return false; /* the estimate is never one too high: not expected */
        if (*f < 1000000000000000000u)
            return true;
    }
    return false;
}

/* Half the gap between value and its neighbouring doubles in units of 10^(E - 17) (the
 * units of eighteen_digits' F): 2^(e - 54) 10^(17 - E) for |value| = m 2^(e - 53), within
 * a relative 2^-52 (10^k is exact in double up to k = 22, one rounding beyond). */
static double half_gap_in_units(int e, int exponent)
{
    uint64_t bits;
    int scale = 17 - exponent;
    double power_of_two, power_of_ten = scale <= 22 ? exact_pow10[scale]
                                                    : exact_pow10[22] * exact_pow10[scale - 22];
    bits = (uint64_t)(e - 54 + 1023) << 52; /* normal: |value| >= 1e-15 gives e >= -49 */
    memcpy(&power_of_two, &bits, sizeof bits);
    return power_of_two * power_of_ten;
}

/* Whether the decimal `scaled` (units of 10^(E - 17)) reads back as value, from F and its
 * sticky bit alone: the exact |value| 10^(17 - E) is F, or lies strictly between F and
 * F + 1, so the distance to `scaled` is known within one unit, and `half_gap` within a
 * relative 2^-52. 1 or 0 when the bounds decide, -1 when they do not (a distance within
 * about a unit of the half gap: a possible tie, decided exactly by reads_back) and for
 * the binade's lowest mantissa, whose gap below is half the gap above. */
static int reads_back_from_floor(uint64_t scaled, uint64_t f, bool sticky, double half_gap,
                                 uint64_t m)
{
    uint64_t near, far; /* the distance is within [near, far] */
    if (m == (UINT64_C(1) << 52))
        return -1;
    if (scaled > f) {
        far = scaled - f;
        near = sticky ? far - 1 : far;
    } else {
        near = f - scaled;
        far = sticky ? near + 1 : near;
    }
    if ((double)far < half_gap * (1 - 0x1p-40))
        return 1;
    if ((double)near > half_gap * (1 + 0x1p-40))
        return 0;
    return -1;
}

/* mci_format_double's search with the digits of all three precisions from one exact
 * product: p digits are F / 10^(18 - p) rounded half-even on the remainder and the sticky
 * bit (a carry to 10^p moves to the next exponent). False when it cannot decide (the
 * caller then tries each precision on its own). */
static bool format_from_one_product(double value, char text[MCI_DOUBLE_TEXT_MAX], size_t *len)
{
    uint64_t m, f, div = 1000;
    bool sticky;
    int e, exponent;
    double half_gap;
    if (value == 0)
        return false;
    split_double(value, &m, &e);
    if (!eighteen_digits(m, e, &f, &sticky, &exponent))
        return false;
    half_gap = half_gap_in_units(e, exponent);
    for (int p = 15; p <= 17; p++, div /= 10) {
        uint64_t q = f / div, r = f % div, half = div / 2, digits;
        int back, digits_exponent = exponent;
        q += r > half || (r == half && (sticky || (q & 1)));
        digits = q;
        if (q == pow10_u64[p]) {
            digits = q / 10;
            digits_exponent++;
        }
        back = p == 17 ? 1 : reads_back_from_floor(q * div, f, sticky, half_gap, m);
        if (back < 0)
            back = reads_back(value, digits, p - 1 - digits_exponent);
        if (back < 0)
            return false;
        if (back == 1) {
            *len = layout_g(text, value, digits, p, digits_exponent);
            return true;
        }
    }
    return false;
}

size_t mci_format_double(char buf[MCI_DOUBLE_TEXT_MAX], double value)
{
    char text[64] = "0";
    size_t len = 1;
    if (isnan(value) || isinf(value)) {
        const char *word = isnan(value) ? "nan" : value < 0 ? "-inf" : "inf";
        len = strlen(word);
        memcpy(buf, word, len + 1);
        return len;
    }
    if (format_from_one_product(value, buf, &len)) /* laid out in place */
        return len;
    /* The shortest of 15, 16 and 17 significant digits that reads back as value, one
     * precision at a time (the general path: each try costs two 128-bit products). */
    for (int precision = 15; precision <= 17; precision++)
        if (format_round_trips(value, precision, text, &len))
            break;
    memcpy(buf, text, len + 1);
    return len;
}

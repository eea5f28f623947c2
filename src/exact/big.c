/*
 * Fixed-capacity exact integers (big.h): conversion from doubles, the ring operations on
 * GMP's mpn layer, and the correctly rounded quotient of two of them.
 */
#include "exact/big.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

_Static_assert(GMP_NUMB_BITS == 64, "mci_big assumes 64-bit limbs");

/* Index of the lowest set bit of m != 0 (portable: a de Bruijn multiply-and-lookup). */
static int trailing_zeros(uint64_t m)
{
    static const int8_t table[64] = {
        0,  1,  2,  53, 3,  7,  54, 27, 4,  38, 41, 8,  34, 55, 48, 28,
        62, 5,  39, 46, 44, 42, 22, 9,  24, 35, 59, 56, 49, 18, 29, 11,
        63, 52, 6,  26, 37, 40, 33, 47, 61, 45, 43, 21, 23, 58, 17, 10,
        51, 25, 36, 32, 60, 20, 57, 16, 50, 31, 19, 15, 30, 14, 13, 12};
    return table[((m & -m) * 0x022fdd63cc95386dULL) >> 58];
}

/* x = significand * 2^exponent with an odd significand (x finite, nonzero), read from
 * the IEEE 754 fields. */
void mci_split_double(double x, uint64_t *significand, int *exponent)
{
    uint64_t bits, m;
    int biased, tz;
    memcpy(&bits, &x, sizeof bits);
    biased = (int)((bits >> 52) & 0x7ff);
    m = bits & 0xfffffffffffffULL;
    if (biased) {
        m |= 1ULL << 52;
        *exponent = biased - 1075;
    } else {
        *exponent = -1074; /* subnormal */
    }
    tz = trailing_zeros(m);
    *significand = m >> tz;
    *exponent += tz;
}

void mci_bit_range(double x, int *lsb, int *msb)
{
    uint64_t bits, m;
    int biased;
    memcpy(&bits, &x, sizeof bits);
    biased = (int)((bits >> 52) & 0x7ff);
    m = bits & 0xfffffffffffffULL;
    if (biased) {
        m |= 1ULL << 52;
        *msb = biased - 1023;
        *lsb = biased - 1075 + trailing_zeros(m);
        return;
    }
    *lsb = -1074 + trailing_zeros(m); /* subnormal */
    for (*msb = -1074; m > 1; m >>= 1)
        ++*msb;
}

int mci_lsb_exponent(double x)
{
    uint64_t m;
    int e;
    if (x == 0)
        return INT_MAX;
    mci_split_double(x, &m, &e);
    return e;
}

static void big_normalize(mci_big *r, int n, int negative)
{
    while (n > 0 && r->limb[n - 1] == 0)
        n--;
    r->size = negative ? -n : n;
}

static int abs_size(const mci_big *a)
{
    return a->size < 0 ? -a->size : a->size;
}

/* r = limbs[0..n) with the given sign; limbs may live anywhere (a scratch array). */
static void big_assign(mci_big *r, const mp_limb_t *limbs, int n, int negative)
{
    /* Strip high zero limbs first: a product's n = na + nb may exceed the capacity by
     * one even though its value (bounded by the degree analysis in big.h) fits. */
    while (n > 0 && limbs[n - 1] == 0)
        n--;
    memcpy(r->limb, limbs, (size_t)n * sizeof(mp_limb_t));
    r->size = negative ? -n : n;
}

void mci_big_from_double(mci_big *r, double x, int e0)
{
    uint64_t m;
    int e, shift, word, bit;
    if (x == 0) {
        r->size = 0;
        return;
    }
    mci_split_double(x, &m, &e);
    shift = e - e0;
    word = shift / GMP_NUMB_BITS;
    bit = shift % GMP_NUMB_BITS;
    memset(r->limb, 0, (size_t)(word + 2) * sizeof(mp_limb_t));
    r->limb[word] = (mp_limb_t)(m << bit);
    r->limb[word + 1] = bit ? (mp_limb_t)(m >> (GMP_NUMB_BITS - bit)) : 0;
    big_normalize(r, word + 2, x < 0);
}

void mci_big_set_int(mci_big *r, int value)
{
    r->limb[0] = (mp_limb_t)(value < 0 ? -(long)value : value);
    big_normalize(r, 1, value < 0);
}

void mci_big_copy(mci_big *r, const mci_big *a)
{
    if (r != a) {
        memcpy(r->limb, a->limb, (size_t)abs_size(a) * sizeof(mp_limb_t));
        r->size = a->size;
    }
}

void mci_big_neg(mci_big *r, const mci_big *a)
{
    mci_big_copy(r, a);
    r->size = -r->size;
}

int mci_big_sign(const mci_big *a)
{
    return (a->size > 0) - (a->size < 0);
}

void mci_big_shift_left(mci_big *r, const mci_big *a, unsigned bits)
{
    int n = abs_size(a), words = (int)(bits / GMP_NUMB_BITS), negative = a->size < 0;
    unsigned rest = bits % GMP_NUMB_BITS;
    mp_limb_t out[MCI_BIG_LIMBS + 1];
    if (n == 0) {
        r->size = 0;
        return;
    }
    memset(out, 0, (size_t)words * sizeof(mp_limb_t));
    if (rest) {
        out[words + n] = mpn_lshift(out + words, a->limb, n, rest);
    } else {
        memcpy(out + words, a->limb, (size_t)n * sizeof(mp_limb_t));
        out[words + n] = 0;
    }
    big_assign(r, out, words + n + 1, negative);
}

int mci_big_export(const mci_big *a, mp_limb_t *out, int capacity)
{
    int n = abs_size(a);
    if (n > capacity)
        return INT_MIN;
    memcpy(out, a->limb, (size_t)n * sizeof(mp_limb_t));
    return a->size;
}

void mci_big_import(mci_big *r, const mp_limb_t *limbs, int size)
{
    int n = size < 0 ? -size : size;
    memcpy(r->limb, limbs, (size_t)n * sizeof(mp_limb_t));
    r->size = size;
}

/* Compare magnitudes: -1, 0 or +1. */
static int compare_abs(const mci_big *a, const mci_big *b)
{
    int na = abs_size(a), nb = abs_size(b);
    if (na != nb)
        return na < nb ? -1 : 1;
    return mpn_cmp(a->limb, b->limb, na);
}

/* r = a + (negate_b ? -b : b); r may alias a or b. */
static void big_add_signed(mci_big *r, const mci_big *a, const mci_big *b, int negate_b)
{
    int na = abs_size(a), nb = abs_size(b);
    int neg_a = a->size < 0, neg_b = (b->size < 0) != negate_b;
    mp_limb_t sum[MCI_BIG_LIMBS];
    if (nb == 0) {
        mci_big_copy(r, a);
        return;
    }
    if (na == 0) {
        mci_big_copy(r, b);
        r->size = neg_b ? -nb : nb;
        return;
    }
    if (neg_a == neg_b) {
        const mci_big *big = na >= nb ? a : b, *small = na >= nb ? b : a;
        int nbig = na >= nb ? na : nb, nsmall = na >= nb ? nb : na;
        sum[nbig] = mpn_add(sum, big->limb, nbig, small->limb, nsmall);
        big_assign(r, sum, nbig + 1, neg_a);
    } else if (compare_abs(a, b) >= 0) {
        mpn_sub(sum, a->limb, na, b->limb, nb);
        big_assign(r, sum, na, neg_a);
    } else {
        mpn_sub(sum, b->limb, nb, a->limb, na);
        big_assign(r, sum, nb, neg_b);
    }
}

void mci_big_add(mci_big *r, const mci_big *a, const mci_big *b)
{
    big_add_signed(r, a, b, 0);
}

void mci_big_sub(mci_big *r, const mci_big *a, const mci_big *b)
{
    big_add_signed(r, a, b, 1);
}

void mci_big_mul(mci_big *r, const mci_big *a, const mci_big *b)
{
    int na = abs_size(a), nb = abs_size(b);
    mp_limb_t product[2 * MCI_BIG_LIMBS];
    if (na == 0 || nb == 0) {
        r->size = 0;
        return;
    }
    if (na >= nb)
        mpn_mul(product, a->limb, na, b->limb, nb);
    else
        mpn_mul(product, b->limb, nb, a->limb, na);
    big_assign(r, product, na + nb, (a->size < 0) != (b->size < 0));
}

/* |a| shifted left by `shift` bits into limbs (room for abs_size(a) + shift/64 + 1). */
static int shifted_magnitude(mp_limb_t *out, const mci_big *a, int shift)
{
    int n = abs_size(a), words = shift / GMP_NUMB_BITS, bits = shift % GMP_NUMB_BITS;
    memset(out, 0, (size_t)words * sizeof *out);
    if (bits) {
        out[words + n] = mpn_lshift(out + words, a->limb, n, (unsigned)bits);
        n++;
    } else {
        memcpy(out + words, a->limb, (size_t)n * sizeof *out);
    }
    n += words;
    while (n > 0 && out[n - 1] == 0)
        n--;
    return n;
}

/* q = floor(|num| 2^shift / |den|) (callers choose shift so that it fits two limbs), r
 * the remainder in *rn limbs; returns whether the remainder is nonzero. */
static int divide_shifted(const mci_big *num, const mci_big *den, int shift, mp_limb_t *q,
                          mp_limb_t *r, int *rn)
{
    static _Thread_local mp_limb_t n[MCI_BIG_LIMBS + 3], d[MCI_BIG_LIMBS + 3];
    int nn = shifted_magnitude(n, num, shift > 0 ? shift : 0);
    int dn = shifted_magnitude(d, den, shift < 0 ? -shift : 0);
    if (nn < dn) {
        q[0] = 0;
        memcpy(r, n, (size_t)nn * sizeof *r);
        memset(r + nn, 0, (size_t)(dn - nn) * sizeof *r);
    } else {
        mpn_tdiv_qr(q, r, 0, n, nn, d, dn);
    }
    *rn = dn;
    return !mpn_zero_p(r, dn);
}

double mci_big_ratio_to_double(const mci_big *num, const mci_big *den, int exp2)
{
    static _Thread_local mp_limb_t q[MCI_BIG_LIMBS + 3], r[MCI_BIG_LIMBS + 3];
    int nn = abs_size(num), dn = abs_size(den), shift, negative, rn;
    long nbits, dbits;
    uint64_t top;
    double x;
    if (nn == 0 || dn == 0)
        return 0;
    negative = (num->size < 0) != (den->size < 0);
    nbits = (long)mpn_sizeinbase(num->limb, (mp_size_t)nn, 2);
    dbits = (long)mpn_sizeinbase(den->limb, (mp_size_t)dn, 2);
    /* q = floor(N 2^shift / D) then lies in [2^62, 2^64): 9 or more bits below the
     * 53 kept, the lowest of which becomes a sticky bit for the remainder. */
    shift = (int)(63 - (nbits - dbits));
    if (exp2 - shift + 62 < -1022) {
        /* The result is below 2^-1021, where the unit is 2^-1074: round N/D 2^(exp2+1074)
         * to an integer directly (ties to even) instead of rounding twice. */
        shift = exp2 + 1074;
        if (shift < 0) /* outside the contract (exp2 >= -1074): not reached by callers */
            return negative ? -0.0 : 0.0;
        int inexact = divide_shifted(num, den, shift, q, r, &rn);
        top = (uint64_t)q[0];
        if (inexact) {
            /* Compare 2r with D: above half rounds up, exactly half rounds to even. */
            mci_big twice_r, d_abs;
            twice_r.size = rn;
            memcpy(twice_r.limb, r, (size_t)rn * sizeof *r);
            while (twice_r.size > 0 && twice_r.limb[twice_r.size - 1] == 0)
                twice_r.size--;
            mci_big_add(&twice_r, &twice_r, &twice_r);
            mci_big_copy(&d_abs, den);
            if (d_abs.size < 0)
                d_abs.size = -d_abs.size;
            int c = compare_abs(&twice_r, &d_abs);
            if (c > 0 || (c == 0 && (top & 1)))
                top++;
        }
        x = ldexp((double)top, -1074);
        return negative ? -x : x;
    }
    if (divide_shifted(num, den, shift, q, r, &rn))
        q[0] |= 1;
    top = (uint64_t)q[0];
    return ldexp(negative ? -(double)top : (double)top, exp2 - shift);
}

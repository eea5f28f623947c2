/*
 * Short exact integers for the exact point cache's fills (exact/wide.h): two's
 * complement numbers of at most eight 64-bit limbs that track how many limbs they use,
 * all on the stack, every operation inline.
 *
 * Why: on rotated CAD input (a Menger sponge exported with six digits) the scaled
 * coordinates have about 56 bits, so a point's exact numbers have 3 to 7 limbs; mci_big
 * computed them at some 8,000 (LPI) and 22,000 (TPI) instructions per point, mostly in
 * the overhead of its general layout (conversions that clear limbs, copies of results,
 * GMP's dispatch), where products of one or two limbs are a few instructions each.
 *
 * A value is limb[0..n) read as a two's complement number (limb n - 1 carries the
 * sign), 1 <= n <= MCI_WIDE_LIMBS. Results are exact when they lie strictly between
 * -2^511 and 2^511: callers prove that from the degree of their polynomial (kernel.c).
 */
#ifndef MESHCSG_EXACT_WIDE_H
#define MESHCSG_EXACT_WIDE_H

#include <gmp.h>
#include <limits.h>
#include <stdbool.h>
#include <stdint.h>

#define MCI_WIDE_LIMBS 8

__extension__ typedef __int128 mci_wide_i128;
__extension__ typedef unsigned __int128 mci_wide_u128;

typedef struct mci_wide {
    int n;
    uint64_t limb[MCI_WIDE_LIMBS];
} mci_wide;

static inline bool mci_wide_negative(const mci_wide *a)
{
    return a->limb[a->n - 1] >> 63;
}

/* Limb i of a, sign-extended beyond its n limbs. */
static inline uint64_t mci_wide_limb(const mci_wide *a, int i)
{
    return i < a->n ? a->limb[i] : mci_wide_negative(a) ? UINT64_MAX : 0;
}

/* Drops top limbs that only repeat the sign, so that later operations loop less. */
static inline void mci_wide_trim(mci_wide *a)
{
    while (a->n > 1) {
        uint64_t top = a->limb[a->n - 1], below = a->limb[a->n - 2] >> 63;
        if (!((top == 0 && below == 0) || (top == UINT64_MAX && below == 1)))
            break;
        a->n--;
    }
}

static inline void mci_wide_from_i128(mci_wide *r, mci_wide_i128 v)
{
    r->limb[0] = (uint64_t)v;
    r->limb[1] = (uint64_t)((mci_wide_u128)v >> 64);
    r->n = 2;
    mci_wide_trim(r);
}

/* r = a + b, or a - b when `subtract`; r may alias a or b. */
static inline void mci_wide_add_signed(mci_wide *r, const mci_wide *a, const mci_wide *b,
                                       bool subtract)
{
    int n = (a->n > b->n ? a->n : b->n) + 1;
    uint64_t flip = subtract ? UINT64_MAX : 0, out[MCI_WIDE_LIMBS];
    mci_wide_u128 sum = subtract; /* a + ~b + 1 = a - b */
    n = n < MCI_WIDE_LIMBS ? n : MCI_WIDE_LIMBS;
    for (int i = 0; i < n; i++) {
        sum += (mci_wide_u128)mci_wide_limb(a, i) + (mci_wide_limb(b, i) ^ flip);
        out[i] = (uint64_t)sum;
        sum >>= 64;
    }
    for (int i = 0; i < n; i++)
        r->limb[i] = out[i];
    r->n = n;
    mci_wide_trim(r);
}

static inline void mci_wide_add(mci_wide *r, const mci_wide *a, const mci_wide *b)
{
    mci_wide_add_signed(r, a, b, false);
}

static inline void mci_wide_sub(mci_wide *r, const mci_wide *a, const mci_wide *b)
{
    mci_wide_add_signed(r, a, b, true);
}

/* limb[0..n) negated in place (two's complement over n limbs). */
static inline void mci_wide_negate_limbs(uint64_t *limb, int n)
{
    uint64_t carry = 1;
    for (int i = 0; i < n; i++) {
        uint64_t x = ~limb[i] + carry;
        carry = carry && x == 0;
        limb[i] = x;
    }
}

/* |a| into out[0..a->n) as an unsigned number; returns its limbs in use. */
static inline int mci_wide_magnitude(const mci_wide *a, uint64_t *out)
{
    int n = a->n;
    for (int i = 0; i < n; i++)
        out[i] = a->limb[i];
    if (mci_wide_negative(a))
        mci_wide_negate_limbs(out, n);
    while (n > 0 && out[n - 1] == 0)
        n--;
    return n;
}

/* r = a b: the magnitudes' schoolbook product over the limbs in use, then the sign.
 * r may alias a or b. */
static inline void mci_wide_mul(mci_wide *r, const mci_wide *a, const mci_wide *b)
{
    uint64_t x[MCI_WIDE_LIMBS], y[MCI_WIDE_LIMBS], p[MCI_WIDE_LIMBS];
    bool negative = mci_wide_negative(a) != mci_wide_negative(b);
    int nx = mci_wide_magnitude(a, x), ny = mci_wide_magnitude(b, y);
    int n = nx + ny + 1; /* one more limb for the sign */
    n = n < MCI_WIDE_LIMBS ? n : MCI_WIDE_LIMBS;
    for (int i = 0; i < n; i++)
        p[i] = 0;
    for (int i = 0; i < nx; i++) {
        uint64_t carry = 0;
        int j;
        for (j = 0; j < ny && i + j < n; j++) {
            mci_wide_u128 t = (mci_wide_u128)x[i] * y[j] + p[i + j] + carry;
            p[i + j] = (uint64_t)t;
            carry = (uint64_t)(t >> 64);
        }
        if (i + j < n)
            p[i + j] = carry;
    }
    if (negative)
        mci_wide_negate_limbs(p, n);
    for (int i = 0; i < n; i++)
        r->limb[i] = p[i];
    r->n = n; /* at least 1 */
    mci_wide_trim(r);
}

/* r = a b for a 64-bit b: one row of the schoolbook product (the LPI's numbers are
 * sums of such products). r may alias a. */
static inline void mci_wide_mul_i64(mci_wide *r, const mci_wide *a, int64_t b)
{
    uint64_t x[MCI_WIDE_LIMBS], y = b < 0 ? 0 - (uint64_t)b : (uint64_t)b, carry = 0;
    bool negative = mci_wide_negative(a) != (b < 0);
    int nx = mci_wide_magnitude(a, x), n = nx + 1;
    n = n < MCI_WIDE_LIMBS ? n : MCI_WIDE_LIMBS;
    for (int i = 0; i < nx; i++) {
        mci_wide_u128 t = (mci_wide_u128)x[i] * y + carry;
        r->limb[i] = (uint64_t)t;
        carry = (uint64_t)(t >> 64);
    }
    if (nx < n)
        r->limb[nx] = carry;
    r->n = n; /* at least 1 */
    if (negative)
        mci_wide_negate_limbs(r->limb, n);
    mci_wide_trim(r);
}

/* Four-limb numbers (256-bit two's complement, no length) for the LPI, whose numbers
 * stay below 2^(4D+4) <= 2^252: fixed loops the compiler unrolls, at a fraction of the
 * cost of the length-tracking operations above. */
typedef struct mci_wide4 {
    uint64_t limb[4];
} mci_wide4;

static inline void mci_wide4_negate(mci_wide4 *a)
{
    mci_wide_negate_limbs(a->limb, 4);
}

/* r = a b for |a| < 2^127 and a 64-bit b: two 64 x 64-bit products. */
static inline void mci_wide4_mul_i128_i64(mci_wide4 *r, mci_wide_i128 a, int64_t b)
{
    mci_wide_u128 x = a < 0 ? -(mci_wide_u128)a : (mci_wide_u128)a;
    uint64_t y = b < 0 ? 0 - (uint64_t)b : (uint64_t)b;
    mci_wide_u128 low = (mci_wide_u128)(uint64_t)x * y;
    mci_wide_u128 high = (mci_wide_u128)(uint64_t)(x >> 64) * y + (low >> 64);
    r->limb[0] = (uint64_t)low;
    r->limb[1] = (uint64_t)high;
    r->limb[2] = (uint64_t)(high >> 64);
    r->limb[3] = 0;
    if ((a < 0) != (b < 0))
        mci_wide4_negate(r);
}

/* r = a b for a 64-bit b, the product within the four limbs. r may alias a. */
static inline void mci_wide4_mul_i64(mci_wide4 *r, const mci_wide4 *a, int64_t b)
{
    mci_wide4 x = *a;
    uint64_t y = b < 0 ? 0 - (uint64_t)b : (uint64_t)b, carry = 0;
    bool negative = (x.limb[3] >> 63) != (b < 0);
    if (x.limb[3] >> 63)
        mci_wide4_negate(&x);
    for (int i = 0; i < 4; i++) {
        mci_wide_u128 t = (mci_wide_u128)x.limb[i] * y + carry;
        r->limb[i] = (uint64_t)t;
        carry = (uint64_t)(t >> 64);
    }
    if (negative)
        mci_wide4_negate(r);
}

static inline void mci_wide4_add(mci_wide4 *r, const mci_wide4 *a, const mci_wide4 *b)
{
    mci_wide_u128 sum = 0;
    for (int i = 0; i < 4; i++) {
        sum += (mci_wide_u128)a->limb[i] + b->limb[i];
        r->limb[i] = (uint64_t)sum;
        sum >>= 64;
    }
}

static inline void mci_wide_from_wide4(mci_wide *r, const mci_wide4 *a)
{
    for (int i = 0; i < 4; i++)
        r->limb[i] = a->limb[i];
    r->n = 4;
    mci_wide_trim(r);
}

static inline int mci_wide_sign(const mci_wide *a)
{
    if (mci_wide_negative(a))
        return -1;
    for (int i = 0; i < a->n; i++)
        if (a->limb[i])
            return 1;
    return 0;
}

/* a as mci_big_export writes it: |a|'s limbs into out[0..capacity) and the signed limb
 * count, or INT_MIN when they do not fit. */
static inline int mci_wide_export(const mci_wide *a, mp_limb_t *out, int capacity)
{
    uint64_t m[MCI_WIDE_LIMBS];
    int n = mci_wide_magnitude(a, m);
    if (n > capacity)
        return INT_MIN;
    for (int i = 0; i < n; i++)
        out[i] = (mp_limb_t)m[i];
    return mci_wide_negative(a) ? -n : n;
}

#endif

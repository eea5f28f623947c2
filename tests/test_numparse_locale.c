/*
 * Number parsing and formatting (src/base/numparse.c) ignore the process locale: in a German
 * numeric locale, whose decimal point is a comma, "2.5" still reads as 2.5, "2,5" stops
 * at the comma, and doubles are written with '.' and read back exactly.
 *
 * Needs the de_DE.UTF-8 locale (tools/ensure-deps.sh generates it when run as root);
 * without it the test reports itself skipped (exit 77), never passed.
 */
#define _POSIX_C_SOURCE 200809L

#include "base/numparse.h"
#include "testlib.h"

#include <locale.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

static uint64_t rng_state = 0x2545f4914f6cdd1dull;

static double random_double(void)
{
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
    double d;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    memcpy(&d, &z, sizeof d);
    return d;
}

TEST(parsing_ignores_the_decimal_comma)
{
    static const char two_and_a_half[] = "2.5", comma[] = "2,5";
    const char *next = NULL;
    double v = 0;
    CHECK(mci_parse_double(two_and_a_half, two_and_a_half + 3, &v, &next) && v == 2.5 &&
          next == two_and_a_half + 3);
    CHECK(mci_parse_double(comma, comma + 3, &v, &next) && v == 2.0 && next == comma + 1);
}

TEST(formatting_writes_a_point_and_reads_back)
{
    char out[MCI_DOUBLE_TEXT_MAX];
    const char *next = NULL;
    CHECK_MSG(mci_format_double(out, 0.5) == 3 && strcmp(out, "0.5") == 0, "got %s", out);
    CHECK_MSG(mci_format_double(out, -1.25e-7) && strcmp(out, "-1.25e-07") == 0, "got %s",
              out);
    for (int i = 0; i < 20000; i++) {
        double d = random_double(), back = 0;
        size_t len;
        if (!isfinite(d))
            continue;
        len = mci_format_double(out, d);
        CHECK_MSG(mci_parse_double(out, out + len, &back, &next) && test_same_double(back, d),
                  "%a -> %s", d, out);
    }
}

int main(void)
{
    if (!setlocale(LC_NUMERIC, "de_DE.UTF-8")) {
        test_skip("the de_DE.UTF-8 locale is not installed (as root: apt-get install locales "
                  "&& localedef -i de_DE -f UTF-8 de_DE.UTF-8; tools/ensure-deps.sh does it)");
        return test_summary();
    }
    {
        /* The locale really uses a comma: otherwise the test would prove nothing. */
        char buf[16];
        snprintf(buf, sizeof buf, "%.1f", 2.5);
        CHECK_MSG(strcmp(buf, "2,5") == 0, "de_DE.UTF-8 prints 2.5 as %s", buf);
    }
    RUN(parsing_ignores_the_decimal_comma);
    RUN(formatting_writes_a_point_and_reads_back);
    setlocale(LC_NUMERIC, "C");
    return test_summary();
}

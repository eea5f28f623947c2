/*
 * text() (src/text/text.c) against OpenSCAD 2021.01.
 *
 * The known answers come from OpenSCAD 2021.01 itself (Debian 12's openscad 2021.01-6, with
 * FreeType 2.12.1, HarfBuzz 6.0.0, fontconfig 2.14.1 and fonts-liberation2 2.1.5, the
 * libraries meshcsg links here): each text() was exported to SVG (`openscad -o t.svg
 * t.scad`), once as it is and once moved by each whole number in x and in y, so that
 * every coordinate was printed with six digits below 1 and OpenSCAD's exact Clipper
 * points (integers in units of 2^-16, its CLIPPER_SCALE) could be read back. OpenSCAD
 * turns each outline point p into trunc(p * 2^16), unites the glyphs and cleans the
 * result (Clipper drops points within about 1.4 units of the line through their
 * neighbours). So each case checks, on our outlines truncated the same way:
 *  - the number of loops and of points (equal to OpenSCAD's unless its cleaning dropped
 *    a few nearly collinear points, which `dropped` counts);
 *  - twice the enclosed area in units of 2^-32, an integer: exactly OpenSCAD's when
 *    nothing was dropped, within what the dropped points can change otherwise;
 * and, untruncated, that the even-odd region (shape/region.h) has the loops' area. For
 * "Hello" all of OpenSCAD's points are listed and each must be one of ours truncated.
 * The fonts come from the Debian package fonts-liberation2 (tools/ensure-deps.sh
 * installs it); without it fontconfig substitutes another font, which the log says and
 * these tests report as the missing package.
 */
#include "testlib.h"

#include "base/core.h"
#include "shape/region.h"
#include "text/text.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

static mci_ctx ctx;
static char warnings[4096]; /* the warnings of the last call, each followed by "; " */

static void keep_warning(void *user, mcsg_log_level level, const char *message)
{
    size_t used = strlen(warnings);
    (void)user;
    if (level == MCSG_LOG_WARNING && used + strlen(message) + 2 < sizeof warnings) {
        strcat(warnings, message);
        strcat(warnings, "; ");
    }
}

/* OpenSCAD's defaults: size 10, spacing 1, $fn 0, $fa 12, $fs 2. */
static mci_text_params params(const char *text)
{
    mci_text_params p = {.text = text, .size = 10, .spacing = 1, .fa = 12, .fs = 2};
    return p;
}

static mcsg_status outlines_of(const mci_text_params *p, mci_outlines *o, mcsg_error *err)
{
    warnings[0] = '\0';
    return mci_text_outlines(&ctx, p, o, err);
}

/* Fails, saying what to install, when fontconfig had to replace a Liberation font. */
static void check_font_found(void)
{
    CHECK_MSG(!strstr(warnings, "not found"),
              "the Liberation fonts are missing: %sinstall the Debian package "
              "fonts-liberation2 (apt-get install fonts-liberation2, or make deps)",
              warnings);
}

static int64_t trunc_units(double v)
{
    return (int64_t)(v * 65536.0); /* toward zero, as OpenSCAD's conversion to Clipper */
}

/* Twice the area of the loops with their points truncated to 2^-16, in units of 2^-32,
 * sign turned so that the font's clockwise outer loops count positive. */
static int64_t twice_truncated_area(const mci_outlines *o)
{
    int64_t sum = 0;
    for (size_t k = 0; k < o->loop_count; k++) {
        uint32_t first = o->loop_start[k], end = o->loop_start[k + 1];
        for (uint32_t i = first; i < end; i++) {
            uint32_t j = i + 1 < end ? i + 1 : first;
            sum += trunc_units(o->xy[2 * j]) * trunc_units(o->xy[2 * i + 1]) -
                   trunc_units(o->xy[2 * i]) * trunc_units(o->xy[2 * j + 1]);
        }
    }
    return sum;
}

static double loops_area(const mci_outlines *o)
{
    double sum = 0;
    for (size_t k = 0; k < o->loop_count; k++)
        sum -= mci_outline_area2(o, k) / 2;
    return sum;
}

static double region_area(const mci_outlines *o)
{
    mci_region r;
    mcsg_error err;
    double sum = 0;
    CHECK_OK(mci_region_from_outlines(&ctx, o, &r, &err), &err);
    for (size_t t = 0; t < r.tri_count; t++) {
        const double *a = r.xy + 2 * r.tris[3 * t], *b = r.xy + 2 * r.tris[3 * t + 1],
                     *c = r.xy + 2 * r.tris[3 * t + 2];
        sum += ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) / 2;
    }
    mci_region_free(&ctx, &r);
    return sum;
}

/* One known answer: text()'s arguments, then OpenSCAD's loops, points and twice its area
 * (units of 2^-32), and how many of our points its cleaning dropped. */
typedef struct known {
    const char *scad; /* the OpenSCAD call, for messages */
    const char *text;
    double size, spacing;
    const char *font, *halign, *valign, *direction, *language, *script;
    double fn, fa, fs;
    size_t loops, points;
    int64_t twice_area;
    size_t dropped;
} known;

static void check_known(const known *k)
{
    mci_text_params p = {.text = k->text,
                         .size = k->size,
                         .spacing = k->spacing,
                         .font = k->font,
                         .halign = k->halign,
                         .valign = k->valign,
                         .direction = k->direction,
                         .language = k->language,
                         .script = k->script,
                         .fn = k->fn,
                         .fa = k->fa,
                         .fs = k->fs};
    mci_outlines o;
    mcsg_error err;
    int64_t twice, bound;
    CHECK_OK(outlines_of(&p, &o, &err), &err);
    check_font_found();
    CHECK_MSG(o.loop_count == k->loops && o.point_count == k->points + k->dropped,
              "%s: %zu loops, %zu points; OpenSCAD %zu loops, %zu points (+%zu)", k->scad,
              o.loop_count, o.point_count, k->loops, k->points, k->dropped);
    twice = twice_truncated_area(&o);
    /* A dropped point took a triangle of height below 1.5 units off a short edge. */
    bound = (int64_t)k->dropped << 18;
    CHECK_MSG(llabs(twice - k->twice_area) <= bound,
              "%s: twice the truncated area %lld, OpenSCAD's %lld", k->scad, (long long)twice,
              (long long)k->twice_area);
    if (o.loop_count > 0) {
        double area = loops_area(&o), region = region_area(&o);
        CHECK_MSG(fabs(region - area) <= 1e-9 * area, "%s: region %.17g, loops %.17g", k->scad,
                  region, area);
    }
    mci_outlines_free(&ctx, &o);
}

#define FONT_SERIF_ITALIC "Liberation Serif:style=Italic"
#define FONT_MONO_BOLD "Liberation Mono:style=Bold"
#define FONT_SANS_BOLD "Liberation Sans:style=Bold"

/* First of all: every font the known answers use is there (else nothing else runs). */
TEST(liberation_fonts_installed)
{
    static const char *const fonts[] = {"Liberation Sans:style=Regular", FONT_SANS_BOLD,
                                        FONT_SERIF_ITALIC, FONT_MONO_BOLD};
    for (size_t i = 0; i < sizeof fonts / sizeof fonts[0]; i++) {
        mci_text_params p = params("x");
        mci_outlines o;
        mcsg_error err;
        p.font = fonts[i];
        CHECK_OK(outlines_of(&p, &o, &err), &err);
        check_font_found();
        mci_outlines_free(&ctx, &o);
    }
}

TEST(known_answers_from_openscad)
{
#define N NULL
    /* clang-format off */
    static const known cases[] = {
        /* call; text, size, spacing; font, halign, valign, direction, language, script;
         * $fn, $fa, $fs; OpenSCAD's loops, points, twice the area; points dropped */
        {"text(\"OpenSCAD\")", "OpenSCAD", 10, 1, N, N, N, N, N, N, 0, 12, 2,
         13, 545, INT64_C(1885783611449), 0},
        {"text(\"Hello\", size=7, halign=\"center\", valign=\"center\")", "Hello", 7, 1,
         N, "center", "center", N, N, N, 0, 12, 2, 7, 111, INT64_C(416553466271), 0},
        {"text(\"ab\", font=\"" FONT_SERIF_ITALIC "\", spacing=1.2)", "ab", 10, 1.2,
         FONT_SERIF_ITALIC, N, N, N, N, N, 0, 12, 2, 4, 146, INT64_C(330896015827), 0},
        {"text(\"xyz\", direction=\"ttb\")", "xyz", 10, 1, N, N, N, "ttb", N, N, 0, 12, 2,
         3, 65, INT64_C(490548379351), 2},
        {"text(\"S&p\", $fn=4)", "S&p", 10, 1, N, N, N, N, N, N, 4, 12, 2,
         6, 182, INT64_C(740206411597), 0},
        {"text(\"Wg@8\", size=3, $fs=0.5, $fa=5, halign=\"right\", valign=\"top\")", "Wg@8",
         3, 1, N, "right", "top", N, N, N, 0, 5, 0.5, 8, 602, INT64_C(120007537235), 4},
        {"text(\"Q\u00e9\", size=5, font=\"" FONT_MONO_BOLD "\", valign=\"bottom\", $fn=40)",
         "Q\xc3\xa9", 5, 1, FONT_MONO_BOLD, N, "bottom", N, N, N, 40, 12, 2,
         5, 233, INT64_C(176224156031), 0},
        {"text(\"\u05e9\u05dc\u05d5\u05dd abc\", size=6) (right to left, detected)",
         "\xd7\xa9\xd7\x9c\xd7\x95\xd7\x9d abc", 6, 1, N, N, N, N, N, N, 0, 12, 2,
         10, 305, INT64_C(506020470985), 0},
        {"text(\"AVA\", direction=\"btt\", spacing=0.8, halign=\"center\")", "AVA", 10, 0.8,
         N, "center", N, "btt", N, N, 0, 12, 2, 5, 51, INT64_C(676594075938), 0},
        {"text(\"fi To\", language=\"tr\", script=\"Latn\")", "fi To", 10, 1,
         N, N, N, N, "tr", "Latn", 0, 12, 2, 6, 112, INT64_C(573037296729), 0},
        {"text(\"abc\", size=-4)", "abc", -4, 1, N, N, N, N, N, N, 0, 12, 2,
         5, 140, INT64_C(92904420163), 0},
        {"text(\"o\", $fn=16)", "o", 10, 1, N, N, N, N, N, N, 16, 12, 2,
         2, 45, INT64_C(183878076750), 0},
        /* Counts beyond int: OpenSCAD's conversion gives INT_MIN there, so 2 segments. */
        {"text(\"o\", $fn=1e10)", "o", 10, 1, N, N, N, N, N, N, 1e10, 12, 2,
         2, 30, INT64_C(177494292707), 0},
        {"text(\"o\", $fa=0, $fs=0)", "o", 10, 1, N, N, N, N, N, N, 0, 0, 0,
         2, 30, INT64_C(177494292707), 0},
        {"text(\"Bold 1\", font=\"" FONT_SANS_BOLD "\", size=4.5, spacing=1.05, "
         "halign=\"right\", valign=\"bottom\")", "Bold 1", 4.5, 1.05,
         FONT_SANS_BOLD, "right", "bottom", N, N, N, 0, 12, 2,
         9, 123, INT64_C(297794748310), 0},
    };
    /* clang-format on */
#undef N
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++)
        check_known(&cases[i]);
}

/* Every point of OpenSCAD's text("Hello", size=7, halign="center", valign="center"), in
 * units of 2^-16, loop after loop (4, 4, 12, 33, 13, 21, 24 points). */
static const int32_t hello_points[] = {
    185360,  239309,  129364,  239309,  129364,  -222351, 185360,  -222351, 323599,  239309,
    267604,  239309,  267604,  -222351, 323599,  -222351, -597279, -19206,  -360228, -19206,
    -360228, -222351, -300810, -222351, -300810, 215977,  -360228, 215977,  -360228, 30567,
    -597279, 30567,   -597279, 215977,  -656696, 215977,  -656696, -222351, -597279, -222351,
    -16996,  -219723, 28733,   -193176, 57388,   -148932, 8237,    -134936, 1478,    -149003,
    -8426,   -161343, -21475,  -171957, -37702,  -180079, -57144,  -184953, -79801,  -186577,
    -108043, -183086, -131377, -172613, -149802, -155157, -163108, -131270, -171092, -101508,
    -173753, -65871,  66412,   -65871,  66412,   -58407,  49924,   40968,   459,     100594,
    -81980,  120469,  -126586, 115526,  -163762, 100698,  -193507, 75984,   -215196, 42006,
    -228209, -613,    -232547, -51874,  -228209, -105554, -215196, -149625, -193507, -184086,
    -163520, -208800, -125618, -223629, -79801,  -228572, -173129, -22941,  -169448, 6525,
    -160894, 31462,   -147467, 51872,   -129716, 66995,   -108198, 76069,   -82911,  79094,
    -57093,  76381,   -35629,  68241,   -18521,  54675,   -5557,   35198,   3464,    9326,
    8545,    -22941,  584132,  -223767, 621775,  -209353, 651606,  -185330, 673210,  -151490,
    686173,  -107627, 690494,  -53741,  686449,  580,     674315,  44496,   654092,  78007,
    625299,  101597,  587451,  115751,  540546,  120469,  456725,  101112,  406432,  43042,
    389668,  -53741,  393850,  -105916, 406397,  -149208, 427308,  -183618, 456414,  -208592,
    493538,  -223577, 538679,  -228572, 509902,  -183481, 487244,  -172333, 470082,  -153754,
    458070,  -127778, 450864,  -94440,  448461,  -53741,  450898,  -12141,  458209,  21403,
    470394,  46894,   488040,  64783,   511735,  75516,   541478,  79094,   570911,  75586,
    594087,  65060,   611006,  47518,   622500,  22233,   629397,  -11519,  631696,  -53741,
    629294,  -95530,  622087,  -129231, 610075,  -154846, 592463,  -172818, 568457,  -183602,
    538055,  -187197};

static bool has_truncated(const mci_outlines *o, int64_t x, int64_t y)
{
    for (size_t i = 0; i < o->point_count; i++) {
        if (trunc_units(o->xy[2 * i]) == x && trunc_units(o->xy[2 * i + 1]) == y)
            return true;
    }
    return false;
}

TEST(openscad_points_of_hello)
{
    mci_text_params p = params("Hello");
    mci_outlines o;
    mcsg_error err;
    size_t n = sizeof hello_points / sizeof hello_points[0] / 2, missing = 0;
    p.size = 7;
    p.halign = p.valign = "center";
    CHECK_OK(outlines_of(&p, &o, &err), &err);
    check_font_found();
    CHECK_EQ_SIZE(o.point_count, n);
    for (size_t i = 0; i < n; i++)
        missing += !has_truncated(&o, hello_points[2 * i], hello_points[2 * i + 1]);
    CHECK_MSG(missing == 0, "%zu of OpenSCAD's %zu points are not ours", missing, n);
    mci_outlines_free(&ctx, &o);
}

/* No font given is OpenSCAD's default, Liberation Sans Regular; blanks are trimmed. */
TEST(default_font)
{
    mci_text_params p = params("Ag"), named = params("Ag"), blank = params("Ag");
    mci_outlines a, b, c;
    mcsg_error err;
    named.font = "Liberation Sans:style=Regular";
    blank.font = " \t";
    CHECK_OK(outlines_of(&p, &a, &err), &err);
    check_font_found();
    CHECK_OK(outlines_of(&named, &b, &err), &err);
    CHECK_OK(outlines_of(&blank, &c, &err), &err);
    CHECK(a.point_count > 0 && a.point_count == b.point_count &&
          a.point_count == c.point_count);
    CHECK(a.point_count == b.point_count &&
          memcmp(a.xy, b.xy, 2 * a.point_count * sizeof *a.xy) == 0);
    mci_outlines_free(&ctx, &a);
    mci_outlines_free(&ctx, &b);
    mci_outlines_free(&ctx, &c);
}

TEST(empty_text)
{
    mci_text_params p = params("");
    mci_outlines o;
    mcsg_error err;
    CHECK_OK(outlines_of(&p, &o, &err), &err);
    CHECK_EQ_SIZE(o.loop_count, 0);
    CHECK_EQ_SIZE(o.point_count, 0);
    CHECK(o.loop_start && o.loop_start[0] == 0);
    mci_outlines_free(&ctx, &o);
    p.text = NULL;
    CHECK_OK(outlines_of(&p, &o, &err), &err);
    CHECK_EQ_SIZE(o.loop_count, 0);
    mci_outlines_free(&ctx, &o);
    p.text = "   "; /* spaces only advance */
    CHECK_OK(outlines_of(&p, &o, &err), &err);
    CHECK_EQ_SIZE(o.loop_count, 0);
    mci_outlines_free(&ctx, &o);
}

TEST(invalid_arguments)
{
    static const char *const bad_utf8[] = {"a\xff",    "\xc0\x80",         "\xed\xa0\x80",
                                           "\xe2\x82", "\xf4\x90\x80\x80", "ab\x80"};
    mci_text_params p = params("x");
    mci_outlines o;
    mcsg_error err;
    for (size_t i = 0; i < sizeof bad_utf8 / sizeof bad_utf8[0]; i++) {
        p.text = bad_utf8[i];
        CHECK(outlines_of(&p, &o, &err) == MCSG_ERR_INVALID_ARG);
        CHECK_CONTAINS(err.message, "UTF-8");
        CHECK(o.xy == NULL && o.loop_start == NULL && o.loop_count == 0);
    }
    p = params("x");
    p.size = INFINITY;
    CHECK(outlines_of(&p, &o, &err) == MCSG_ERR_INVALID_ARG);
    CHECK_CONTAINS(err.message, "size");
    p = params("x");
    p.spacing = NAN;
    CHECK(outlines_of(&p, &o, &err) == MCSG_ERR_INVALID_ARG);
    CHECK_CONTAINS(err.message, "spacing");
    /* fontconfig cannot parse this pattern (OpenSCAD 2021.01 crashes on it). */
    p = params("x");
    p.font = "Liberation Sans:size=abc";
    CHECK(outlines_of(&p, &o, &err) == MCSG_ERR_INVALID_ARG);
    CHECK_CONTAINS(err.message, "not a fontconfig pattern");
    CHECK(o.xy == NULL && o.loop_start == NULL);
}

/* A font fontconfig does not have is replaced (as in OpenSCAD, which says nothing); the
 * log names the replacement. Unknown alignments warn with OpenSCAD's words. */
TEST(warnings_as_logged)
{
    mci_text_params p = params("xy");
    mci_outlines o;
    mcsg_error err;
    p.font = "No Such Font Family:style=Regular";
    CHECK_OK(outlines_of(&p, &o, &err), &err);
    CHECK(o.loop_count > 0);
    CHECK_CONTAINS(warnings, "font \"No Such Font Family:style=Regular\" not found, using");
    mci_outlines_free(&ctx, &o);
    p = params("xy");
    p.halign = "middle";
    p.valign = "centre";
    CHECK_OK(outlines_of(&p, &o, &err), &err);
    CHECK_CONTAINS(warnings, "Unknown value for the halign parameter (use \"left\", \"right\" "
                             "or \"center\"): 'middle'");
    CHECK_CONTAINS(warnings, "Unknown value for the valign parameter (use \"baseline\", "
                             "\"bottom\", \"top\" or \"center\"): 'centre'");
    mci_outlines_free(&ctx, &o);
    p.text = "";
    CHECK_OK(outlines_of(&p, &o, &err), &err);
    CHECK_CONTAINS(warnings, "'middle'");
    mci_outlines_free(&ctx, &o);
}

/* Unknown alignments are OpenSCAD's defaults; spacing scales the advances only. */
TEST(alignment_and_spacing)
{
    mci_text_params p = params("Ab"), q = params("Ab");
    mci_outlines a, b;
    mcsg_error err;
    q.halign = "bogus";
    q.valign = "baseline";
    CHECK_OK(outlines_of(&p, &a, &err), &err);
    CHECK_OK(outlines_of(&q, &b, &err), &err);
    CHECK(a.point_count == b.point_count &&
          memcmp(a.xy, b.xy, 2 * a.point_count * sizeof *a.xy) == 0);
    mci_outlines_free(&ctx, &b);
    q = params("Ab");
    q.spacing = 2;
    CHECK_OK(outlines_of(&q, &b, &err), &err);
    /* The first glyph stays; the second moves right. */
    CHECK(a.point_count == b.point_count && a.xy[0] == b.xy[0] && a.xy[1] == b.xy[1]);
    CHECK(b.xy[2 * (b.point_count - 1)] > a.xy[2 * (a.point_count - 1)]);
    mci_outlines_free(&ctx, &a);
    mci_outlines_free(&ctx, &b);
}

/* The same call gives the same bytes, also from several threads at once (the font
 * configuration is built by whichever thread comes first). */
typedef struct text_job {
    mci_outlines o;
    mcsg_status st;
} text_job;

static void *run_job(void *arg)
{
    text_job *j = arg;
    mci_text_params p = params("OpenSCAD");
    mcsg_error err;
    j->st = mci_text_outlines(&ctx, &p, &j->o, &err);
    return NULL;
}

TEST(deterministic_and_thread_safe)
{
    text_job jobs[4];
    pthread_t threads[4];
    for (int i = 0; i < 4; i++)
        CHECK(pthread_create(&threads[i], NULL, run_job, &jobs[i]) == 0);
    for (int i = 0; i < 4; i++)
        pthread_join(threads[i], NULL);
    for (int i = 0; i < 4; i++) {
        CHECK(jobs[i].st == MCSG_OK);
        CHECK(jobs[i].o.point_count == 545 && jobs[i].o.loop_count == 13);
        CHECK(jobs[i].o.point_count == jobs[0].o.point_count &&
              memcmp(jobs[i].o.xy, jobs[0].o.xy, 2 * jobs[0].o.point_count * sizeof(double)) ==
                  0);
        CHECK(memcmp(jobs[i].o.loop_start, jobs[0].o.loop_start, 14 * sizeof(uint32_t)) == 0);
    }
    for (int i = 0; i < 4; i++)
        mci_outlines_free(&ctx, &jobs[i].o);
}

static mcsg_status text_with(const void *user, const mcsg_options *opts, mcsg_error *err)
{
    const mci_text_params *p = user;
    mci_ctx c;
    mci_outlines o;
    mcsg_status st;
    mci_ctx_init(&c, opts);
    st = mci_text_outlines(&c, p, &o, err);
    if (st == MCSG_OK) {
        CHECK_EQ_SIZE(o.point_count, 545);
        mci_outlines_free(&c, &o);
    }
    return st;
}

TEST(allocation_failures)
{
    mci_text_params p = params("OpenSCAD");
    CHECK(test_allocation_failures("text()", text_with, &p, false) > 0);
}

int main(void)
{
    mcsg_options opts = {0};
    opts.log = keep_warning;
    mci_ctx_init(&ctx, &opts);
    RUN(liberation_fonts_installed);
    if (test_failures > 0)
        return test_summary();
    RUN(known_answers_from_openscad);
    RUN(openscad_points_of_hello);
    RUN(default_font);
    RUN(empty_text);
    RUN(invalid_arguments);
    RUN(warnings_as_logged);
    RUN(alignment_and_spacing);
    RUN(deterministic_and_thread_safe);
    RUN(allocation_failures);
    return test_summary();
}

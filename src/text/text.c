/*
 * OpenSCAD 2021.01's text() (its src/text.cc, FreetypeRenderer.cc, DrawingCallback.cc and
 * FontCache.cc), done again in C from what they do, so that the outlines are OpenSCAD's
 * points before its Clipper union:
 *  - curve segments: n = get_fragments_from_r(size, $fn, $fs, $fa) as an int, then
 *    max(n / 8 + 1, 2) with an integer division ("font curves are short");
 *  - the font: fontconfig's best match for the pattern (blank: "Liberation Sans:style=
 *    Regular") with outline and scalable required, among the system's fonts plus
 *    ~/.fonts and the folders of $OPENSCAD_FONT_PATH; a Unicode charmap if there is one;
 *  - FreeType's size: a character height of 100000 (26.6 units) at 100 dpi, glyphs
 *    loaded with FT_LOAD_DEFAULT (hinted), which OpenSCAD does;
 *  - script: the one given, else the one script of the text's characters (Common,
 *    Inherited and Unknown ignored, a mix of scripts detects none); direction: the one
 *    given (HarfBuzz reads its first letter), else the script's; language "en";
 *    HarfBuzz shapes with its FreeType font functions;
 *  - a point p of an outline (26.6 units) lands at size * (p / 1e5 + offset + advance),
 *    HarfBuzz's offsets and advances scaled by 1 / 1.024e5 (OpenSCAD keeps this 2.4%
 *    mismatch for compatibility), advances times spacing;
 *  - conic and cubic Bezier curves: points at t = i * (1 / segments), i = 1..segments,
 *    in Bernstein form, evaluated in OpenSCAD's order of operations;
 *  - alignment: horizontal text: width = sum of the advances, ascent and descent the
 *    largest of the glyphs' grid-fitted boxes; vertical text: width = the widest box,
 *    ascent = sum of the y advances; halign right -width, center -width / 2; valign top
 *    -ascent, center descent / 2 - ascent / 2, bottom descent.
 * The fontconfig configuration is built once per process (pthread_once; building it
 * reads every font folder's cache) and only read afterwards, which fontconfig allows
 * from several threads. FreeType and HarfBuzz objects belong to one call.
 */
#define _XOPEN_SOURCE 700 /* realpath */

#include "text/text.h"

#include <fontconfig/fontconfig.h>
#include <ft2build.h>
#include FT_FREETYPE_H
#include FT_GLYPH_H
#include FT_OUTLINE_H
#include FT_TRUETYPE_IDS_H
#include <hb-ft.h>
#include <hb.h>

#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* fontconfig holds a pattern's elements at an offset from it rather than by a pointer, so
 * LeakSanitizer takes the patterns of the configuration, kept for the life of the process,
 * for leaks (they are freed with it). Under the sanitizers, building it is not watched. */
#if defined(__SANITIZE_ADDRESS__)
#define MCI_LSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define MCI_LSAN 1
#endif
#endif
#ifdef MCI_LSAN
#include <sanitizer/lsan_interface.h>
#endif

#define DEFAULT_FONT "Liberation Sans:style=Regular"
/* OpenSCAD's GRID_FINE: below this size get_fragments_from_r gives 3. */
#define GRID_FINE 0.00000095367431640625
#define PI_DOUBLE 3.14159265358979323846
/* FreeType's character height (26.6) and the divisor of outline coordinates. */
#define FT_CHAR_SIZE 100000
#define SCALE 1e5
/* HarfBuzz's positions are divided by 1.024e5, not 1e5: OpenSCAD's mismatch, kept. */
static const double UNSCALE = 1.0 / 1.024e5;
/* More points than this are refused rather than allocated (as for other 2D shapes). */
#define MAX_TEXT_POINTS (UINT32_C(1) << 26)

/* ---- the fontconfig configuration, built once ---- */

static pthread_once_t font_config_once = PTHREAD_ONCE_INIT;
static FcConfig *font_config; /* written once under font_config_once, then only read */

static void add_font_dir(FcConfig *config, const char *dir)
{
    struct stat st;
    char resolved[PATH_MAX];
    /* OpenSCAD adds existing folders only, made absolute. */
    if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode) || !realpath(dir, resolved))
        return;
    FcConfigAppFontAddDir(config, (const FcChar8 *)resolved);
}

/* The folders of $OPENSCAD_FONT_PATH, separated by ':'. */
static void add_env_font_dirs(FcConfig *config, const char *paths)
{
    char dir[PATH_MAX];
    while (paths && *paths) {
        size_t n = strcspn(paths, ":");
        if (n > 0 && n < sizeof dir) {
            memcpy(dir, paths, n);
            dir[n] = '\0';
            add_font_dir(config, dir);
        }
        paths += n + (paths[n] == ':');
    }
}

static void load_font_config(void)
{
    const char *home = getenv("HOME");
    char dir[PATH_MAX];
    FcConfig *config;
#ifdef MCI_LSAN
    __lsan_disable();
#endif
    config = FcInitLoadConfig();
    if (config) {
        if (home && (size_t)snprintf(dir, sizeof dir, "%s/.fonts", home) < sizeof dir)
            add_font_dir(config, dir);
        add_env_font_dirs(config, getenv("OPENSCAD_FONT_PATH"));
        FcConfigBuildFonts(config); /* its result is ignored by OpenSCAD too */
        font_config = config;
    }
#ifdef MCI_LSAN
    __lsan_enable();
#endif
}

/* ---- UTF-8 ---- */

/* The code point at s[*at] (valid UTF-8 as glib's g_utf8_validate reads it: shortest
 * forms, no surrogates, nothing past U+10FFFF), *at moved past it; false if invalid. */
static bool utf8_next(const unsigned char *s, size_t n, size_t *at, uint32_t *cp)
{
    static const uint32_t least[5] = {0, 0, 0x80, 0x800, 0x10000};
    size_t i = *at;
    unsigned c = s[i];
    int len = c < 0x80 ? 1 : c < 0xC2 ? 0 : c < 0xE0 ? 2 : c < 0xF0 ? 3 : c < 0xF5 ? 4 : 0;
    uint32_t v;
    if (len == 0 || n - i < (size_t)len)
        return false;
    v = len == 1 ? c : c & (0x7Fu >> len);
    for (int k = 1; k < len; k++) {
        if ((s[i + k] & 0xC0) != 0x80)
            return false;
        v = v << 6 | (s[i + k] & 0x3Fu);
    }
    if (v < least[len] || v > 0x10FFFF || (v >= 0xD800 && v <= 0xDFFF))
        return false;
    *cp = v;
    *at = i + (size_t)len;
    return true;
}

static mcsg_status check_utf8(const char *text, mcsg_error *err)
{
    size_t n = strlen(text), at = 0;
    uint32_t cp;
    while (at < n) {
        if (!utf8_next((const unsigned char *)text, n, &at, &cp))
            return mci_fail(err, MCSG_ERR_INVALID_ARG,
                            "text(): the text is not valid UTF-8 (at byte %zu)", at);
    }
    return MCSG_OK;
}

/* ---- script, direction, segments ---- */

static bool ignored_script(hb_script_t s)
{
    return s == HB_SCRIPT_COMMON || s == HB_SCRIPT_INHERITED || s == HB_SCRIPT_UNKNOWN ||
           s == HB_SCRIPT_INVALID;
}

/* OpenSCAD's detection: the script given, else the one script of the characters. */
static hb_script_t detect_script(const char *given, const char *text)
{
    hb_script_t script = hb_script_from_string(given, -1), s;
    size_t n = strlen(text), at = 0;
    uint32_t cp;
    if (script != HB_SCRIPT_INVALID)
        return script;
    while (at < n && utf8_next((const unsigned char *)text, n, &at, &cp)) {
        s = hb_unicode_script(hb_unicode_funcs_get_default(), cp);
        if (ignored_script(s))
            continue;
        if (script == HB_SCRIPT_INVALID)
            script = s;
        else if (script != s && script != HB_SCRIPT_UNKNOWN)
            script = HB_SCRIPT_UNKNOWN;
    }
    return script;
}

/* The script and direction HarfBuzz shapes with. OpenSCAD stores a detected script as
 * its ISO 15924 tag and reads it back, and keeps the given string otherwise. */
static void shaping_properties(const mci_text_params *p, const char *text, hb_script_t *script,
                               hb_direction_t *direction)
{
    const char *given = p->script ? p->script : "";
    hb_script_t detected = detect_script(given, text);
    hb_direction_t d = hb_direction_from_string(p->direction ? p->direction : "", -1);
    char tag[5] = {0};
    if (d == HB_DIRECTION_INVALID)
        d = hb_script_get_horizontal_direction(detected);
    /* Scripts of either direction (Runic, ...) give none; HarfBuzz's own guess then takes
     * left to right, and shaping needs a direction. */
    *direction = d == HB_DIRECTION_INVALID ? HB_DIRECTION_LTR : d;
    if (ignored_script(detected)) {
        *script = hb_script_from_string(given, -1);
        return;
    }
    hb_tag_to_string(hb_script_to_iso15924_tag(detected), tag);
    *script = hb_script_from_string(tag, -1);
}

/* Points per Bezier curve: text.cc's fraction of get_fragments_from_r(size). */
static unsigned long curve_segments(const mci_text_params *p)
{
    double n;
    int fragments;
    if (p->size < GRID_FINE || isinf(p->fn) || isnan(p->fn))
        n = 3;
    else if (p->fn > 0)
        n = p->fn >= 3 ? p->fn : 3;
    else /* fmin and fmax ignore a NaN, as std::fmin and std::fmax do */
        n = ceil(fmax(fmin(360.0 / p->fa, p->size * 2 * PI_DOUBLE / p->fs), 5));
    /* OpenSCAD's int conversion of a count beyond int is undefined; x86-64 gives INT_MIN
     * (cvttsd2si), so OpenSCAD draws the minimum of 2 segments there. */
    if (!(n < 2147483648.0))
        return 2;
    fragments = (int)n;
    return fragments / 8 + 1 < 2 ? 2 : (unsigned long)(fragments / 8 + 1);
}

/* ---- one call's state ---- */

typedef struct text_run {
    const mci_ctx *ctx;
    const mci_text_params *p;
    mcsg_error *err;
    const char *text;
    unsigned long segments;
    FT_Library library;
    FT_Face face;
    hb_font_t *font;
    hb_buffer_t *buffer;
    FT_Glyph *glyphs;   /* the glyphs that loaded, in HarfBuzz's order */
    unsigned *glyph_at; /* each one's index in HarfBuzz's buffer */
    unsigned glyph_count;
    /* drawing (DrawingCallback): the loop being drawn starts at point loop_first */
    mci_outlines *out;
    size_t point_cap, loop_cap, loop_first;
    double pen[2], offset[2], advance[2];
    mcsg_status st; /* the first failure inside FreeType's callbacks */
} text_run;

static void run_free(text_run *r)
{
    for (unsigned i = 0; i < r->glyph_count; i++)
        FT_Done_Glyph(r->glyphs[i]);
    mci_free(r->ctx, r->glyphs);
    mci_free(r->ctx, r->glyph_at);
    if (r->buffer)
        hb_buffer_destroy(r->buffer);
    if (r->font)
        hb_font_destroy(r->font); /* before the face it reads */
    if (r->face)
        FT_Done_Face(r->face);
    if (r->library)
        FT_Done_FreeType(r->library);
}

/* ---- the font ---- */

/* Equal names as fontconfig compares families: blanks and ASCII case ignored. */
static bool same_name(const char *a, const char *b)
{
    for (;; a++, b++) {
        while (*a == ' ')
            a++;
        while (*b == ' ')
            b++;
        if (*a == '\0' || *b == '\0')
            return *a == *b;
        if ((*a >= 'A' && *a <= 'Z' ? *a + 32 : *a) != (*b >= 'A' && *b <= 'Z' ? *b + 32 : *b))
            return false;
    }
}

static bool has_string(FcPattern *pattern, const char *object, const FcChar8 *want)
{
    FcChar8 *value;
    for (int i = 0; FcPatternGetString(pattern, object, i, &value) == FcResultMatch; i++) {
        if (same_name((const char *)value, (const char *)want))
            return true;
    }
    return false;
}

/* OpenSCAD says nothing when fontconfig replaces a font it does not have; a warning
 * here tells why the letters look different. */
static void warn_if_replaced(const mci_ctx *ctx, const char *name, FcPattern *requested,
                             FcPattern *match)
{
    FcChar8 *want, *family = NULL, *style = NULL;
    bool same = true;
    if (FcPatternGetString(requested, FC_FAMILY, 0, &want) == FcResultMatch)
        same = has_string(match, FC_FAMILY, want);
    if (same && FcPatternGetString(requested, FC_STYLE, 0, &want) == FcResultMatch)
        same = has_string(match, FC_STYLE, want);
    if (same)
        return;
    FcPatternGetString(match, FC_FAMILY, 0, &family);
    FcPatternGetString(match, FC_STYLE, 0, &style);
    mci_log(ctx, MCSG_LOG_WARNING, "text(): font \"%s\" not found, using \"%s:style=%s\"",
            name, family ? (const char *)family : "?", style ? (const char *)style : "?");
}

/* fontconfig's best match for the pattern `name`: its file and face index. */
static mcsg_status match_font(text_run *r, const char *name, FcPattern **match)
{
    FcPattern *requested = FcNameParse((const FcChar8 *)name), *pattern;
    FcResult result;
    mcsg_status st = MCSG_OK;
    *match = NULL;
    if (!requested)
        return mci_fail(r->err, MCSG_ERR_INVALID_ARG,
                        "text(): font \"%s\" is not a fontconfig pattern", name);
    /* fontconfig fails only for want of memory until the match itself. */
    pattern = FcPatternDuplicate(requested);
    if (!pattern || !FcPatternAddBool(pattern, FC_OUTLINE, FcTrue) ||
        !FcPatternAddBool(pattern, FC_SCALABLE, FcTrue) ||
        !FcConfigSubstitute(font_config, pattern, FcMatchPattern)) {
        st = mci_fail_nomem(r->err, "finding a font for text()");
    } else {
        FcDefaultSubstitute(pattern);
        *match = FcFontMatch(font_config, pattern, &result);
        if (*match)
            warn_if_replaced(r->ctx, name, requested, *match);
        else
            st = mci_fail(r->err, MCSG_ERR_IO, "text(): no font found for \"%s\"", name);
    }
    FcPatternDestroy(requested);
    if (pattern)
        FcPatternDestroy(pattern);
    return st;
}

/* OpenSCAD's charmap choice: Unicode, else the first of its list of fallbacks. */
static void select_charmap(const mci_ctx *ctx, FT_Face face)
{
    static const int tries[][2] = {{TT_PLATFORM_MICROSOFT, TT_MS_ID_UNICODE_CS},
                                   {TT_PLATFORM_ISO, TT_ISO_ID_10646},
                                   {TT_PLATFORM_APPLE_UNICODE, -1},
                                   {TT_PLATFORM_MICROSOFT, TT_MS_ID_SYMBOL_CS},
                                   {TT_PLATFORM_MACINTOSH, TT_MAC_ID_ROMAN},
                                   {TT_PLATFORM_ISO, TT_ISO_ID_8859_1},
                                   {TT_PLATFORM_ISO, TT_ISO_ID_7BIT_ASCII}};
    if (FT_Select_Charmap(face, FT_ENCODING_UNICODE) == 0)
        return;
    for (size_t t = 0; t < sizeof tries / sizeof tries[0]; t++) {
        for (int i = 0; i < face->num_charmaps; i++) {
            FT_CharMap map = face->charmaps[i];
            if (map->platform_id == tries[t][0] &&
                (tries[t][1] < 0 || map->encoding_id == tries[t][1]) &&
                FT_Set_Charmap(face, map) == 0)
                return;
        }
    }
    mci_log(ctx, MCSG_LOG_WARNING, "text(): could not select a char map for font %s/%s",
            face->family_name ? face->family_name : "?",
            face->style_name ? face->style_name : "?");
}

/* A Windows symbol font keeps its characters at U+F000 and up. */
static bool is_symbol_font(FT_Face face)
{
    FT_UInt glyph;
    FT_ULong code;
    if (!face->charmap || face->charmap->platform_id != TT_PLATFORM_MICROSOFT ||
        face->charmap->encoding_id != TT_MS_ID_SYMBOL_CS)
        return false;
    code = FT_Get_First_Char(face, &glyph);
    return glyph != 0 && code >= 0xF000;
}

/* The font's name with blanks trimmed, OpenSCAD's default when nothing is left. */
static char *font_name(const mci_ctx *ctx, const char *font)
{
    const char *s = font ? font : "", *e;
    char *name;
    while (*s == ' ' || (*s >= '\t' && *s <= '\r'))
        s++;
    e = s + strlen(s);
    while (e > s && (e[-1] == ' ' || (e[-1] >= '\t' && e[-1] <= '\r')))
        e--;
    if (e == s) {
        s = DEFAULT_FONT;
        e = s + strlen(s);
    }
    name = mci_malloc(ctx, (size_t)(e - s) + 1);
    if (name) {
        memcpy(name, s, (size_t)(e - s));
        name[e - s] = '\0';
    }
    return name;
}

static mcsg_status open_face(text_run *r)
{
    char *name = font_name(r->ctx, r->p->font);
    FcPattern *match = NULL;
    FcChar8 *file;
    int index;
    mcsg_status st;
    if (!name)
        return mci_fail_nomem(r->err, "finding a font for text()");
    st = match_font(r, name, &match);
    if (st == MCSG_OK && (FcPatternGetString(match, FC_FILE, 0, &file) != FcResultMatch ||
                          FcPatternGetInteger(match, FC_INDEX, 0, &index) != FcResultMatch))
        st = mci_fail(r->err, MCSG_ERR_IO, "text(): no font file for \"%s\"", name);
    if (st == MCSG_OK && FT_New_Face(r->library, (const char *)file, index, &r->face) != 0) {
        r->face = NULL;
        st = mci_fail(r->err, MCSG_ERR_IO, "text(): cannot read font file %s",
                      (const char *)file);
    }
    if (st == MCSG_OK) {
        select_charmap(r->ctx, r->face);
        if (FT_Set_Char_Size(r->face, 0, FT_CHAR_SIZE, 100, 100) != 0)
            st = mci_fail(r->err, MCSG_ERR_IO, "text(): cannot set the size of font %s", name);
    }
    if (match)
        FcPatternDestroy(match);
    mci_free(r->ctx, name);
    return st;
}

/* ---- shaping and glyphs ---- */

static void add_text(text_run *r)
{
    size_t n = strlen(r->text), at = 0;
    uint32_t cp;
    if (!is_symbol_font(r->face)) {
        hb_buffer_add_utf8(r->buffer, r->text, (int)n, 0, (int)n);
        return;
    }
    /* Characters below U+0100 move to the symbol page U+F000 (as OpenSCAD does, after
     * Microsoft's recommendation for symbol fonts), one at a time. */
    while (at < n && utf8_next((const unsigned char *)r->text, n, &at, &cp)) {
        hb_codepoint_t c = cp < 0x100 ? 0xF000 + cp : cp;
        hb_buffer_add_codepoints(r->buffer, &c, 1, 0, 1);
    }
}

static mcsg_status shape(text_run *r)
{
    hb_script_t script;
    hb_direction_t direction;
    hb_language_t language;
    if (strlen(r->text) > INT_MAX)
        return mci_fail(r->err, MCSG_ERR_LIMIT, "text(): the text is too long");
    shaping_properties(r->p, r->text, &script, &direction);
    r->font = hb_ft_font_create(r->face, NULL);
    r->buffer = hb_buffer_create();
    hb_buffer_set_direction(r->buffer, direction);
    hb_buffer_set_script(r->buffer, script);
    language = hb_language_from_string(r->p->language ? r->p->language : "en", -1);
    hb_buffer_set_language(r->buffer, language);
    add_text(r);
    hb_shape(r->font, r->buffer, NULL, 0);
    if (!hb_buffer_allocation_successful(r->buffer))
        return mci_fail_nomem(r->err, "shaping text()");
    return MCSG_OK;
}

/* Load every glyph HarfBuzz chose; one that fails is left out, with OpenSCAD's message. */
static mcsg_status load_glyphs(text_run *r)
{
    unsigned count;
    hb_glyph_info_t *info = hb_buffer_get_glyph_infos(r->buffer, &count);
    if (count == 0)
        return MCSG_OK;
    r->glyphs = mci_malloc_array(r->ctx, count, sizeof *r->glyphs);
    r->glyph_at = mci_malloc_array(r->ctx, count, sizeof *r->glyph_at);
    if (!r->glyphs || !r->glyph_at)
        return mci_fail_nomem(r->err, "drawing text()");
    for (unsigned i = 0; i < count; i++) {
        FT_Glyph glyph;
        const char *failed = "load";
        if (FT_Load_Glyph(r->face, info[i].codepoint, FT_LOAD_DEFAULT) == 0) {
            failed = FT_Get_Glyph(r->face->glyph, &glyph) == 0 ? NULL : "get";
            if (!failed && glyph->format != FT_GLYPH_FORMAT_OUTLINE) {
                FT_Done_Glyph(glyph);
                failed = "get an outline of";
            }
        }
        if (failed) {
            mci_log(r->ctx, MCSG_LOG_WARNING,
                    "text(): could not %s glyph %u for char at index %u in text '%s'", failed,
                    info[i].codepoint, i, r->text);
            continue;
        }
        r->glyphs[r->glyph_count] = glyph;
        r->glyph_at[r->glyph_count++] = i;
    }
    return MCSG_OK;
}

/* ---- alignment ---- */

/* std::max(a, b): a unless a < b. */
static double max_of(double a, double b)
{
    return a < b ? b : a;
}

static double x_offset(const mci_ctx *ctx, const char *halign, double width)
{
    if (halign && strcmp(halign, "right") == 0)
        return -width;
    if (halign && strcmp(halign, "center") == 0)
        return -width / 2.0;
    if (halign && strcmp(halign, "left") != 0)
        mci_log(ctx, MCSG_LOG_WARNING,
                "Unknown value for the halign parameter (use \"left\", \"right\" or "
                "\"center\"): '%s'",
                halign);
    return 0;
}

static double y_offset(const mci_ctx *ctx, const char *valign, double ascend, double descend)
{
    if (valign && strcmp(valign, "top") == 0)
        return -ascend;
    if (valign && strcmp(valign, "center") == 0)
        return descend / 2.0 - ascend / 2.0;
    if (valign && strcmp(valign, "bottom") == 0)
        return descend;
    if (valign && strcmp(valign, "baseline") != 0)
        mci_log(ctx, MCSG_LOG_WARNING,
                "Unknown value for the valign parameter (use \"baseline\", \"bottom\", "
                "\"top\" or \"center\"): '%s'",
                valign);
    return 0;
}

/* The text's offset from halign and valign: its width and height from the glyphs'
 * advances and grid-fitted boxes. */
static void text_offset(text_run *r, double offset[2])
{
    const hb_glyph_position_t *pos = hb_buffer_get_glyph_positions(r->buffer, NULL);
    bool horizontal = HB_DIRECTION_IS_HORIZONTAL(hb_buffer_get_direction(r->buffer));
    double width = 0, ascend = 0, descend = 0;
    for (unsigned i = 0; i < r->glyph_count; i++) {
        const hb_glyph_position_t *g = &pos[r->glyph_at[i]];
        FT_BBox box;
        FT_Glyph_Get_CBox(r->glyphs[i], FT_GLYPH_BBOX_GRIDFIT, &box);
        if (horizontal) {
            width += g->x_advance * UNSCALE * r->p->spacing;
            ascend = max_of(ascend, max_of(0.0, (double)box.yMax * UNSCALE));
            descend = max_of(descend, max_of(0.0, (double)-box.yMin * UNSCALE));
        } else {
            width = max_of(width, (double)(box.xMax - box.xMin) * UNSCALE);
            ascend += g->y_advance * UNSCALE * r->p->spacing;
        }
    }
    offset[0] = x_offset(r->ctx, r->p->halign, width);
    offset[1] = y_offset(r->ctx, r->p->valign, ascend, descend);
}

/* ---- drawing (FreeType's outline callbacks) ---- */

static bool add_point(text_run *r, double vx, double vy)
{
    mci_outlines *o = r->out;
    double x = r->p->size * ((vx + r->offset[0]) + r->advance[0]);
    double y = r->p->size * ((vy + r->offset[1]) + r->advance[1]);
    if (o->point_count > r->loop_first && o->xy[2 * o->point_count - 2] == x &&
        o->xy[2 * o->point_count - 1] == y)
        return true; /* a repeated point adds no edge */
    if (o->point_count >= MAX_TEXT_POINTS) {
        r->st = mci_fail(r->err, MCSG_ERR_LIMIT, "text(): more than %u points",
                         (unsigned)MAX_TEXT_POINTS);
        return false;
    }
    if (!mci_grow_array(r->ctx, (void **)&o->xy, &r->point_cap, o->point_count + 1,
                        2 * sizeof *o->xy, 256)) {
        r->st = mci_fail_nomem(r->err, "drawing text()");
        return false;
    }
    o->xy[2 * o->point_count] = x;
    o->xy[2 * o->point_count + 1] = y;
    o->point_count++;
    return true;
}

/* Ends the loop being drawn: its closing point (the first again) dropped, and the whole
 * loop if fewer than three points are left, since it encloses nothing. */
static bool close_loop(text_run *r)
{
    mci_outlines *o = r->out;
    size_t first = r->loop_first, n = o->point_count - first;
    if (n > 1 && o->xy[2 * first] == o->xy[2 * o->point_count - 2] &&
        o->xy[2 * first + 1] == o->xy[2 * o->point_count - 1])
        n--;
    o->point_count = first + (n < 3 ? 0 : n);
    r->loop_first = o->point_count;
    if (n < 3)
        return true;
    if (!mci_grow_array(r->ctx, (void **)&o->loop_start, &r->loop_cap, o->loop_count + 2,
                        sizeof *o->loop_start, 16)) {
        r->st = mci_fail_nomem(r->err, "drawing text()");
        return false;
    }
    o->loop_start[++o->loop_count] = (uint32_t)o->point_count;
    return true;
}

static int move_to(const FT_Vector *to, void *user)
{
    text_run *r = user;
    if (!close_loop(r))
        return 1;
    r->pen[0] = to->x / SCALE;
    r->pen[1] = to->y / SCALE;
    return add_point(r, r->pen[0], r->pen[1]) ? 0 : 1;
}

static int line_to(const FT_Vector *to, void *user)
{
    text_run *r = user;
    r->pen[0] = to->x / SCALE;
    r->pen[1] = to->y / SCALE;
    return add_point(r, r->pen[0], r->pen[1]) ? 0 : 1;
}

/* Quadratic Bezier: pen (1-t)^2 + c 2 (1-t) t + to t^2, in OpenSCAD's order (its
 * pow(x, 2) is x * x: gcc computes it so, and it is the correctly rounded square). */
static int conic_to(const FT_Vector *control, const FT_Vector *to, void *user)
{
    text_run *r = user;
    double c[2] = {control->x / SCALE, control->y / SCALE};
    double e[2] = {to->x / SCALE, to->y / SCALE};
    for (unsigned long i = 1; i <= r->segments; i++) {
        double t = (double)i * (1.0 / (double)r->segments), u = 1 - t;
        double x = r->pen[0] * (u * u) + c[0] * 2 * u * t + e[0] * (t * t);
        double y = r->pen[1] * (u * u) + c[1] * 2 * u * t + e[1] * (t * t);
        if (!add_point(r, x, y))
            return 1;
    }
    memcpy(r->pen, e, sizeof e);
    return 0;
}

/* Cubic Bezier (CFF fonts): pen (1-t)^3 + c1 3 (1-t)^2 t + c2 3 (1-t) t^2 + to t^3. */
static int cubic_to(const FT_Vector *control1, const FT_Vector *control2, const FT_Vector *to,
                    void *user)
{
    text_run *r = user;
    double c1[2] = {control1->x / SCALE, control1->y / SCALE};
    double c2[2] = {control2->x / SCALE, control2->y / SCALE};
    double e[2] = {to->x / SCALE, to->y / SCALE}, v[2];
    for (unsigned long i = 1; i <= r->segments; i++) {
        double t = (double)i * (1.0 / (double)r->segments), u = 1 - t;
        double u3 = pow(u, 3), t3 = pow(t, 3);
        for (int k = 0; k < 2; k++)
            v[k] =
                r->pen[k] * u3 + c1[k] * 3 * (u * u) * t + c2[k] * 3 * u * (t * t) + e[k] * t3;
        if (!add_point(r, v[0], v[1]))
            return 1;
    }
    memcpy(r->pen, e, sizeof e);
    return 0;
}

static mcsg_status draw(text_run *r)
{
    static const FT_Outline_Funcs funcs = {move_to, line_to, conic_to, cubic_to, 0, 0};
    const hb_glyph_position_t *pos = hb_buffer_get_glyph_positions(r->buffer, NULL);
    double offset[2];
    text_offset(r, offset);
    for (unsigned i = 0; i < r->glyph_count && r->st == MCSG_OK; i++) {
        const hb_glyph_position_t *g = &pos[r->glyph_at[i]];
        r->offset[0] = offset[0] + g->x_offset * UNSCALE;
        r->offset[1] = offset[1] + g->y_offset * UNSCALE;
        /* FreeType's own errors (a broken outline) leave the glyph partly drawn, as in
         * OpenSCAD, which ignores them; the callbacks' failures stop. */
        FT_Outline_Decompose(&((FT_OutlineGlyph)r->glyphs[i])->outline, &funcs, r);
        if (r->st == MCSG_OK)
            close_loop(r);
        r->advance[0] += g->x_advance * UNSCALE * r->p->spacing;
        r->advance[1] += g->y_advance * UNSCALE * r->p->spacing;
    }
    return r->st;
}

/* ---- the entry point ---- */

static mcsg_status check_params(const mci_text_params *p, const char *text, mcsg_error *err)
{
    if (!isfinite(p->size))
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "text(): size %g is not finite", p->size);
    if (!isfinite(p->spacing))
        return mci_fail(err, MCSG_ERR_INVALID_ARG, "text(): spacing %g is not finite",
                        p->spacing);
    return check_utf8(text, err);
}

static mcsg_status render(text_run *r)
{
    mcsg_status st;
    pthread_once(&font_config_once, load_font_config);
    if (!font_config)
        return mci_fail(r->err, MCSG_ERR_IO, "text(): cannot load fontconfig's configuration");
    if (FT_Init_FreeType(&r->library) != 0) {
        r->library = NULL;
        return mci_fail(r->err, MCSG_ERR_IO, "text(): cannot start FreeType");
    }
    st = open_face(r);
    if (st == MCSG_OK)
        st = shape(r);
    if (st == MCSG_OK)
        st = load_glyphs(r);
    if (st == MCSG_OK)
        st = draw(r);
    return st;
}

mcsg_status mci_text_outlines(const mci_ctx *ctx, const mci_text_params *p, mci_outlines *out,
                              mcsg_error *err)
{
    text_run r = {.ctx = ctx, .p = p, .err = err, .out = out, .loop_cap = 1};
    mcsg_status st;
    memset(out, 0, sizeof *out);
    r.text = p->text ? p->text : "";
    r.segments = curve_segments(p);
    st = check_params(p, r.text, err);
    if (st != MCSG_OK)
        return st;
    out->loop_start = mci_calloc_array(ctx, 1, sizeof *out->loop_start);
    if (!out->loop_start)
        return mci_fail_nomem(err, "drawing text()");
    if (r.text[0] != '\0') {
        st = render(&r);
    } else { /* OpenSCAD checks the alignment of an empty text too */
        x_offset(ctx, p->halign, 0);
        y_offset(ctx, p->valign, 0, 0);
    }
    run_free(&r);
    if (st != MCSG_OK)
        mci_outlines_free(ctx, out);
    return st;
}

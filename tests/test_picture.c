/*
 * Pictures (tools/picture.c) checked on their pixels: a cube seen from the top fills a
 * known square, faces take the colour of their leaf from provenance, the nearer face
 * hides the farther, edges darken, and the PNG file reads back to the same pixels.
 */
#include "testlib.h"
#include "picture.h"

#include <png.h>
#include <stdlib.h>
#include <string.h>

static const uint8_t *pixel(const picture *p, int x, int row)
{
    return p->rgb + 3 * ((size_t)row * (size_t)p->width + (size_t)x);
}

static int is_white(const uint8_t *c)
{
    return c[0] == 255 && c[1] == 255 && c[2] == 255;
}

static int same_colour(const uint8_t *a, const uint8_t *b)
{
    return memcmp(a, b, 3) == 0;
}

/* Evaluates CSG text with provenance; group[t] is triangle t's leaf. */
static void evaluate(const char *text, mcsg_mesh *out, uint32_t **group)
{
    mcsg_tree *tree = NULL;
    mcsg_provenance *prov = NULL;
    mcsg_error err;
    *group = NULL;
    memset(out, 0, sizeof *out);
    CHECK_OK(mcsg_scad_read_memory(text, strlen(text), "picture", NULL, NULL, &tree, &err),
             &err);
    if (!tree)
        return;
    CHECK_OK(mcsg_eval(tree, NULL, out, &prov, NULL, &err), &err);
    *group = malloc((out->triangle_count + 1) * sizeof **group);
    for (size_t t = 0; *group && t < out->triangle_count; t++)
        (*group)[t] = prov[t].leaf;
    mcsg_free(prov, NULL);
    mcsg_tree_free(tree);
}

TEST(a_cube_from_the_top_fills_a_known_square)
{
    /* 10 units across in 100 pixels with 5% margins: 9 pixels a unit, the square from
     * 5 to 95; pixel centres at k + 0.5 */
    const double size[3] = {10, 10, 10};
    mcsg_mesh cube;
    picture p;
    mcsg_error err;
    size_t wrong_inside = 0, wrong_outside = 0;
    CHECK_OK(mcsg_make_cube(size, 1, NULL, &cube, &err), &err);
    CHECK(picture_draw(&cube, NULL, VIEW_TOP, 100, 100, 0, &p));
    for (int row = 0; row < 100; row++)
        for (int x = 0; x < 100; x++) {
            int inside = x >= 5 && x <= 94 && row >= 5 && row <= 94;
            if (inside && is_white(pixel(&p, x, row)))
                wrong_inside++;
            if (!inside && !is_white(pixel(&p, x, row)))
                wrong_outside++;
        }
    CHECK_EQ_SIZE(wrong_inside, 0);
    CHECK_EQ_SIZE(wrong_outside, 0);
    /* one face, one normal: one colour everywhere in the square */
    CHECK(same_colour(pixel(&p, 5, 5), pixel(&p, 94, 94)));
    CHECK(same_colour(pixel(&p, 5, 94), pixel(&p, 50, 50)));
    picture_free(&p);
    mcsg_mesh_free(&cube, NULL);
}

TEST(colours_follow_provenance)
{
    /* two boxes side by side, one leaf each: from the top the left half has leaf 0's
     * colour and the right half leaf 1's, both shaded alike (same normal) */
    mcsg_mesh m;
    uint32_t *group;
    picture p;
    uint8_t base0[3], base1[3];
    evaluate("union() { cube([10, 10, 10]); translate([10, 0, 0]) cube([10, 10, 4]); }",
             &m, &group);
    if (!group)
        return;
    CHECK(picture_draw(&m, group, VIEW_TOP, 200, 100, 0, &p));
    const uint8_t *left = pixel(&p, 50, 50), *right = pixel(&p, 150, 50);
    CHECK(!is_white(left) && !is_white(right) && !same_colour(left, right));
    for (int x = 15; x < 95; x += 7)
        CHECK(same_colour(pixel(&p, x, 30), left));
    for (int x = 105; x < 185; x += 7)
        CHECK(same_colour(pixel(&p, x, 70), right));
    picture_group_colour(0, base0);
    picture_group_colour(1, base1);
    /* the same light on both: each channel is its leaf's colour times one factor */
    for (int k = 0; k < 3; k++)
        CHECK_MSG(abs(left[k] * base1[k] - right[k] * base0[k]) <= 2 * (base0[k] + base1[k]),
                  "channel %d: %d of %d against %d of %d", k, left[k], base0[k], right[k],
                  base1[k]);
    picture_free(&p);
    free(group);
    mcsg_mesh_free(&m, NULL);
}

TEST(the_nearer_face_hides_the_farther)
{
    /* from the front (-y) the small box at y < 0 is in front of the big one */
    mcsg_mesh m;
    uint32_t *group;
    picture p, alone;
    evaluate("union() { cube([10, 10, 10]); translate([4, -6, 4]) cube([2, 2, 2]); }", &m,
             &group);
    if (!group)
        return;
    CHECK(picture_draw(&m, group, VIEW_FRONT, 100, 100, 0, &p));
    CHECK(picture_draw(&m, NULL, VIEW_FRONT, 100, 100, 0, &alone));
    /* the centre shows leaf 1's face; a corner of the big box, leaf 0's */
    CHECK(!same_colour(pixel(&p, 50, 50), pixel(&p, 10, 10)));
    CHECK(same_colour(pixel(&alone, 50, 50), pixel(&alone, 10, 10)));
    picture_free(&p);
    picture_free(&alone);
    free(group);
    mcsg_mesh_free(&m, NULL);
}

TEST(edges_darken_and_iso_sees_three_faces)
{
    const double size[3] = {1, 1, 1};
    mcsg_mesh cube;
    picture plain, edged;
    mcsg_error err;
    size_t darker = 0, colours = 0;
    uint8_t seen[8][3];
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    CHECK(picture_draw(&cube, NULL, VIEW_ISO, 120, 120, 0, &plain));
    CHECK(picture_draw(&cube, NULL, VIEW_ISO, 120, 120, 1, &edged));
    for (int i = 0; i < 120 * 120; i++) {
        const uint8_t *a = plain.rgb + 3 * i, *b = edged.rgb + 3 * i;
        darker += b[0] < a[0];
        int known = is_white(a);
        for (size_t k = 0; k < colours && !known; k++)
            known = same_colour(seen[k], a);
        if (!known && colours < 8)
            memcpy(seen[colours++], a, 3);
    }
    CHECK(darker > 100);
    CHECK_EQ_SIZE(colours, 3); /* top, front and right, each lit differently */
    picture_free(&plain);
    picture_free(&edged);
    mcsg_mesh_free(&cube, NULL);
}

TEST(png_reads_back_to_the_same_pixels)
{
    const double size[3] = {2, 3, 4};
    mcsg_mesh cube;
    picture p;
    mcsg_error err;
    char why[256];
    png_image image;
    const char *path = test_tmp("picture.png");
    CHECK_OK(mcsg_make_cube(size, 0, NULL, &cube, &err), &err);
    CHECK(picture_draw(&cube, NULL, VIEW_ISO, 64, 48, 1, &p));
    CHECK_MSG(picture_write_png(&p, path, why, sizeof why), "%s", why);
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    CHECK(png_image_begin_read_from_file(&image, path));
    CHECK(image.width == 64 && image.height == 48);
    image.format = PNG_FORMAT_RGB;
    uint8_t *back = malloc(PNG_IMAGE_SIZE(image));
    CHECK(back && png_image_finish_read(&image, NULL, back, 0, NULL));
    CHECK(back && memcmp(back, p.rgb, 64 * 48 * 3) == 0);
    free(back);
    CHECK(!picture_write_png(&p, "/nonexistent-dir/x.png", why, sizeof why));
    CHECK_CONTAINS(why, "cannot create /nonexistent-dir/x.png");
    picture_free(&p);
    mcsg_mesh_free(&cube, NULL);
}

TEST(options_parse)
{
    int w = 0, h = 0;
    picture_view v;
    CHECK(picture_size_parse("800x600", &w, &h) && w == 800 && h == 600);
    CHECK(!picture_size_parse("15x600", &w, &h));
    CHECK(!picture_size_parse("800x", &w, &h));
    CHECK(!picture_size_parse("800x600x2", &w, &h));
    CHECK(!picture_size_parse("big", &w, &h));
    CHECK(picture_view_parse("side", &v) && v == VIEW_SIDE);
    CHECK(!picture_view_parse("below", &v));
}

int main(void)
{
    RUN(a_cube_from_the_top_fills_a_known_square);
    RUN(colours_follow_provenance);
    RUN(the_nearer_face_hides_the_farther);
    RUN(edges_darken_and_iso_sees_three_faces);
    RUN(png_reads_back_to_the_same_pixels);
    RUN(options_parse);
    return test_summary();
}

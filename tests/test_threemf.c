/*
 * 3MF: the 3MF Consortium's sample files (tests/data/3mf) read with their known counts,
 * volumes and placements; several meshes written and read back bit for bit, the same
 * bytes every time; components, transforms and units; import() giving a leaf per build
 * item; and the errors a broken file gets, each naming the file, the part and the line.
 */
#include "testlib.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zip.h>

static char *read_all(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    char *data = NULL;
    long n;
    if (f && fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (data = malloc((size_t)n + 1)) && fread(data, 1, (size_t)n, f) == (size_t)n)
        *size = (size_t)n;
    else {
        free(data);
        data = NULL;
    }
    if (f)
        fclose(f);
    return data;
}

static double volume(const mcsg_mesh *m)
{
    mcsg_check_report r;
    mcsg_error err;
    CHECK_OK(mcsg_mesh_check(m, NULL, &r, &err), &err);
    CHECK(mcsg_check_report_is_valid(&r));
    return r.volume;
}

static void bounds(const mcsg_mesh *m, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++)
        lo[k] = INFINITY, hi[k] = -INFINITY;
    for (size_t v = 0; v < m->vertex_count; v++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], m->vertices[3 * v + k]);
            hi[k] = fmax(hi[k], m->vertices[3 * v + k]);
        }
}

TEST(consortium_samples)
{
    mcsg_mesh *items, merged;
    char **names;
    size_t count;
    mcsg_error err;
    double lo[3], hi[3];
    CHECK_OK(mcsg_3mf_read(test_data("3mf/box.3mf"), NULL, &items, &names, &count, &err),
             &err);
    CHECK_EQ_SIZE(count, 1);
    if (count == 1) {
        CHECK_EQ_SIZE(items[0].vertex_count, 8);
        CHECK_EQ_SIZE(items[0].triangle_count, 12);
        CHECK_EQ_DOUBLE(volume(&items[0]), 6000);
    }
    mcsg_3mf_free(items, names, count, NULL);

    /* one cylinder placed six times, 21 apart in x and 20.7964 in y */
    CHECK_OK(mcsg_3mf_read(test_data("3mf/multiple_cylinders.3mf"), NULL, &items, &names,
                           &count, &err), &err);
    CHECK_EQ_SIZE(count, 6);
    for (size_t k = 0; k < count; k++) {
        CHECK(strcmp(names[k], "Cylinder") == 0);
        CHECK_EQ_SIZE(items[k].triangle_count, 88);
        CHECK(fabs(volume(&items[k]) - volume(&items[0])) < 1e-9 * volume(&items[0]));
    }
    if (count == 6) {
        bounds(&items[5], lo, hi);
        CHECK_EQ_DOUBLE(lo[0], 42);
        CHECK_EQ_DOUBLE(lo[1], 0.002 + 20.7964);
    }
    mcsg_3mf_free(items, names, count, NULL);
    /* mcsg_mesh_read: every item in one mesh, detected by content */
    CHECK_OK(mcsg_mesh_read(test_data("3mf/multiple_cylinders.3mf"), MCSG_FORMAT_AUTO, NULL,
                            &merged, &err), &err);
    CHECK_EQ_SIZE(merged.triangle_count, 6 * 88);
    mcsg_mesh_free(&merged, NULL);

    CHECK_OK(mcsg_mesh_read(test_data("3mf/torus.3mf"), MCSG_FORMAT_3MF, NULL, &merged, &err),
             &err);
    CHECK_EQ_SIZE(merged.vertex_count, 1100);
    CHECK(volume(&merged) > 0);
    mcsg_mesh_free(&merged, NULL);
    /* colours of the materials extension are skipped */
    CHECK_OK(mcsg_mesh_read(test_data("3mf/pyramid_vertexcolor.3mf"), MCSG_FORMAT_AUTO, NULL,
                            &merged, &err), &err);
    CHECK_EQ_SIZE(merged.triangle_count, 4);
    mcsg_mesh_free(&merged, NULL);
}

TEST(several_meshes_round_trip_bit_for_bit)
{
    const double size[3] = {1.5, 2, 0.1};
    mcsg_mesh in[2], *back = NULL;
    size_t count = 0;
    mcsg_error err;
    mcsg_resolution res = {7, 0, 0};
    const char *a = test_tmp("two.3mf"), *b = test_tmp("two-again.3mf");
    CHECK_OK(mcsg_make_cube(size, 1, NULL, &in[0], &err), &err);
    CHECK_OK(mcsg_make_sphere(1.0 / 3, res, NULL, &in[1], &err), &err);
    CHECK_OK(mcsg_3mf_write(a, in, 2, NULL, &err), &err);
    CHECK_OK(mcsg_3mf_read(a, NULL, &back, NULL, &count, &err), &err);
    CHECK_EQ_SIZE(count, 2);
    for (size_t k = 0; k < count && k < 2; k++) {
        CHECK_EQ_SIZE(back[k].vertex_count, in[k].vertex_count);
        CHECK_EQ_SIZE(back[k].triangle_count, in[k].triangle_count);
        CHECK(memcmp(back[k].vertices, in[k].vertices,
                     3 * in[k].vertex_count * sizeof(double)) == 0);
        CHECK(memcmp(back[k].triangles, in[k].triangles,
                     3 * in[k].triangle_count * sizeof(uint32_t)) == 0);
    }
    mcsg_3mf_free(back, NULL, count, NULL);
    /* the same meshes give the same bytes (no time stamps) */
    CHECK_OK(mcsg_3mf_write(b, in, 2, NULL, &err), &err);
    size_t na = 0, nb = 0;
    char *da = read_all(a, &na), *db = read_all(b, &nb);
    CHECK(da && db && na == nb && memcmp(da, db, na) == 0);
    free(da);
    free(db);
    CHECK(mcsg_3mf_write(a, in, 0, NULL, &err) == MCSG_ERR_INVALID_ARG);
    mcsg_mesh_free(&in[0], NULL);
    mcsg_mesh_free(&in[1], NULL);
}

/* A 3MF file from model XML (the relationships part naming it). */
static const char *make_3mf(const char *name, const char *model_xml, const char *part)
{
    static const char rels_fmt[] =
        "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">"
        "<Relationship Target=\"/%s\" Id=\"r\" Type=\"http://schemas.microsoft.com/"
        "3dmanufacturing/2013/01/3dmodel\"/></Relationships>";
    static char rels[512];
    const char *path = test_tmp(name);
    int error = 0;
    zip_t *zip;
    remove(path);
    zip = zip_open(path, ZIP_CREATE | ZIP_TRUNCATE, &error);
    snprintf(rels, sizeof rels, rels_fmt, part);
    CHECK(zip != NULL);
    if (!zip)
        return path;
    zip_source_t *r = zip_source_buffer(zip, rels, strlen(rels), 0);
    zip_source_t *m = zip_source_buffer(zip, model_xml, strlen(model_xml), 0);
    CHECK(zip_file_add(zip, "_rels/.rels", r, 0) >= 0);
    CHECK(zip_file_add(zip, part, m, 0) >= 0);
    CHECK(zip_close(zip) == 0);
    return path;
}

#define MODEL_OPEN "<model xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\""
#define TETRA                                                                              \
    "<object id=\"1\" name=\"tetra\"><mesh><vertices><vertex x=\"0\" y=\"0\" z=\"0\"/>"     \
    "<vertex x=\"1\" y=\"0\" z=\"0\"/><vertex x=\"0\" y=\"1\" z=\"0\"/>"                    \
    "<vertex x=\"0\" y=\"0\" z=\"1\"/></vertices><triangles>"                              \
    "<triangle v1=\"0\" v2=\"2\" v3=\"1\"/><triangle v1=\"0\" v2=\"1\" v3=\"3\"/>"          \
    "<triangle v1=\"1\" v2=\"2\" v3=\"3\"/><triangle v1=\"0\" v2=\"3\" v3=\"2\"/>"          \
    "</triangles></mesh></object>"

TEST(components_transforms_and_units)
{
    /* in inches, at another part name: an object of two components (one moved by 5 in x),
     * placed mirrored in x; and the tetrahedron itself */
    const char *path = make_3mf(
        "components.3mf",
        MODEL_OPEN " unit=\"inch\"><resources>" TETRA
        "<object id=\"2\"><components><component objectid=\"1\" "
        "transform=\"1 0 0 0 1 0 0 0 1 5 0 0\"/><component objectid=\"1\"/></components>"
        "</object></resources><build><item objectid=\"2\" transform=\"-1 0 0 0 1 0 0 0 1 0 0 "
        "0\"/><item objectid=\"1\"/></build></model>",
        "3D/other.model");
    mcsg_mesh *items;
    char **names;
    size_t count;
    mcsg_error err;
    double lo[3], hi[3];
    CHECK_OK(mcsg_3mf_read(path, NULL, &items, &names, &count, &err), &err);
    CHECK_EQ_SIZE(count, 2);
    if (count != 2)
        return;
    CHECK_EQ_SIZE(items[0].triangle_count, 8);
    bounds(&items[0], lo, hi);
    CHECK_EQ_DOUBLE(lo[0], -6 * 25.4);
    CHECK_EQ_DOUBLE(hi[0], 0);
    CHECK_EQ_DOUBLE(hi[2], 25.4);
    /* the mirror turned the triangles: still facing outward */
    CHECK(volume(&items[0]) > 0);
    CHECK(strcmp(names[0], "") == 0 && strcmp(names[1], "tetra") == 0);
    CHECK(fabs(volume(&items[1]) - 25.4 * 25.4 * 25.4 / 6) < 1e-9);
    mcsg_3mf_free(items, names, count, NULL);
}

TEST(import_gives_a_leaf_per_build_item)
{
    char text[512];
    mcsg_tree *tree;
    mcsg_error err;
    snprintf(text, sizeof text, "import(\"%s\");", test_data("3mf/multiple_cylinders.3mf"));
    CHECK_OK(mcsg_scad_read_memory(text, strlen(text), "import.scad", NULL, NULL, &tree, &err),
             &err);
    if (!tree)
        return;
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 6);
    CHECK(mcsg_tree_node_kind(tree, mcsg_tree_root(tree)) == MCSG_NODE_UNION);
    CHECK_CONTAINS(mcsg_tree_node_label(tree, 5), "item 6 (Cylinder)");
    mcsg_tree_free(tree);
}

/* read_error NAME XML PART MESSAGE: reading fails with a message containing MESSAGE. */
static void read_error(const char *name, const char *xml, const char *message)
{
    mcsg_mesh *items;
    size_t count;
    mcsg_error err;
    const char *path = make_3mf(name, xml, "3D/3dmodel.model");
    CHECK(mcsg_3mf_read(path, NULL, &items, NULL, &count, &err) != MCSG_OK);
    CHECK_CONTAINS(err.message, message);
    CHECK_CONTAINS(err.message, name);
}

TEST(errors_name_file_part_and_line)
{
    mcsg_mesh *items;
    size_t count;
    mcsg_error err;
    read_error("badnumber.3mf", MODEL_OPEN "><resources>\n<object id=\"1\"><mesh><vertices>\n"
               "<vertex x=\"0\" y=\"zero\" z=\"0\"/>", "3D/3dmodel.model:3: y=\"zero\" is not a number");
    read_error("badindex.3mf", MODEL_OPEN "><resources><object id=\"1\"><mesh><vertices>"
               "<vertex x=\"0\" y=\"0\" z=\"0\"/></vertices><triangles>"
               "<triangle v1=\"0\" v2=\"1\" v3=\"0\"/>", "v2=\"1\" is not an index below 1");
    read_error("unit.3mf", MODEL_OPEN " unit=\"parsec\">", "unit \"parsec\"");
    read_error("xml.3mf", MODEL_OPEN "><resources><object", "malformed XML");
    read_error("noitem.3mf", MODEL_OPEN "><resources>" TETRA "</resources></model>",
               "no build item");
    read_error("noobject.3mf", MODEL_OPEN "><build><item objectid=\"7\"/></build></model>",
               "objectid 7 names no object");
    read_error("itself.3mf", MODEL_OPEN "><resources><object id=\"1\"><components>"
               "<component objectid=\"1\"/></components></object></resources>"
               "<build><item objectid=\"1\"/></build></model>", "within themselves");
    /* 16 levels of 16 placements: 16^16 tetrahedra from a few hundred bytes */
    {
        char xml[16384]; /* about 8.5 KB */
        int at = snprintf(xml, sizeof xml, "%s><resources>" TETRA, MODEL_OPEN);
        for (int level = 2; level <= 17; level++) {
            at += snprintf(xml + at, sizeof xml - (size_t)at, "<object id=\"%d\"><components>",
                           level);
            for (int k = 0; k < 16; k++)
                at += snprintf(xml + at, sizeof xml - (size_t)at,
                               "<component objectid=\"%d\"/>", level - 1);
            at += snprintf(xml + at, sizeof xml - (size_t)at, "</components></object>");
        }
        snprintf(xml + at, sizeof xml - (size_t)at,
                 "</resources><build><item objectid=\"17\"/></build></model>");
        read_error("bomb.3mf", xml, "expand to more than 2^32-1");
    }
    read_error("transform.3mf", MODEL_OPEN "><resources>" TETRA "</resources><build><item "
               "objectid=\"1\" transform=\"1 0 0\"/></build></model>", "is not 12 numbers");
    CHECK(mcsg_3mf_read_memory("PK\3\4 not a zip", 14, "junk.3mf", NULL, &items, NULL, &count,
                               &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "junk.3mf: not a 3MF file");
    CHECK(mcsg_3mf_read(test_data("3mf/missing.3mf"), NULL, &items, NULL, &count, &err) ==
          MCSG_ERR_IO);
}

int main(void)
{
    RUN(consortium_samples);
    RUN(several_meshes_round_trip_bit_for_bit);
    RUN(components_transforms_and_units);
    RUN(import_gives_a_leaf_per_build_item);
    RUN(errors_name_file_part_and_line);
    return test_summary();
}

/*
 * AMF: OpenSCAD 2021.01's own AMF tests (tests/data/amf: its .amf files and the .csg
 * exports of the .scad files importing them) evaluated against the counts and volumes of
 * OpenSCAD's renders; the reader's rules (objects, volumes, what is ignored, how a value's
 * text is read, zipped files); its errors, each naming the file and the line; import()'s
 * leaves and labels; and allocation failures.
 */
#include "testlib.h"

#include "base/core.h"
#include "io/amf.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zip.h>

/* ---- OpenSCAD's test files -------------------------------------------------------- */

/* Measured with `meshcsg check` on `openscad -o NAME.stl NAME.scad` (2021.01) for each
 * of OpenSCAD's testdata/scad/amf files. OpenSCAD's exports write six significant digits,
 * so volumes agree to 1e-6 relative where the file's numbers have more (multi-volume-
 * binary: 1494.4382264998903 exported, 1494.4382128501657 from the file's own numbers)
 * and exactly elsewhere. */
typedef struct reference {
    const char *name;
    size_t leaves, vertices, triangles;
    double volume;
} reference;

static const reference REFERENCES[] = {
    {"cube-with-hole", 1, 72, 144, 719.06967394159938},
    {"multi-volume-binary", 3, 617, 1226, 1494.4382264998903}, /* 3 objects, unioned */
    {"sphere20face", 1, 12, 20, 317.01862873499311},
    /* one object of two volumes sharing a face: OpenSCAD writes its polygon set as it is,
     * 5 vertices and 8 triangles, the shared face twice (1/6 + 1/6); evaluated, the
     * shared face cancels out: 6 triangles, the same volume */
    {"split_pyramid", 1, 5, 6, 1.0 / 3},
    {"tetra_multicolor", 1, 4, 4, 0.078125}, /* inches, not converted: OpenSCAD ignores units */
};

static void check_openscad_test(const reference *ref)
{
    char rel[256];
    mcsg_tree *tree = NULL;
    mcsg_mesh out;
    mcsg_eval_stats stats;
    mcsg_check_report report;
    mcsg_error err;
    double volume;
    snprintf(rel, sizeof rel, "amf/scad/amf/%s.csg", ref->name);
    CHECK_OK(mcsg_scad_read(test_data(rel), NULL, &tree, &err), &err);
    if (!tree)
        return;
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), ref->leaves);
    CHECK_OK(mcsg_eval(tree, NULL, &out, NULL, &stats, &err), &err);
    volume = test_signed_volume(&out);
    CHECK_MSG(fabs(volume - ref->volume) <= 1e-6 * ref->volume, "%s: volume %.17g, OpenSCAD's "
              "%.17g", ref->name, volume, ref->volume);
    CHECK_MSG(out.vertex_count == ref->vertices && out.triangle_count == ref->triangles,
              "%s: %zu vertices, %zu triangles", ref->name, out.vertex_count,
              out.triangle_count);
    CHECK_OK(mcsg_mesh_check(&out, NULL, &report, &err), &err);
    CHECK(mcsg_check_report_is_valid(&report));
    mcsg_mesh_free(&out, NULL);
    mcsg_tree_free(tree);
}

TEST(openscad_amf_tests_match_its_renders)
{
    for (size_t k = 0; k < sizeof REFERENCES / sizeof *REFERENCES; k++)
        check_openscad_test(&REFERENCES[k]);
}

TEST(openscad_broken_amf_is_an_error)
{
    mcsg_tree *tree = NULL;
    mcsg_error err;
    /* OpenSCAD warns "Failed to parse file" and imports nothing */
    CHECK(mcsg_scad_read(test_data("amf/scad/amf/amf_broken.csg"), NULL, &tree, &err) ==
          MCSG_ERR_PARSE);
    CHECK(tree == NULL);
    CHECK_CONTAINS(err.message, "amf_broken.csg:1:1: import(\"../../amf/amf_broken.amf\"): ");
    CHECK_CONTAINS(err.message, "amf_broken.amf:9: <y>a</y> is not a number");
}

TEST(files_read_as_meshes)
{
    mcsg_mesh m;
    mcsg_error err;
    /* the zipped file: three objects side by side, each its vertices as listed */
    CHECK_OK(mcsg_mesh_read(test_data("amf/amf/multi-volume-binary.amf"), MCSG_FORMAT_AUTO,
                            NULL, &m, &err), &err);
    CHECK_EQ_SIZE(m.vertex_count, 1200);
    CHECK_EQ_SIZE(m.triangle_count, 1226);
    CHECK(fabs(test_signed_volume(&m) - 1494.4382128501657) < 1e-9);
    mcsg_mesh_free(&m, NULL);
    CHECK_OK(mcsg_mesh_read(test_data("amf/amf/cube-with-hole.amf"), MCSG_FORMAT_AUTO, NULL, &m,
                            &err), &err);
    CHECK_EQ_SIZE(m.vertex_count, 186);
    CHECK_EQ_SIZE(m.triangle_count, 144);
    mcsg_mesh_free(&m, NULL);
    CHECK(mcsg_mesh_read(test_data("amf/amf/amf_broken.amf"), MCSG_FORMAT_AUTO, NULL, &m, &err)
          == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "amf_broken.amf:9: <y>a</y> is not a number");
}

/* ---- the reader's rules ------------------------------------------------------------ */

static mci_ctx ctx;

static mcsg_status read_text(const char *text, size_t size, const char *name,
                             mci_amf_objects *out, mcsg_error *err)
{
    mci_io_source src = {&ctx, name, text, (const unsigned char *)text, size, err};
    return mci_amf_read(&src, out);
}

#define TETRA_VERTICES                                                                     \
    "<vertices><vertex><coordinates><x>0</x><y>0</y><z>0</z></coordinates></vertex>\n"      \
    "<vertex><coordinates><x>1</x><y>0</y><z>0</z></coordinates></vertex>\n"                \
    "<vertex><coordinates><x>0</x><y>1</y><z>0</z></coordinates></vertex>\n"                \
    "<vertex><coordinates><x>0</x><y>0</y><z>1</z></coordinates></vertex></vertices>\n"
#define TRI(a, b, c) "<triangle><v1>" #a "</v1><v2>" #b "</v2><v3>" #c "</v3></triangle>"
#define TETRA_VOLUME "<volume>" TRI(0, 2, 1) TRI(0, 1, 3) TRI(0, 3, 2) TRI(1, 2, 3) "</volume>"

/* Two objects: a tetrahedron split into two volumes, named, in inches (ignored); then a
 * tetrahedron moved by 5 in x whose indices start again at 0; an empty object; a
 * constellation placing them (ignored), a material, colours and metadata. */
static const char TWO_OBJECTS[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<amf unit=\"inch\" version=\"1.1\"><metadata type=\"name\">file</metadata>\n"
    "<object id=\"4\"><metadata type=\"Name\">first</metadata><color><r>1</r></color>\n"
    "<mesh>" TETRA_VERTICES "<volume materialid=\"2\">" TRI(0, 2, 1) TRI(0, 1, 3)
    "</volume><volume>" TRI(0, 3, 2) TRI(1, 2, 3) "</volume></mesh></object>\n"
    "<object id=\"7\"><mesh><vertices>"
    "<vertex><coordinates><x>5</x><y>0</y><z>0</z></coordinates></vertex>"
    "<vertex><coordinates><x>6</x><y>0</y><z>0</z></coordinates></vertex>"
    "<vertex><coordinates><x>5</x><y>1</y><z>0</z></coordinates></vertex>"
    "<vertex><coordinates><x>5</x><y>0</y><z>1</z></coordinates></vertex></vertices>"
    TETRA_VOLUME "</mesh></object>\n"
    "<object id=\"8\"/>\n"
    "<constellation id=\"9\"><instance objectid=\"4\"><deltax>100</deltax></instance>"
    "</constellation><material id=\"2\"><color><r>1</r><g>0</g><b>0</b></color></material>"
    "</amf>\n";

TEST(objects_volumes_and_what_is_ignored)
{
    mci_amf_objects o;
    mcsg_mesh merged;
    mcsg_error err;
    CHECK_OK(read_text(TWO_OBJECTS, sizeof TWO_OBJECTS - 1, "two.amf", &o, &err), &err);
    CHECK_EQ_SIZE(o.count, 3);
    if (o.count != 3)
        return;
    CHECK_EQ_SIZE(o.meshes[0].vertex_count, 4);
    CHECK_EQ_SIZE(o.meshes[0].triangle_count, 4); /* both volumes */
    CHECK_EQ_DOUBLE(test_signed_volume(&o.meshes[0]), 1.0 / 6); /* not in millimetres */
    CHECK_EQ_SIZE(o.meshes[1].triangle_count, 4);
    CHECK_EQ_DOUBLE(o.meshes[1].vertices[0], 5); /* the constellation moved nothing */
    CHECK_EQ_SIZE(o.meshes[1].triangles[0], 0);
    CHECK_EQ_SIZE(o.meshes[2].vertex_count + o.meshes[2].triangle_count, 0);
    CHECK(strcmp(o.names[0], "first") == 0 && strcmp(o.names[1], "") == 0);
    mci_amf_objects_free(&ctx, &o);
    /* mcsg_mesh_read: side by side, detected by content without a name */
    CHECK_OK(mcsg_mesh_read_memory(TWO_OBJECTS, sizeof TWO_OBJECTS - 1, MCSG_FORMAT_AUTO, NULL,
                                   NULL, &merged, &err), &err);
    CHECK_EQ_SIZE(merged.vertex_count, 8);
    CHECK_EQ_SIZE(merged.triangle_count, 8);
    CHECK_EQ_SIZE(merged.triangles[3 * 4], 4); /* the second object's indices moved */
    CHECK_EQ_DOUBLE(test_signed_volume(&merged), 2.0 / 6);
    mcsg_mesh_free(&merged, NULL);
    /* no objects: nothing, as OpenSCAD imports nothing */
    CHECK_OK(read_text("<amf/>", 6, "none.amf", &o, &err), &err);
    CHECK_EQ_SIZE(o.count, 0);
    mci_amf_objects_free(&ctx, &o);
}

/* The first vertex's x of a one-tetrahedron file whose first <x> holds `x_text`. */
static mcsg_status first_x(const char *x_text, double *x, mcsg_error *err)
{
    char text[2048];
    mci_amf_objects o;
    mcsg_status st;
    snprintf(text, sizeof text, "<amf><object><mesh><vertices><vertex><coordinates><x>%s</x>"
             "<y>0</y><z>0</z></coordinates></vertex></vertices></mesh></object></amf>", x_text);
    st = read_text(text, strlen(text), "x.amf", &o, err);
    if (st == MCSG_OK) {
        CHECK_EQ_SIZE(o.count, 1);
        *x = o.count == 1 && o.meshes[0].vertex_count == 1 ? o.meshes[0].vertices[0] : -1;
        mci_amf_objects_free(&ctx, &o);
    }
    return st;
}

TEST(a_value_is_its_text_node_parsed_whole)
{
    /* as boost::lexical_cast reads them (checked against OpenSCAD 2021.01's import) */
    static const struct { const char *text; double x; } good[] = {
        {"+2", 2}, {"2.", 2}, {".5", 0.5}, {"1e-1", 0.1}, {"-0", -0.0}, {"1&#48;", 10},
        /* text split by a comment or a child element: the last node counts */
        {"1<!-- c -->7", 7}, {"1<b>3</b>8", 8},
    };
    static const char *const bad[] = {" 1", "1 ", "\n1\n", "0x1", "1e", "a", ""};
    mcsg_error err;
    double x = 0;
    for (size_t k = 0; k < sizeof good / sizeof *good; k++) {
        CHECK_OK(first_x(good[k].text, &x, &err), &err);
        CHECK_MSG(x == good[k].x && signbit(x) == signbit(good[k].x), "%s: %g", good[k].text, x);
    }
    CHECK_OK(first_x("inf", &x, &err), &err); /* left to the mesh check, as OpenSCAD does */
    CHECK(isinf(x));
    for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
        CHECK_MSG(first_x(bad[k], &x, &err) == MCSG_ERR_PARSE, "%s read", bad[k]);
        CHECK_CONTAINS(err.message, "x.amf:");
    }
    /* a CDATA section is no text node: the vertex has no x */
    CHECK(first_x("<![CDATA[5]]>", &x, &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "without <x>");
    CHECK(first_x("\n\n1", &x, &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "x.amf:3: <x>??1</x> is not a number");
}

/* A tetrahedron object whose first triangle is `triangle` (XML). */
static mcsg_status tetra_with(const char *triangle, mcsg_error *err)
{
    char text[2048];
    mci_amf_objects o;
    mcsg_status st;
    snprintf(text, sizeof text, "<amf>\n<object>\n<mesh>\n" TETRA_VERTICES "<volume>\n%s\n"
             TRI(0, 1, 3) "</volume></mesh></object></amf>", triangle);
    st = read_text(text, strlen(text), "t.amf", &o, err);
    if (st == MCSG_OK)
        mci_amf_objects_free(&ctx, &o);
    return st;
}

TEST(errors_name_the_file_and_line)
{
    mci_amf_objects o;
    mcsg_error err;
    CHECK_OK(tetra_with(TRI(+0, 00, 2), &err), &err); /* integers as lexical_cast reads them */
    CHECK(tetra_with(TRI(0, 4, 2), &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "t.amf:9: <v2>4</v2> is not the index of one of the 4 vertices");
    CHECK(tetra_with(TRI(-1, 1, 2), &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "<v1>-1</v1> is not the index");
    CHECK(tetra_with(TRI(0.0, 1, 2), &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "<v1>0.0</v1> is not an integer");
    CHECK(tetra_with("<triangle><v1>0</v1><v2>1</v2></triangle>", &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "t.amf:9: a <triangle> without <v3>");
    /* indices count only the vertices listed before, in the same object */
    {
        const char *early = "<amf><object><mesh><volume>" TRI(0, 0, 0) "</volume></mesh>"
                            "</object></amf>";
        CHECK(read_text(early, strlen(early), "early.amf", &o, &err) == MCSG_ERR_PARSE);
    }
    CHECK_CONTAINS(err.message, "early.amf:1: <v1>0</v1> is not the index of one of the 0 ");
    /* truncated XML */
    CHECK(read_text(TWO_OBJECTS, 300, "cut.amf", &o, &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "cut.amf:5: malformed XML");
    CHECK(o.count == 0 && o.meshes == NULL);
    CHECK(read_text("", 0, "empty.amf", &o, &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "empty.amf:1: malformed XML: no element found");
    {
        const char *model = "<?xml version=\"1.0\"?>\n<model/>";
        CHECK(read_text(model, strlen(model), "r.amf", &o, &err) == MCSG_ERR_PARSE);
    }
    CHECK_CONTAINS(err.message, "r.amf:2: the root element is <model>, not <amf>");
    /* a value no number is that long */
    {
        char big[1200];
        double x;
        memset(big, '1', sizeof big - 1);
        big[sizeof big - 1] = '\0';
        CHECK(first_x(big, &x, &err) == MCSG_ERR_PARSE);
        CHECK_CONTAINS(err.message, "a value of more than 1024 characters");
    }
}

TEST(entity_expansion_is_bounded)
{
    char text[4096];
    int at = snprintf(text, sizeof text, "<!DOCTYPE amf [<!ENTITY e0 \"0000000000\">");
    mci_amf_objects o;
    mcsg_error err;
    for (int k = 1; k < 10; k++)
        at += snprintf(text + at, sizeof text - (size_t)at,
                       "<!ENTITY e%d \"&e%d;&e%d;&e%d;&e%d;&e%d;&e%d;&e%d;&e%d;&e%d;&e%d;\">", k,
                       k - 1, k - 1, k - 1, k - 1, k - 1, k - 1, k - 1, k - 1, k - 1, k - 1);
    at += snprintf(text + at, sizeof text - (size_t)at, "]><amf><metadata>&e9;</metadata></amf>");
    /* 10^10 characters from 1 KB: expat refuses past its amplification limit */
    CHECK(read_text(text, (size_t)at, "laughs.amf", &o, &err) == MCSG_ERR_LIMIT);
    CHECK_CONTAINS(err.message, "laughs.amf:1: entities expand beyond");
}

/* ---- zip archives ------------------------------------------------------------------- */

/* A zip of `count` entries (names[k], texts[k]) in a malloc'ed buffer. */
static void *zip_of(const char *const *names, const char *const *texts, int count, size_t *size)
{
    zip_error_t ze;
    zip_source_t *zs;
    zip_t *zip;
    void *bytes = NULL;
    zip_error_init(&ze);
    zs = zip_source_buffer_create(NULL, 0, 0, &ze);
    zip_source_keep(zs);
    zip = zip_open_from_source(zs, ZIP_TRUNCATE, &ze);
    for (int k = 0; zip && k < count; k++) {
        zip_source_t *s = zip_source_buffer(zip, texts[k], strlen(texts[k]), 0);
        CHECK(s && zip_file_add(zip, names[k], s, 0) >= 0);
    }
    CHECK(zip && zip_close(zip) == 0);
    if (zip_source_open(zs) == 0 && zip_source_seek(zs, 0, SEEK_END) == 0) {
        zip_int64_t n = zip_source_tell(zs);
        bytes = malloc((size_t)n);
        CHECK(bytes && zip_source_seek(zs, 0, SEEK_SET) == 0 &&
              zip_source_read(zs, bytes, (zip_uint64_t)n) == n);
        *size = (size_t)n;
        zip_source_close(zs);
    }
    zip_source_free(zs);
    zip_error_fini(&ze);
    return bytes;
}

static int warnings;
static char last_warning[512];

static void count_warning(void *user, mcsg_log_level level, const char *message)
{
    (void)user;
    if (level == MCSG_LOG_WARNING) {
        warnings++;
        snprintf(last_warning, sizeof last_warning, "%s", message);
    }
}

TEST(zipped_files)
{
    static const char *const names[] = {"docs/readme.txt", "parts/part.amf"};
    const char *texts[] = {"not AMF", TWO_OBJECTS};
    const char *broken = "<amf><object>\n<mesh>";
    mcsg_options opts = {0};
    mci_ctx logged;
    mci_amf_objects o;
    mcsg_error err;
    size_t size = 0;
    char *zip;
    opts.log = count_warning;
    mci_ctx_init(&logged, &opts);
    /* the entry named like the file, in whatever folder */
    zip = zip_of(names, texts, 2, &size);
    CHECK_OK(read_text(zip, size, "/some/where/part.amf", &o, &err), &err);
    CHECK_EQ_SIZE(o.count, 3);
    mci_amf_objects_free(&ctx, &o);
    CHECK(read_text(zip, size, "other.amf", &o, &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "other.amf: the zipped AMF has no entry other.amf and 2 entries");
    free(zip);
    /* else the only entry, with a warning as OpenSCAD's */
    zip = zip_of(names + 1, texts + 1, 1, &size);
    {
        mci_io_source src = {&logged, "renamed.amf", zip, (const unsigned char *)zip, size, &err};
        warnings = 0;
        CHECK_OK(mci_amf_read(&src, &o), &err);
        CHECK_EQ_SIZE(o.count, 3);
        CHECK(warnings == 1);
        CHECK_CONTAINS(last_warning, "reading its only entry, parts/part.amf");
        mci_amf_objects_free(&ctx, &o);
    }
    free(zip);
    /* errors inside name the entry */
    zip = zip_of(names + 1, &broken, 1, &size);
    CHECK(read_text(zip, size, "part.amf", &o, &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "part.amf: parts/part.amf:2: malformed XML");
    free(zip);
    CHECK(read_text("PK\3\4 not a zip", 14, "junk.amf", &o, &err) == MCSG_ERR_PARSE);
    CHECK_CONTAINS(err.message, "junk.amf: not a readable zip archive");
}

/* ---- import() ------------------------------------------------------------------------ */

TEST(import_gives_a_leaf_per_object)
{
    const char *path = test_tmp("objects.amf");
    FILE *f = fopen(path, "wb");
    char text[512];
    mcsg_tree *tree = NULL;
    mcsg_mesh out;
    mcsg_error err;
    mcsg_options opts = {0};
    CHECK(f && fwrite(TWO_OBJECTS, 1, sizeof TWO_OBJECTS - 1, f) == sizeof TWO_OBJECTS - 1);
    if (f)
        fclose(f);
    snprintf(text, sizeof text, "translate([0, 0, 1]) import(\"%s\");", path);
    CHECK_OK(mcsg_scad_read_memory(text, strlen(text), "i.scad", NULL, NULL, &tree, &err), &err);
    if (!tree)
        return;
    /* the empty third object makes no leaf */
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 2);
    CHECK(mcsg_tree_node_kind(tree, mcsg_tree_root(tree)) == MCSG_NODE_UNION);
    CHECK_CONTAINS(mcsg_tree_node_label(tree, 0), "objects.amf\") object 1 (first) at i.scad:1:22");
    CHECK_CONTAINS(mcsg_tree_node_label(tree, 1), "objects.amf\") object 2 at i.scad:1:22");
    CHECK_OK(mcsg_eval(tree, NULL, &out, NULL, NULL, &err), &err);
    CHECK_EQ_DOUBLE(test_signed_volume(&out), 2.0 / 6);
    mcsg_mesh_free(&out, NULL);
    mcsg_tree_free(tree);
    /* a file without objects imports nothing, with a warning */
    f = fopen(path, "wb");
    CHECK(f && fputs("<amf><object id=\"1\"/></amf>", f) >= 0);
    if (f)
        fclose(f);
    opts.log = count_warning;
    warnings = 0;
    CHECK_OK(mcsg_scad_read_memory(text, strlen(text), "i.scad", NULL, &opts, &tree, &err),
             &err);
    CHECK(warnings == 1);
    CHECK_CONTAINS(last_warning, "import() is empty");
    CHECK(tree && mcsg_tree_leaf_count(tree) == 0);
    mcsg_tree_free(tree);
    /* a missing file */
    CHECK(mcsg_scad_read_memory("import(\"no-such.amf\");", 22, "m.scad", NULL, NULL, &tree,
                                &err) == MCSG_ERR_IO);
    CHECK_CONTAINS(err.message, "m.scad:1:1: import(\"no-such.amf\")");
}

/* ---- allocation failures -------------------------------------------------------------- */

static mcsg_status read_under(const void *what, const mcsg_options *opts, mcsg_error *err)
{
    mci_ctx c;
    mci_amf_objects o;
    mcsg_mesh merged;
    mcsg_status st;
    mci_ctx_init(&c, opts);
    mci_io_source src = {&c, "alloc.amf", what, what, sizeof TWO_OBJECTS - 1, err};
    st = mci_amf_read(&src, &o);
    if (st != MCSG_OK)
        return st;
    CHECK_EQ_SIZE(o.count, 3);
    mci_amf_objects_free(&c, &o);
    st = mci_amf_read_merged(&src, &merged);
    if (st == MCSG_OK) {
        CHECK_EQ_SIZE(merged.triangle_count, 8);
        mcsg_mesh_free(&merged, opts);
    }
    return st;
}

static mcsg_status import_under(const void *what, const mcsg_options *opts, mcsg_error *err)
{
    mcsg_tree *tree = NULL;
    mcsg_status st = mcsg_scad_read_memory(what, strlen(what), "a.scad", NULL, opts, &tree, err);
    if (st == MCSG_OK) {
        CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), 3);
        mcsg_tree_free(tree);
    }
    return st;
}

/* Runs may succeed: trimming a finished mesh (mci_io_builder_finish) is optional. */
TEST(allocation_failures)
{
    char text[512];
    CHECK(test_allocation_failures("mci_amf_read", read_under, TWO_OBJECTS, true) > 10);
    snprintf(text, sizeof text, "import(\"%s\");", test_data("amf/amf/multi-volume-binary.amf"));
    CHECK(test_allocation_failures("import multi-volume-binary.amf", import_under, text, true) >
          10);
}

int main(void)
{
    mci_ctx_init(&ctx, NULL);
    RUN(openscad_amf_tests_match_its_renders);
    RUN(openscad_broken_amf_is_an_error);
    RUN(files_read_as_meshes);
    RUN(objects_volumes_and_what_is_ignored);
    RUN(a_value_is_its_text_node_parsed_whole);
    RUN(errors_name_the_file_and_line);
    RUN(entity_expansion_is_bounded);
    RUN(zipped_files);
    RUN(import_gives_a_leaf_per_object);
    RUN(allocation_failures);
    return test_summary();
}

/*
 * libFuzzer target for the CSG-language reader: LLVMFuzzerTestOneInput parses the input
 * with mcsg_scad_read_memory and checks what comes back, abort()ing on a violation:
 *  - the status is one the reader documents (success, malformed input, unsupported
 *    feature, size limit, out of memory), and a failure's message names the input with
 *    a line and column ("fuzz.scad:L:C: ...") unless it is an allocation failure;
 *  - a tree has a valid root, every child was created before its parent, and every leaf
 *    triangle indexes an existing vertex;
 *  - a small tree (at most 32 nodes and 2000 leaf triangles) evaluates with mcsg_eval to
 *    success, an invalid mesh (a polyhedron's faces are the text's), a limit or out of
 *    memory, never an internal error.
 * Modules that use their children's geometry (hull, minkowski, offset, projection,
 * linear_extrude, rotate_extrude, resize) evaluate it during reading, so
 * the reader's own calls reach the evaluator and src/shape whatever the tree's size.
 * Everything runs on one thread: the budget's counter is not atomic.
 * The allocator caps live memory at 256 MiB, so that huge $fn values or long vector
 * arithmetic end as MCSG_ERR_NOMEM instead of exhausting the machine. Inputs containing
 * "import" are skipped: an import may name any file (/dev/zero, /dev/stdin) and reading
 * files is the mesh readers' business, fuzzed by their own targets. Replayed over
 * fuzz/corpus/scad/ by CTest (fuzz/replay_main.c).
 */
#include "fuzz_alloc.h"
#include "meshcsg.h"

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Bounds on the trees evaluated whole: the evaluator has its own target (fuzz_eval); here
 * it only has to take what the reader makes, and a run must stay fast. */
#define MAX_EVAL_NODES 32
#define MAX_EVAL_TRIANGLES 2000

static int contains(const uint8_t *data, size_t size, const char *word)
{
    size_t n = strlen(word);
    for (size_t i = 0; i + n <= size; i++) {
        if (memcmp(data + i, word, n) == 0)
            return 1;
    }
    return 0;
}

/* Total leaf triangles, to keep whole-tree evaluations small. */
static size_t tree_triangles(const mcsg_tree *tree)
{
    size_t total = 0;
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(tree); id++) {
        const mcsg_mesh *m = mcsg_tree_leaf_mesh(tree, id);
        total += m ? m->triangle_count : 0;
    }
    return total;
}

/* Evaluate a small tree: a leaf may break the input contract (a polyhedron's faces are
 * the text's), so an invalid mesh is an allowed answer; an internal error is not. */
static void eval_small_tree(const mcsg_tree *tree, const mcsg_options *opts)
{
    mcsg_mesh out;
    mcsg_eval_stats stats;
    mcsg_error err;
    mcsg_status st;
    if (mcsg_tree_node_count(tree) > MAX_EVAL_NODES || tree_triangles(tree) > MAX_EVAL_TRIANGLES)
        return;
    st = mcsg_eval(tree, opts, &out, NULL, &stats, &err);
    if (st == MCSG_OK)
        mcsg_mesh_free(&out, opts);
    else if (st != MCSG_ERR_INVALID_MESH && st != MCSG_ERR_NOMEM && st != MCSG_ERR_LIMIT)
        abort();
}

static void check_tree(const mcsg_tree *tree)
{
    size_t n = mcsg_tree_node_count(tree);
    if (n == 0 || mcsg_tree_root(tree) >= n)
        abort();
    for (mcsg_node_id id = 0; id < n; id++) {
        const mcsg_mesh *m = mcsg_tree_leaf_mesh(tree, id);
        for (size_t i = 0; i < mcsg_tree_child_count(tree, id); i++) {
            if (mcsg_tree_child(tree, id, i) >= id)
                abort();
        }
        for (size_t i = 0; m && i < 3 * m->triangle_count; i++) {
            if (m->triangles[i] >= m->vertex_count)
                abort();
        }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_budget b = {0};
    mcsg_options opts;
    mcsg_tree *tree = NULL;
    mcsg_error err;
    mcsg_status st;
    if (contains(data, size, "import"))
        return 0;
    opts = capped_options(&b);
    opts.threads = 1; /* the budget's counter is not atomic, and modules that evaluate
                         their children (hull, projection, ...) run mcsg_eval */
    st = mcsg_scad_read_memory((const char *)data, size, "fuzz.scad", NULL, &opts, &tree, &err);
    if (st == MCSG_OK) {
        check_tree(tree);
        eval_small_tree(tree, &opts);
        mcsg_tree_free(tree);
    } else if (tree != NULL || (st != MCSG_ERR_PARSE && st != MCSG_ERR_UNSUPPORTED &&
                                st != MCSG_ERR_LIMIT && st != MCSG_ERR_NOMEM)) {
        abort();
    } else if (st != MCSG_ERR_NOMEM && strncmp(err.message, "fuzz.scad:", 10) != 0) {
        abort();
    }
    if (b.live != 0)
        abort(); /* a leak */
    return 0;
}

/*
 * libFuzzer target for the CSG-language reader: LLVMFuzzerTestOneInput parses the input
 * with mcsg_scad_read_memory and checks what comes back, abort()ing on a violation:
 *  - the status is one the reader documents (success, malformed input, unsupported
 *    feature, size limit, out of memory), and a failure's message names the input with
 *    a line and column ("fuzz.scad:L:C: ...") unless it is an allocation failure;
 *  - a tree has a valid root, every child was created before its parent, and every leaf
 *    triangle indexes an existing vertex.
 * The allocator caps live memory at 256 MiB, so that huge $fn values or long vector
 * arithmetic end as MCSG_ERR_NOMEM instead of exhausting the machine. Inputs containing
 * "import" are skipped: an import may name any file (/dev/zero, /dev/stdin) and reading
 * files is the mesh readers' business, fuzzed by their own targets. Replayed over
 * fuzz/corpus/scad/ by CTest (fuzz/replay_main.c).
 */
#include "meshcsg.h"

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define BUDGET ((size_t)256 << 20)

typedef struct budget {
    size_t live;
} budget;

/* Each block starts with a header holding its size, padded for any alignment. */
typedef union header {
    size_t size;
    max_align_t align;
} header;

static void *capped_realloc(void *user, void *ptr, size_t size)
{
    budget *b = user;
    header *h = ptr ? (header *)ptr - 1 : NULL;
    size_t old = h ? h->size : 0;
    if (size > BUDGET || b->live - old + size > BUDGET)
        return NULL;
    h = realloc(h, sizeof *h + size);
    if (!h)
        return NULL;
    b->live = b->live - old + size;
    h->size = size;
    return h + 1;
}

static void *capped_malloc(void *user, size_t size) { return capped_realloc(user, NULL, size); }

static void capped_free(void *user, void *ptr)
{
    header *h = (header *)ptr - 1;
    ((budget *)user)->live -= h->size;
    free(h);
}

static int contains(const uint8_t *data, size_t size, const char *word)
{
    size_t n = strlen(word);
    for (size_t i = 0; i + n <= size; i++) {
        if (memcmp(data + i, word, n) == 0)
            return 1;
    }
    return 0;
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
    budget b = {0};
    mcsg_options opts;
    mcsg_tree *tree = NULL;
    mcsg_error err;
    mcsg_status st;
    if (contains(data, size, "import"))
        return 0;
    memset(&opts, 0, sizeof opts);
    opts.allocator.malloc_fn = capped_malloc;
    opts.allocator.realloc_fn = capped_realloc;
    opts.allocator.free_fn = capped_free;
    opts.allocator.user = &b;
    st = mcsg_scad_read_memory((const char *)data, size, "fuzz.scad", NULL, &opts, &tree, &err);
    if (st == MCSG_OK) {
        check_tree(tree);
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

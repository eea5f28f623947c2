/*
 * The built-in ring scene must be bit-identical to ../shared/scenes/make_scenes.py's
 * ring_spheres_N, so that results can be compared with reference.tsv. The expected
 * hashes were computed from the Python generator's OFF files (read back exactly) when
 * this test was written; they also pin the scene against accidental change.
 */
#include "testlib.h"
#include "scenes.h"

#include <string.h>

#define HASH_100 0x2faabdeea2811b6dULL
#define HASH_200 0xde8a87664287e6b6ULL
#define HASH_800 0x65b0a00429e7c2e7ULL

static uint64_t fnv1a(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 0x100000001b3ULL;
    }
    return h;
}

static uint64_t scene_hash(const mcsg_tree *tree)
{
    uint64_t h = 0xcbf29ce484222325ULL;
    for (mcsg_node_id id = 0; id < mcsg_tree_node_count(tree); id++) {
        const mcsg_mesh *m = mcsg_tree_leaf_mesh(tree, id);
        if (!m)
            continue;
        h = fnv1a(h, m->vertices, m->vertex_count * 3 * sizeof(double));
        h = fnv1a(h, m->triangles, m->triangle_count * 3 * sizeof(uint32_t));
    }
    return h;
}

static void check_ring(int n, uint64_t expected_hash)
{
    mcsg_tree *tree;
    mcsg_error err;
    CHECK_OK(scene_ring_spheres(n, 1, NULL, &tree, &err), &err);
    if (!tree)
        return;
    CHECK_EQ_SIZE(mcsg_tree_leaf_count(tree), (size_t)n + 1);
    CHECK_EQ_SIZE(mcsg_tree_node_count(tree), 2 * (size_t)n + 1);
    CHECK_MSG(scene_hash(tree) == expected_hash, "ring_spheres_%d hash %016llx", n,
              (unsigned long long)scene_hash(tree));
    /* Alternating union / difference, left-deep: the root is the last operation. */
    CHECK(mcsg_tree_node_kind(tree, mcsg_tree_root(tree)) ==
          (n % 2 ? MCSG_NODE_UNION : MCSG_NODE_DIFFERENCE));
    mcsg_tree_free(tree);
}

TEST(ring_scenes_match_the_shared_generator)
{
    check_ring(100, HASH_100);
    check_ring(200, HASH_200);
    check_ring(800, HASH_800);
}

int main(void)
{
    RUN(ring_scenes_match_the_shared_generator);
    return test_summary();
}

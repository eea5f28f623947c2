/*
 * The per-thread table of exact points (exact/exact_cache.h): direct-mapped by a hash of
 * the defining vertices' addresses, with a tag array apart from the entries so that a
 * fresh table costs one small memset and its entries' pages are touched only when used.
 */
#include "exact/exact_cache.h"
#include "base/parallel.h"

#include <string.h>

/* 8,192 entries of about 1.1 KB (9 MB, its pages touched as entries are used): on a
 * Menger sponge export, 4,096 entries stored 220,000 points, 8,192 206,000 and 32,768
 * 140,000 for about 100,000 distinct ones; a face's points stay while it is sorted and
 * triangulated, not from one step to the next. */
#define TABLE_BITS 13
#define TABLE_SIZE (1u << TABLE_BITS)

typedef struct exact_table {
    uint32_t tag[TABLE_SIZE]; /* 0: empty; else the hash's high bits, never 0 */
    mci_exact_point entry[TABLE_SIZE];
} exact_table;

static uint64_t definition_hash(const mci_point *p)
{
    uint64_t h = (uint64_t)p->kind + 1;
    for (int i = 0; i < mci_point_vertex_count(p); i++) {
        h = (h ^ (uint64_t)(uintptr_t)p->v[i]) * 0x9e3779b97f4a7c15u;
        h ^= h >> 29;
    }
    return h;
}

static uint32_t tag_of(uint64_t h)
{
    return (uint32_t)(h >> 32) | 1u;
}

static exact_table *thread_table(void)
{
    bool fresh;
    exact_table *t = mci_thread_scratch(sizeof *t, &fresh);
    if (t && fresh)
        memset(t->tag, 0, sizeof t->tag);
    return t;
}

/* The entry of p's definition in this thread's table, NULL without a table; *tag gets
 * the entry's tag slot and *want the tag p's entry carries. */
static mci_exact_point *locate(const mci_point *p, uint32_t **tag, uint32_t *want)
{
    exact_table *t = thread_table();
    uint64_t h;
    if (!t)
        return NULL;
    h = definition_hash(p);
    *tag = &t->tag[h & (TABLE_SIZE - 1)];
    *want = tag_of(h);
    return &t->entry[h & (TABLE_SIZE - 1)];
}

static bool same_definition(const mci_exact_point *e, const mci_point *p)
{
    int n = mci_point_vertex_count(p);
    if (e->kind != p->kind || memcmp(e->v, p->v, (size_t)n * sizeof p->v[0]) != 0)
        return false;
    for (int i = 0; i < n; i++)
        if (memcmp(e->coords[i], p->v[i], sizeof e->coords[i]) != 0)
            return false;
    return true;
}

mci_exact_point *mci_exact_cache_find(const mci_point *p, bool *held)
{
    uint32_t *tag = NULL, want = 0;
    mci_exact_point *e = locate(p, &tag, &want);
    *held = e && *tag == want && same_definition(e, p);
    return e;
}

void mci_exact_cache_claim(mci_exact_point *e, const mci_point *p)
{
    int n = mci_point_vertex_count(p);
    uint32_t *tag = NULL, want = 0;
    if (locate(p, &tag, &want) != e)
        return;
    e->kind = p->kind;
    memcpy(e->v, p->v, (size_t)n * sizeof p->v[0]);
    for (int i = 0; i < n; i++)
        memcpy(e->coords[i], p->v[i], sizeof e->coords[i]);
    *tag = want;
}

void mci_exact_cache_clear(const mci_point *p)
{
    uint32_t *tag = NULL, want = 0;
    if (locate(p, &tag, &want))
        *tag = 0;
}

size_t mci_exact_cache_count(void)
{
    bool fresh;
    const exact_table *t = mci_thread_scratch(sizeof(exact_table), &fresh);
    size_t n = 0;
    if (!t || fresh)
        return 0;
    for (size_t i = 0; i < TABLE_SIZE; i++)
        n += t->tag[i] != 0;
    return n;
}

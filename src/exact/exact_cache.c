/*
 * The per-thread table of exact points (exact/exact_cache.h): direct-mapped by a hash of
 * the defining vertices' addresses, with a tag array apart from the entries so that a
 * fresh table costs one small memset and its entries' pages are touched only when used.
 */
#include "exact/exact_cache.h"
#include "base/parallel.h"

#include <string.h>

/* 4096 entries of about 1 KB: a face's points in the worst arrangements measured (a few
 * thousand) stay in the table while the face is sorted and triangulated. */
#define TABLE_BITS 12
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

mci_exact_point *mci_exact_cache_slot(const mci_point *p)
{
    exact_table *t = thread_table();
    uint64_t h;
    if (!t)
        return NULL;
    h = definition_hash(p);
    return &t->entry[h & (TABLE_SIZE - 1)];
}

/* The table that holds entry e, and e's index in it. */
static uint32_t *tag_for(mci_exact_point *e)
{
    exact_table *t = thread_table();
    return t ? &t->tag[e - t->entry] : NULL;
}

bool mci_exact_cache_holds(const mci_exact_point *e, const mci_point *p)
{
    int n = mci_point_vertex_count(p);
    uint32_t *tag = tag_for((mci_exact_point *)e);
    if (!tag || *tag != tag_of(definition_hash(p)) || e->kind != p->kind ||
        memcmp(e->v, p->v, (size_t)n * sizeof p->v[0]) != 0)
        return false;
    for (int i = 0; i < n; i++)
        if (memcmp(e->coords[i], p->v[i], sizeof e->coords[i]) != 0)
            return false;
    return true;
}

void mci_exact_cache_claim(mci_exact_point *e, const mci_point *p)
{
    int n = mci_point_vertex_count(p);
    uint32_t *tag = tag_for(e);
    if (!tag)
        return;
    e->kind = p->kind;
    memcpy(e->v, p->v, (size_t)n * sizeof p->v[0]);
    for (int i = 0; i < n; i++)
        memcpy(e->coords[i], p->v[i], sizeof e->coords[i]);
    *tag = tag_of(definition_hash(p));
}

void mci_exact_cache_clear(mci_exact_point *e)
{
    uint32_t *tag = tag_for(e);
    if (tag)
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

/*
 * Reading the files of import() calls before the tree is built, several at once.
 *
 * Parsing a big mesh file is most of mcsg_scad_read's time, and the walk that builds the
 * tree meets the imports one after another. So every import() whose file argument is a
 * string literal is read first, on the options' threads; the walk then takes the meshes
 * from here. Nothing observable changes: a file is resolved as import does it, a file
 * that fails to read is read again when its call is reached (which reports the error
 * where and when it did), and the messages a read logs are captured and logged again by
 * the call that uses the mesh, from the calling thread and in program order. A file
 * named by several calls is read once; each call but the last gets a copy.
 */
#include "base/parallel.h"
#include "scad/scad.h"

#include <stdlib.h>
#include <string.h>

typedef struct prefetched {
    char *path;
    uint32_t uses;      /* literal import() calls naming this path, not served yet */
    mcsg_status status; /* of the read */
    bool log_lost;      /* a message could not be kept (out of memory) */
    mcsg_mesh mesh;
    mci_buf log;        /* messages: a level byte, the text, a NUL; in order */
    const mci_ctx *ctx;
} prefetched;

/* The literal file name of import call `stmt` (positional or file=/filename=), if any. */
static bool literal_file(const scad_program *prog, const scad_stmt *stmt, const char **file,
                         uint32_t *len)
{
    for (uint32_t i = 0; i < stmt->arg_count; i++) {
        const scad_arg *arg = &prog->args[stmt->arg_begin + i];
        const char *name = prog->text + arg->name_start;
        const scad_expr *e = &prog->exprs[arg->expr_begin];
        bool file_slot = arg->name_len == 0
                             ? i == 0
                             : (arg->name_len == 4 && memcmp(name, "file", 4) == 0) ||
                                   (arg->name_len == 8 && memcmp(name, "filename", 8) == 0);
        if (!file_slot || arg->expr_end != arg->expr_begin + 1 || e->op != EX_STRING ||
            e->b == 0)
            continue;
        *file = (const char *)prog->strings.data + e->a;
        *len = e->b;
        return memchr(*file, 0, *len) == NULL && !scad_is_3mf_name(*file, *len) &&
               !scad_is_amf_name(*file, *len) && !scad_is_dxf_name(*file, *len) &&
               !scad_is_svg_name(*file, *len);
    }
    return false;
}

bool scad_is_3mf_name(const char *file, uint32_t len)
{
    return len >= 4 && file[len - 4] == '.' && file[len - 3] == '3' &&
           (file[len - 2] | 32) == 'm' && (file[len - 1] | 32) == 'f';
}

bool scad_is_amf_name(const char *file, uint32_t len)
{
    return len >= 4 && file[len - 4] == '.' && (file[len - 3] | 32) == 'a' &&
           (file[len - 2] | 32) == 'm' && (file[len - 1] | 32) == 'f';
}

bool scad_is_dxf_name(const char *file, uint32_t len)
{
    return len >= 4 && file[len - 4] == '.' && (file[len - 3] | 32) == 'd' &&
           (file[len - 2] | 32) == 'x' && (file[len - 1] | 32) == 'f';
}

bool scad_is_svg_name(const char *file, uint32_t len)
{
    return len >= 4 && file[len - 4] == '.' && (file[len - 3] | 32) == 's' &&
           (file[len - 2] | 32) == 'v' && (file[len - 1] | 32) == 'g';
}

/* The path import() opens for `file`: relative names under the base directory. */
static char *resolve(const mci_ctx *ctx, const char *dir, const char *file, uint32_t len)
{
    size_t dir_len = dir && file[0] != '/' ? strlen(dir) : 0;
    bool slash = dir_len && dir[dir_len - 1] != '/';
    char *path = mci_malloc(ctx, dir_len + slash + len + 1);
    if (!path)
        return NULL;
    if (dir_len) /* dir may be NULL, and memcpy's pointers may not */
        memcpy(path, dir, dir_len);
    if (slash)
        path[dir_len] = '/';
    memcpy(path + dir_len + slash, file, len);
    path[dir_len + slash + len] = 0;
    return path;
}

static int compare_paths(const void *a, const void *b)
{
    return strcmp(((const prefetched *)a)->path, ((const prefetched *)b)->path);
}

/* One entry per distinct literal path, sorted by path, uses counted. */
static bool collect(const scad_context *sc, scad_prefetch *pf)
{
    const scad_program *prog = sc->prog;
    const mci_ctx *ctx = sc->ev.ctx;
    size_t n = 0, kept = 0;
    for (uint32_t s = 0; s < prog->stmt_count; s++)
        n += prog->stmts[s].kind == ST_CALL && prog->stmts[s].module == MOD_IMPORT;
    if (n == 0)
        return true;
    if (!(pf->entries = mci_calloc_array(ctx, n, sizeof *pf->entries)))
        return false;
    for (uint32_t s = 0; s < prog->stmt_count; s++) {
        const scad_stmt *stmt = &prog->stmts[s];
        const char *file;
        uint32_t len;
        if (stmt->kind != ST_CALL || stmt->module != MOD_IMPORT ||
            !literal_file(prog, stmt, &file, &len))
            continue;
        if (!(pf->entries[pf->count].path = resolve(ctx, sc->base_dir, file, len)))
            return false;
        pf->entries[pf->count].ctx = ctx;
        pf->entries[pf->count++].uses = 1;
    }
    if (pf->count > 1)
        qsort(pf->entries, pf->count, sizeof *pf->entries, compare_paths);
    for (size_t i = 0; i < pf->count; i++) {
        if (kept > 0 && strcmp(pf->entries[kept - 1].path, pf->entries[i].path) == 0) {
            pf->entries[kept - 1].uses++;
            mci_free(ctx, pf->entries[i].path);
            continue;
        }
        pf->entries[kept++] = pf->entries[i];
    }
    pf->count = kept;
    return true;
}

static void capture(void *user, mcsg_log_level level, const char *message)
{
    prefetched *p = user;
    unsigned char byte = (unsigned char)level;
    if (!mci_buf_append(p->ctx, &p->log, &byte, 1) ||
        !mci_buf_append(p->ctx, &p->log, message, strlen(message) + 1))
        p->log_lost = true;
}

typedef struct read_job {
    scad_prefetch *pf;
    const mcsg_options *opts;
} read_job;

static mcsg_status read_one(void *user, size_t i, mcsg_error *err)
{
    const read_job *j = user;
    prefetched *p = &j->pf->entries[i];
    mcsg_options opts;
    mcsg_error read_err;
    if (j->opts)
        opts = *j->opts;
    else
        memset(&opts, 0, sizeof opts);
    opts.log = capture;
    opts.log_user = p;
    opts.progress = NULL;
    opts.threads = 1;
    p->status = mcsg_mesh_read(p->path, MCSG_FORMAT_AUTO, &opts, &p->mesh, &read_err);
    /* Running out of memory ends the read here; other failures are repeated, and
     * reported, by the call (which may never run). */
    if (p->status == MCSG_ERR_NOMEM) {
        if (err)
            *err = read_err;
        return MCSG_ERR_NOMEM;
    }
    return p->log_lost ? mci_fail_nomem(err, "reading CSG text") : MCSG_OK;
}

mcsg_status scad_prefetch_imports(scad_context *sc, mcsg_error *err)
{
    scad_prefetch *pf = &sc->prefetch;
    read_job job = {pf, sc->opts};
    memset(pf, 0, sizeof *pf);
    if (!collect(sc, pf))
        return mci_fail_nomem(err, "reading CSG text");
    return mci_parallel_for(sc->ev.ctx, pf->count, read_one, &job, err);
}

static prefetched *find(const scad_prefetch *pf, const char *path)
{
    size_t lo = 0, hi = pf->count;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        int c = strcmp(pf->entries[mid].path, path);
        if (c == 0)
            return &pf->entries[mid];
        if (c < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    return NULL;
}

mcsg_status scad_prefetch_take(scad_context *sc, const char *path, mcsg_mesh *mesh,
                               bool *found, mcsg_error *err)
{
    prefetched *p = find(&sc->prefetch, path);
    *found = false;
    if (!p || p->uses == 0 || p->status != MCSG_OK)
        return MCSG_OK;
    if (p->uses > 1) {
        mcsg_status st = mcsg_mesh_copy(&p->mesh, sc->opts, mesh, err);
        if (st != MCSG_OK)
            return st;
    } else {
        *mesh = p->mesh;
        memset(&p->mesh, 0, sizeof p->mesh);
    }
    p->uses--;
    *found = true;
    for (size_t at = 0; at < p->log.len;) {
        const char *text = (const char *)p->log.data + at + 1;
        mci_log(sc->ev.ctx, (mcsg_log_level)p->log.data[at], "%s", text);
        at += 2 + strlen(text);
    }
    return MCSG_OK;
}

void scad_prefetch_free(scad_context *sc)
{
    const mci_ctx *ctx = sc->ev.ctx;
    scad_prefetch *pf = &sc->prefetch;
    if (!pf->entries)
        return;
    for (size_t i = 0; i < pf->count; i++) {
        mci_free(ctx, pf->entries[i].path);
        mci_mesh_free(ctx, &pf->entries[i].mesh);
        mci_buf_free(ctx, &pf->entries[i].log);
    }
    mci_free(ctx, pf->entries);
    memset(pf, 0, sizeof *pf);
}

/*
 * 3MF reading and writing (threemf.c): the build items of a 3MF file as meshes, and
 * meshes as a 3MF file of one object and build item each. Not part of the public API.
 */
#ifndef MESHCSG_IO_THREEMF_H
#define MESHCSG_IO_THREEMF_H

#include "io/mesh_io.h"

/* A 3MF file's build items: one mesh each (components and transforms applied,
 * millimetres), and the name of the object each places ("" when it has none). */
typedef struct mci_3mf_items {
    mcsg_mesh *meshes;
    char **names;
    size_t count;
} mci_3mf_items;

mcsg_status mci_3mf_read(const mci_io_source *src, mci_3mf_items *out);
void mci_3mf_items_free(const mci_ctx *ctx, mci_3mf_items *items);
/* Every build item in one mesh (their shells side by side). */
mcsg_status mci_3mf_read_merged(const mci_io_source *src, mcsg_mesh *out);
/* The zip container's bytes; MCSG_ERR_NOMEM when libzip or an allocation fails. */
mcsg_status mci_3mf_write(const mci_ctx *ctx, const mcsg_mesh *meshes, size_t count,
                          mci_buf *out);

#endif

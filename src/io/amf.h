/*
 * AMF (Additive Manufacturing File format, ISO/ASTM 52915) read as OpenSCAD 2021.01's
 * import() reads it (amf.c): the triangles of each object's volumes as one mesh per
 * object, plain XML or a zip archive holding it. Reading only. Not part of the public
 * API: mcsg_mesh_read reads .amf files through it, import() through mci_amf_read_file.
 */
#ifndef MESHCSG_IO_AMF_H
#define MESHCSG_IO_AMF_H

#include "io/mesh_io.h"

/* An AMF file's objects in file order. Each mesh holds the object's vertices as listed
 * and the triangles of all its volumes, volume after volume (OpenSCAD makes one polygon
 * set per object); names[k] is the object's <metadata type="name"> ("" without one). */
typedef struct mci_amf_objects {
    mcsg_mesh *meshes;
    char **names;
    size_t count;
} mci_amf_objects;

/* Reads src: a zip archive (it starts with "PK") is opened and its entry named like
 * src->name's last path component is read, or its only entry; anything else is the XML.
 * Only the elements OpenSCAD reads count: amf/object/mesh/vertices/vertex/coordinates
 * with x, y, z and amf/object/mesh/volume/triangle with v1, v2, v3, each number the whole
 * text of its element. Units, constellations, materials, colours and metadata other than
 * an object's name change nothing (OpenSCAD ignores them). A document without objects
 * gives count 0. Errors: MCSG_ERR_PARSE naming "NAME:LINE:" ("NAME: ENTRY:LINE:" inside
 * a zip) for malformed XML, a root element other than <amf>, a number that is not one, a
 * vertex or triangle missing a value, or a triangle index not below the count of the
 * object's vertices listed before it (OpenSCAD reads past its list there);
 * MCSG_ERR_LIMIT past 2^32-1 vertices or triangles in an object or 1 GiB of zipped XML;
 * MCSG_ERR_NOMEM. *out is zeroed first, owned by the caller on success and empty after a
 * failure. expat and libzip allocate with malloc, the meshes with src->ctx. */
mcsg_status mci_amf_read(const mci_io_source *src, mci_amf_objects *out);

/* mci_amf_read of the file at `path` (errors name it; MCSG_ERR_IO when it cannot be
 * read). */
mcsg_status mci_amf_read_file(const mci_ctx *ctx, const char *path, mci_amf_objects *out,
                              mcsg_error *err);

void mci_amf_objects_free(const mci_ctx *ctx, mci_amf_objects *objects);

/* Every object in one mesh, side by side (mcsg_mesh_read's view of an AMF file). */
mcsg_status mci_amf_read_merged(const mci_io_source *src, mcsg_mesh *out);

/* Whether a file name ends in ".amf" (case-insensitive), as OpenSCAD's import() decides. */
bool mci_amf_is_name(const char *name);

/* Whether the bytes are XML whose first element is <amf> (after an optional byte order
 * mark, XML declaration, comments and document type): content detection for
 * mcsg_mesh_read, which no other mesh format it reads can match. */
bool mci_amf_looks_like(const char *text, size_t size);

#endif

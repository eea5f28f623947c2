/*
 * Internal interface of the modules that use their children's geometry: the sweeps of
 * extrude.c, called by geometry.c.
 */
#ifndef MESHCSG_SCAD_GEOMETRY_H
#define MESHCSG_SCAD_GEOMETRY_H

#include "scad/scad.h"
#include "shape/region.h"

/* The region (with its boundary as outlines carrying region vertex ids) extruded as
 * linear_extrude or rotate_extrude with op's parameters, as a closed mesh. */
mcsg_status scad_linear_extrude(scad_context *sc, const scad_geometry_op *op,
                                const mci_region *r, const mci_outlines *o, mcsg_mesh *out,
                                mcsg_error *err);
mcsg_status scad_rotate_extrude(scad_context *sc, const scad_geometry_op *op,
                                const mci_region *r, const mci_outlines *o, mcsg_mesh *out,
                                mcsg_error *err);

#endif

/*
 * parts.h - private to repair/: which closed shells of a checked mesh are
 * parts to print and which are cavities inside them (docs/check.md,
 * "Parts and cavities").  topology.c is the only user.
 */
#ifndef STRATUM_REPAIR_PARTS_H
#define STRATUM_REPAIR_PARTS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "st_error.h"

struct parts_out {
	size_t parts;	  /* outward shells in empty space, with their cavities */
	size_t cavities;  /* inward shells in material */
	size_t misnested; /* shells in material facing out, or in empty space facing in */
	size_t unpaired;  /* singular edges whose triangles do not pair up as a solid's */
};

/*
 * parts_nest - group the *nshells shells of m into parts.  in_layer[t]
 * says whether triangle t is analysed; shell[t] numbers its shell
 * (0..*nshells-1), joined across two-triangle edges.  With nest false (the
 * mesh is not a closed, intersection-free, consistently oriented set of
 * shells, so nesting means nothing) every shell is its own part.
 * Otherwise, when singular is set (there are singular edges), shell and
 * *nshells are first regrouped as Def. 3.10 needs for a solid: at a
 * singular edge each triangle joins the one it faces through the material
 * (hull_manifold_components), and out->unpaired counts the edges where
 * that fails.  Then each shell's side
 * follows from the sign of its volume and its place from exact
 * containment tests: walking in from empty space, an outward shell enters
 * material, an inward one leaves it, and a shell that does neither is
 * misnested.  part (NULL or m->ntris entries) receives each triangle's
 * part, UINT32_MAX for triangles not analysed; around (NULL or m->ntris
 * entries) for each part the part whose cavity holds it, UINT32_MAX for
 * none.  Returns 0 or a negative
 * class with err filled.
 */
int parts_nest(const struct mesh *m, const uint8_t *in_layer, uint32_t *shell, size_t *nshells,
	       bool nest, bool singular, uint32_t *part, uint32_t *around, struct parts_out *out,
	       struct st_error *err);

#endif /* STRATUM_REPAIR_PARTS_H */

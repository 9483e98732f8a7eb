/*
 * repair.h - seed 000's as-exact-as-possible repair: any triangle soup in,
 * printable solids out (Definition 3.11), with nothing that was already
 * solid moved.
 *
 * The pipeline (seed 000 §4, with the healing of §5.2 made automatic):
 *  0. heal (repair/heal.c): weld vertices closer than a few float ulps,
 *     stitch boundary that lies within gamma of other boundary, fill holes
 *     whose patch closes a small part of a shell; what is left open stays
 *     a sheet;
 *  1. clean: drop irregular triangles, set degenerate ones aside as wire
 *     segments, keep one layer of equivalent triangles (Def. 3.1);
 *  2. resolve every self-intersection exactly (CGAL Epeck, constrained
 *     triangulation of each cut triangle), so the mesh is a polyhedron;
 *  3. outer hull by non-manifold region growing (Algorithms 1 and 2):
 *     M_solid (outer), M_sheet (double-sided), interior triangles deleted,
 *     components enclosed by another component deleted unless the input
 *     faced them inwards (cavities, kept);
 *  4. when M_sheet or visible wires exist: thicken them to solids of total
 *     thickness epsilon and run 2-3 again on M_solid and the new solids;
 *  5. round to the output precision, re-checking exactly, so the written
 *     file is itself printable; drop parts smaller than epsilon in every
 *     direction and number the rest (solids with their cavities).
 *
 * Exactness: vertices created by step 2 are exact rationals inside the CGAL
 * bridge until step 5; every decision (radial order around a singular edge,
 * seed orientation, containment) is an exact predicate.
 */
#ifndef STRATUM_REPAIR_REPAIR_H
#define STRATUM_REPAIR_REPAIR_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "st_error.h"

/* How coordinates of the result must be representable when written. */
enum repair_precision {
	REPAIR_FLOAT32,	/* binary STL: every coordinate a float */
	REPAIR_FLOAT64,	/* ASCII STL / OBJ with 17 significant digits */
};

struct repair_options {
	double epsilon;		/* thickness for sheets and wires, mm (> 0) */
	enum repair_precision precision;
	int threads;		/* cores for the exact passes; 0 = all */
	/* Healing (docs/repair.md "Healing"): < 0 picks the default, 0 = off. */
	double weld;		/* mm: weld vertices this close; default 8 float32 ulps */
	double stitch;		/* mm: gamma, stitch boundary this close; default 1.5 eps */
	bool keep_holes;	/* no stitching or hole filling (the seed's pipeline) */
	/* Called now and then with the phase as a sentence ("cutting the
	 * crossing triangles") and 0..1 of that phase done, from worker
	 * threads too but one call at a time; may be NULL. */
	void (*progress)(void *ctx, const char *stage, double done);
	void *progress_ctx;
};

/* What the repair did; every count refers to triangles unless named. */
/* Hole areas listed one by one in the report (the rest only summed). */
#define REPAIR_HOLES_LISTED 8

struct repair_report {
	size_t input_triangles;
	/* Healing, before everything else (docs/repair.md "Healing"). */
	double weld_tolerance;		/* mm, as used */
	size_t welded_vertices;		/* merged into another vertex */
	size_t weld_collapsed;		/* triangles welding shrank to an edge, dropped */
	double stitch_tolerance;	/* mm, gamma as used; 0 = stitching off */
	size_t stitched_vertices;	/* boundary vertices snapped onto other boundary */
	size_t stitched_gaps;		/* pairs of boundary loops joined */
	double stitch_max_gap;		/* mm: longest snap */
	size_t stitch_collapsed;	/* triangles stitching shrank to an edge, dropped */
	size_t holes_filled;		/* boundary loops closed by a patch */
	size_t fill_triangles;		/* triangles the patches added */
	double fill_area;		/* mm^2, all patches */
	double hole_area[REPAIR_HOLES_LISTED]; /* mm^2, the first holes filled */
	size_t holes_kept;		/* loops left open: their shells stay sheets */
	double kept_patch_fraction;	/* smallest patch/shell area ratio among kept shells */
	size_t holes_crossing;		/* of those kept: their patch would cross the model */
	size_t irregular_removed;	/* repeated vertex index */
	size_t degenerate_removed;	/* collinear corners: kept as wires */
	size_t duplicates_removed;	/* equivalent triangles beyond one layer */
	uint64_t intersecting_pairs;	/* pairs cut by the first exact pass */
	size_t triangles_split;		/* triangles re-triangulated (first pass) */
	size_t interior_deleted;	/* not on the outer hull (first pass) */
	size_t enclosed_deleted;	/* in components inside another (first pass) */
	size_t enclosed_components;	/* those components: shells facing out inside a solid */
	size_t cavities;		/* inward shells kept as cavities (in the output) */
	size_t parts_dropped;		/* parts smaller than epsilon in every direction */
	size_t dropped_triangles;	/* their triangles */
	size_t sheet_triangles;		/* M_sheet after the first pass */
	double sheet_area;		/* mm^2 */
	size_t sheet_components;	/* edge-connected parts of M_sheet */
	size_t wires;			/* wire segments thickened */
	double wire_length;		/* mm */
	size_t wires_discarded;		/* on the surface or inside the solid */
	bool second_pass;		/* thickening happened, steps 2-3 ran again */
	size_t thickened_triangles;	/* triangles the thickening produced */
	size_t second_sheet_triangles;	/* M_sheet of the second pass: must be 0 */
	int rounding_rounds;		/* re-check rounds after rounding (0 = none needed) */
	size_t rounding_dropped;	/* zero-thickness slivers rounding collapsed, dropped */
	size_t rounding_merged;		/* vertices snap rounding merged into a neighbour */
	double solid_deviation;		/* mm: solid parts vs input triangles (doubles; ~1e-13) */
	double rounding_deviation;	/* mm: largest move a vertex made when rounded */
	double sheet_deviation;		/* mm: thickened surface to its sheet/wire, max */
	size_t output_triangles;
	size_t output_vertices;
	size_t components;		/* parts: outward shells with their cavities */
	size_t batches;			/* independent groups repaired apart (1: whole) */
	bool batch_fallback;		/* one group's result lay in another's: redone whole */
	bool printable;			/* the result passes Def. 3.11 after rounding */
	char why[256];			/* when !printable: the reason, one sentence */
};

/* Defaults: epsilon 0.4 mm, float32 output, all cores, no progress, healing
 * with default tolerances. */
void repair_options_init(struct repair_options *opt);

/*
 * repair_mesh - repair in into a new mesh *out (caller frees with
 * mesh_free), filling *rep.  *out holds every part; component[i] (when
 * component is non-NULL, a malloc'd array the caller frees) gives the
 * part of output triangle i, numbered 0..rep->components-1: a solid
 * (a manifold-connected shell, Def. 3.10) and the cavities inside it, so
 * that each part written alone passes `stratum check` as the whole does.
 *
 * Returns 0 with rep->printable telling whether a printable result was
 * reached (when not, *out still holds the best result and rep->why says
 * what is wrong), or a negative class with err filled and *out NULL:
 * ST_ERR_ARG (bad options), ST_ERR_NOMEM, ST_ERR_INTERNAL; then *rep
 * holds what the first core run measured before the failure.
 */
int repair_mesh(const struct mesh *in, const struct repair_options *opt, struct mesh **out,
		uint32_t **component, struct repair_report *rep, struct st_error *err);

#endif /* STRATUM_REPAIR_REPAIR_H */

/*
 * repair_impl.h - private to repair/: the pipeline's parts shared by
 * repair.c (healing, rounding, the whole mesh), repair_core.c (one core
 * run) and repair_batches.c (independent groups).
 */
#ifndef STRATUM_REPAIR_REPAIR_IMPL_H
#define STRATUM_REPAIR_REPAIR_IMPL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "batch.h"
#include "exact.h"
#include "mesh.h"
#include "repair.h"
#include "st_error.h"
#include "vec3.h"

/* What one core run produces. */
struct core_out {
	struct exact_mesh *result;	/* M_solid, oriented outwards */
	size_t irregular, degenerate, duplicates;
	uint64_t pairs;
	size_t split, interior, enclosed, enclosed_components;
	size_t sheet, sheet_components, second_sheet;
	double sheet_area, wire_length, sheet_deviation;
	size_t wires, wires_discarded, thickened;
	bool second_pass;
};

/*
 * repair_core - seed 000 §4 on one mesh: clean, refine, hull, and when
 * thicken_sheets_too, thicken sheets and visible wires and refine + hull
 * once more.  co->result receives M_solid, oriented outwards (co is
 * filled on failure too, as far as it got).  Returns 0 or a negative
 * class with err filled.
 */
int repair_core(const struct mesh *in, const struct repair_options *opt, bool thicken_sheets_too,
		struct core_out *co, struct st_error *err);

/* Tell opt's progress callback, if any, that stage is done to this fraction. */
static inline void repair_progress(const struct repair_options *opt, const char *stage,
				   double done)
{
	if (opt->progress)
		opt->progress(opt->progress_ctx, stage, done);
}

/*
 * A unit in the last place of the output precision at the largest
 * coordinate of verts (0 when all are 0): points closer than this are one
 * point once written.
 */
static inline double repair_output_ulp(const double (*verts)[3], size_t nv,
				       enum repair_precision prec)
{
	return vec3_ulp(verts, nv, prec == REPAIR_FLOAT32 ? 24 : 53);
}

/*
 * repair_rounded - repair in (healed already) up to the rounded mesh
 * *rounded: clean, refine, hull, thicken, second pass, round and re-check;
 * fills the core and rounding half of rep.  *known: the self-intersection
 * count of *rounded when a pass already proved it, else -1.  Returns 0 or
 * a negative class with err filled.
 */
int repair_rounded(const struct mesh *in, const struct repair_options *opt,
		   struct mesh **rounded, long long *known, struct repair_report *rep,
		   struct st_error *err);

/*
 * repair_rounded_batches - repair_rounded for each batch of bs (the
 * independent groups of in, batch.h) on all the cores, the results put
 * side by side in *rounded, batch after batch; *batch_of receives the
 * batch of each triangle of *rounded (caller frees).  The groups' results
 * lie apart, so *known is the sum of their counts.
 */
int repair_rounded_batches(const struct mesh *in, const struct repair_options *opt,
			   const struct batches *bs, struct mesh **rounded, uint32_t **batch_of,
			   long long *known, struct repair_report *rep, struct st_error *err);

#endif /* STRATUM_REPAIR_REPAIR_IMPL_H */

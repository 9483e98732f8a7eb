/*
 * repair_impl.h - private to repair/: the pipeline's halves shared by
 * repair.c (the whole mesh) and repair_batches.c (independent groups).
 */
#ifndef STRATUM_REPAIR_REPAIR_IMPL_H
#define STRATUM_REPAIR_REPAIR_IMPL_H

#include <stdint.h>

#include "batch.h"
#include "mesh.h"
#include "repair.h"
#include "st_error.h"

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

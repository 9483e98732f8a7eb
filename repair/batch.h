/*
 * batch.h - private to repair/: independent groups of a mesh, repaired one
 * by one (docs/repair.md "Independent groups").
 *
 * Two groups of triangles are independent when no triangle of one comes
 * near a triangle of the other (BATCH_REACH) and neither encloses the
 * other: nothing one group's repair does (cuts, the outer hull, slabs and
 * wires of at most epsilon/2, rounding) can reach the other.  Repairing
 * each group alone and putting the results side by side then gives the
 * result of repairing the whole, with a fraction of the memory, and the
 * groups keep both cores busy.  Enclosure is checked on the results
 * (repair_finish_parts in output.h): where one lies in another, the whole
 * is repaired at once after all.
 */
#ifndef STRATUM_REPAIR_BATCH_H
#define STRATUM_REPAIR_BATCH_H

#include <stddef.h>
#include <stdint.h>

#include "mesh.h"
#include "st_error.h"

/*
 * Distance, in epsilons, below which two triangles belong to one group.
 * Thickening puts nothing further than epsilon/2 from its sheet or wire
 * (docs/repair.md), so triangles more than epsilon apart stay apart; the
 * 5 % over that covers the doubles of the test.  The caller adds what
 * rounding may move.
 */
#define BATCH_REACH 1.05

/* Triangles above which a batch takes no further group. */
#define BATCH_TRIANGLES 4096

/*
 * Batches: each a set of whole groups, in the order of their first
 * triangle; batch b holds the triangles tri[start[b] .. start[b+1]), in
 * input order.
 */
struct batches {
	size_t n;
	size_t *start;	/* n + 1 entries */
	uint32_t *tri;
};

/*
 * batches_find - split m into groups whose triangles all lie further than
 * reach mm from the other groups' (BATCH_REACH epsilon and the rounding,
 * batch_reach in repair.c) and gather them into batches of about BATCH_TRIANGLES triangles.  A mesh that is one
 * group (or whose boxes are too tangled to sort cheaply) is one batch.
 * Returns 0, or ST_ERR_NOMEM with err filled.
 */
int batches_find(const struct mesh *m, double reach, struct batches *out, struct st_error *err);

void batches_free(struct batches *b);

/*
 * Called for each batch, on one of the worker threads: repair sub (the
 * batch as a mesh of its own, triangles in input order) with `threads`
 * cores.  Returns 0 or a negative class with err filled.
 */
typedef int (*batch_fn)(void *ctx, size_t batch, const struct mesh *sub, int threads,
			struct st_error *err);

/*
 * batches_run - call fn for every batch of b, on up to `threads` worker
 * threads (0 = all cores).  A batch with more than half the triangles runs
 * first, alone, with every core; the rest run one per core, largest
 * first.  done, when not NULL, is called after each batch (serialised)
 * with the fraction of triangles done.  Stops at the first failure and
 * returns its class (err filled), else 0.
 */
int batches_run(const struct mesh *m, const struct batches *b, int threads, batch_fn fn,
		void *ctx, void (*done)(void *ctx, double fraction), struct st_error *err);

#endif /* STRATUM_REPAIR_BATCH_H */

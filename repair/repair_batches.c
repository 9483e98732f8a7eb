/*
 * repair_batches.c - the repair of independent groups side by side
 * (repair_impl.h, batch.h; docs/repair.md "Independent groups").
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "batch.h"
#include "repair_impl.h"

/* Add what one batch's repair_rounded measured to the whole's report. */
static void report_add(struct repair_report *sum, const struct repair_report *b)
{
	sum->irregular_removed += b->irregular_removed;
	sum->degenerate_removed += b->degenerate_removed;
	sum->duplicates_removed += b->duplicates_removed;
	sum->intersecting_pairs += b->intersecting_pairs;
	sum->triangles_split += b->triangles_split;
	sum->interior_deleted += b->interior_deleted;
	sum->enclosed_deleted += b->enclosed_deleted;
	sum->enclosed_components += b->enclosed_components;
	sum->sheet_triangles += b->sheet_triangles;
	sum->sheet_area += b->sheet_area;
	sum->sheet_components += b->sheet_components;
	sum->wires += b->wires;
	sum->wire_length += b->wire_length;
	sum->wires_discarded += b->wires_discarded;
	sum->second_pass |= b->second_pass;
	sum->thickened_triangles += b->thickened_triangles;
	sum->second_sheet_triangles += b->second_sheet_triangles;
	sum->sheet_deviation = fmax(sum->sheet_deviation, b->sheet_deviation);
	sum->solid_deviation = fmax(sum->solid_deviation, b->solid_deviation);
	sum->rounding_deviation = fmax(sum->rounding_deviation, b->rounding_deviation);
	if (b->rounding_rounds > sum->rounding_rounds)
		sum->rounding_rounds = b->rounding_rounds;
	sum->rounding_dropped += b->rounding_dropped;
	sum->rounding_merged += b->rounding_merged;
}

/* The batches' results, filled by the worker threads. */
struct batch_results {
	const struct repair_options *opt;
	size_t ntris; /* of the whole mesh */
	struct mesh **rounded;
	long long *known;
	struct repair_report *rep;
};

/* The phases of the group that runs alone, named as its. */
static void big_progress(void *ctx, const char *stage, double done)
{
	const struct batch_results *r = ctx;
	char s[128];

	snprintf(s, sizeof(s), "largest group: %s", stage);
	r->opt->progress(r->opt->progress_ctx, s, done);
}

static int repair_batch(void *ctx, size_t b, const struct mesh *sub, int threads,
			struct st_error *err)
{
	struct batch_results *r = ctx;
	struct repair_options o = *r->opt;
	struct mesh_report mr;
	int rc;

	o.threads = threads;
	/* batches_run reports, from one thread at a time; a group of most of
	 * the mesh runs first and alone, so it tells its own phases */
	o.progress = r->opt->progress && 2 * sub->ntris > r->ntris ? big_progress : NULL;
	o.progress_ctx = r;
	rc = repair_rounded(sub, &o, &r->rounded[b], &r->known[b], &r->rep[b], err);
	/* Counted here, on this batch's core, rather than on the whole later. */
	if (!rc && r->known[b] < 0) {
		rc = mesh_analyze(r->rounded[b], threads, &mr, err);
		r->known[b] = rc ? -1 : (long long)mr.self_intersections;
	}
	return rc;
}

static void batch_done(void *ctx, double fraction)
{
	struct batch_results *r = ctx;

	if (r->opt->progress)
		r->opt->progress(r->opt->progress_ctx, "repairing the separate groups", fraction);
}

/* repair_impl.h */
int repair_rounded_batches(const struct mesh *in, const struct repair_options *opt,
				  const struct batches *bs, struct mesh **rounded,
				  uint32_t **batch_of, long long *known,
				  struct repair_report *rep, struct st_error *err)
{
	struct batch_results r = {.opt = opt, .ntris = in->ntris};
	struct mesh_builder *all = NULL;
	int rc;

	r.rounded = calloc(bs->n, sizeof(*r.rounded));
	r.known = calloc(bs->n, sizeof(*r.known));
	r.rep = calloc(bs->n, sizeof(*r.rep));
	all = mesh_builder_new(in->ntris);
	if (!r.rounded || !r.known || !r.rep || !all) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory for %zu groups", bs->n);
		goto out;
	}
	batch_done(&r, 0);
	rc = batches_run(in, bs, opt->threads, repair_batch, &r, batch_done, err);
	*known = 0;
	for (size_t b = 0; b < bs->n; b++) {
		report_add(rep, &r.rep[b]);
		if (!rc && r.rounded[b])
			rc = mesh_builder_append(all, r.rounded[b], err);
		*known += r.known[b];
	}
	if (!rc) {
		*rounded = mesh_builder_finish(all);
		all = NULL;
		*batch_of = *rounded ? malloc(((*rounded)->ntris + 1) * sizeof(**batch_of)) : NULL;
		if (!*batch_of)
			rc = st_error_set(err, ST_ERR_NOMEM, "out of memory joining the groups");
		for (size_t b = 0, t = 0; !rc && b < bs->n; b++)
			for (size_t i = 0; i < r.rounded[b]->ntris; i++)
				(*batch_of)[t++] = (uint32_t)b;
	}
out:
	mesh_builder_free(all);
	for (size_t b = 0; r.rounded && b < bs->n; b++)
		mesh_free(r.rounded[b]);
	free(r.rounded);
	free(r.known);
	free(r.rep);
	return rc;
}


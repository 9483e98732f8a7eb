/*
 * output.c - the last step of the repair (output.h): check the rounded
 * result as `stratum check` will, drop parts a nozzle cannot draw, number
 * the parts for --split.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "output.h"

/*
 * Whether a checked result may be written: printable as `stratum check`
 * judges it (several parts and cavities allowed, docs/check.md) and free
 * of the warnings a repair must not leave behind.
 */
bool repair_result_printable(const struct mesh_report *mr)
{
	return mr->printable && !mr->reasons[MESH_REASON_DUPLICATE] &&
	       !mr->reasons[MESH_REASON_INSIDE_OUT] &&
	       !mr->reasons[MESH_REASON_INCONSISTENT_ORIENTATION];
}

/* The first blocking reason of a report, as one sentence. */
static void explain(const struct mesh_report *mr, char *why, size_t cap)
{
	for (int r = 0; r < MESH_REASON_COUNT; r++)
		if (mr->reasons[r] && r != MESH_REASON_SEVERAL_PARTS &&
		    r != MESH_REASON_NOT_MANIFOLD_CONNECTED) {
			snprintf(why, cap, "the result has %s", mesh_reason_text((enum mesh_reason)r));
			return;
		}
	snprintf(why, cap, "the result is not printable");
}

/*
 * Leave out the parts (each solid with its cavities) that are smaller than
 * epsilon in every direction: a nozzle of that width cannot draw them.
 * part gives each triangle's part; the rest of m is kept as it is, so
 * what was printable stays so.  Returns a new mesh (NULL on OOM), or m
 * itself when nothing is that small.
 */
static struct mesh *drop_tiny_parts(struct mesh *m, const uint32_t *part, size_t nparts,
				    double epsilon, struct repair_report *rep)
{
	double (*lo)[3] = malloc((nparts + 1) * sizeof(*lo));
	double (*hi)[3] = malloc((nparts + 1) * sizeof(*hi));
	uint8_t *tiny = calloc(nparts + 1, 1);
	struct mesh_builder *b = NULL;
	struct mesh *res = NULL;
	size_t ntiny = 0;
	int rc = 0;

	if (!lo || !hi || !tiny)
		goto out;
	for (size_t p = 0; p < nparts; p++)
		for (int k = 0; k < 3; k++) {
			lo[p][k] = HUGE_VAL;
			hi[p][k] = -HUGE_VAL;
		}
	for (size_t t = 0; t < m->ntris; t++)
		for (int c = 0; c < 3 && part[t] < nparts; c++)
			for (int k = 0; k < 3; k++) {
				lo[part[t]][k] = fmin(lo[part[t]][k], m->verts[m->tris[t][c]][k]);
				hi[part[t]][k] = fmax(hi[part[t]][k], m->verts[m->tris[t][c]][k]);
			}
	for (size_t p = 0; p < nparts; p++) {
		tiny[p] = hi[p][0] - lo[p][0] < epsilon && hi[p][1] - lo[p][1] < epsilon &&
			  hi[p][2] - lo[p][2] < epsilon;
		ntiny += tiny[p];
	}
	if (ntiny == 0) {
		res = m;
		goto out;
	}
	b = mesh_builder_new(m->ntris);
	if (!b)
		goto out;
	for (size_t t = 0; t < m->ntris && !rc; t++) {
		uint32_t w[3];
		if (part[t] < nparts && tiny[part[t]]) {
			rep->dropped_triangles++;
			continue;
		}
		for (int k = 0; k < 3 && !rc; k++)
			rc = mesh_builder_vertex(b, m->verts[m->tris[t][k]], &w[k], NULL);
		if (!rc)
			rc = mesh_builder_triangle(b, w[0], w[1], w[2], NULL);
	}
	if (!rc) {
		res = mesh_builder_finish(b);
		b = NULL;
		rep->parts_dropped += ntiny;
	}
out:
	mesh_builder_free(b);
	free(lo);
	free(hi);
	free(tiny);
	return res;
}

/*
 * The last step: check *m as `stratum check` will (known: its
 * self-intersection count if already known, else -1), drop parts smaller
 * than epsilon, number the parts for --split and fill the output half of
 * rep.  *m may be replaced.  Returns 0 or a negative class.
 */
/*
 * Whether every part of the analysed mesh holds one batch's triangles and
 * every part in a cavity lies in a part of its own batch.
 */
static bool parts_within_batches(const struct mesh *m, const uint32_t *part,
				 const uint32_t *around, size_t nparts, const uint32_t *batch)
{
	uint32_t *owner = malloc((nparts + 1) * sizeof(*owner));
	bool within = owner != NULL;

	for (size_t p = 0; within && p < nparts; p++)
		owner[p] = UINT32_MAX;
	for (size_t t = 0; within && t < m->ntris; t++) {
		if (part[t] == UINT32_MAX)
			continue;
		if (owner[part[t]] == UINT32_MAX)
			owner[part[t]] = batch[t];
		within = owner[part[t]] == batch[t];
	}
	for (size_t p = 0; within && p < nparts; p++)
		within = around[p] == UINT32_MAX || owner[around[p]] == owner[p];
	free(owner);
	return within;
}

int repair_finish_parts(struct mesh **m, const struct repair_options *opt, long long known,
			const uint32_t *batch, bool *apart, uint32_t **component,
			struct repair_report *rep, struct st_error *err)
{
	uint32_t *part = malloc(((*m)->ntris + 1) * sizeof(*part));
	struct mesh_report mr;
	double lo[3], hi[3];
	int rc;

	mesh_bbox(*m, lo, hi); /* of everything, for the message below */

	if (!part)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory numbering the parts");
	uint32_t *around = batch ? malloc(((*m)->ntris + 1) * sizeof(*around)) : NULL;
	if (batch && !around) {
		free(part);
		return st_error_set(err, ST_ERR_NOMEM, "out of memory numbering the parts");
	}
	rc = mesh_analyze_nesting(*m, opt->threads, known, &mr, part, around, err);
	if (!rc && batch) {
		*apart = !mr.misnested_shells &&
			 parts_within_batches(*m, part, around, mr.parts, batch);
		if (!*apart) {
			free(around);
			free(part);
			return 0;
		}
	}
	free(around);
	if (!rc && repair_result_printable(&mr)) {
		struct mesh *kept = drop_tiny_parts(*m, part, mr.parts, opt->epsilon, rep);
		if (!kept) {
			rc = st_error_set(err, ST_ERR_NOMEM, "out of memory dropping small parts");
		} else if (kept != *m) {
			mesh_free(*m);
			*m = kept;
			/* Fewer triangles: still no intersections, new numbers. */
			rc = mesh_analyze_parts(*m, opt->threads, 0, &mr, part, err);
		}
	}
	if (rc) {
		free(part);
		return rc;
	}
	rep->output_triangles = (*m)->ntris;
	rep->output_vertices = (*m)->nverts;
	rep->components = mr.parts;
	rep->cavities = mr.cavities;
	rep->printable = repair_result_printable(&mr);
	if (!rep->printable && rep->parts_dropped && mr.triangles == 0)
		snprintf(rep->why, sizeof(rep->why),
			 "every part is smaller than epsilon (%g mm) in all three directions (the "
			 "model is %.3g x %.3g x %.3g mm: if it was drawn in metres or inches, "
			 "scale it up)",
			 opt->epsilon, hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
	else if (!rep->printable)
		explain(&mr, rep->why, sizeof(rep->why));
	if (component)
		*component = part;
	else
		free(part);
	return 0;
}


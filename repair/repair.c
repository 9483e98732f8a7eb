/*
 * repair.c - seed 000's repair pipeline end to end (repair.h).
 *
 * Healing first (heal.h), then one core run (repair_core.c: §4.1 and
 * §4.2) on the whole mesh or on each independent group (batch.h).
 * Rounding the exact result to the output precision can in rare cases
 * create new contacts, so the rounded mesh is checked and, if needed,
 * goes through the core again.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "batch.h"
#include "exact.h"
#include "heal.h"
#include "ids.h"
#include "output.h"
#include "repair_impl.h"
#include "repair.h"
#include "vec3.h"

/* Rounding rounds before giving up (each usually fixes all it finds). */
#define MAX_ROUNDING_ROUNDS 10

void repair_options_init(struct repair_options *opt)
{
	memset(opt, 0, sizeof(*opt));
	opt->epsilon = 0.4;
	opt->precision = REPAIR_FLOAT32;
	opt->threads = 0;
	opt->weld = -1;		/* heal.h: HEAL_WELD_ULPS float32 ulps */
	opt->stitch = -1;	/* heal.h: HEAL_STITCH_FACTOR * epsilon */
	opt->keep_holes = false;
}

/*
 * Grid cells a vertex may end from its exact place when rounding has to
 * pick another corner of its cell or merge it into a neighbour: two cells
 * let points in neighbouring cells merge, as points in one cell do when
 * rounded plainly.
 */
#define SNAP_REACH_CELLS 2

/*
 * Round em's vertices to the output precision into a new welded mesh, by
 * snap rounding (exact_mesh_snap_round): no move that would make triangles
 * meet is made.  *moved: largest distance a vertex moved; *changed:
 * whether any did; *merged: vertices merged into a neighbour; *clean:
 * every vertex found a safe place, so the rounded mesh has no intersecting
 * pair, as em has none (exact_mesh_snap_round in exact.h).
 */
static int round_result(const struct exact_mesh *em, enum repair_precision prec, int threads,
			struct mesh **out, double *moved, bool *changed, size_t *merged,
			bool *clean, struct st_error *err)
{
	const size_t nv = exact_mesh_nverts(em);
	const double reach = SNAP_REACH_CELLS * repair_output_ulp(exact_mesh_verts(em), nv, prec);
	struct exact_mesh *snapped = NULL;
	struct exact_snap_stats st;
	int rc;

	*out = NULL;
	rc = exact_mesh_snap_round(em, prec == REPAIR_FLOAT32 ? 24 : 53, reach, threads, &snapped,
				   &st, err);
	if (rc)
		return rc;
	*moved = fmax(*moved, st.max_move);
	*merged += st.collapsed;
	if (st.rounded || st.other_corner || st.collapsed || st.unplaced)
		*changed = true;
	*clean = st.unplaced == 0;
	*clean = st.unplaced == 0;

	const size_t n = exact_mesh_ntris(snapped);
	const uint32_t (*tris)[3] = exact_mesh_tris(snapped);
	const double (*verts)[3] = exact_mesh_verts(snapped);
	struct mesh_builder *b = mesh_builder_new(n);
	uint32_t *index = malloc((exact_mesh_nverts(snapped) + 1) * sizeof(*index));

	if (!b || !index) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory writing the result");
		goto out;
	}
	for (size_t v = 0; v < exact_mesh_nverts(snapped) && !rc; v++)
		rc = mesh_builder_vertex(b, verts[v], &index[v], err);
	for (size_t t = 0; t < n && !rc; t++)
		rc = mesh_builder_triangle(b, index[tris[t][0]], index[tris[t][1]],
					   index[tris[t][2]], err);
	if (!rc) {
		*out = mesh_builder_finish(b);
		b = NULL;
		if (!*out)
			rc = st_error_set(err, ST_ERR_NOMEM, "out of memory writing the result");
	}
out:
	mesh_builder_free(b);
	free(index);
	exact_mesh_free(snapped);
	return rc;
}

/*
 * Drop what rounding collapsed without moving anything: triangles that
 * repeat a vertex (an edge or the whole triangle shrank to a point), and
 * pairs of equal triangles (a part thinner than the grid, flattened to two
 * layers).  Every edge keeps an even count, so a closed mesh stays closed.
 * Returns a new mesh, or NULL when out of memory.
 */
static struct mesh *drop_collapsed(const struct mesh *m)
{
	struct tri_key *keys = malloc((m->ntris + 1) * sizeof(*keys));
	uint8_t *drop = calloc(m->ntris + 1, 1);
	struct mesh_builder *b = mesh_builder_new(m->ntris);
	struct mesh *out = NULL;
	struct st_error err;
	size_t nk = 0;
	int rc = 0;

	if (!keys || !drop || !b)
		goto done;
	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t *v = m->tris[t];
		if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
			drop[t] = 1;
			continue;
		}
		sort3(v, keys[nk].v);
		keys[nk++].t = (uint32_t)t;
	}
	qsort(keys, nk, sizeof(*keys), tri_key_compare);
	/* Equal triangles come in runs; drop them pairwise. */
	for (size_t i = 0; i + 1 < nk; i++)
		if (!memcmp(keys[i].v, keys[i + 1].v, sizeof(keys[i].v))) {
			drop[keys[i].t] = drop[keys[i + 1].t] = 1;
			i++;
		}
	for (size_t t = 0; t < m->ntris && !rc; t++) {
		uint32_t w[3];
		if (drop[t])
			continue;
		for (int k = 0; k < 3 && !rc; k++)
			rc = mesh_builder_vertex(b, m->verts[m->tris[t][k]], &w[k], &err);
		if (!rc)
			rc = mesh_builder_triangle(b, w[0], w[1], w[2], &err);
	}
	if (!rc) {
		out = mesh_builder_finish(b);
		b = NULL;
	}
done:
	mesh_builder_free(b);
	free(keys);
	free(drop);
	return out;
}

/*
 * Largest distance of a solid vertex from the input triangle it came from.
 * Pieces are constructed exactly in their triangle's plane, so this is 0
 * up to the double approximation of rational points (about 1e-15 mm); a
 * vertex that is an input corner of its triangle counts as 0 outright.
 */
static double solid_deviation(const struct mesh *in, const struct exact_mesh *em)
{
	const size_t n = exact_mesh_ntris(em);
	const uint32_t (*tris)[3] = exact_mesh_tris(em);
	const uint32_t *origin = exact_mesh_origin(em);
	const double (*verts)[3] = exact_mesh_verts(em);
	double worst = 0;

	for (size_t t = 0; t < n; t++) {
		if (origin[t] >= in->ntris)
			continue; /* made by thickening */
		const uint32_t *o = in->tris[origin[t]];
		const double *a = in->verts[o[0]], *b = in->verts[o[1]], *c = in->verts[o[2]];
		for (int k = 0; k < 3; k++) {
			const double *p = verts[tris[t][k]];
			if (!memcmp(p, a, sizeof(double[3])) || !memcmp(p, b, sizeof(double[3])) ||
			    !memcmp(p, c, sizeof(double[3])))
				continue;
			worst = fmax(worst, vec3_point_triangle_distance(p, a, b, c));
		}
	}
	return worst;
}

/* Copy the first core run's figures into the report. */
static void report_core(struct repair_report *rep, const struct core_out *co)
{
	rep->irregular_removed = co->irregular;
	rep->degenerate_removed = co->degenerate;
	rep->duplicates_removed = co->duplicates;
	rep->intersecting_pairs = co->pairs;
	rep->triangles_split = co->split;
	rep->interior_deleted = co->interior;
	rep->enclosed_deleted = co->enclosed;
	rep->enclosed_components = co->enclosed_components;
	rep->sheet_triangles = co->sheet;
	rep->sheet_area = co->sheet_area;
	rep->sheet_components = co->sheet_components;
	rep->wires = co->wires;
	rep->wire_length = co->wire_length;
	rep->wires_discarded = co->wires_discarded;
	rep->second_pass = co->second_pass;
	rep->thickened_triangles = co->thickened;
	rep->second_sheet_triangles = co->second_sheet;
	rep->sheet_deviation = co->sheet_deviation;
}

/* repair_impl.h */
int repair_rounded(const struct mesh *in, const struct repair_options *opt,
		   struct mesh **rounded_out, long long *known, struct repair_report *rep,
		   struct st_error *err)
{
	struct core_out co;
	struct mesh *cur = NULL, *rounded = NULL;
	struct mesh_report mr;
	int rc;

	co.result = NULL;
	rc = repair_core(in, opt, true, &co, err);
	report_core(rep, &co); /* on failure too: what was measured so far */
	if (rc)
		goto out_free;
	rep->solid_deviation = solid_deviation(in, co.result);

	/* Round, check, and run the core again on what rounding broke.  The
	 * exact passes leave no intersecting pair, and rounding that placed
	 * every vertex safely keeps it so: then the analysis takes the count
	 * as 0 instead of searching all pairs again (clean). */
	bool checked = false, clean = false;
	for (;;) {
		bool changed = false;
		double moved = 0;
		repair_progress(opt, "rounding the coordinates", 0);
		rc = round_result(co.result, opt->precision, opt->threads, &rounded, &moved, &changed,
				  &rep->rounding_merged, &clean, err);
		/* Rounds add up: each moves the previous round's result. */
		rep->rounding_deviation += moved;
		exact_mesh_free(co.result);
		co.result = NULL;
		mesh_free(cur);
		cur = NULL;
		if (rc)
			goto out_free;
		if (!changed || rep->rounding_rounds >= MAX_ROUNDING_ROUNDS)
			break;
		rc = mesh_analyze_known(rounded, opt->threads, clean ? 0 : -1, &mr, err);
		if (rc)
			goto out_free;
		checked = true;
		if (repair_result_printable(&mr))
			break;
		checked = false;
		/* Often rounding only collapsed slivers: dropping them is
		 * enough, and needs no new (rational) points. */
		if (mr.self_intersections == 0 && mr.degenerate == 0) {
			struct mesh *pruned = drop_collapsed(rounded);
			if (!pruned) {
				rc = st_error_set(err, ST_ERR_NOMEM, "out of memory after rounding");
				goto out_free;
			}
			/* Fewer triangles than a mesh without crossings. */
			rc = mesh_analyze_known(pruned, opt->threads, 0, &mr, err);
			if (rc) {
				mesh_free(pruned);
				goto out_free;
			}
			if (repair_result_printable(&mr)) {
				mesh_free(rounded);
				rounded = pruned;
				checked = true;
				break;
			}
			mesh_free(pruned);
		}
		rep->rounding_rounds++;
		cur = rounded;
		rounded = NULL;
		rc = repair_core(cur, opt, false, &co, err);
		if (rc)
			goto out_free;
		rep->rounding_dropped += co.sheet;
	}
	/* A mesh checked in the loop has its count already. */
	*known = checked ? (long long)mr.self_intersections : clean ? 0 : -1;
	*rounded_out = rounded;
	return 0;

out_free:
	exact_mesh_free(co.result);
	mesh_free(cur);
	mesh_free(rounded);
	return rc;
}

/*
 * How close two triangles may come and still be repaired apart: what
 * thickening may grow (BATCH_REACH epsilon) and both sides' rounding.
 */
static double batch_reach(const struct mesh *in, const struct repair_options *opt)
{
	const double ulp = repair_output_ulp((const double(*)[3])in->verts, in->nverts, opt->precision);

	return BATCH_REACH * opt->epsilon + 2 * SNAP_REACH_CELLS * ulp;
}

int repair_mesh(const struct mesh *in, const struct repair_options *opt, struct mesh **out,
		uint32_t **component, struct repair_report *rep, struct st_error *err)
{
	struct mesh *rounded = NULL, *healed = NULL;
	struct batches bs = {0};
	struct repair_report healed_rep;
	uint32_t *batch_of = NULL;
	long long known = -1;
	bool apart = true;
	int rc;

	if (out)
		*out = NULL;
	if (component)
		*component = NULL;
	if (!in || !opt || !out || !rep)
		return st_error_set(err, ST_ERR_ARG, "repair: NULL mesh, options or output");
	if (!(opt->epsilon > 0) || !isfinite(opt->epsilon))
		return st_error_set(err, ST_ERR_ARG,
				    "repair: epsilon %g mm must be a positive thickness",
				    opt->epsilon);
	if (opt->precision != REPAIR_FLOAT32 && opt->precision != REPAIR_FLOAT64)
		return st_error_set(err, ST_ERR_ARG, "repair: unknown output precision %d",
				    (int)opt->precision);
	if (opt->threads < 0)
		return st_error_set(err, ST_ERR_ARG, "repair: thread count %d is negative",
				    opt->threads);
	memset(rep, 0, sizeof(*rep));
	rep->input_triangles = in->ntris;
	/* Weld, stitch and fill before anything is decided (heal.h). */
	rc = heal_mesh(in, opt, &healed, rep, err);
	if (rc)
		return rc;
	if (healed)
		in = healed;

	/* Groups that cannot touch, even thickened and rounded, are
	 * repaired apart (batch.h). */
	healed_rep = *rep;
	repair_progress(opt, "finding the separate groups", 0);
	rc = batches_find(in, batch_reach(in, opt), &bs, err);
	if (!rc && bs.n > 1)
		rc = repair_rounded_batches(in, opt, &bs, &rounded, &batch_of, &known, rep, err);
	else if (!rc)
		rc = repair_rounded(in, opt, &rounded, &known, rep, err);
	rep->batches = bs.n > 1 ? bs.n : 1;
	batches_free(&bs);
	if (rc)
		goto out_free;

	repair_progress(opt, "checking the repaired mesh", 0);
	rc = repair_finish_parts(&rounded, opt, known, batch_of, &apart, component, rep, err);
	if (!rc && !apart) {
		/* One group's result lies inside another's, where the outer
		 * hull of the whole deletes it: repair the whole at once. */
		mesh_free(rounded);
		rounded = NULL;
		*rep = healed_rep;
		rep->batches = 1;
		rep->batch_fallback = true;
		rc = repair_rounded(in, opt, &rounded, &known, rep, err);
		if (!rc)
			rc = repair_finish_parts(&rounded, opt, known, NULL, NULL, component, rep,
						 err);
	}
	if (rc)
		goto out_free;
	*out = rounded;
	free(batch_of);
	mesh_free(healed);
	return 0;

out_free:
	free(batch_of);
	mesh_free(rounded);
	mesh_free(healed);
	return rc;
}

/*
 * repair_core.c - one core run of the repair (seed 000 §4.1, §4.2): clean,
 * refine exactly, grow the outer hull; then, when there are sheets or
 * visible wires, thicken them and run refine + hull again on M_solid and
 * the new solids.  repair.c rounds the result and runs this again on what
 * rounding broke (repair_impl.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "exact.h"
#include "hull.h"
#include "ids.h"
#include "repair_impl.h"
#include "thicken.h"
#include "vec3.h"

/* Origins of triangles that are not pieces of an input triangle. */
#define ORIGIN_THICKENED 0xfffffffeu

/* Sides of the prism that stands in for an epsilon-diameter cylinder. */
#define WIRE_SIDES 12

struct segment {
	double p[3], q[3];
};

/*
 * Step 1 (seed 000 §4.1, §4.2.1 last paragraphs): the layer of regular,
 * non-degenerate, pairwise non-equivalent triangles (first of each set of
 * equivalent ones, in input order) into *layer (n_layer of them), and the
 * wire segments of irregular and degenerate ones into *wires.
 */
static int clean(const struct mesh *in, uint32_t **layer, size_t *n_layer, struct segment **wires,
		 size_t *n_wires, struct core_out *co, struct st_error *err)
{
	uint8_t *usable = calloc(in->ntris + 1, 1);
	struct tri_key *keys = malloc((in->ntris + 1) * sizeof(*keys));
	uint32_t *out = malloc((in->ntris + 1) * sizeof(*out));
	struct segment *segs = malloc((in->ntris + 1) * sizeof(*segs));
	size_t nk = 0, ns = 0, nl = 0;

	if (!usable || !keys || !out || !segs) {
		free(usable);
		free(keys);
		free(out);
		free(segs);
		return st_error_set(err, ST_ERR_NOMEM, "out of memory cleaning %zu triangles",
				    in->ntris);
	}
	for (size_t t = 0; t < in->ntris; t++) {
		const uint32_t *v = in->tris[t];
		const double *p[3] = {in->verts[v[0]], in->verts[v[1]], in->verts[v[2]]};

		if (v[0] == v[1] && v[1] == v[2]) {
			co->irregular++; /* a point: draws nothing */
		} else if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2]) {
			co->irregular++;
			const uint32_t a = v[0], b = v[0] == v[1] ? v[2] : v[1];
			memcpy(segs[ns].p, in->verts[a], sizeof(segs[ns].p));
			memcpy(segs[ns].q, in->verts[b], sizeof(segs[ns].q));
			ns++;
		} else if (exact_collinear(p[0], p[1], p[2])) {
			co->degenerate++;
			/* The segment is spanned by the farthest pair. */
			int i = 0, j = 1;
			double best = vec3_dist(p[0], p[1]);
			if (vec3_dist(p[1], p[2]) > best) {
				i = 1;
				j = 2;
				best = vec3_dist(p[1], p[2]);
			}
			if (vec3_dist(p[0], p[2]) > best) {
				i = 0;
				j = 2;
			}
			memcpy(segs[ns].p, p[i], sizeof(segs[ns].p));
			memcpy(segs[ns].q, p[j], sizeof(segs[ns].q));
			ns++;
		} else {
			sort3(v, keys[nk].v);
			keys[nk].t = (uint32_t)t;
			nk++;
		}
	}
	qsort(keys, nk, sizeof(*keys), tri_key_compare);
	for (size_t i = 0; i < nk; i++) {
		if (i > 0 && !memcmp(keys[i].v, keys[i - 1].v, sizeof(keys[i].v))) {
			co->duplicates++;
			continue;
		}
		usable[keys[i].t] = 1;
	}
	for (size_t t = 0; t < in->ntris; t++)
		if (usable[t])
			out[nl++] = (uint32_t)t;
	free(usable);
	free(keys);
	*layer = out;
	*n_layer = nl;
	*wires = segs;
	*n_wires = ns;
	return 0;
}

/* Steps 2-3 on em, in place: refine, then tag.  tag/flip are malloc'd. */
static int refine_and_grow(struct exact_mesh *em, const struct repair_options *opt,
			   struct exact_refine_stats *rs, struct hull_stats *hs, uint8_t **tag,
			   uint8_t **flip, struct st_error *err)
{
	int rc = exact_mesh_refine(em, opt->threads, rs, err);
	size_t n;

	*tag = *flip = NULL;
	if (rc)
		return rc;
	n = exact_mesh_ntris(em);
	*tag = malloc(n + 1);
	*flip = malloc(n + 1);
	if (!*tag || !*flip) {
		free(*tag);
		free(*flip);
		*tag = *flip = NULL;
		return st_error_set(err, ST_ERR_NOMEM, "out of memory tagging %zu triangles", n);
	}
	repair_progress(opt, "walking the outer hull", 0);
	rc = hull_extract(em, *tag, *flip, hs, err);
	if (rc) {
		free(*tag);
		free(*flip);
		*tag = *flip = NULL;
	}
	return rc;
}

/*
 * A closed prism of WIRE_SIDES sides and radius r around segment pq,
 * oriented outwards, appended to em.
 */
static int append_cylinder(struct exact_mesh *em, const struct segment *s, double r,
			   struct st_error *err)
{
	double d[3] = {s->q[0] - s->p[0], s->q[1] - s->p[1], s->q[2] - s->p[2]};
	const double len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
	double u[3], w[3], verts[2 * WIRE_SIDES + 2][3];
	uint32_t tris[4 * WIRE_SIDES][3];
	size_t nt = 0;

	for (int k = 0; k < 3; k++)
		d[k] /= len;
	/* u: perpendicular to d, from the axis d is least aligned with. */
	const int a = fabs(d[0]) <= fabs(d[1]) && fabs(d[0]) <= fabs(d[2]) ? 0
		      : fabs(d[1]) <= fabs(d[2])			    ? 1
									    : 2;
	double e[3] = {0, 0, 0};
	e[a] = 1;
	u[0] = d[1] * e[2] - d[2] * e[1];
	u[1] = d[2] * e[0] - d[0] * e[2];
	u[2] = d[0] * e[1] - d[1] * e[0];
	const double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
	for (int k = 0; k < 3; k++)
		u[k] /= ul;
	w[0] = d[1] * u[2] - d[2] * u[1];
	w[1] = d[2] * u[0] - d[0] * u[2];
	w[2] = d[0] * u[1] - d[1] * u[0];
	for (int i = 0; i < WIRE_SIDES; i++) {
		const double th = 2 * M_PI * i / WIRE_SIDES, c = cos(th), sn = sin(th);
		for (int k = 0; k < 3; k++) {
			verts[i][k] = s->p[k] + r * (c * u[k] + sn * w[k]);
			verts[WIRE_SIDES + i][k] = s->q[k] + r * (c * u[k] + sn * w[k]);
		}
	}
	memcpy(verts[2 * WIRE_SIDES], s->p, sizeof(verts[0]));
	memcpy(verts[2 * WIRE_SIDES + 1], s->q, sizeof(verts[0]));
	for (uint32_t i = 0; i < WIRE_SIDES; i++) {
		const uint32_t j = (i + 1) % WIRE_SIDES;
		const uint32_t a0 = i, a1 = j, b0 = WIRE_SIDES + i, b1 = WIRE_SIDES + j;
		const uint32_t cp = 2 * WIRE_SIDES, cq = 2 * WIRE_SIDES + 1;
		uint32_t side1[3] = {a0, a1, b1}, side2[3] = {a0, b1, b0};
		uint32_t cap1[3] = {cp, a1, a0}, cap2[3] = {cq, b0, b1};
		memcpy(tris[nt++], side1, sizeof(side1));
		memcpy(tris[nt++], side2, sizeof(side2));
		memcpy(tris[nt++], cap1, sizeof(cap1));
		memcpy(tris[nt++], cap2, sizeof(cap2));
	}
	return exact_mesh_append(em, (const double(*)[3])verts, 2 * WIRE_SIDES + 2,
				 (const uint32_t(*)[3])tris, nt, ORIGIN_THICKENED, NULL, err);
}

/* List the triangles whose tag is want (0 = any nonzero) into a new array. */
static uint32_t *list_tagged(const uint8_t *tag, size_t n, int want, size_t *count)
{
	uint32_t *l = malloc((n + 1) * sizeof(*l));
	size_t c = 0;

	if (!l)
		return NULL;
	for (size_t t = 0; t < n; t++)
		if (want ? tag[t] == want : tag[t] != 0)
			l[c++] = (uint32_t)t;
	*count = c;
	return l;
}

/*
 * Thicken M_sheet of em (tag both) into slabs and the visible wires into
 * cylinders; return a new exact mesh of M_solid plus the new solids.
 */
static int thicken(const struct exact_mesh *em, const uint8_t *tag, const uint8_t *flip,
		   const uint32_t (*before)[3], size_t nbefore, const struct segment *wires, size_t n_wires, const struct repair_options *opt,
		   struct core_out *co, struct exact_mesh **out, struct st_error *err)
{
	const size_t n = exact_mesh_ntris(em);
	const uint32_t (*tris)[3] = exact_mesh_tris(em);
	const double (*verts)[3] = exact_mesh_verts(em);
	uint8_t *keep = malloc(n + 1);
	uint32_t *surface = NULL, *closed = NULL;
	size_t ns = 0, nc = 0;
	struct exact_mesh *res = NULL;
	int rc = 0;

	*out = NULL;
	if (!keep)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory thickening");
	for (size_t t = 0; t < n; t++)
		keep[t] = tag[t] == HULL_OUTER;
	rc = exact_mesh_select(em, keep, flip, &res, err);
	if (rc)
		goto out;

	/* Sheets: slabs of total thickness epsilon (thicken.c). */
	size_t nsheet = 0;
	uint32_t *sheet = list_tagged(tag, n, HULL_OUTER | HULL_INNER, &nsheet);
	if (!sheet) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory thickening sheets");
		goto out;
	}
	for (size_t i = 0; i < nsheet; i++)
		co->sheet_area += vec3_tri_area(verts[tris[sheet[i]][0]], verts[tris[sheet[i]][1]],
					   verts[tris[sheet[i]][2]]);
	if (nsheet) {
		struct thick_out slab;
		const uint8_t *whole = NULL;
		const uint32_t *parent = exact_mesh_parents(em, &whole);
		uint32_t (*units)[3] = NULL, *ids = NULL;
		uint8_t *free_edges = NULL;
		size_t nunits = 0;
		repair_progress(opt, "thickening the sheets", 0);
		rc = thicken_units(tris, sheet, nsheet, parent, whole, before, nbefore, n, &units,
				   &free_edges, &nunits, err);
		free(sheet);
		if (rc)
			goto out;
		ids = malloc((nunits + 1) * sizeof(*ids));
		if (!ids) {
			free(units);
			free(free_edges);
			rc = st_error_set(err, ST_ERR_NOMEM, "out of memory thickening sheets");
			goto out;
		}
		for (size_t i = 0; i < nunits; i++)
			ids[i] = (uint32_t)i;
		rc = thicken_sheets(verts, (const uint32_t(*)[3])units, ids, free_edges, nunits,
				    opt->epsilon / 2,
				    repair_output_ulp(verts, exact_mesh_nverts(em), opt->precision), &slab,
				    err);
		free(units);
		free(free_edges);
		free(ids);
		if (rc)
			goto out;
		co->sheet_deviation = fmax(co->sheet_deviation, slab.deviation);
		co->thickened += slab.ntris;
		/* Walls hold the sheet's own points exactly, as in M_solid. */
		rc = exact_mesh_append_ref(res, em, slab.sheet_ref,
					   (const double(*)[3])slab.verts, slab.nverts,
					   (const uint32_t(*)[3])slab.tris, slab.ntris,
					   ORIGIN_THICKENED, NULL, err);
		free(slab.verts);
		free(slab.sheet_ref);
		free(slab.tris);
		if (rc)
			goto out;
	} else {
		free(sheet);
	}

	/* Wires: hidden ones (on the surface or inside M_solid) are dropped. */
	if (n_wires) {
		surface = list_tagged(tag, n, 0, &ns);
		closed = list_tagged(tag, n, HULL_OUTER, &nc);
		if (!surface || !closed) {
			rc = st_error_set(err, ST_ERR_NOMEM, "out of memory testing wires");
			goto out;
		}
		repair_progress(opt, "thickening the wires", 0);
	}
	for (size_t i = 0; i < n_wires; i++) {
		bool hidden;
		rc = exact_segment_hidden(em, surface, ns, closed, nc, wires[i].p, wires[i].q,
					  &hidden, err);
		if (rc)
			goto out;
		if (hidden) {
			co->wires_discarded++;
			continue;
		}
		co->wires++;
		co->wire_length += vec3_dist(wires[i].p, wires[i].q);
		rc = append_cylinder(res, &wires[i], opt->epsilon / 2, err);
		if (rc)
			goto out;
		co->thickened += 4 * WIRE_SIDES;
		/* Every cylinder vertex is exactly r from the axis (rounding
		 * aside), the caps end at the segment's ends. */
		co->sheet_deviation = fmax(co->sheet_deviation, opt->epsilon / 2);
	}
out:
	free(keep);
	free(surface);
	free(closed);
	if (rc) {
		exact_mesh_free(res);
		return rc;
	}
	*out = res;
	return 0;
}

/* repair_impl.h */
int repair_core(const struct mesh *in, const struct repair_options *opt, bool thicken_sheets_too,
		struct core_out *co, struct st_error *err)
{
	uint32_t *layer = NULL;
	uint32_t (*lt)[3] = NULL; /* the layer's triangles: what the first pass cut */
	struct segment *wires = NULL;
	size_t n_layer = 0, n_wires = 0;
	struct exact_mesh *em = NULL, *next = NULL;
	uint8_t *tag = NULL, *flip = NULL;
	struct exact_refine_stats rs;
	struct hull_stats hs;
	int rc;

	memset(co, 0, sizeof(*co));
	repair_progress(opt, "cleaning the mesh", 0);
	rc = clean(in, &layer, &n_layer, &wires, &n_wires, co, err);
	if (rc)
		return rc;
	lt = malloc((n_layer + 1) * sizeof(*lt));
	if (!lt) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory copying the layer");
		goto out;
	}
	for (size_t i = 0; i < n_layer; i++)
		memcpy(lt[i], in->tris[layer[i]], sizeof(lt[i]));
	rc = exact_mesh_new((const double(*)[3])in->verts, in->nverts, (const uint32_t(*)[3])lt,
			    n_layer, layer, &em, err);
	if (rc)
		goto out;

	exact_mesh_set_progress(em, opt->progress, opt->progress_ctx);
	repair_progress(opt, "finding the crossing pairs", 0);
	rc = refine_and_grow(em, opt, &rs, &hs, &tag, &flip, err);
	if (rc)
		goto out;
	co->pairs = rs.intersecting_pairs;
	co->split = rs.triangles_split;
	co->interior = hs.interior;
	co->enclosed = hs.enclosed;
	co->enclosed_components = hs.enclosed_components;
	co->sheet = hs.sheet;
	co->sheet_components = hs.sheet_components;

	/* After rounding, sheets and wires are parts thinner than the rounding
	 * grid that collapsed: M_solid without them is closed, and thickening
	 * them would add epsilon-thick slabs around rounding noise. */
	if (thicken_sheets_too && (hs.sheet || n_wires)) {
		rc = thicken(em, tag, flip, (const uint32_t(*)[3])lt, n_layer, wires, n_wires, opt, co, &next, err);
		if (rc)
			goto out;
	}
	if (next && (hs.sheet || co->wires)) {
		free(tag);
		free(flip);
		tag = flip = NULL;
		exact_mesh_free(em);
		em = next;
		next = NULL;
		co->second_pass = true;
		exact_mesh_set_progress(em, opt->progress, opt->progress_ctx);
		repair_progress(opt, "finding the crossing pairs of the thickened mesh", 0);
		rc = refine_and_grow(em, opt, &rs, &hs, &tag, &flip, err);
		if (rc)
			goto out;
		co->second_sheet = hs.sheet;
		/* Seed 000 §4.2.1: M_solid and closed slabs leave no sheet.
		 * One left means a bug here, not bad input: no third pass
		 * hides it. */
		if (hs.sheet) {
			rc = st_error_set(err, ST_ERR_INTERNAL,
					  "repair: the second pass left %zu sheet triangles "
					  "(it must leave none)",
					  hs.sheet);
			goto out;
		}
	}
	if (next) {
		/* Only hidden wires: M_solid as selected by thicken(). */
		co->result = next;
		next = NULL;
	} else {
		uint8_t *keep = malloc(exact_mesh_ntris(em) + 1);
		if (!keep) {
			rc = st_error_set(err, ST_ERR_NOMEM, "out of memory selecting M_solid");
			goto out;
		}
		for (size_t t = 0; t < exact_mesh_ntris(em); t++)
			keep[t] = tag[t] == HULL_OUTER;
		rc = exact_mesh_select(em, keep, flip, &co->result, err);
		free(keep);
	}
out:
	free(layer);
	free(lt);
	free(wires);
	free(tag);
	free(flip);
	exact_mesh_free(em);
	exact_mesh_free(next);
	return rc;
}

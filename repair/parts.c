/*
 * parts.c - parts and cavities of a checked mesh (parts.h).
 *
 * Shells are the manifold-connected components of Def. 3.10 (triangles
 * joined across two-triangle edges).  A file may hold several parts side
 * by side, touching along edges or at vertices, and cavities: closed
 * shells inside a part whose triangles face into the void.  Which shell
 * lies in which follows from exact point-in-shell tests (CGAL bridge); the
 * side a shell faces from the sign of its volume, which is a sum over a
 * closed, consistently oriented surface.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "exact.h"
#include "hull.h"
#include "ids.h"
#include "parts.h"
#include "st_grow.h"

/* Per shell: bounding box, signed volume, triangles (rows into a list). */
struct shell_info {
	double lo[3], hi[3];
	double volume;
	uint32_t depth;	 /* shells around it */
	int winding;	 /* outward minus inward shells around it: 1 in material */
	uint32_t part;
};

/* Signed volume of triangle pqr seen from c, times 6. */
static double tet6(const double *p, const double *q, const double *r, const double c[3])
{
	const double a[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
	const double b[3] = {q[0] - c[0], q[1] - c[1], q[2] - c[2]};
	const double d[3] = {r[0] - c[0], r[1] - c[1], r[2] - c[2]};

	return a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
	       a[2] * (b[0] * d[1] - b[1] * d[0]);
}

/* Whether a's box lies within b's. */
static bool box_within(const struct shell_info *a, const struct shell_info *b)
{
	for (int k = 0; k < 3; k++)
		if (a->lo[k] < b->lo[k] || a->hi[k] > b->hi[k])
			return false;
	return true;
}

/*
 * The exact mesh of the analysed triangles (*em, their positions in lpos)
 * and, when singular edges need it, the shells regrouped by pairing
 * triangles through the material (hull_manifold_components).
 */
static int exact_shells(const struct mesh *m, const uint8_t *in_layer, uint32_t *shell,
			size_t *nshells, bool singular, uint32_t *lpos, struct exact_mesh **em,
			struct parts_out *out, struct st_error *err)
{
	uint32_t (*lt)[3] = malloc((m->ntris + 1) * sizeof(*lt));
	uint32_t *comp = NULL;
	size_t nl = 0;
	long nc;
	int rc;

	if (!lt)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory telling parts apart");
	for (size_t t = 0; t < m->ntris; t++)
		if (in_layer[t]) {
			memcpy(lt[nl], m->tris[t], sizeof(lt[nl]));
			lpos[t] = (uint32_t)nl++;
		}
	rc = exact_mesh_new((const double(*)[3])m->verts, m->nverts, (const uint32_t(*)[3])lt, nl,
			    NULL, em, err);
	free(lt);
	if (rc || !singular)
		return rc;
	comp = malloc((nl + 1) * sizeof(*comp));
	if (!comp)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory telling parts apart");
	nc = hull_manifold_components(*em, comp, &out->unpaired, err);
	if (nc >= 0) {
		for (size_t t = 0; t < m->ntris; t++)
			if (in_layer[t])
				shell[t] = comp[lpos[t]];
		*nshells = (size_t)nc;
	}
	free(comp);
	return nc < 0 ? (err ? err->code : ST_ERR_INTERNAL) : 0;
}

/* An edge of a triangle of a shell, to find shells that share edges. */
struct shell_edge {
	uint32_t lo, hi, shell;
};

static int compare_shell_edge(const void *pa, const void *pb)
{
	const struct shell_edge *a = pa, *b = pb;

	if (a->lo != b->lo)
		return a->lo < b->lo ? -1 : 1;
	if (a->hi != b->hi)
		return a->hi < b->hi ? -1 : 1;
	return a->shell < b->shell ? -1 : a->shell > b->shell;
}

static int compare_pair(const void *pa, const void *pb)
{
	const uint64_t a = *(const uint64_t *)pa, b = *(const uint64_t *)pb;

	return a < b ? -1 : a > b;
}

/*
 * The pairs of different shells that share an edge (a singular edge), as
 * sorted keys lo << 32 | hi.  Two shells facing the same way (both
 * outwards, or both inwards) that stayed apart at a shared edge lie
 * outside each other: had one been inside the other, a triangle of the
 * outer one would have met the inner one first turning into its material
 * and the two would have been paired (or found unpaired).  Nothing
 * crosses, so that holds everywhere and no ray test is needed.  (A part
 * touching the wall of the cavity it sits in faces the other way and is
 * tested.)  This spares one test over the body per pocket on scans with
 * hundreds of pockets.  Returns the count or -1 on OOM.
 */
static long touching_pairs(const struct mesh *m, const uint8_t *in_layer, const uint32_t *shell,
			   uint64_t **out)
{
	struct shell_edge *e = malloc((3 * m->ntris + 1) * sizeof(*e));
	uint64_t *pairs = NULL;
	size_t ne = 0, np = 0, cap = 0;

	*out = NULL;
	if (!e)
		return -1;
	for (size_t t = 0; t < m->ntris; t++)
		for (int k = 0; in_layer[t] && k < 3; k++) {
			const uint32_t a = m->tris[t][k], b = m->tris[t][(k + 1) % 3];
			e[ne].lo = a < b ? a : b;
			e[ne].hi = a < b ? b : a;
			e[ne++].shell = shell[t];
		}
	qsort(e, ne, sizeof(*e), compare_shell_edge);
	for (size_t i = 0; i + 1 < ne; i++) {
		if (e[i].lo != e[i + 1].lo || e[i].hi != e[i + 1].hi ||
		    e[i].shell == e[i + 1].shell)
			continue;
		uint64_t *p = st_grow(pairs, &cap, np + 1, sizeof(*p));
		if (!p) {
			free(e);
			free(pairs);
			return -1;
		}
		pairs = p;
		/* Shells along one edge come sorted: consecutive pairs cover
		 * two shells per edge, the usual case. */
		pairs[np++] = (uint64_t)e[i].shell << 32 | e[i + 1].shell;
	}
	free(e);
	if (np)
		qsort(pairs, np, sizeof(*pairs), compare_pair);
	*out = pairs;
	return (long)np;
}

/* Whether shells a and b are listed in the sorted touching pairs. */
static bool touching(const uint64_t *pairs, size_t n, uint32_t a, uint32_t b)
{
	const uint64_t key = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;

	return n && bsearch(&key, pairs, n, sizeof(*pairs), compare_pair) != NULL;
}

/* A shell by where its box starts along x, for the sweep below. */
struct lo_x {
	double x;
	uint32_t id;
};

static int compare_lo_x(const void *pa, const void *pb)
{
	const struct lo_x *a = pa, *b = pb;

	if (a->x != b->x)
		return a->x < b->x ? -1 : 1;
	return a->id < b->id ? -1 : a->id > b->id;
}

/*
 * For every shell i, the shells j != i whose boxes hold i's box, in
 * increasing j: shells j's[off[i]] .. j's[off[i + 1] - 1] of *within.
 * A sweep along x (a box holding i's starts at or before i's and ends at
 * or after it), not a test of every pair: a soup's repair leaves tens of
 * thousands of parts.  Returns the pair count or -1 on OOM.
 */
static long boxes_within(const struct shell_info *s, size_t n, uint32_t *off, uint32_t **within)
{
	struct lo_x *by_lo = malloc((n + 1) * sizeof(*by_lo));
	uint32_t *active = malloc((n + 1) * sizeof(*active));
	uint64_t *pairs = NULL;
	size_t np = 0, cap = 0, nactive = 0, next = 0;

	*within = NULL;
	if (!by_lo || !active)
		goto nomem;
	for (size_t i = 0; i < n; i++)
		by_lo[i] = (struct lo_x){s[i].lo[0], (uint32_t)i};
	qsort(by_lo, n, sizeof(*by_lo), compare_lo_x);
	for (size_t q = 0; q < n; q++) {
		const uint32_t i = by_lo[q].id;
		const double x = by_lo[q].x;
		size_t kept = 0;

		while (next < n && by_lo[next].x <= x)
			active[nactive++] = by_lo[next++].id;
		for (size_t a = 0; a < nactive; a++) {
			const uint32_t j = active[a];
			if (s[j].hi[0] < x)
				continue; /* ends before every later box starts */
			active[kept++] = j;
			if (j == i || !box_within(&s[i], &s[j]))
				continue;
			uint64_t *p = st_grow(pairs, &cap, np + 1, sizeof(*p));
			if (!p)
				goto nomem;
			pairs = p;
			pairs[np++] = (uint64_t)i << 32 | j;
		}
		nactive = kept;
	}
	if (np)
		qsort(pairs, np, sizeof(*pairs), compare_pair);
	*within = malloc((np + 1) * sizeof(**within));
	if (!*within)
		goto nomem;
	memset(off, 0, (n + 1) * sizeof(*off));
	for (size_t k = 0; k < np; k++) {
		(*within)[k] = (uint32_t)pairs[k];
		off[(pairs[k] >> 32) + 1]++;
	}
	for (size_t i = 0; i < n; i++)
		off[i + 1] += off[i];
	free(by_lo);
	free(active);
	free(pairs);
	return (long)np;
nomem:
	free(by_lo);
	free(active);
	free(pairs);
	return -1;
}

/*
 * Whether shell j (rows off[j] .. off[j + 1] of list) holds triangle probe
 * of another shell.  A shell of more than a few triangles is filed once
 * (ix[j]) so each probe tests only the triangles its ray can meet: filing
 * costs less than one plain scan (measured on a soup's 68 529 parts), and
 * a shell is often asked about many probes.
 */
#define INDEX_MIN_TRIANGLES 64

static int shell_holds(const struct exact_mesh *em, const uint32_t *list, const uint32_t *off,
		       uint32_t j, uint32_t probe, struct exact_ray_index **ix, bool *inside,
		       struct st_error *err)
{
	const size_t n = off[j + 1] - off[j];

	if (n < INDEX_MIN_TRIANGLES)
		return exact_mesh_inside(em, list + off[j], n, probe, inside, err);
	if (!ix[j]) {
		int rc = exact_ray_index_new(em, list + off[j], n, &ix[j], err);
		if (rc)
			return rc;
	}
	return exact_mesh_inside_indexed(em, ix[j], probe, inside, err);
}

int parts_nest(const struct mesh *m, const uint8_t *in_layer, uint32_t *shell, size_t *nshells_io,
	       bool nest, bool singular, uint32_t *part, uint32_t *around, struct parts_out *out,
	       struct st_error *err)
{
	struct shell_info *s = NULL;
	uint32_t *off = NULL, *list = NULL, *lpos = NULL, *outer = NULL;
	struct id_depth *order = NULL;
	struct exact_mesh *em = NULL;
	uint64_t *touch = NULL;
	uint32_t *within = NULL, *within_off = NULL;
	struct exact_ray_index **ix = NULL;
	long ntouch = 0;
	size_t nl = 0, nshells = *nshells_io;
	double c[3] = {0, 0, 0};
	int rc = 0;

	memset(out, 0, sizeof(*out));
	for (size_t i = 0; around && i < m->ntris; i++)
		around[i] = UINT32_MAX;
	if (!nest || (nshells < 2 && !singular)) {
		/* Nothing to group: each shell is a part (most files: one). */
		out->parts = nshells;
		if (part)
			for (size_t t = 0; t < m->ntris; t++)
				part[t] = in_layer[t] ? shell[t] : UINT32_MAX;
		return 0;
	}
	lpos = malloc((m->ntris + 1) * sizeof(*lpos));
	if (!lpos)
		goto out_nomem;
	rc = exact_shells(m, in_layer, shell, &nshells, singular, lpos, &em, out, err);
	if (rc)
		goto out;
	*nshells_io = nshells;
	s = calloc(nshells + 1, sizeof(*s));
	off = calloc(nshells + 2, sizeof(*off));
	if (!s || !off)
		goto out_nomem;
	for (size_t i = 0; i < nshells; i++)
		for (int k = 0; k < 3; k++) {
			s[i].lo[k] = HUGE_VAL;
			s[i].hi[k] = -HUGE_VAL;
		}
	/* Boxes; the volumes are taken about the centre of all of them. */
	for (size_t t = 0; t < m->ntris; t++) {
		if (!in_layer[t])
			continue;
		struct shell_info *si = &s[shell[t]];
		for (int j = 0; j < 3; j++)
			for (int k = 0; k < 3; k++) {
				const double x = m->verts[m->tris[t][j]][k];
				si->lo[k] = x < si->lo[k] ? x : si->lo[k];
				si->hi[k] = x > si->hi[k] ? x : si->hi[k];
			}
		off[shell[t] + 1]++;
		nl++;
	}
	if (nshells)
		for (int k = 0; k < 3; k++) {
			double lo = HUGE_VAL, hi = -HUGE_VAL;
			for (size_t i = 0; i < nshells; i++) {
				lo = fmin(lo, s[i].lo[k]);
				hi = fmax(hi, s[i].hi[k]);
			}
			c[k] = 0.5 * (lo + hi);
		}
	for (size_t t = 0; t < m->ntris; t++)
		if (in_layer[t])
			s[shell[t]].volume += tet6(m->verts[m->tris[t][0]], m->verts[m->tris[t][1]],
						   m->verts[m->tris[t][2]], c) / 6.0;
	for (size_t i = 0; i < nshells; i++)
		s[i].part = (uint32_t)i;
	out->parts = nshells;
	if (nshells < 2)
		goto assign;

	/* The analysed triangles listed by shell, as exact-mesh indices. */
	list = malloc((nl + 1) * sizeof(*list));
	order = malloc(nshells * sizeof(*order));
	outer = malloc(nshells * sizeof(*outer));
	if (!list || !order || !outer)
		goto out_nomem;
	for (size_t i = 0; i < nshells; i++)
		off[i + 1] += off[i];
	for (size_t t = 0; t < m->ntris; t++)
		if (in_layer[t])
			list[off[shell[t]]++] = lpos[t];
	for (size_t i = nshells; i > 0; i--)
		off[i] = off[i - 1];
	off[0] = 0;

	ntouch = touching_pairs(m, in_layer, shell, &touch);
	within_off = malloc((nshells + 1) * sizeof(*within_off));
	if (ntouch < 0 || !within_off || boxes_within(s, nshells, within_off, &within) < 0)
		goto out_nomem;
	ix = calloc(nshells + 1, sizeof(*ix));
	if (!ix)
		goto out_nomem;
	/* outer[i]: the innermost outward shell around i (UINT32_MAX: none);
	 * depth and winding from every shell around i. */
	for (size_t i = 0; i < nshells && !rc; i++) {
		uint32_t best = UINT32_MAX;
		for (size_t w = within_off[i]; w < within_off[i + 1] && !rc; w++) {
			const uint32_t j = within[w];
			bool inside = false;
			if ((s[i].volume > 0) == (s[j].volume > 0) &&
			    touching(touch, (size_t)ntouch, (uint32_t)i, (uint32_t)j))
				continue;
			rc = shell_holds(em, list, off, j, list[off[i]], ix, &inside, err);
			if (rc || !inside)
				continue;
			s[i].depth++;
			s[i].winding += s[j].volume > 0 ? 1 : -1;
			/* Nested shells' boxes nest too: the smallest is innermost. */
			if (s[j].volume > 0 &&
			    (best == UINT32_MAX || box_within(&s[j], &s[best])))
				best = (uint32_t)j;
		}
		outer[i] = best;
		order[i].depth = s[i].depth;
		order[i].id = (uint32_t)i;
	}
	if (rc)
		goto out;
	qsort(order, nshells, sizeof(*order), id_depth_compare);
	out->parts = 0;
	for (size_t n = 0; n < nshells; n++) {
		const uint32_t i = order[n].id;
		const int inside = s[i].winding + (s[i].volume > 0 ? 1 : -1);

		if (s[i].winding == 1 && inside == 0 && outer[i] != UINT32_MAX) {
			out->cavities++;
			s[i].part = s[outer[i]].part; /* outer is shallower: numbered */
			continue;
		}
		if (s[i].winding != 0 || inside != 1)
			out->misnested++;
		s[i].part = (uint32_t)out->parts++;
		/* outer is shallower, so numbered; its part holds this one. */
		if (around && outer[i] != UINT32_MAX)
			around[s[i].part] = s[outer[i]].part;
	}

assign:
	if (part)
		for (size_t t = 0; t < m->ntris; t++)
			part[t] = in_layer[t] ? s[shell[t]].part : UINT32_MAX;
	goto out;

out_nomem:
	rc = st_error_set(err, ST_ERR_NOMEM, "out of memory telling parts from cavities");
out:
	exact_mesh_free(em);
	free(s);
	free(off);
	free(list);
	free(lpos);
	free(order);
	free(outer);
	free(touch);
	free(within);
	free(within_off);
	for (size_t j = 0; ix && j < nshells; j++)
		exact_ray_index_free(ix[j]);
	free(ix);
	return rc;
}

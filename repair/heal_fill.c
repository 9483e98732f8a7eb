/*
 * heal_fill.c - step 3 of the healing (heal.h; docs/repair.md, "Healing"):
 * close the holes of shells that are nearly closed, leave open surfaces
 * alone.
 *
 * A shell is a vertex-connected part of the mesh.  Its holes are the loops
 * of its boundary edges, walked opposite to the triangles along them so a
 * patch is oriented like its shell.  All holes of a shell are triangulated
 * (repair/exact/holefill.h); the patches are kept only when every hole
 * has one and together they cover at most HEAL_FILL_FRACTION of the
 * shell's area: filling then closes the shell, and the patch is small
 * against it.  An open surface -- a fin, a flag, a wall, an open box --
 * needs a patch as large as a good part of itself and stays as it is, for
 * the repair to thicken as a sheet.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "heal.h"
#include "holefill.h"
#include "exact.h"
#include "ids.h"
#include "vec3.h"
#include "st_grow.h"

/* One hole: vertices loop[first..first+n) of the loop table. */
struct hole {
	size_t first, n;
	uint32_t shell;
	double area;	/* mm^2 of its patch, once triangulated */
};

/* The holes of a mesh and what walking them found. */
struct holes {
	uint32_t *vert;		/* loop vertices, hole after hole */
	uint32_t *third;	/* far corner of the triangle along each edge */
	struct hole *h;
	size_t nh, nv;
	uint8_t *tangled;	/* per shell root: a boundary vertex without one way on */
};

static void holes_free(struct holes *hs)
{
	free(hs->vert);
	free(hs->third);
	free(hs->h);
	free(hs->tangled);
}

/* A hole edge from -> to, the reverse of a boundary edge of triangle t. */
struct hole_edge {
	uint32_t from, to, far, t;
};

static int compare_hole_edge(const void *pa, const void *pb)
{
	const struct hole_edge *x = pa, *y = pb;

	if (x->from != y->from)
		return x->from < y->from ? -1 : 1;
	return x->to < y->to ? -1 : x->to > y->to;
}

/* Index of the first of the n edges e (sorted by a, b) equal to {a, b}, or n. */
static size_t find_edge(const struct heal_edge *e, size_t n, uint32_t a, uint32_t b)
{
	const uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
	size_t l = 0, h = n;

	while (l < h) {
		const size_t m = l + (h - l) / 2;
		if (e[m].a < lo || (e[m].a == lo && e[m].b < hi))
			l = m + 1;
		else
			h = m;
	}
	return l < n && e[l].a == lo && e[l].b == hi ? l : n;
}

/* The corner of triangle t that is neither a nor b. */
static uint32_t third_corner(const uint32_t t[3], uint32_t a, uint32_t b)
{
	int k = 0;

	while (t[k] == a || t[k] == b)
		k++;
	return t[k];
}

/*
 * At a pinch (a vertex v with several hole edges leaving it): the hole
 * edge leaving v from the same fan as triangle t, found turning around v
 * through t's fan: from t across its other edge at v (to corner c),
 * triangle by triangle, each edge shared by exactly two.  Returns its index
 * in be (nb of them, sorted), or nb when the fan is not a simple one.
 */
static size_t fan_next(const struct heal_work *w, const struct heal_edge *e, size_t ne,
		       const struct hole_edge *be, size_t nb, uint32_t v, uint32_t t, uint32_t c)
{
	for (size_t steps = 0; steps < ne; steps++) {
		/* Is v -> c the hole edge of t's boundary edge c -> v? */
		const struct hole_edge key = {.from = v, .to = c};
		const struct hole_edge *hit = bsearch(&key, be, nb, sizeof(*be), compare_hole_edge);
		if (hit && hit->t == t)
			return (size_t)(hit - be);
		const size_t i = find_edge(e, ne, v, c);
		if (i == ne || i + 2 > ne || e[i + 1].a != e[i].a || e[i + 1].b != e[i].b ||
		    (i + 2 < ne && e[i + 2].a == e[i].a && e[i + 2].b == e[i].b))
			return nb; /* singular, or oriented against t: no way round */
		const uint32_t u = e[i].t == t ? e[i + 1].t : e[i].t;
		c = third_corner(w->tris[u], v, c);
		t = u;
	}
	return nb;
}

/*
 * Walk the boundary of w into holes.  Boundary edge a->b of triangle
 * (a, b, c) gives the hole edge b->a with far corner c.  At a vertex with
 * one hole edge out the walk takes it; where two fans meet (a pinch) it
 * leaves along the fan it did not come along (fan_next finds the one it
 * came along).  A hole that cannot be walked
 * back to its start (triangles oriented against each other, a singular
 * fan) makes its shell tangled: such a shell is not filled.
 */
static int find_holes(const struct heal_work *w, const uint32_t *shell, struct holes *hs,
		      struct st_error *err)
{
	struct heal_edge *e = NULL;
	struct hole_edge *be = NULL;
	size_t ne = 0, nb = 0;
	uint8_t *used = NULL;
	int rc;

	memset(hs, 0, sizeof(*hs));
	rc = heal_edges(w, &e, &ne, err);
	if (rc)
		return rc;
	be = malloc((ne + 1) * sizeof(*be));
	hs->tangled = calloc(w->nverts + 1, 1);
	hs->vert = malloc((ne + 1) * sizeof(*hs->vert));
	hs->third = malloc((ne + 1) * sizeof(*hs->third));
	hs->h = malloc((ne + 1) * sizeof(*hs->h));
	if (!be || !hs->tangled || !hs->vert || !hs->third || !hs->h) {
		rc = st_error_set(err, ST_ERR_NOMEM, "heal: out of memory finding holes");
		goto out;
	}
	for (size_t i = 0; i < ne;) {
		size_t j = i + 1;
		while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b)
			j++;
		if (j == i + 1) {
			const uint32_t *t = w->tris[e[i].t];
			int k = 0;
			while (t[k] == e[i].a || t[k] == e[i].b)
				k++;
			/* t walks t[k+1] -> t[k+2] along the edge; the hole back. */
			be[nb].from = t[(k + 2) % 3];
			be[nb].to = t[(k + 1) % 3];
			be[nb].far = t[k];
			be[nb].t = e[i].t;
			nb++;
		}
		i = j;
	}
	qsort(be, nb, sizeof(*be), compare_hole_edge);
	used = calloc(nb + 1, 1);
	if (!used) {
		rc = st_error_set(err, ST_ERR_NOMEM, "heal: out of memory finding holes");
		goto out;
	}
	for (size_t s = 0; s < nb; s++) {
		if (used[s] || hs->tangled[shell[be[s].from]])
			continue;
		struct hole *h = &hs->h[hs->nh];
		size_t x = s;
		h->first = hs->nv;
		h->shell = shell[be[s].from];
		h->area = 0;
		while (x < nb && !used[x]) {
			used[x] = 1;
			hs->vert[hs->nv] = be[x].from;
			hs->third[hs->nv] = be[x].far;
			hs->nv++;
			/* The hole edges leaving be[x].to: one, or a pinch. */
			const uint32_t v = be[x].to;
			const struct hole_edge key = {.from = v, .to = 0};
			size_t lo = 0, hi = nb;
			while (lo < hi) {
				const size_t m = lo + (hi - lo) / 2;
				if (compare_hole_edge(&be[m], &key) < 0)
					lo = m + 1;
				else
					hi = m;
			}
			if (lo + 2 < nb && be[lo + 2].from == v) {
				x = nb; /* three holes at one vertex: no way to tell */
			} else if (lo + 1 < nb && be[lo + 1].from == v) {
				/* Two fans meet at v, two hole sectors between them:
				 * the one this hole ran along ends at the other fan. */
				const size_t own = fan_next(w, e, ne, be, nb, v, be[x].t, be[x].far);
				x = own == lo ? lo + 1 : own == lo + 1 ? lo : nb;
			} else {
				x = lo < nb && be[lo].from == v ? lo : nb;
			}
		}
		h->n = hs->nv - h->first;
		if (x != s || h->n < 3) /* did not come back: a boundary that does not close */
			hs->tangled[h->shell] = 1;
		else
			hs->nh++;
	}
out:
	free(e);
	free(be);
	free(used);
	if (rc)
		holes_free(hs);
	return rc;
}

/* A patch waiting for its shell's verdict: triangles over mesh vertices. */
struct patch {
	uint32_t (*tris)[3];
	size_t n, cap;
	double area;
};

static int patch_add(struct patch *p, const uint32_t t[3])
{
	uint32_t (*nt)[3] = st_grow(p->tris, &p->cap, p->n + 1, sizeof(*nt));

	if (!nt)
		return -1;
	p->tris = nt;
	memcpy(p->tris[p->n++], t, sizeof(uint32_t[3]));
	return 0;
}

/* Append np points to w's vertices; their ids follow the old ones. */
static int add_points(struct heal_work *w, const double (*pts)[3], size_t np,
		      struct st_error *err)
{
	double (*nv)[3];

	if (np == 0)
		return 0;
	if (w->nverts + np > MESH_MAX_ELEMENTS)
		return st_error_set(err, ST_ERR_RANGE, "heal: too many vertices after filling");
	nv = st_grow(w->verts, &w->cap_verts, w->nverts + np, sizeof(*nv));
	if (!nv)
		return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory filling a hole");
	memcpy(nv[w->nverts], pts, np * sizeof(*nv));
	w->verts = nv;
	w->nverts += np;
	return 0;
}

/*
 * Fill hole h into p (appending): triangulated, refined and faired
 * (holefill.h); the faired patch's new points become vertices of w.  *ok
 * false when CGAL found no triangulation.
 */
static int fill_one(struct heal_work *w, const struct holes *hs, struct hole *h,
		    struct patch *p, bool *ok, struct st_error *err)
{
	double (*loop)[3] = malloc(h->n * sizeof(*loop));
	double (*far)[3] = malloc(h->n * sizeof(*far));
	double (*pts)[3] = NULL;
	uint32_t (*tris)[3] = NULL;
	size_t nt = 0, np = 0;
	const size_t first_new = w->nverts;
	int rc;

	*ok = false;
	if (!loop || !far) {
		free(loop);
		free(far);
		return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory filling a hole");
	}
	for (size_t i = 0; i < h->n; i++) {
		memcpy(loop[i], w->verts[hs->vert[h->first + i]], sizeof(loop[i]));
		memcpy(far[i], w->verts[hs->third[h->first + i]], sizeof(far[i]));
	}
	rc = exact_fill_hole((const double(*)[3])loop, h->n, (const double(*)[3])far, &pts, &np,
			     &tris, &nt, err);
	free(loop);
	free(far);
	if (!rc)
		rc = add_points(w, (const double(*)[3])pts, np, err);
	free(pts);
	for (size_t t = 0; t < nt && !rc; t++) {
		uint32_t m[3];
		for (int k = 0; k < 3; k++) {
			const uint32_t i = tris[t][k];
			m[k] = i < h->n ? hs->vert[h->first + i] : (uint32_t)(first_new + i - h->n);
		}
		h->area += vec3_tri_area(w->verts[m[0]], w->verts[m[1]], w->verts[m[2]]);
		if (patch_add(p, m))
			rc = st_error_set(err, ST_ERR_NOMEM, "heal: out of memory filling a hole");
	}
	free(tris);
	if (rc)
		return rc;
	p->area += h->area;
	*ok = nt > 0;
	return 0;
}

static int compare_hole_shell(const void *pa, const void *pb)
{
	const struct hole *a = pa, *b = pb;

	if (a->shell != b->shell)
		return a->shell < b->shell ? -1 : 1;
	return (a->first > b->first) - (a->first < b->first);
}

/* Append the patch's triangles to w. */
static int append_patch(struct heal_work *w, const struct patch *p, struct st_error *err)
{
	uint32_t (*nt)[3];

	if (w->ntris + p->n > MESH_MAX_ELEMENTS)
		return st_error_set(err, ST_ERR_RANGE, "heal: too many triangles after filling");
	nt = st_grow(w->tris, &w->cap_tris, w->ntris + p->n, sizeof(*nt));
	if (!nt)
		return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory filling holes");
	w->tris = nt;
	memcpy(w->tris[w->ntris], p->tris, p->n * sizeof(*p->tris));
	w->ntris += p->n;
	return 0;
}

/*
 * Pairs of w's triangles of shell sh (shell[] per vertex of the first
 * nt_old triangles) and the ones after them that meet outside a shared
 * face, exactly; skip is scratch for w->ntris flags.
 */
static int count_crossings(const struct heal_work *w, const uint32_t *shell, uint32_t sh,
			   size_t nt_old, uint8_t *skip, uint64_t *count, struct st_error *err)
{
	/* Triangles from nt_old on are the patch, over new vertices too. */
	for (size_t t = 0; t < w->ntris; t++)
		skip[t] = t < nt_old && shell[w->tris[t][0]] != sh;
	return exact_count_self_intersections((const double(*)[3])w->verts, w->nverts,
					      (const uint32_t(*)[3])w->tris, w->ntris, skip, 0,
					      count, err);
}

/*
 * Whether patch p would cross its own shell sh: the exact count of
 * intersecting pairs of the shell with p appended against the count
 * without it.  Such a patch (a hole whose rim is far from flat, spanned
 * through the model) would be cut by the repair into flaps that stick out;
 * its hole is left open.  What crosses other shells is a union the repair
 * resolves like any other.
 */
static int patch_crosses(struct heal_work *w, const uint32_t *shell, uint32_t sh,
			 const struct patch *p, bool *crossing, struct st_error *err)
{
	uint64_t without = 0, with = 0;
	const size_t nt_old = w->ntris;
	uint8_t *skip;
	int rc;

	*crossing = false;
	rc = append_patch(w, p, err); /* first, so skip is sized for both counts */
	if (rc)
		return rc;
	skip = malloc(w->ntris + 1);
	if (!skip) {
		w->ntris -= p->n;
		return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory checking a patch");
	}
	rc = count_crossings(w, shell, sh, nt_old, skip, &with, err);
	w->ntris -= p->n; /* the caller appends it if it is kept */
	if (!rc)
		rc = count_crossings(w, shell, sh, nt_old, skip, &without, err);
	free(skip);
	*crossing = !rc && with > without;
	return rc;
}

int heal_fill(struct heal_work *w, struct repair_report *rep, struct st_error *err)
{
	uint32_t *shell = malloc((w->nverts + 1) * sizeof(*shell));
	double *area = calloc(w->nverts + 1, sizeof(*area));
	struct holes hs = {0};
	struct patch p = {0};
	size_t nt0 = w->ntris;
	int rc = 0;

	rep->kept_patch_fraction = 0;
	if (!shell || !area) {
		rc = st_error_set(err, ST_ERR_NOMEM, "heal: out of memory finding shells");
		goto out;
	}
	for (size_t v = 0; v < w->nverts; v++)
		shell[v] = (uint32_t)v;
	for (size_t t = 0; t < nt0; t++) {
		uf_union(shell, w->tris[t][0], w->tris[t][1]);
		uf_union(shell, w->tris[t][0], w->tris[t][2]);
	}
	for (size_t v = 0; v < w->nverts; v++)
		shell[v] = uf_find(shell, (uint32_t)v);
	for (size_t t = 0; t < nt0; t++) {
		const uint32_t *c = w->tris[t];
		area[shell[c[0]]] += vec3_tri_area(w->verts[c[0]], w->verts[c[1]], w->verts[c[2]]);
	}
	rc = find_holes(w, shell, &hs, err);
	if (rc)
		goto out;
	/* Loops of tangled shells are not walked; count each shell once. */
	for (size_t v = 0; v < w->nverts; v++)
		if (hs.tangled[v])
			rep->holes_kept++;
	qsort(hs.h, hs.nh, sizeof(*hs.h), compare_hole_shell);
	for (size_t i = 0; i < hs.nh;) {
		size_t j = i;
		bool all = !hs.tangled[hs.h[i].shell];
		p.n = 0;
		p.area = 0;
		for (j = i; j < hs.nh && hs.h[j].shell == hs.h[i].shell; j++) {
			bool ok = false;
			if (!all)
				continue;
			rc = fill_one(w, &hs, &hs.h[j], &p, &ok, err);
			if (rc)
				goto out;
			all = ok;
		}
		const double shell_area = area[hs.h[i].shell];
		const double frac = shell_area > 0 ? p.area / shell_area : HUGE_VAL;
		bool crossing = false;
		if (all && frac <= HEAL_FILL_FRACTION) {
			rc = patch_crosses(w, shell, hs.h[i].shell, &p, &crossing, err);
			if (rc)
				goto out;
		}
		if (all && frac <= HEAL_FILL_FRACTION && !crossing) {
			for (size_t k = i; k < j; k++) {
				if (rep->holes_filled < REPAIR_HOLES_LISTED)
					rep->hole_area[rep->holes_filled] = hs.h[k].area;
				rep->holes_filled++;
			}
			rep->fill_area += p.area;
			rep->fill_triangles += p.n;
			rc = append_patch(w, &p, err);
			if (rc)
				goto out;
		} else {
			rep->holes_kept += j - i;
			if (crossing)
				rep->holes_crossing += j - i;
			if (rep->kept_patch_fraction == 0 || frac < rep->kept_patch_fraction)
				rep->kept_patch_fraction = frac;
		}
		i = j;
	}
out:
	free(shell);
	free(area);
	free(p.tris);
	holes_free(&hs);
	return rc;
}

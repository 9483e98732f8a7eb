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
#include "ids.h"
#include "vec3.h"

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

/*
 * Walk the boundary of w into holes.  Boundary edge a->b of triangle
 * (a, b, c) gives the hole edge b->a with far corner c.  A vertex with
 * other than one hole edge out (a pinch, or triangles oriented against
 * each other) makes its shell tangled: such a shell is not filled.
 */
static int find_holes(const struct heal_work *w, const uint32_t *shell, struct holes *hs,
		      struct st_error *err)
{
	struct heal_edge *e = NULL;
	size_t ne = 0, nb = 0;
	uint32_t *out_to = NULL, *out_far = NULL, *outs = NULL;
	uint8_t *seen = NULL;
	int rc;

	memset(hs, 0, sizeof(*hs));
	rc = heal_edges(w, &e, &ne, err);
	if (rc)
		return rc;
	out_to = malloc((w->nverts + 1) * sizeof(*out_to));
	out_far = malloc((w->nverts + 1) * sizeof(*out_far));
	outs = calloc(w->nverts + 1, sizeof(*outs));
	seen = calloc(w->nverts + 1, 1);
	hs->tangled = calloc(w->nverts + 1, 1);
	hs->vert = malloc((ne + 1) * sizeof(*hs->vert));
	hs->third = malloc((ne + 1) * sizeof(*hs->third));
	hs->h = malloc((ne + 1) * sizeof(*hs->h));
	if (!out_to || !out_far || !outs || !seen || !hs->tangled || !hs->vert || !hs->third ||
	    !hs->h) {
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
			const uint32_t from = t[(k + 2) % 3], to = t[(k + 1) % 3];
			outs[from]++;
			out_to[from] = to;
			out_far[from] = t[k];
			nb++;
		}
		i = j;
	}
	for (size_t v = 0; v < w->nverts; v++)
		if (outs[v] > 1)
			hs->tangled[shell[v]] = 1;
	for (size_t v = 0; v < w->nverts; v++) {
		if (outs[v] != 1 || seen[v] || hs->tangled[shell[v]])
			continue;
		struct hole *h = &hs->h[hs->nh];
		uint32_t x = (uint32_t)v;
		h->first = hs->nv;
		h->shell = shell[v];
		h->area = 0;
		while (!seen[x] && outs[x] == 1 && hs->nv < nb) {
			seen[x] = 1;
			hs->vert[hs->nv] = x;
			hs->third[hs->nv] = out_far[x];
			hs->nv++;
			x = out_to[x];
		}
		h->n = hs->nv - h->first;
		if (x != v || h->n < 3) /* did not come back: a boundary that does not close */
			hs->tangled[shell[v]] = 1;
		else
			hs->nh++;
	}
out:
	free(e);
	free(out_to);
	free(out_far);
	free(outs);
	free(seen);
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
	if (p->n == p->cap) {
		size_t cap = p->cap ? 2 * p->cap : 64;
		uint32_t (*nt)[3];
		if (cap > SIZE_MAX / sizeof(*nt))
			return -1;
		nt = realloc(p->tris, cap * sizeof(*nt));
		if (!nt)
			return -1;
		p->tris = nt;
		p->cap = cap;
	}
	memcpy(p->tris[p->n++], t, sizeof(uint32_t[3]));
	return 0;
}

/* Triangulate hole h into p (appending); *ok false when CGAL found none. */
static int fill_one(const struct heal_work *w, const struct holes *hs, struct hole *h,
		    struct patch *p, bool *ok, struct st_error *err)
{
	double (*loop)[3] = malloc(h->n * sizeof(*loop));
	double (*far)[3] = malloc(h->n * sizeof(*far));
	uint32_t (*tris)[3] = NULL;
	size_t nt = 0;
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
	rc = exact_fill_hole((const double(*)[3])loop, h->n, (const double(*)[3])far, &tris, &nt,
			     err);
	free(loop);
	free(far);
	if (rc)
		return rc;
	for (size_t t = 0; t < nt; t++) {
		uint32_t m[3];
		for (int k = 0; k < 3; k++)
			m[k] = hs->vert[h->first + tris[t][k]];
		h->area += vec3_tri_area(w->verts[m[0]], w->verts[m[1]], w->verts[m[2]]);
		if (patch_add(p, m)) {
			free(tris);
			return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory filling a hole");
		}
	}
	free(tris);
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
	if (w->ntris + p->n > w->cap_tris) {
		size_t cap = 2 * w->cap_tris + p->n;
		uint32_t (*nt)[3];
		if (cap > MESH_MAX_ELEMENTS)
			return st_error_set(err, ST_ERR_RANGE, "heal: too many triangles after filling");
		nt = realloc(w->tris, cap * sizeof(*nt));
		if (!nt)
			return st_error_set(err, ST_ERR_NOMEM, "heal: out of memory filling holes");
		w->tris = nt;
		w->cap_tris = cap;
	}
	memcpy(w->tris[w->ntris], p->tris, p->n * sizeof(*p->tris));
	w->ntris += p->n;
	return 0;
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
		if (all && frac <= HEAL_FILL_FRACTION) {
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

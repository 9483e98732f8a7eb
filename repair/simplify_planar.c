/*
 * simplify_planar.c - planar simplification end to end (simplify_planar.h):
 * clusters (planar_grow.c), each re-triangulated (planar_retri.c), then
 * the whole checked for open or non-manifold edges and for crossings
 * (planar_cdt.h, exact); a cluster that fails is left as it was and its
 * neighbours are redone keeping its vertices, until nothing fails.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "planar_cdt.h"
#include "planar_impl.h"

void planar_options_init(struct planar_options *opt)
{
	opt->angle = PLANAR_ANGLE_DEFAULT;
	opt->flatness = PLANAR_FLATNESS_DEFAULT;
	opt->threads = 0;
}

static void ctx_free(struct planar_ctx *x)
{
	for (size_t c = 0; c < x->ncl; c++)
		free(x->cl[c].tris);
	free(x->cl);
	free(x->usable);
	free(x->nb);
	free(x->area);
	free(x->unit);
	free(x->vt_start);
	free(x->vt);
	free(x->clean);
	free(x->edges);
	free(x->cluster);
	free(x->cl_tris);
	free(x->role);
	free(x->kept);
	free(x->next);
	free(x->stamp);
	free(x->seen);
}

/*
 * Leave cluster c as it was: its vertices are kept, so every cluster
 * around one of them that was to drop it as a seam vertex is redone.
 */
static void refuse(struct planar_ctx *x, uint32_t c, size_t *counter)
{
	struct planar_cluster *cl = &x->cl[c];

	free(cl->tris);
	cl->tris = NULL;
	cl->ntris = 0;
	cl->state = PLANAR_REFUSED;
	cl->dirty = false;
	(*counter)++;
	for (size_t i = 0; i < cl->n; i++) {
		const uint32_t *v = x->m->tris[x->cl_tris[cl->first + i]];
		for (int k = 0; k < 3; k++) {
			if (x->kept[v[k]])
				continue;
			x->kept[v[k]] = 1;
			if (x->role[v[k]] != PLANAR_SEAM)
				continue;
			for (size_t j = x->vt_start[v[k]]; j < x->vt_start[v[k] + 1]; j++) {
				struct planar_cluster *o = &x->cl[x->cluster[x->vt[j]]];
				o->dirty = o->state != PLANAR_REFUSED;
			}
		}
	}
}

/* Re-triangulate every dirty cluster; refusals may make others dirty. */
static int settle(struct planar_ctx *x, struct planar_report *rep, struct st_error *err)
{
	bool again = true;

	while (again) {
		again = false;
		for (uint32_t c = 0; c < x->ncl; c++) {
			struct planar_cluster *cl = &x->cl[c];
			size_t *refusal;
			int rc;

			if (!cl->dirty)
				continue;
			cl->dirty = false;
			rc = planar_retriangulate(x, c, &refusal, rep, err);
			if (rc)
				return rc;
			if (refusal) {
				refuse(x, c, refusal);
				again = true;
			}
		}
	}
	return 0;
}

/* The mesh as it stands: usable triangles, new ones flagged fresh, with
 * the cluster each comes from. */
struct assembly {
	uint32_t (*tris)[3];
	uint32_t *cluster;
	uint8_t *fresh, *hit;
	size_t n;
};

static int assemble(const struct planar_ctx *x, struct assembly *a)
{
	const struct mesh *m = x->m;
	size_t n = 0;

	for (size_t c = 0; c < x->ncl; c++)
		n += x->cl[c].state == PLANAR_NEW ? x->cl[c].ntris : x->cl[c].n;
	a->tris = malloc((n + 1) * sizeof(*a->tris));
	a->cluster = malloc((n + 1) * sizeof(*a->cluster));
	a->fresh = malloc(n + 1);
	a->hit = malloc(n + 1);
	if (!a->tris || !a->cluster || !a->fresh || !a->hit)
		return ST_ERR_NOMEM;
	a->n = 0;
	for (uint32_t c = 0; c < x->ncl; c++) {
		const struct planar_cluster *cl = &x->cl[c];
		const bool fresh = cl->state == PLANAR_NEW;
		const size_t k = fresh ? cl->ntris : cl->n;
		for (size_t i = 0; i < k; i++) {
			memcpy(a->tris[a->n], fresh ? cl->tris[i] : m->tris[x->cl_tris[cl->first + i]],
			       sizeof(a->tris[0]));
			a->cluster[a->n] = c;
			a->fresh[a->n++] = fresh;
		}
	}
	return 0;
}

static void assembly_free(struct assembly *a)
{
	free(a->tris);
	free(a->cluster);
	free(a->fresh);
	free(a->hit);
	memset(a, 0, sizeof(*a));
}

/* A directed edge of the assembly. */
struct dedge {
	uint32_t a, b, tri; /* a < b */
	uint8_t forward;    /* runs a -> b in its triangle */
};

static int dedge_compare(const void *pa, const void *pb)
{
	const struct dedge *p = pa, *q = pb;

	if (p->a != q->a)
		return p->a < q->a ? -1 : 1;
	return p->b < q->b ? -1 : p->b > q->b;
}

/*
 * Flag (hit) every new triangle on an edge that would not be as closed and
 * manifold as before: an edge that existed keeps its facet count, a new
 * one has exactly two facets running it in opposite directions.
 */
static int check_edges(const struct planar_ctx *x, struct assembly *a)
{
	struct dedge *e = malloc((3 * a->n + 1) * sizeof(*e));
	size_t ne = 0;

	if (!e)
		return ST_ERR_NOMEM;
	for (size_t t = 0; t < a->n; t++)
		for (int k = 0; k < 3; k++) {
			const uint32_t p = a->tris[t][k], q = a->tris[t][(k + 1) % 3];
			e[ne++] = (struct dedge){p < q ? p : q, p < q ? q : p, (uint32_t)t, p < q};
		}
	qsort(e, ne, sizeof(*e), dedge_compare);
	for (size_t i = 0; i < ne;) {
		size_t j = i, fresh = 0, forward = 0;
		while (j < ne && e[j].a == e[i].a && e[j].b == e[i].b) {
			fresh += a->fresh[e[j].tri];
			forward += e[j].forward;
			j++;
		}
		if (fresh) {
			const uint32_t before = planar_edge_count(x, e[i].a, e[i].b);
			const size_t count = j - i;
			bool ok = before ? count == before : count == 2;
			if (count == 2)
				ok = ok && forward == 1;
			for (size_t k = i; k < j && !ok; k++)
				a->hit[e[k].tri] |= a->fresh[e[k].tri];
		}
		i = j;
	}
	free(e);
	return 0;
}

/* Refuse the clusters of flagged triangles; true when any was. */
static bool refuse_hit(struct planar_ctx *x, const struct assembly *a, size_t *counter)
{
	bool any = false;

	for (size_t t = 0; t < a->n; t++)
		if (a->hit[t] && x->cl[a->cluster[t]].state == PLANAR_NEW) {
			refuse(x, a->cluster[t], counter);
			any = true;
		}
	return any;
}

/* Until no check fails: re-triangulate, check edges, check crossings. */
static int simplify_clusters(struct planar_ctx *x, struct planar_report *rep,
			     struct st_error *err)
{
	struct assembly a = {0};
	int rc = 0;

	for (size_t c = 0; c < x->ncl; c++)
		x->cl[c].dirty = x->cl[c].n > 1;
	for (;;) {
		if ((rc = settle(x, rep, err)))
			break;
		assembly_free(&a);
		if ((rc = assemble(x, &a)))
			break;
		memset(a.hit, 0, a.n);
		if ((rc = check_edges(x, &a)))
			break;
		if (refuse_hit(x, &a, &rep->refused_topology))
			continue;
		rc = planar_cdt_crossings((const double(*)[3])x->m->verts, x->m->nverts,
					  (const uint32_t(*)[3])a.tris, a.n, a.fresh, a.hit, err);
		if (rc || !refuse_hit(x, &a, &rep->refused_crossing))
			break;
	}
	if (rc == ST_ERR_NOMEM)
		st_error_set(err, rc, "planar simplification: out of memory checking %zu triangles",
			     a.n);
	assembly_free(&a);
	return rc;
}

/* The output: input order, a cluster's new triangles where its first was. */
static int build_output(const struct planar_ctx *x, struct mesh **out, uint32_t **origin,
			struct st_error *err)
{
	const struct mesh *m = x->m;
	struct mesh_builder *b = mesh_builder_new(m->ntris);
	uint32_t *org = malloc((m->ntris + 1) * sizeof(*org));
	uint32_t *index = malloc((m->nverts + 1) * sizeof(*index));
	size_t n = 0;
	int rc = 0;

	if (!b || !org || !index) {
		rc = st_error_set(err, ST_ERR_NOMEM, "planar simplification: out of memory");
		goto out;
	}
	for (size_t v = 0; v < m->nverts; v++)
		index[v] = PLANAR_NONE;
	for (size_t t = 0; t < m->ntris && !rc; t++) {
		const uint32_t c = x->cluster[t];
		const struct planar_cluster *cl = c == PLANAR_NONE ? NULL : &x->cl[c];
		const bool fresh = cl && cl->state == PLANAR_NEW;
		const uint32_t(*src)[3] = fresh ? (const uint32_t(*)[3])cl->tris
						: (const uint32_t(*)[3])&m->tris[t];
		const size_t k = fresh ? cl->ntris : 1;

		if (fresh && x->cl_tris[cl->first] != t)
			continue; /* its triangles went out with its first facet */
		for (size_t i = 0; i < k && !rc; i++) {
			uint32_t w[3];
			for (int j = 0; j < 3 && !rc; j++) {
				if (index[src[i][j]] == PLANAR_NONE)
					rc = mesh_builder_vertex(b, m->verts[src[i][j]],
								 &index[src[i][j]], err);
				w[j] = index[src[i][j]];
			}
			if (!rc)
				rc = mesh_builder_triangle(b, w[0], w[1], w[2], err);
			org[n++] = (uint32_t)t;
		}
	}
	if (!rc) {
		*out = mesh_builder_finish(b);
		b = NULL;
		if (!*out)
			rc = st_error_set(err, ST_ERR_NOMEM, "planar simplification: out of memory");
	}
	if (!rc && origin) {
		*origin = org;
		org = NULL;
	}
out:
	mesh_builder_free(b);
	free(org);
	free(index);
	return rc;
}

/*
 * The last word: the result analysed as `stratum check` does and compared
 * with the input.  The per-cluster checks make a difference impossible;
 * one found here is a bug, reported rather than written.
 */
static int compare_reports(const struct mesh_report *a, const struct mesh_report *b,
			   struct st_error *err)
{
	const char *what = a->components != b->components		   ? "components"
			   : a->manifold_components != b->manifold_components ? "shells"
			   : a->parts != b->parts				   ? "parts"
			   : a->cavities != b->cavities			   ? "cavities"
			   : a->euler != b->euler				   ? "Euler characteristic"
			   : a->boundary_edges != b->boundary_edges		   ? "boundary edges"
			   : a->singular_edges != b->singular_edges		   ? "singular edges"
			   : a->nonmanifold_vertices != b->nonmanifold_vertices ? "non-manifold vertices"
			   : a->consistently_oriented && !b->consistently_oriented ? "orientation"
			   : b->self_intersections > a->self_intersections	   ? "self-intersections"
			   : a->printable && !b->printable			   ? "printable"
										   : NULL;

	if (!what)
		return 0;
	return st_error_set(err, ST_ERR_INTERNAL,
			    "planar simplification changed the %s of the mesh (a bug: nothing "
			    "written; run without --simplify-planar)", what);
}

int planar_simplify(const struct mesh *in, const struct planar_options *opt, struct mesh **out,
		    uint32_t **origin, struct planar_report *rep, struct st_error *err)
{
	struct planar_ctx x = {0};
	struct mesh_report before, after;
	int rc;

	if (out)
		*out = NULL;
	if (origin)
		*origin = NULL;
	if (!in || !opt || !out || !rep)
		return st_error_set(err, ST_ERR_ARG, "planar simplification: NULL argument");
	if (!(opt->angle >= 0 && opt->angle <= PLANAR_ANGLE_MAX) ||
	    !(opt->flatness >= 0 && opt->flatness <= PLANAR_FLATNESS_MAX) || opt->threads < 0)
		return st_error_set(err, ST_ERR_ARG,
				    "planar simplification: angle %g (0..%g degrees), flatness %g "
				    "(0..%g mm) or threads %d out of range",
				    opt->angle, PLANAR_ANGLE_MAX, opt->flatness, PLANAR_FLATNESS_MAX,
				    opt->threads);
	memset(rep, 0, sizeof(*rep));
	rep->triangles_before = in->ntris;
	rep->vertices_before = in->nverts;
	x.m = in;
	x.opt = opt;
	if ((rc = mesh_analyze(in, opt->threads, &before, err)) || (rc = planar_grow(&x, err)) ||
	    (rc = simplify_clusters(&x, rep, err)) || (rc = build_output(&x, out, origin, err)))
		goto out;
	for (size_t c = 0; c < x.ncl; c++) {
		rep->clusters += x.cl[c].n > 1;
		if (x.cl[c].state == PLANAR_NEW) {
			rep->retriangulated++;
			rep->max_deviation = fmax(rep->max_deviation, x.cl[c].deviation);
		}
	}
	for (size_t t = 0; t < in->ntris; t++)
		rep->area += x.area[t];
	rep->triangles_after = (*out)->ntris;
	rep->vertices_after = (*out)->nverts;
	if ((rc = mesh_analyze(*out, opt->threads, &after, err)) ||
	    (rc = compare_reports(&before, &after, err)))
		goto out;
	rep->volume_before = before.volume;
	rep->volume_after = after.volume;
out:
	if (rc) {
		mesh_free(*out);
		*out = NULL;
		if (origin) {
			free(*origin);
			*origin = NULL;
		}
	}
	ctx_free(&x);
	return rc;
}

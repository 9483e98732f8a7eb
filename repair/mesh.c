/*
 * mesh.c - indexed mesh construction with exact vertex welding.
 *
 * Welding uses an open-addressing hash table of vertex indices keyed by the
 * bit pattern of the coordinates, so only bit-identical positions merge.
 */
#include "mesh.h"
#include "st_grow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct mesh_builder {
	struct mesh *mesh;
	uint32_t *slots;	/* vertex index + 1, 0 = empty */
	size_t nslots;		/* power of two */
};

/* Bit pattern of a coordinate with -0.0 folded onto +0.0 (same point). */
static uint64_t coord_bits(double v)
{
	uint64_t u;

	if (v == 0.0)
		v = 0.0;
	memcpy(&u, &v, sizeof(u));
	return u;
}

/* One multiply per coordinate pattern and a splitmix64-style finish: the
 * finish spreads the high mantissa bits (round coordinates leave the low
 * ones zero) onto the low bits that pick the slot; reading a 1M-triangle
 * STL spends most of its time here, so one round, not three. */
static uint64_t hash_point(const double p[3])
{
	uint64_t h = coord_bits(p[0]) * 0x9e3779b97f4a7c15ull;

	h ^= coord_bits(p[1]) * 0xc2b2ae3d27d4eb4full;
	h ^= coord_bits(p[2]) * 0x165667b19e3779f9ull;
	h ^= h >> 29;
	h *= 0xbf58476d1ce4e5b9ull;
	h ^= h >> 32;
	return h;
}

static bool same_point(const double a[3], const double b[3])
{
	return coord_bits(a[0]) == coord_bits(b[0]) && coord_bits(a[1]) == coord_bits(b[1]) &&
	       coord_bits(a[2]) == coord_bits(b[2]);
}

/* Rebuild the hash table with nslots slots (a power of two). */
static int rehash(struct mesh_builder *b, size_t nslots)
{
	uint32_t *slots = calloc(nslots, sizeof(*slots));

	if (!slots)
		return -1;
	for (size_t v = 0; v < b->mesh->nverts; v++) {
		size_t i = hash_point(b->mesh->verts[v]) & (nslots - 1);
		while (slots[i])
			i = (i + 1) & (nslots - 1);
		slots[i] = (uint32_t)v + 1;
	}
	free(b->slots);
	b->slots = slots;
	b->nslots = nslots;
	return 0;
}

struct mesh_builder *mesh_builder_new(size_t tri_hint)
{
	struct mesh_builder *b = calloc(1, sizeof(*b));
	size_t nslots = 1024;

	if (!b)
		return NULL;
	b->mesh = calloc(1, sizeof(*b->mesh));
	if (!b->mesh)
		goto out_free_builder;
	/* A closed mesh has about half as many vertices as triangles. */
	if (tri_hint > MESH_MAX_ELEMENTS)
		tri_hint = 0;
	while (nslots < tri_hint + tri_hint / 4 && nslots < ((size_t)1 << 40))
		nslots *= 2;
	if (tri_hint && (st_grow_at((void **)&b->mesh->tris, &b->mesh->cap_tris, tri_hint,
				    sizeof(*b->mesh->tris)) ||
			 st_grow_at((void **)&b->mesh->verts, &b->mesh->cap_verts,
				    tri_hint / 2 + 16, sizeof(*b->mesh->verts))))
		goto out_free_mesh;
	if (rehash(b, nslots))
		goto out_free_mesh;
	return b;

out_free_mesh:
	mesh_free(b->mesh);
out_free_builder:
	free(b);
	return NULL;
}

int mesh_builder_vertex(struct mesh_builder *b, const double p[3], uint32_t *index,
			struct st_error *err)
{
	struct mesh *m = b->mesh;
	size_t i = hash_point(p) & (b->nslots - 1);

	while (b->slots[i]) {
		uint32_t v = b->slots[i] - 1;
		if (same_point(m->verts[v], p)) {
			*index = v;
			return 0;
		}
		i = (i + 1) & (b->nslots - 1);
	}
	if (m->nverts >= MESH_MAX_ELEMENTS)
		return st_error_set(err, ST_ERR_RANGE, "more than %u distinct vertices",
				    (unsigned)MESH_MAX_ELEMENTS);
	if (st_grow_at((void **)&m->verts, &m->cap_verts, m->nverts + 1, sizeof(*m->verts)))
		goto out_nomem;
	for (int k = 0; k < 3; k++)
		m->verts[m->nverts][k] = p[k] == 0.0 ? 0.0 : p[k];
	b->slots[i] = (uint32_t)m->nverts + 1;
	*index = (uint32_t)m->nverts++;
	/* Keep the load factor at or below 1/2. */
	if (m->nverts * 2 > b->nslots && rehash(b, b->nslots * 2))
		goto out_nomem;
	return 0;

out_nomem:
	return st_error_set(err, ST_ERR_NOMEM, "out of memory while welding %zu vertices",
			    m->nverts);
}

void mesh_builder_prefetch(const struct mesh_builder *b, const double p[3])
{
	__builtin_prefetch(&b->slots[hash_point(p) & (b->nslots - 1)]);
}

int mesh_builder_triangle(struct mesh_builder *b, uint32_t a, uint32_t c1, uint32_t c2,
			  struct st_error *err)
{
	struct mesh *m = b->mesh;

	if (a >= m->nverts || c1 >= m->nverts || c2 >= m->nverts)
		return st_error_set(err, ST_ERR_ARG, "triangle refers to a vertex that does not exist");
	if (m->ntris >= MESH_MAX_ELEMENTS)
		return st_error_set(err, ST_ERR_RANGE, "more than %u triangles",
				    (unsigned)MESH_MAX_ELEMENTS);
	if (st_grow_at((void **)&m->tris, &m->cap_tris, m->ntris + 1, sizeof(*m->tris)))
		return st_error_set(err, ST_ERR_NOMEM, "out of memory after %zu triangles",
				    m->ntris);
	m->tris[m->ntris][0] = a;
	m->tris[m->ntris][1] = c1;
	m->tris[m->ntris][2] = c2;
	m->ntris++;
	return 0;
}

int mesh_builder_append(struct mesh_builder *b, const struct mesh *part, struct st_error *err)
{
	uint32_t *remap = malloc((part->nverts ? part->nverts : 1) * sizeof(*remap));
	int rc = 0;

	if (!remap)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory joining %zu vertices",
				    part->nverts);
	/* part's vertices are in first-use order, so welding them in index
	 * order keeps b's vertex order what one pass would have produced. */
	for (size_t v = 0; v < part->nverts && !rc; v++) {
		if (v + MESH_WELD_AHEAD < part->nverts)
			mesh_builder_prefetch(b, part->verts[v + MESH_WELD_AHEAD]);
		rc = mesh_builder_vertex(b, part->verts[v], &remap[v], err);
	}
	for (size_t t = 0; t < part->ntris && !rc; t++)
		rc = mesh_builder_triangle(b, remap[part->tris[t][0]], remap[part->tris[t][1]],
					   remap[part->tris[t][2]], err);
	free(remap);
	return rc;
}

struct mesh *mesh_builder_finish(struct mesh_builder *b)
{
	struct mesh *m = b->mesh;

	free(b->slots);
	free(b);
	return m;
}

void mesh_builder_free(struct mesh_builder *b)
{
	if (!b)
		return;
	mesh_free(b->mesh);
	free(b->slots);
	free(b);
}

void mesh_free(struct mesh *m)
{
	if (!m)
		return;
	free(m->verts);
	free(m->tris);
	free(m);
}

void mesh_bbox(const struct mesh *m, double min[3], double max[3])
{
	for (int k = 0; k < 3; k++)
		min[k] = max[k] = m->nverts ? m->verts[0][k] : 0.0;
	for (size_t v = 1; v < m->nverts; v++) {
		for (int k = 0; k < 3; k++) {
			min[k] = fmin(min[k], m->verts[v][k]);
			max[k] = fmax(max[k], m->verts[v][k]);
		}
	}
}

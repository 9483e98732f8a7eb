/*
 * ids.h - private to repair/: small helpers over uint32_t vertex,
 * triangle and component ids shared by the topology report, the parts
 * split, the outer hull and the repair pipeline.
 */
#ifndef STRATUM_REPAIR_IDS_H
#define STRATUM_REPAIR_IDS_H

#include <stdint.h>

/* Union-find root of x, with path halving. */
static inline uint32_t uf_find(uint32_t *parent, uint32_t x)
{
	while (parent[x] != x) {
		parent[x] = parent[parent[x]];
		x = parent[x];
	}
	return x;
}

/* Join the sets of a and b; the lower root stays the root. */
static inline void uf_union(uint32_t *parent, uint32_t a, uint32_t b)
{
	a = uf_find(parent, a);
	b = uf_find(parent, b);
	if (a != b)
		parent[a < b ? b : a] = a < b ? a : b;
}

/* The three ids of in, ascending: the key of a triangle's vertex set. */
static inline void sort3(const uint32_t in[3], uint32_t out[3])
{
	uint32_t a = in[0], b = in[1], c = in[2], t;

	if (a > b) {
		t = a;
		a = b;
		b = t;
	}
	if (b > c) {
		t = b;
		b = c;
		c = t;
	}
	if (a > b) {
		t = a;
		a = b;
		b = t;
	}
	out[0] = a;
	out[1] = b;
	out[2] = c;
}

/* A triangle by its sorted corners (sort3) and its index t. */
struct tri_key {
	uint32_t v[3];
	uint32_t t;
};

/* qsort order of tri_key: by corners, equal triangles by index. */
static inline int tri_key_compare(const void *a, const void *b)
{
	const struct tri_key *x = a, *y = b;

	for (int k = 0; k < 3; k++)
		if (x->v[k] != y->v[k])
			return x->v[k] < y->v[k] ? -1 : 1;
	return x->t < y->t ? -1 : x->t > y->t;
}

/* An id and how many shells enclose it: sorted outermost first, then by id. */
struct id_depth {
	uint32_t depth, id;
};

static inline int id_depth_compare(const void *pa, const void *pb)
{
	const struct id_depth *a = pa, *b = pb;

	if (a->depth != b->depth)
		return a->depth < b->depth ? -1 : 1;
	return a->id < b->id ? -1 : a->id > b->id;
}

#endif /* STRATUM_REPAIR_IDS_H */

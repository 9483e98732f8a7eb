/*
 * weld.c - welding a whole file's corners at once on several threads
 * (mesh_weld_corners, mesh_weld_read), for the binary STL reader.
 *
 * Why: welding a 1M-triangle file corner by corner was a third of
 * `stratum check`'s time, nearly all of it waiting for hash slots and
 * vertices from memory; two halves welded apart still had to be joined
 * on one thread.  Here the points are split by their hash: thread p
 * welds only the corners whose hash falls in its part, in file order,
 * into a table of its own, so no thread waits for another and nothing is
 * welded twice.  The parts' vertices are then merged in order of their
 * first corner, which is the order mesh_builder_vertex gives them.
 */
#include "mesh.h"

#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

/* Threads at most; the parts index is packed beside the local index. */
#define WELD_MAX_PARTS 8
/* Corners hashed ahead of the one being welded (see MESH_WELD_AHEAD). */
#define WELD_AHEAD 16
/* Facets a part reads and welds at a time: their corners stay in cache. */
#define WELD_RUN MESH_WELD_RUN

/* A float's bits with -0 folded onto +0 (the same point). */
static uint32_t float_bits(float v)
{
	uint32_t u;

	if (v == 0.0f)
		v = 0.0f;
	memcpy(&u, &v, sizeof(u));
	return u;
}

/* The part of a hash: its high 32 bits scaled to [0, parts) (no division,
 * which cost as much as the rest of a lookup). */
static unsigned part_of(uint64_t h, unsigned parts)
{
	return (unsigned)(((h >> 32) * parts) >> 32);
}

/* A slot holds the point itself beside its number, so that the one
 * cache line a probe loads (prefetched ahead) answers it. */
struct weld_slot {
	uint32_t bits[3]; /* float_bits of the point */
	uint32_t id;	  /* local vertex + 1, 0 empty */
};

/* One part: its table, its vertices (first corner, position). */
struct weld_part {
	const float (*corner)[3]; /* the whole file's corners, or NULL: read */
	mesh_corner_reader read;  /* runs of facets into buf, when corner is NULL */
	void *ctx;
	float (*buf)[3];	  /* WELD_RUN facets' corners */
	size_t ntris;
	unsigned index, parts;
	struct weld_slot *slots;
	size_t nslots;	 /* power of two */
	uint32_t *first; /* [local] its first corner */
	float (*pos)[3]; /* [local] its point */
	size_t nlocal, cap;
	uint32_t *out;	 /* [corner] local * parts + index, for this part's corners */
	bool nomem, unread;
};

static uint64_t hash_bits(const uint32_t b[3])
{
	uint64_t h = (uint64_t)b[0] * 0x9e3779b97f4a7c15ull;

	h ^= (uint64_t)b[1] * 0xc2b2ae3d27d4eb4full;
	h ^= (uint64_t)b[2] * 0x165667b19e3779f9ull;
	h ^= h >> 29;
	h *= 0xbf58476d1ce4e5b9ull;
	h ^= h >> 32;
	return h;
}

/* Memory for a large table read in random order (the slots here, the
 * mesh's vertices and triangles in every pass of the check), on huge
 * pages where the kernel has them: with 4 KiB pages most lookups in
 * such a table walk the page tables first. */
static void *huge_alloc(size_t bytes)
{
	const size_t huge = (size_t)2 << 20;
	void *p;

	if (bytes < huge)
		return malloc(bytes ? bytes : 1);
	p = aligned_alloc(huge, (bytes + huge - 1) / huge * huge);
	if (p)
		madvise(p, bytes, MADV_HUGEPAGE); /* a hint: 4 KiB pages work too */
	return p;
}

static struct weld_slot *new_slots(size_t n)
{
	struct weld_slot *s = huge_alloc(n * sizeof(*s));

	if (s)
		memset(s, 0, n * sizeof(*s));
	return s;
}

static bool grow_part(struct weld_part *w)
{
	size_t nslots = w->nslots * 2;
	struct weld_slot *slots = new_slots(nslots);

	if (!slots)
		return false;
	for (size_t i = 0; i < w->nslots; i++) {
		if (!w->slots[i].id)
			continue;
		size_t j = hash_bits(w->slots[i].bits) & (nslots - 1);
		while (slots[j].id)
			j = (j + 1) & (nslots - 1);
		slots[j] = w->slots[i];
	}
	free(w->slots);
	w->slots = slots;
	w->nslots = nslots;
	return true;
}

/* Weld corner c (its point p, bits b, hash h) into part w. */
static bool weld_one(struct weld_part *w, size_t c, const float p[3], const uint32_t b[3],
		     uint64_t h)
{
	size_t i = h & (w->nslots - 1);

	for (; w->slots[i].id; i = (i + 1) & (w->nslots - 1)) {
		const struct weld_slot *s = &w->slots[i];
		if (s->bits[0] == b[0] && s->bits[1] == b[1] && s->bits[2] == b[2]) {
			w->out[c] = (s->id - 1) * w->parts + w->index;
			return true;
		}
	}
	if (w->nlocal == w->cap) {
		size_t cap = w->cap * 2 + 1024;
		uint32_t *f = realloc(w->first, cap * sizeof(*f));
		if (!f)
			return false;
		w->first = f;
		float(*q)[3] = realloc(w->pos, cap * sizeof(*q));
		if (!q)
			return false;
		w->pos = q;
		w->cap = cap;
	}
	w->first[w->nlocal] = (uint32_t)c;
	memcpy(w->pos[w->nlocal], p, sizeof(w->pos[0]));
	w->slots[i] = (struct weld_slot){{b[0], b[1], b[2]}, (uint32_t)++w->nlocal};
	w->out[c] = (uint32_t)(w->nlocal - 1) * w->parts + w->index;
	/* Load factor at most 1/2, as the builder's. */
	return w->nlocal * 2 <= w->nslots || grow_part(w);
}

/* The n corners from corner c0 on (their points in corner[0..n)), in
 * order; those of this part are welded, their slots prefetched
 * WELD_AHEAD corners before. */
static bool weld_run(struct weld_part *w, const float (*corner)[3], size_t c0, size_t n)
{
	uint64_t ring[WELD_AHEAD];
	uint32_t bits[WELD_AHEAD][3];

	for (size_t c = 0; c < n + WELD_AHEAD; c++) {
		if (c >= WELD_AHEAD) {
			size_t at = c - WELD_AHEAD;
			uint64_t h = ring[at % WELD_AHEAD];
			if (part_of(h, w->parts) == w->index &&
			    !weld_one(w, c0 + at, corner[at], bits[at % WELD_AHEAD], h))
				return false;
		}
		if (c < n) {
			/* Into the entry of corner at, just welded. */
			uint32_t *b = bits[c % WELD_AHEAD];
			for (int k = 0; k < 3; k++)
				b[k] = float_bits(corner[c][k]);
			ring[c % WELD_AHEAD] = hash_bits(b);
			if (part_of(ring[c % WELD_AHEAD], w->parts) == w->index)
				__builtin_prefetch(&w->slots[ring[c % WELD_AHEAD] & (w->nslots - 1)]);
		}
	}
	return true;
}

/* Every facet in file order, WELD_RUN at a time: from the caller's
 * array, or read into this part's buffer (each part reads every facet,
 * so no array of all the corners is made: on a 1M-triangle file that
 * array and its pass cost more than the reading). */
static void *weld_part_run(void *arg)
{
	struct weld_part *w = arg;

	for (size_t t = 0; t < w->ntris; t += WELD_RUN) {
		const size_t n = w->ntris - t < WELD_RUN ? w->ntris - t : WELD_RUN;
		const float(*corner)[3] = w->corner ? w->corner + 3 * t : (const float(*)[3])w->buf;

		if (!w->corner && !w->read(w->ctx, t, n, w->buf)) {
			w->unread = true;
			return NULL;
		}
		if (!weld_run(w, corner, 3 * t, 3 * n)) {
			w->nomem = true;
			return NULL;
		}
	}
	return NULL;
}

/* Global vertex numbers: the parts' vertices merged by first corner.
 * Each part's list is already in that order. */
static int number_vertices(struct weld_part *w, unsigned parts, struct mesh *m,
			   uint32_t **global)
{
	size_t at[WELD_MAX_PARTS] = {0}, total = 0;

	for (unsigned p = 0; p < parts; p++) {
		total += w[p].nlocal;
		global[p] = malloc((w[p].nlocal ? w[p].nlocal : 1) * sizeof(**global));
		if (!global[p])
			return ST_ERR_NOMEM;
	}
	if (total > MESH_MAX_ELEMENTS)
		return ST_ERR_RANGE;
	m->verts = huge_alloc(total * sizeof(*m->verts));
	if (!m->verts)
		return ST_ERR_NOMEM;
	m->cap_verts = total ? total : 1;
	for (size_t g = 0; g < total; g++) {
		unsigned best = parts;
		for (unsigned p = 0; p < parts; p++)
			if (at[p] < w[p].nlocal &&
			    (best == parts || w[p].first[at[p]] < w[best].first[at[best]]))
				best = p;
		const float *q = w[best].pos[at[best]];
		for (int k = 0; k < 3; k++)
			m->verts[g][k] = q[k] == 0.0f ? 0.0 : (double)q[k];
		global[best][at[best]++] = (uint32_t)g;
	}
	m->nverts = total;
	return 0;
}

/* Part count for this machine: what the weld can use, at least one. */
static unsigned weld_parts(int threads, size_t ncorners)
{
	long n = threads > 0 ? threads : sysconf(_SC_NPROCESSORS_ONLN);

	if (n < 1)
		n = 1;
	if (n > WELD_MAX_PARTS)
		n = WELD_MAX_PARTS;
	/* Local indices times parts must fit 32 bits. */
	while (n > 1 && ncorners > (size_t)UINT32_MAX / (size_t)n)
		n--;
	return (unsigned)n;
}

/* The weld of mesh_weld_corners and mesh_weld_read: corners from the
 * array corner, or through read when it is NULL. */
static int weld(const float (*corner)[3], mesh_corner_reader read, void *ctx, size_t ntris,
		int threads, struct mesh **out, struct st_error *err)
{
	const size_t ncorners = 3 * ntris;
	const unsigned parts = weld_parts(threads, ncorners);
	struct weld_part w[WELD_MAX_PARTS];
	pthread_t thread[WELD_MAX_PARTS];
	uint32_t *global[WELD_MAX_PARTS] = {0};
	bool started[WELD_MAX_PARTS] = {0};
	struct mesh *m = calloc(1, sizeof(*m));
	uint32_t *ids = huge_alloc(ncorners * sizeof(*ids));
	size_t nslots = 1024;
	int rc = 0;

	*out = NULL;
	if (ncorners / 3 != ntris || ntris > MESH_MAX_ELEMENTS || ncorners > UINT32_MAX) {
		free(m);
		free(ids);
		return st_error_set(err, ST_ERR_RANGE, "%zu triangles are more than a mesh holds",
				    ntris);
	}
	/* The builder's table size (a closed mesh has about half as many
	 * vertices as triangles, 5/8 of that fills a part to a load of 0.4),
	 * shared out between the parts. */
	while (nslots < (ntris + ntris / 4) / 2 / parts)
		nslots *= 2;
	memset(w, 0, sizeof(w));
	if (!m || !ids)
		rc = ST_ERR_NOMEM;
	for (unsigned p = 0; p < parts && !rc; p++) {
		w[p] = (struct weld_part){.corner = corner, .read = read, .ctx = ctx, .ntris = ntris,
					  .index = p, .parts = parts, .nslots = nslots, .out = ids};
		w[p].slots = new_slots(nslots);
		if (!corner)
			w[p].buf = malloc(3 * WELD_RUN * sizeof(*w[p].buf));
		if (!w[p].slots || (!corner && !w[p].buf))
			rc = ST_ERR_NOMEM;
	}
	/* Part 0 on this thread; a part whose thread cannot start runs here too. */
	for (unsigned p = 1; p < parts && !rc; p++)
		started[p] = pthread_create(&thread[p], NULL, weld_part_run, &w[p]) == 0;
	if (!rc)
		weld_part_run(&w[0]);
	for (unsigned p = 1; p < parts; p++) {
		if (started[p])
			pthread_join(thread[p], NULL);
		else if (!rc)
			weld_part_run(&w[p]);
	}
	for (unsigned p = 0; p < parts && !rc; p++)
		if (w[p].unread)
			rc = ST_ERR_PARSE;
		else if (w[p].nomem)
			rc = ST_ERR_NOMEM;
	if (!rc)
		rc = number_vertices(w, parts, m, global);
	if (!rc) {
		/* Corner ids become vertex numbers in place (one part's
		 * already are). */
		for (size_t c = 0; parts > 1 && c < ncorners; c++)
			ids[c] = global[ids[c] % parts][ids[c] / parts];
		m->tris = (uint32_t(*)[3])ids;
		m->ntris = m->cap_tris = ntris;
		ids = NULL;
		*out = m;
		m = NULL;
	}
	for (unsigned p = 0; p < parts; p++) {
		free(w[p].slots);
		free(w[p].first);
		free(w[p].pos);
		free(w[p].buf);
		free(global[p]);
	}
	free(ids);
	mesh_free(m);
	if (rc == ST_ERR_RANGE)
		return st_error_set(err, rc, "more than %u distinct vertices",
				    (unsigned)MESH_MAX_ELEMENTS);
	if (rc == ST_ERR_PARSE)
		return st_error_set(err, rc, "a facet of %zu did not read", ntris);
	if (rc)
		return st_error_set(err, rc, "out of memory welding %zu triangles", ntris);
	return 0;
}

int mesh_weld_corners(const float (*corner)[3], size_t ntris, int threads, struct mesh **out,
		      struct st_error *err)
{
	return weld(corner, NULL, NULL, ntris, threads, out, err);
}

int mesh_weld_read(mesh_corner_reader read, void *ctx, size_t ntris, int threads,
		   struct mesh **out, struct st_error *err)
{
	return weld(NULL, read, ctx, ntris, threads, out, err);
}

/*
 * refine_time.c - time the exact pass of the repair alone (issue 15 item 4):
 *   refine_time FILE [THREADS]
 * reads FILE, keeps its regular, non-degenerate triangles once each (as the
 * repair's cleaning does, without the wires; corners sorted, as the cuts do
 * not depend on orientation), and times exact_mesh_refine
 * (the pair search, the exact cuts and the re-triangulation) on them.
 * Prints one line: "triangles pairs split seconds triangles_per_s".
 * Independent of what the repair does after the exact pass (outer hull,
 * thickening, rounding), so it measures inputs whose later steps fail too.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "exact.h"
#include "meshio.h"

/* Sorted corners of a triangle, for spotting duplicates. */
struct key {
	uint32_t v[3];
};

static int compare_key(const void *a, const void *b)
{
	return memcmp(a, b, sizeof(struct key));
}

static void sort3(const uint32_t in[3], uint32_t out[3])
{
	uint32_t a = in[0], b = in[1], c = in[2], t;

	if (a > b) { t = a; a = b; b = t; }
	if (b > c) { t = b; b = c; c = t; }
	if (a > b) { t = a; a = b; b = t; }
	out[0] = a;
	out[1] = b;
	out[2] = c;
}

static double now(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int main(int argc, char **argv)
{
	struct st_error err = {0};
	struct mesh *m = NULL;
	struct exact_mesh *em = NULL;
	struct exact_refine_stats rs;
	int threads = argc > 2 ? atoi(argv[2]) : 0;

	if (argc < 2 || argc > 3 || threads < 0) {
		fprintf(stderr, "usage: refine_time FILE [THREADS]\n");
		return 2;
	}
	if (meshio_read(argv[1], MESHIO_AUTO, &m, NULL, &err)) {
		fprintf(stderr, "refine_time: %s\n", err.msg);
		return 1;
	}
	struct key *keys = malloc((m->ntris + 1) * sizeof(*keys));
	uint32_t (*tris)[3] = malloc((m->ntris + 1) * sizeof(*tris));
	size_t nk = 0, n = 0;
	if (!keys || !tris) {
		fprintf(stderr, "refine_time: out of memory\n");
		return 1;
	}
	for (size_t t = 0; t < m->ntris; t++) {
		const uint32_t *v = m->tris[t];
		if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2] ||
		    exact_collinear(m->verts[v[0]], m->verts[v[1]], m->verts[v[2]]))
			continue;
		sort3(v, keys[nk++].v);
	}
	qsort(keys, nk, sizeof(*keys), compare_key);
	for (size_t i = 0; i < nk; i++)
		if (i == 0 || memcmp(&keys[i], &keys[i - 1], sizeof(keys[i])))
			memcpy(tris[n++], keys[i].v, sizeof(tris[0]));
	free(keys);
	if (exact_mesh_new((const double(*)[3])m->verts, m->nverts, (const uint32_t(*)[3])tris, n,
			   NULL, &em, &err)) {
		fprintf(stderr, "refine_time: %s\n", err.msg);
		return 1;
	}
	const double t0 = now();
	if (exact_mesh_refine(em, threads, &rs, &err)) {
		fprintf(stderr, "refine_time: %s\n", err.msg);
		return 1;
	}
	const double dt = now() - t0;
	printf("%zu %llu %zu %.3f %.0f\n", m->ntris, (unsigned long long)rs.intersecting_pairs,
	       rs.triangles_split, dt, dt > 0 ? (double)m->ntris / dt : 0.0);
	exact_mesh_free(em);
	free(tris);
	mesh_free(m);
	return 0;
}

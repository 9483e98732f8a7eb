/*
 * adaptive_cusp.c - the cusp of adaptive against uniform layers at equal
 * layer count (issue 21 item 3, docs/benchmarks.md):
 *   adaptive_cusp FILE MAX_CUSP [MIN MAX]
 * reads FILE (STL, OBJ, OFF), plans adaptive layers (slicer/adaptive.h;
 * MIN and MAX default to 0.07 and 0.3 mm, a 0.4 mm nozzle's, the first
 * layer MIN thick), then uniform layers of the mesh's height over the same
 * count, and measures both with adaptive_measure (h |n_z| over the sloped
 * facets each layer crosses: the largest, and the mean weighted by the
 * area in each layer).  Prints one Markdown row:
 *   | triangles | bound | layers | adaptive max | mean | uniform h | max | mean |
 *   max and mean reduction in percent | plan ms |
 */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "adaptive.h"
#include "meshio.h"

static double now_ms(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

int main(int argc, char **argv)
{
	struct mesh *m = NULL;
	struct st_error err = {0};
	struct adaptive_settings s = {.min_height = 0.07, .max_height = 0.3};
	struct layer_span *ap = NULL, *up = NULL;
	struct adaptive_cusp ac, uc;
	size_t an, un;
	double lo[3], hi[3], t0, ms;

	if (argc != 3 && argc != 5) {
		fprintf(stderr, "usage: adaptive_cusp FILE MAX_CUSP [MIN MAX]\n");
		return 2;
	}
	s.max_cusp = atof(argv[2]);
	if (argc == 5) {
		s.min_height = atof(argv[3]);
		s.max_height = atof(argv[4]);
	}
	s.first_height = s.min_height;
	if (meshio_read(argv[1], MESHIO_AUTO, &m, NULL, &err)) {
		fprintf(stderr, "adaptive_cusp: %s\n", err.msg);
		return 65;
	}
	mesh_bbox(m, lo, hi);
	t0 = now_ms();
	if (adaptive_plan(m, &s, &ap, &an, &err) || an == 0) {
		fprintf(stderr, "adaptive_cusp: %s\n", an ? err.msg : "no layers");
		return 1;
	}
	ms = now_ms() - t0;
	double h = (hi[2] - lo[2]) / (double)an;
	if (slice_plan_uniform(hi[2] - lo[2], h, h, &up, &un, &err) ||
	    adaptive_measure(m, ap, an, NULL, &ac, &err) ||
	    adaptive_measure(m, up, un, NULL, &uc, &err)) {
		fprintf(stderr, "adaptive_cusp: %s\n", err.msg);
		return 1;
	}
	printf("| %zu | %g | %zu / %zu | %.4f | %.4f | %.4f | %.4f | %.4f | %.0f %% | %.0f %% | %.0f "
	       "|\n",
	       m->ntris, s.max_cusp, an, un, ac.max, ac.mean, h, uc.max, uc.mean,
	       100.0 * (1.0 - ac.max / uc.max), 100.0 * (1.0 - ac.mean / uc.mean), ms);
	free(ap);
	free(up);
	mesh_free(m);
	return 0;
}

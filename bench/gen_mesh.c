/*
 * gen_mesh.c - write a generated closed mesh for the benchmarks:
 *   gen_mesh torus NU NV OUT.stl     torus with NU x NV quads (2*NU*NV triangles)
 *   gen_mesh spheres N OUT.stl       N overlapping spheres (self-intersections)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "meshio.h"

int main(int argc, char **argv)
{
	struct st_error err = {0};
	struct mesh *m = NULL;

	if (argc == 5 && !strcmp(argv[1], "torus")) {
		m = fx_torus(60.0, 20.0, atoi(argv[2]), atoi(argv[3]));
	} else if (argc == 4 && !strcmp(argv[1], "spheres")) {
		int n = atoi(argv[2]);
		m = fx_sphere(0, 0, 0, 10, 64, 128);
		for (int i = 1; i < n; i++) {
			struct mesh *s = fx_sphere(i * 7.0, 0, 0, 10, 64, 128), *both;
			both = fx_concat(m, s);
			mesh_free(m);
			mesh_free(s);
			m = both;
		}
	} else {
		fprintf(stderr, "usage: gen_mesh torus NU NV OUT.stl | gen_mesh spheres N OUT.stl\n");
		return 2;
	}
	if (meshio_write_stl(argv[argc - 1], m, MESHIO_STL_BINARY, &err)) {
		fprintf(stderr, "gen_mesh: %s\n", err.msg);
		mesh_free(m);
		return 1;
	}
	printf("%s: %zu triangles, %zu vertices\n", argv[argc - 1], m->ntris, m->nverts);
	mesh_free(m);
	return 0;
}

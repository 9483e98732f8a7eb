/*
 * repairtest.h - what the repair suite's files share (check_repair.c,
 * check_repair_sheet.c): run the repair, and judge its result the way a
 * printer would get it (judge), or compare it with the input.
 */
#ifndef STRATUM_TESTS_REPAIRTEST_H
#define STRATUM_TESTS_REPAIRTEST_H

#include <stdint.h>

#include "mesh.h"
#include "repair.h"

#define EPS 0.4 /* mm, the default nozzle-sized thickness */

/* A repair result and what it reported. */
struct fixed {
	struct mesh *out;
	uint32_t *comp;
	struct repair_report rep;
};

/* Run repair_mesh with opt; it must succeed and report consistently. */
struct fixed repair_with(const struct mesh *in, const struct repair_options *opt);
/* Repair with the defaults and the given epsilon. */
struct fixed repair_eps(const struct mesh *in, double eps);
void fixed_free(struct fixed *f);

/*
 * got and want hold the same oriented triangles with bit-identical
 * coordinates, in any order and with any vertex numbering: Hausdorff 0.
 */
void assert_same_triangles(const struct mesh *got, const struct mesh *want, const char *what);
/* Does m contain triangle (p0,p1,p2) with this orientation? */
int has_triangle(const struct mesh *m, const double p0[3], const double p1[3],
		 const double p2[3]);
/* Every output vertex within epsilon/2 (+1e-3) of the input surface. */
void assert_near_input(const struct fixed *f, const struct mesh *in);
/* The triangles of m whose component is c, as a mesh of their own. */
struct mesh *part_mesh(const struct mesh *m, const uint32_t *comp, uint32_t c);
/*
 * The checks every test makes on a result (printable, parts written and read
 * back unchanged); returns the analysis of the whole output as read back.
 */
struct mesh_report judge(const struct fixed *f, enum repair_precision prec, const char *name);

#endif

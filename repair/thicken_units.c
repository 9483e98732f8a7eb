/*
 * thicken_units.c - which triangles the sheets are thickened as (seed 000
 * §4.2.1 after the first pass), and which of their edges touch nothing.
 *
 * The first pass cuts every sheet triangle that another one crosses; the
 * pieces of one triangle lie in its plane and continue each other
 * straight through, so the slab of the whole triangle is the same solid.
 * Thickening it whole instead of piece by piece gives the second pass a
 * fraction of the triangles (a random soup's crossings cut each triangle
 * into four or more), and its top and bottom stay single planar faces,
 * where the pieces' copies would be rounded apart and make every later
 * predicate between them an exact one.  Doubles and vertex ids only.
 */
#include <stdlib.h>
#include <string.h>

#include "thicken.h"

struct unit_edge {
	uint32_t lo, hi, corner; /* corner 3*t+k: edge k of triangle t */
};

static int compare_unit_edge(const void *a, const void *b)
{
	const struct unit_edge *x = a, *y = b;

	if (x->lo != y->lo)
		return x->lo < y->lo ? -1 : 1;
	return x->hi < y->hi ? -1 : x->hi > y->hi;
}

/*
 * Per corner of tris, how many triangles use its edge (at most 255), and
 * per parent whether any of its boundary touches another triangle: an
 * edge of a piece that no other piece of the parent shares lies on the
 * parent's boundary.
 */
static int count_edges(const uint32_t (*tris)[3], size_t ntris, const uint32_t *parent,
		       uint8_t *uses, uint8_t *attached, struct st_error *err)
{
	struct unit_edge *e = malloc((3 * ntris + 1) * sizeof(*e));

	if (!e)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory counting sheet edges");
	for (uint32_t c = 0; c < 3 * ntris; c++) {
		const uint32_t a = tris[c / 3][c % 3], b = tris[c / 3][(c % 3 + 1) % 3];
		e[c] = (struct unit_edge){a < b ? a : b, a < b ? b : a, c};
	}
	qsort(e, 3 * ntris, sizeof(*e), compare_unit_edge);
	for (size_t i = 0, j; i < 3 * ntris; i = j) {
		for (j = i + 1; j < 3 * ntris && e[j].lo == e[i].lo && e[j].hi == e[i].hi; j++)
			;
		for (size_t x = i; x < j; x++) {
			uses[e[x].corner] = (uint8_t)(j - i < 255 ? j - i : 255);
			if (!parent || j - i == 1)
				continue;
			const uint32_t p = parent[e[x].corner / 3];
			size_t same = 0;
			for (size_t y = i; y < j; y++)
				same += parent[e[y].corner / 3] == p;
			if (same == 1)
				attached[p] = 1;
		}
	}
	free(e);
	return 0;
}

int thicken_units(const uint32_t (*tris)[3], const uint32_t *sheet, size_t nsheet,
		  const uint32_t *parent, const uint8_t *whole, const uint32_t (*before)[3],
		  size_t nbefore, size_t ntris, uint32_t (**units)[3], uint8_t **free_edges,
		  size_t *nunits, struct st_error *err)
{
	/* Per parent: pieces in all, pieces listed as sheet. */
	uint32_t *pieces = calloc(nbefore + 1, sizeof(*pieces));
	uint32_t *listed = calloc(nbefore + 1, sizeof(*listed));
	uint8_t *whole_done = calloc(nbefore + 1, 1), *attached = calloc(nbefore + 1, 1);
	uint8_t *uses = malloc(3 * ntris + 1), *fe = malloc(nsheet + 1);
	uint32_t (*u)[3] = malloc((nsheet + 1) * sizeof(*u));
	size_t k = 0;
	int rc = 0;

	*units = NULL;
	*free_edges = NULL;
	*nunits = 0;
	if (!pieces || !listed || !whole_done || !attached || !uses || !fe || !u) {
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory grouping %zu sheet triangles",
				  nsheet);
		goto out;
	}
	rc = count_edges(tris, ntris, parent, uses, attached, err);
	if (rc)
		goto out;
	for (size_t t = 0; parent && t < ntris; t++)
		pieces[parent[t]]++;
	for (size_t i = 0; parent && i < nsheet; i++)
		listed[parent[sheet[i]]]++;
	for (size_t i = 0; i < nsheet; i++) {
		const uint32_t t = sheet[i], p = parent ? parent[t] : UINT32_MAX;
		if (p == UINT32_MAX || pieces[p] < 2 || listed[p] != pieces[p] || !whole[p]) {
			memcpy(u[k], tris[t], sizeof(u[0]));
			fe[k++] = (uint8_t)((uses[3 * t] == 1) | (uses[3 * t + 1] == 1) << 1 |
					    (uses[3 * t + 2] == 1) << 2);
			continue;
		}
		/* The first listed piece stands for the whole, the others
		 * for nothing. */
		if (!whole_done[p]) {
			memcpy(u[k], before[p], sizeof(u[0]));
			fe[k++] = attached[p] ? 0 : 7;
		}
		whole_done[p] = 1;
	}
	*units = u;
	*free_edges = fe;
	*nunits = k;
	u = NULL;
	fe = NULL;
out:
	free(pieces);
	free(listed);
	free(whole_done);
	free(attached);
	free(uses);
	free(fe);
	free(u);
	return rc;
}

/*
 * toolpath.c - layer and path containers shared by the slicer stages and
 * the G-code writer (see toolpath.h).
 */
#include "toolpath.h"

#include <stdlib.h>
#include <string.h>

#include "travel.h"
#include "st_grow.h"

struct layer_stack *layer_stack_new(size_t nlayers, struct st_error *err)
{
	struct layer_stack *s = calloc(1, sizeof(*s));

	if (!s || (nlayers && !(s->layers = calloc(nlayers, sizeof(*s->layers))))) {
		free(s);
		st_error_set(err, ST_ERR_NOMEM, "out of memory for %zu layers", nlayers);
		return NULL;
	}
	s->nlayers = nlayers;
	return s;
}

void layer_paths_clear(struct layer_paths *l)
{
	if (!l)
		return;
	for (size_t p = 0; p < l->n; p++)
		free(l->paths[p].pts);
	free(l->paths);
	travel_map_free(l->travel);
	l->paths = NULL;
	l->n = l->cap = 0;
	l->travel = NULL;
}

void layer_stack_free(struct layer_stack *s)
{
	if (!s)
		return;
	for (size_t l = 0; l < s->nlayers; l++)
		layer_paths_clear(&s->layers[l]);
	free(s->layers);
	free(s);
}

int layer_add_path(struct layer_paths *l, enum path_role role, bool closed,
		   const struct path_point *pts, size_t n, struct st_error *err)
{
	if (!l || !pts || (unsigned)role >= PATH_ROLES || n < (closed ? 3u : 2u))
		return st_error_set(err, ST_ERR_ARG, "toolpath: a %s path needs at least %d points",
				    closed ? "closed" : "open", closed ? 3 : 2);
	for (size_t i = 0; i < n; i++)
		if (pts[i].width <= 0)
			return st_error_set(err, ST_ERR_ARG,
					    "toolpath: point %zu has bead width %lld nm", i,
					    (long long)pts[i].width);
	if (n > SIZE_MAX / sizeof(*pts))
		return st_error_set(err, ST_ERR_NOMEM, "toolpath: %zu points overflow", n);
	struct toolpath *grown = st_grow(l->paths, &l->cap, l->n + 1, sizeof(*grown));
	if (!grown)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory adding a path");
	l->paths = grown;
	struct path_point *copy = malloc(n * sizeof(*copy));
	if (!copy)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory adding a path");
	memcpy(copy, pts, n * sizeof(*copy));
	l->paths[l->n++] = (struct toolpath){.role = role, .closed = closed, .n = n, .pts = copy};
	return 0;
}

const char *path_role_name(enum path_role role)
{
	static const char *const names[PATH_ROLES] = {
		[PATH_OUTER_PERIMETER] = "External perimeter",
		[PATH_INNER_PERIMETER] = "Perimeter",
		[PATH_THIN_WALL] = "Thin wall",
		[PATH_GAP_FILL] = "Gap fill",
		[PATH_SOLID_INFILL] = "Solid infill",
		[PATH_TOP_SKIN] = "Top solid infill",
		[PATH_BOTTOM_SKIN] = "Bottom solid infill",
		[PATH_SPARSE_INFILL] = "Internal infill",
		[PATH_BRIDGE] = "Bridge infill",
		[PATH_SKIRT] = "Skirt/Brim",
		[PATH_BRIM] = "Skirt/Brim",
		[PATH_SUPPORT] = "Support material",
		[PATH_SUPPORT_INTERFACE] = "Support material interface",
		[PATH_IRONING] = "Ironing",
		[PATH_OVERHANG_PERIMETER] = "Overhang perimeter",
	};
	return (unsigned)role < PATH_ROLES ? names[role] : "Unknown";
}

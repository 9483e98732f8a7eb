/*
 * sliceclitest.c - the helpers of sliceclitest.h.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "mesh.h"
#include "meshio.h"
#include "sliceclitest.h"
#include "testutil.h"

const char *stl_file(struct mesh *m, const char *name)
{
	const char *path = tu_path(name);
	struct st_error err = {0};
	int rc = meshio_write_stl(path, m, MESHIO_STL_BINARY, &err);

	mesh_free(m);
	ck_assert_msg(rc == 0, "%s", err.msg);
	return path;
}

char slice_out[1 << 16];

/* m as a binary STL scratch file named name (m is freed), copied to buf. */
void model_file(struct mesh *m, const char *name, char *buf, size_t cap)
{
	snprintf(buf, cap, "%s", stl_file(m, name));
}

/* Slice model for generic-marlin with the extra arguments; the G-code (free it). */
char *slice(const char *model, const char *args)
{
	char gc[4096];
	size_t len;
	int status;

	snprintf(gc, sizeof(gc), "%s", tu_path("settings.gcode"));
	status = tu_run(slice_out, sizeof(slice_out),
			"slice '%s' -o '%s' --printer generic-marlin %s", model, gc, args);
	ck_assert_msg(status == 0, "exit %d: %s", status, slice_out);
	return tu_slurp(gc, &len);
}

/* The feeds of role (its ;TYPE: name) in text, first layer (first) or above. */
struct feeds role_feeds(const char *text, const char *role, bool first)
{
	struct feeds f = {INFINITY, -INFINITY, 0};
	double feed = 0;
	long layer = 0;
	bool in_role = false;

	for (const char *l = text; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		size_t n = strcspn(l, "\n");
		const char *fw = memchr(l, 'F', n), *ew = memchr(l, 'E', n);

		if (!strncmp(l, ";LAYER_CHANGE", 13))
			layer++;
		if (!strncmp(l, ";TYPE:", 6))
			in_role = n == 6 + strlen(role) && !strncmp(l + 6, role, strlen(role));
		if (strncmp(l, "G1 ", 3))
			continue;
		if (fw)
			feed = strtod(fw + 1, NULL);
		if (!in_role || !ew || strtod(ew + 1, NULL) <= 0 ||
		    (!memchr(l, 'X', n) && !memchr(l, 'Y', n)) || (layer == 1) != first)
			continue;
		f.lo = fmin(f.lo, feed);
		f.hi = fmax(f.hi, feed);
		f.moves++;
	}
	return f;
}

/* Every extrusion of role on the layers asked for is at feed (mm/min). */
void assert_feed(const char *text, const char *role, bool first, double feed)
{
	struct feeds f = role_feeds(text, role, first);

	ck_assert_msg(f.moves > 0, "no %s extrusion on %s", role,
		      first ? "the first layer" : "the layers above");
	ck_assert_msg(fabs(f.lo - feed) < 1e-6 && fabs(f.hi - feed) < 1e-6,
		      "%s on %s: F%g to F%g, wanted F%g", role,
		      first ? "the first layer" : "the layers above", f.lo, f.hi, feed);
}

/* The header line "; KEY = VALUE". */
void assert_header(const char *text, const char *line)
{
	char want[256];

	snprintf(want, sizeof(want), "\n; %s\n", line);
	ck_assert_msg(strstr(text, want), "the header has no '%s'", line);
}

/* fx_bridge twice as wide and deep: pillars of 10 x 20 mm, so no wall loop
 * is a small perimeter (at most 2 pi 6.5 mm long). */
struct mesh *wide_bridge(void)
{
	struct mesh *m = fx_bridge();

	for (size_t i = 0; i < m->nverts; i++) {
		m->verts[i][0] *= 2;
		m->verts[i][1] *= 2;
	}
	return m;
}

/* Lines of text starting with cmd before the n-th ;LAYER_CHANGE (n = 0:
 * in the whole text). */
int count_before_layer(const char *text, const char *cmd, int n)
{
	const char *end = text + strlen(text), *l = text;
	int c = 0;

	for (int k = 0; n > 0 && k < n && l; k++)
		l = strstr(l + 1, "\n;LAYER_CHANGE");
	if (n > 0 && l)
		end = l;
	for (l = text; l && l < end; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : NULL)
		c += !strncmp(l, cmd, strlen(cmd));
	return c;
}

/* Layers with a ;TYPE: role, and the smallest X its extrusions reach. */
int role_layers(const char *text, const char *role, double *min_x)
{
	char mark[128];
	int layers = 0;
	const char *last = NULL;

	snprintf(mark, sizeof(mark), "\n;TYPE:%s\n", role);
	*min_x = INFINITY;
	for (const char *l = strstr(text, mark); l; l = strstr(l + 1, mark)) {
		const char *layer = l, *next;

		while (layer > text && strncmp(layer, "\n;LAYER_CHANGE", 14))
			layer--;
		layers += layer != last;
		last = layer;
		next = strstr(l + 1, "\n;TYPE:");
		for (const char *m = l + 1; m && (!next || m < next); m = strchr(m + 1, '\n')) {
			const char *x = m + 1;
			size_t n = strcspn(x, "\n");

			if (!strncmp(x, "G1 X", 4) && memchr(x, 'E', n))
				*min_x = fmin(*min_x, strtod(x + 4, NULL));
		}
	}
	return layers;
}


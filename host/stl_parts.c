/*
 * stl_parts.c - a repaired mesh written as STL, whole or one file per part
 * (stl_parts.h).
 */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "st_error.h"
#include "stl_parts.h"

/*
 * The name of part k (from 1) of OUT: "dir/part.stl" -> "dir/part-k.stl",
 * "part" -> "part-k".  Returns a malloc'd string or NULL on OOM.
 */
static char *part_path(const char *out, size_t k)
{
	const char *slash = strrchr(out, '/');
	const char *base = slash ? slash + 1 : out;
	const char *dot = strrchr(base, '.');
	size_t stem, cap;
	char *s;

	if (!dot || dot == base) /* no extension, or a dot file like ".stl" */
		dot = out + strlen(out);
	stem = (size_t)(dot - out);
	cap = strlen(out) + 24;
	s = malloc(cap);
	if (s)
		snprintf(s, cap, "%.*s-%zu%s", (int)stem, out, k, dot);
	return s;
}

/* Exit status for a failed meshio_write_stl. */
static int write_exit(int rc)
{
	switch (rc) {
	case ST_ERR_IO:
		return ST_EXIT_FAILURE;	/* the job could not finish; input was fine */
	case ST_ERR_RANGE:
		return ST_EXIT_DATAERR; /* coordinates that binary STL cannot hold */
	default:
		return ST_EXIT_SOFTWARE;
	}
}

/*
 * Write component c of m (triangles tri[first..first+n) of the bucketed
 * order) to path.  Returns 0 or the exit status, with the message printed.
 */
static int write_part(const char *input, const char *path, const struct mesh *m,
		      const size_t *order, size_t n, enum meshio_format fmt, char *msg, size_t cap)
{
	struct st_error err = {0};
	struct mesh_builder *b = mesh_builder_new(n);
	struct mesh *part;
	int rc;

	if (!b) {
		snprintf(msg, cap, "%s: out of memory splitting the parts", path);
		return ST_EXIT_SOFTWARE;
	}
	if (cmd_same_file(input, path)) {
		mesh_builder_free(b);
		snprintf(msg, cap, "%s is the input file %s; name another output so the input is kept",
			 path, input);
		return ST_EXIT_USAGE;
	}
	for (size_t i = 0; i < n; i++) {
		const uint32_t *t = m->tris[order[i]];
		uint32_t v[3];

		for (int k = 0; k < 3; k++)
			if (mesh_builder_vertex(b, m->verts[t[k]], &v[k], &err))
				goto out_builder;
		if (mesh_builder_triangle(b, v[0], v[1], v[2], &err))
			goto out_builder;
	}
	part = mesh_builder_finish(b);
	if (!part) {
		snprintf(msg, cap, "%s: out of memory splitting the parts", path);
		return ST_EXIT_SOFTWARE;
	}
	rc = meshio_write_stl(path, part, fmt, &err);
	mesh_free(part);
	if (rc) {
		snprintf(msg, cap, "%s", err.msg);
		return write_exit(rc);
	}
	return 0;

out_builder:
	mesh_builder_free(b);
	snprintf(msg, cap, "%s: %s", path, err.msg);
	return ST_EXIT_SOFTWARE;
}

void stl_outputs_free(struct stl_outputs *o)
{
	for (size_t i = 0; i < o->count; i++)
		free(o->path[i]);
	free(o->path);
	o->path = NULL;
	o->count = 0;
}

int stl_write_outputs(const char *input, const char *out, const struct mesh *m,
		      const uint32_t *component, size_t ncomp, bool split,
		      enum meshio_format fmt, struct stl_outputs *o, char *msg, size_t cap)
{
	size_t *start = NULL, *order = NULL;
	int status = ST_EXIT_SOFTWARE;

	if (!split || ncomp <= 1 || !component) {
		struct st_error err = {0};
		int rc = meshio_write_stl(out, m, fmt, &err);

		if (rc) {
			snprintf(msg, cap, "%s", err.msg);
			return write_exit(rc);
		}
		o->path = malloc(sizeof(*o->path));
		if (!o->path || !(o->path[0] = strdup(out))) {
			snprintf(msg, cap, "out of memory");
			return ST_EXIT_SOFTWARE;
		}
		o->count = 1;
		return 0;
	}

	/* Bucket the triangles by component (counting sort, input order kept). */
	if (ncomp > SIZE_MAX / sizeof(*start) - 1 || m->ntris > SIZE_MAX / sizeof(*order))
		goto out_nomem;
	start = calloc(ncomp + 1, sizeof(*start));
	order = malloc((m->ntris ? m->ntris : 1) * sizeof(*order));
	o->path = calloc(ncomp, sizeof(*o->path));
	if (!start || !order || !o->path)
		goto out_nomem;
	for (size_t t = 0; t < m->ntris; t++) {
		if (component[t] >= ncomp) {
			snprintf(msg, cap, "internal error: triangle %zu is in part %lu of %zu", t,
			    (unsigned long)component[t], ncomp);
			goto out_free;
		}
		start[component[t] + 1]++;
	}
	for (size_t c = 0; c < ncomp; c++)
		start[c + 1] += start[c];
	{
		size_t *fill = calloc(ncomp, sizeof(*fill));

		if (!fill)
			goto out_nomem;
		for (size_t t = 0; t < m->ntris; t++)
			order[start[component[t]] + fill[component[t]]++] = t;
		free(fill);
	}
	for (size_t c = 0; c < ncomp; c++) {
		char *path = part_path(out, c + 1);
		int rc;

		if (!path)
			goto out_nomem;
		rc = write_part(input, path, m, order + start[c], start[c + 1] - start[c], fmt, msg,
				cap);
		if (rc) {
			free(path);
			status = rc;
			goto out_free;
		}
		o->path[o->count++] = path;
	}
	status = 0;
	goto out_free;

out_nomem:
	snprintf(msg, cap, "out of memory splitting the parts");
out_free:
	free(order);
	free(start);
	return status;
}

bool stl_input_is_a_part(const char *in, const char *out)
{
	char *probe = part_path(out, 1);
	char real_in[PATH_MAX], real_dir[PATH_MAX], dir[PATH_MAX];
	const char *slash, *base, *dot, *ibase;
	size_t stem;
	bool match = false;

	if (!probe)
		return false;
	slash = strrchr(probe, '/');
	snprintf(dir, sizeof(dir), "%.*s", slash ? (int)(slash - probe) : 1, slash ? probe : ".");
	base = slash ? slash + 1 : probe;
	/* probe's base is STEM-1EXT: the stem ends at the "-1". */
	dot = strstr(base, "-1");
	while (dot && strstr(dot + 1, "-1"))
		dot = strstr(dot + 1, "-1");
	if (dot && realpath(in, real_in) && realpath(dir, real_dir)) {
		const char *islash = strrchr(real_in, '/');
		const char *ext = dot + 2, *k;

		stem = (size_t)(dot - base);
		ibase = islash + 1;
		if ((size_t)(islash - real_in) == strlen(real_dir) &&
		    !strncmp(real_in, real_dir, strlen(real_dir)) && !strncmp(ibase, base, stem + 1)) {
			k = ibase + stem + 1;
			while (*k >= '0' && *k <= '9')
				k++;
			match = k > ibase + stem + 1 && !strcmp(k, ext);
		}
	}
	free(probe);
	return match;
}

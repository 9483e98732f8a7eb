/*
 * objoff.c - Wavefront OBJ and OFF readers.  Both are line based, strip '#'
 * comments, weld every vertex as it is read (exact positions, through
 * mesh_builder_vertex) and fan-triangulate polygons: a face v0 v1 ... vn-1
 * becomes (v0, vi, vi+1) for i = 1 .. n-2, in order.
 */
#include "meshio_impl.h"
#include "st_grow.h"

#include <stdlib.h>
#include <string.h>

/* Cut the current line at '#'; true if anything but white space is left. */
static bool strip_comment(struct mio_text *t)
{
	char *hash = memchr(t->line, '#', t->len);

	if (hash) {
		*hash = '\0';
		t->len = (size_t)(hash - t->line);
	}
	for (size_t i = 0; i < t->len; i++)
		if (t->line[i] != ' ' && t->line[i] != '\t' && t->line[i] != '\r' &&
		    t->line[i] != '\f' && t->line[i] != '\v')
			return true;
	return false;
}

/* Next line with content; 1, 0 at end of input, or <0 with the error set. */
static int content_line(struct mio_text *t)
{
	int rc;

	while ((rc = mio_next_line(t)) > 0)
		if (strip_comment(t))
			return 1;
	return rc;
}

/* The current line number, for messages. */
static unsigned long long line_no(const struct mio_text *t)
{
	return (unsigned long long)t->lineno;
}

/*
 * A vertex line's numbers after its keyword: x y z (finite), then up to
 * extra more numbers that are ignored (OBJ w or colours, OFF colours).
 */
static int read_position(struct mio_text *t, size_t extra, double p[3])
{
	char shown[40];
	size_t len, n = 0;
	char *tok;

	while ((tok = mio_token(t, &len))) {
		double v;
		enum mio_num r = mio_parse_double(tok, len, &v);

		if (r == MIO_NUM_BAD)
			return mio_err(t->s, ST_ERR_PARSE, "line %llu: %s is not a number",
				       line_no(t), mio_tokstr(tok, shown, sizeof(shown)));
		if (n < 3 && r == MIO_NUM_NONFINITE)
			return mio_err(
			    t->s, ST_ERR_PARSE,
			    "line %llu: vertex has a non-finite coordinate (NaN or infinity)",
			    line_no(t));
		if (n >= 3 + extra)
			return mio_err(t->s, ST_ERR_PARSE,
				       "line %llu: too many numbers for a vertex (at most %zu)",
				       line_no(t), 3 + extra);
		if (n < 3)
			p[n] = v;
		n++;
	}
	if (n < 3)
		return mio_err(t->s, ST_ERR_PARSE,
			       "line %llu: a vertex needs 3 coordinates, found %zu", line_no(t), n);
	return 0;
}

/* Grow the OBJ vertex map (file order -> welded index) by one slot. */
static int map_push(uint32_t **map, size_t *n, size_t *cap, uint32_t v)
{
	uint32_t *p = st_grow(*map, cap, *n + 1, sizeof(**map));

	if (!p)
		return -1;
	*map = p;
	(*map)[(*n)++] = v;
	return 0;
}

/*
 * One corner of an OBJ face: "i", "i/t", "i//n" or "i/t/n"; the texture and
 * normal parts must be integers or empty and are ignored.  Sets *idx to the
 * index into map after resolving negative (relative) indices.
 */
static int obj_corner(struct mio_text *t, const char *tok, size_t len, size_t nverts, size_t *idx)
{
	char shown[40];
	const char *slash = memchr(tok, '/', len);
	size_t head = slash ? (size_t)(slash - tok) : len;
	long long v, dummy;

	if (slash) {
		const char *part = slash + 1, *end = tok + len;
		for (int k = 0; k < 2 && part <= end; k++) {
			const char *next = memchr(part, '/', (size_t)(end - part));
			size_t plen = next ? (size_t)(next - part) : (size_t)(end - part);

			if (plen && !mio_parse_int(part, plen, &dummy))
				goto out_bad;
			if (!next)
				break;
			if (k == 1)
				goto out_bad; /* a third slash */
			part = next + 1;
		}
	}
	if (!mio_parse_int(tok, head, &v))
		goto out_bad;
	if (v == 0)
		return mio_err(t->s, ST_ERR_PARSE,
			       "line %llu: face refers to vertex 0; OBJ vertices count from 1",
			       line_no(t));
	if ((v > 0 && (unsigned long long)v > nverts) || (v < 0 && (unsigned long long)-v > nverts))
		return mio_err(
		    t->s, ST_ERR_PARSE,
		    "line %llu: face refers to vertex %lld but only %zu vertices are defined before it",
		    line_no(t), v, nverts);
	*idx = v > 0 ? (size_t)v - 1 : nverts - (size_t)-v;
	return 0;

out_bad:
	return mio_err(t->s, ST_ERR_PARSE,
		       "line %llu: %s is not a face corner (i, i/t, i//n, i/t/n)", line_no(t),
		       mio_tokstr(tok, shown, sizeof(shown)));
}

/* The corners of an OBJ "f" line, fan-triangulated into b. */
static int obj_face(struct mio_text *t, struct mesh_builder *b, const uint32_t *map, size_t nmap,
		    size_t *ntris)
{
	struct st_error berr;
	uint32_t first = 0, prev = 0;
	size_t n = 0, len, idx = 0;
	char *tok;
	int rc;

	while ((tok = mio_token(t, &len))) {
		if ((rc = obj_corner(t, tok, len, nmap, &idx)))
			return rc;
		if (n >= 2) {
			if (mesh_builder_triangle(b, first, prev, map[idx], &berr))
				return mio_builder_error(t->s, "line", t->lineno, &berr);
			(*ntris)++;
		}
		if (n == 0)
			first = map[idx];
		prev = map[idx];
		n++;
	}
	if (n < 3)
		return mio_err(t->s, ST_ERR_PARSE,
			       "line %llu: a face needs at least 3 vertices, found %zu", line_no(t),
			       n);
	return 0;
}

int objoff_read_obj(struct mio_src *s, struct mesh **out)
{
	struct mio_text *t;
	struct mesh_builder *b;
	struct st_error berr;
	uint32_t *map = NULL;
	size_t nmap = 0, cap = 0, ntris = 0;
	int rc;

	*out = NULL;
	t = malloc(sizeof(*t));
	if (!t)
		return mio_err(s, ST_ERR_NOMEM, "out of memory for the line buffer");
	mio_text_init(t, s);
	b = mesh_builder_new(0);
	if (!b) {
		rc = mio_err(s, ST_ERR_NOMEM, "out of memory for the mesh");
		goto out_free_text;
	}
	while ((rc = content_line(t)) > 0) {
		size_t len;
		char *tok = mio_token(t, &len);

		if (!strcmp(tok, "v")) {
			double p[3];
			uint32_t v;

			/* x y z [w] or x y z r g b [a]: extras ignored. */
			if ((rc = read_position(t, 4, p)))
				goto out_free_builder;
			if (mesh_builder_vertex(b, p, &v, &berr)) {
				rc = mio_builder_error(s, "line", t->lineno, &berr);
				goto out_free_builder;
			}
			if (map_push(&map, &nmap, &cap, v)) {
				rc = mio_err(s, ST_ERR_NOMEM, "line %llu: out of memory",
					     line_no(t));
				goto out_free_builder;
			}
		} else if (!strcmp(tok, "f")) {
			if ((rc = obj_face(t, b, map, nmap, &ntris)))
				goto out_free_builder;
		}
		/* vt, vn, o, g, s, usemtl, mtllib, l, p and the rest: ignored. */
	}
	if (rc < 0)
		goto out_free_builder;
	if (ntris == 0) {
		rc =
		    mio_err(s, ST_ERR_PARSE,
			    "line %llu: the file contains no triangles (no 'f' lines)", line_no(t));
		goto out_free_builder;
	}
	*out = mesh_builder_finish(b);
	rc = *out ? 0 : mio_err(s, ST_ERR_NOMEM, "out of memory finishing the mesh");
	goto out_free_text;

out_free_builder:
	mesh_builder_free(b);
out_free_text:
	free(map);
	free(t);
	return rc;
}

/* ---- OFF ---------------------------------------------------------------- */

/* Parse a count token of the OFF header: 0 .. MESH_MAX_ELEMENTS. */
static bool off_count(const char *tok, size_t len, long long *v)
{
	return tok && mio_parse_int(tok, len, v) && *v >= 0 && *v <= (long long)MESH_MAX_ELEMENTS;
}

/* "OFF" (or COFF, NOFF, CNOFF), then "nv nf [ne]" on the same or next line. */
static int off_header(struct mio_text *t, long long *nv, long long *nf)
{
	char shown[40];
	size_t len;
	char *tok;
	long long ne;
	int rc = content_line(t);

	if (rc <= 0)
		return rc ? rc
			  : mio_err(t->s, ST_ERR_PARSE, "line %llu: no OFF header", line_no(t));
	tok = mio_token(t, &len);
	if (strcmp(tok, "OFF") && strcmp(tok, "COFF") && strcmp(tok, "NOFF") &&
	    strcmp(tok, "CNOFF"))
		return mio_err(t->s, ST_ERR_PARSE, "line %llu: expected the 'OFF' header, found %s",
			       line_no(t), mio_tokstr(tok, shown, sizeof(shown)));
	tok = mio_token(t, &len);
	if (!tok) {
		rc = content_line(t);
		if (rc <= 0)
			return rc ? rc
				  : mio_err(
					t->s, ST_ERR_PARSE,
					"line %llu: the OFF header has no vertex and face counts",
					line_no(t));
		tok = mio_token(t, &len);
	}
	if (!off_count(tok, len, nv))
		goto out_bad;
	tok = mio_token(t, &len);
	if (!off_count(tok, len, nf))
		goto out_bad;
	tok = mio_token(t, &len);
	if (tok && !off_count(tok, len, &ne))
		goto out_bad;
	if (tok && mio_token(t, &len))
		goto out_bad;
	return 0;

out_bad:
	return mio_err(
	    t->s, ST_ERR_PARSE,
	    "line %llu: expected the OFF counts 'vertices faces [edges]' as whole numbers up to %lu",
	    line_no(t), (unsigned long)MESH_MAX_ELEMENTS);
}

/* One OFF face "n i1 ... in [colour]", fan-triangulated into b. */
static int off_face(struct mio_text *t, struct mesh_builder *b, const uint32_t *map, long long nv)
{
	char shown[40];
	struct st_error berr;
	uint32_t first = 0, prev = 0;
	long long n, i;
	size_t len;
	char *tok = mio_token(t, &len);

	if (!mio_parse_int(tok, len, &n))
		return mio_err(t->s, ST_ERR_PARSE,
			       "line %llu: expected a face's vertex count, found %s", line_no(t),
			       mio_tokstr(tok, shown, sizeof(shown)));
	if (n < 3)
		return mio_err(t->s, ST_ERR_PARSE,
			       "line %llu: a face needs at least 3 vertices, found %lld",
			       line_no(t), n);
	for (long long k = 0; k < n; k++) {
		tok = mio_token(t, &len);
		if (!tok)
			return mio_err(t->s, ST_ERR_PARSE,
				       "line %llu: the face announces %lld vertices but lists %lld",
				       line_no(t), n, k);
		if (!mio_parse_int(tok, len, &i))
			return mio_err(t->s, ST_ERR_PARSE, "line %llu: %s is not a vertex index",
				       line_no(t), mio_tokstr(tok, shown, sizeof(shown)));
		if (i < 0 || i >= nv)
			return mio_err(
			    t->s, ST_ERR_PARSE,
			    "line %llu: face refers to vertex %lld but the file has %lld vertices (numbered from 0)",
			    line_no(t), i, nv);
		if (k >= 2 && mesh_builder_triangle(b, first, prev, map[i], &berr))
			return mio_builder_error(t->s, "line", t->lineno, &berr);
		if (k == 0)
			first = map[i];
		prev = map[i];
	}
	/* What follows the indices is an optional colour: numbers, ignored. */
	while ((tok = mio_token(t, &len))) {
		double v;

		if (mio_parse_double(tok, len, &v) == MIO_NUM_BAD)
			return mio_err(
			    t->s, ST_ERR_PARSE,
			    "line %llu: %s after the face's indices is not a colour value",
			    line_no(t), mio_tokstr(tok, shown, sizeof(shown)));
	}
	return 0;
}

int objoff_read_off(struct mio_src *s, struct mesh **out)
{
	struct mio_text *t;
	struct mesh_builder *b = NULL;
	struct st_error berr;
	uint32_t *map = NULL;
	long long nv, nf;
	uint64_t need;
	int rc;

	*out = NULL;
	t = malloc(sizeof(*t));
	if (!t)
		return mio_err(s, ST_ERR_NOMEM, "out of memory for the line buffer");
	mio_text_init(t, s);
	if ((rc = off_header(t, &nv, &nf)))
		goto out_free;
	/* Each vertex takes at least "0 0 0\n", each face "3 0 1 2\n". */
	need = 6 * (uint64_t)nv + 8 * (uint64_t)nf;
	if (need > s->size) {
		rc = mio_err(
		    s, ST_ERR_PARSE,
		    "line %llu: the OFF header announces %lld vertices and %lld faces, which need at least %llu bytes, but the file has %llu bytes",
		    line_no(t), nv, nf, (unsigned long long)need, (unsigned long long)s->size);
		goto out_free;
	}
	if (nf == 0) {
		rc = mio_err(
		    s, ST_ERR_PARSE,
		    "line %llu: the OFF header announces 0 faces; the file contains no triangles",
		    line_no(t));
		goto out_free;
	}
	/* Both counts are now bounded by the file size. */
	map = malloc((size_t)(nv ? nv : 1) * sizeof(*map));
	b = mesh_builder_new((size_t)nf);
	if (!map || !b) {
		rc = mio_err(s, ST_ERR_NOMEM, "out of memory for %lld vertices", nv);
		goto out_free;
	}
	for (long long i = 0; i < nv; i++) {
		double p[3];

		rc = content_line(t);
		if (rc <= 0) {
			if (!rc)
				rc = mio_err(
				    s, ST_ERR_PARSE,
				    "line %llu: the file ends after %lld of %lld vertices (it may be truncated)",
				    line_no(t), i, nv);
			goto out_free;
		}
		/* x y z, then optional normal, colour and texture values. */
		if ((rc = read_position(t, 9, p)))
			goto out_free;
		if (mesh_builder_vertex(b, p, &map[i], &berr)) {
			rc = mio_builder_error(s, "line", t->lineno, &berr);
			goto out_free;
		}
	}
	for (long long i = 0; i < nf; i++) {
		rc = content_line(t);
		if (rc <= 0) {
			if (!rc)
				rc = mio_err(
				    s, ST_ERR_PARSE,
				    "line %llu: the file ends after %lld of %lld faces (it may be truncated)",
				    line_no(t), i, nf);
			goto out_free;
		}
		if ((rc = off_face(t, b, map, nv)))
			goto out_free;
	}
	/* Anything after the last face (an edge list some writers add) is ignored. */
	*out = mesh_builder_finish(b);
	b = NULL;
	rc = *out ? 0 : mio_err(s, ST_ERR_NOMEM, "out of memory finishing the mesh");

out_free:
	mesh_builder_free(b);
	free(map);
	free(t);
	return rc;
}

/*
 * stlio.c - binary and ASCII STL: the two readers (called by meshio.c after
 * detection) and the atomic writer behind meshio_write_stl.
 *
 * Binary STL: an 80-byte header, a uint32 little-endian facet count, then 50
 * bytes per facet (normal, three vertices as float32 LE, a uint16 attribute).
 * A file is binary only if its size is exactly 84 + 50 * count, which both
 * detects the format and bounds the count before anything is allocated.
 * Every float is decoded byte by byte; nothing is fread into a struct.
 */
#include "meshio_impl.h"
#include "st_file.h"
#include "vec3.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define STL_HEADER 80
#define STL_PREFIX 84 /* header + count */
#define STL_FACET 50

_Static_assert(sizeof(float) == 4 && sizeof(uint32_t) == 4, "float must be IEEE binary32");

/* Little-endian uint32 from 4 bytes, whatever the host order. */
static uint32_t get_le32(const unsigned char *b)
{
	return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

/* Store u as 4 little-endian bytes. */
static void put_le32(unsigned char *b, uint32_t u)
{
	for (int i = 0; i < 4; i++)
		b[i] = (unsigned char)(u >> (8 * i));
}

/* A little-endian IEEE binary32 as a double (exact). */
static double get_le_float(const unsigned char *b)
{
	uint32_t u = get_le32(b);
	float f;

	memcpy(&f, &u, sizeof(f));
	return f;
}

/* Store f as little-endian IEEE binary32. */
static void put_le_float(unsigned char *b, float f)
{
	uint32_t u;

	memcpy(&u, &f, sizeof(u));
	put_le32(b, u);
}

/* Bytes a binary STL with count facets must have. */
static uint64_t binary_size(uint32_t count)
{
	return STL_PREFIX + (uint64_t)STL_FACET * count;
}

bool stlio_binary_size_matches(const struct mio_src *s)
{
	return s->off == 0 && s->end - s->p >= STL_PREFIX &&
	       s->size == binary_size(get_le32(s->p + STL_HEADER));
}

int stlio_binary_size_error(struct mio_src *s)
{
	uint32_t count;

	if (s->size < STL_PREFIX || s->off != 0 || s->end - s->p < STL_PREFIX)
		return mio_err(s, ST_ERR_PARSE,
			       "byte %llu: the file ends inside the 84-byte binary STL header",
			       (unsigned long long)s->size);
	count = get_le32(s->p + STL_HEADER);
	return mio_err(
	    s, ST_ERR_PARSE,
	    "byte 80: binary STL header says %lu triangles (needs %llu bytes) but the file has %llu bytes; it is truncated or not an STL file",
	    (unsigned long)count, (unsigned long long)binary_size(count),
	    (unsigned long long)s->size);
}

/* Read facets first .. first+count-1 from s (positioned at the first) into b. */
/* A facet read and checked, waiting to be welded. */
struct facet {
	double p[3][3];
	uint64_t at; /* byte offset in the file */
};

/* Weld one facet's corners and add its triangle. */
static int weld_facet(struct mio_src *s, struct mesh_builder *b, const struct facet *f)
{
	struct st_error berr;
	uint32_t idx[3];

	for (int k = 0; k < 3; k++)
		if (mesh_builder_vertex(b, f->p[k], &idx[k], &berr))
			return mio_builder_error(s, "byte", f->at, &berr);
	if (mesh_builder_triangle(b, idx[0], idx[1], idx[2], &berr))
		return mio_builder_error(s, "byte", f->at, &berr);
	return 0;
}

/* Read and check facet i into f; its corners' hash slots are prefetched. */
static int read_binary_facet(struct mio_src *s, const struct mesh_builder *b, uint32_t i,
			     struct facet *f)
{
	unsigned char fac[STL_FACET];

	f->at = s->off;
	if (mio_read(s, fac, sizeof(fac)) != sizeof(fac))
		return s->read_errno
			   ? mio_read_error(s, s->off)
			   : mio_err(s, ST_ERR_PARSE,
				     "byte %llu: the file ends inside facet %lu (did it "
				     "change while being read?)",
				     (unsigned long long)s->off, (unsigned long)i);
	/* Bytes 0-11 are the normal, ignored; 12-47 the corners. */
	for (int k = 0; k < 3; k++) {
		for (int c = 0; c < 3; c++) {
			size_t o = 12 + 12 * (size_t)k + 4 * (size_t)c;
			f->p[k][c] = get_le_float(fac + o);
			if (!isfinite(f->p[k][c]))
				return mio_err(s, ST_ERR_PARSE,
					       "byte %llu: facet %lu has a non-finite "
					       "coordinate (NaN or infinity)",
					       (unsigned long long)(f->at + o), (unsigned long)i);
		}
		mesh_builder_prefetch(b, f->p[k]);
	}
	return 0;
}

/*
 * Facets are read a few ahead of welding, so that the hash slots their
 * corners probe are on their way from memory when they are welded (most
 * probes miss the cache).  The welding order, and so the mesh, is that of
 * the file; an error is reported only after every facet before it is
 * welded, so the first error in the file is the one reported.
 */
static int read_facets(struct mio_src *s, struct mesh_builder *b, uint32_t first, uint32_t count)
{
	enum { AHEAD = MESH_WELD_AHEAD / 3 };
	struct facet ring[AHEAD];
	uint32_t next = first; /* next facet to weld */
	int rc;

	for (uint32_t i = first; i < first + count; i++) {
		if (i - first >= AHEAD) {
			rc = weld_facet(s, b, &ring[next % AHEAD]);
			if (rc)
				return rc;
			next++;
		}
		rc = read_binary_facet(s, b, i, &ring[i % AHEAD]);
		if (rc) {
			/* The facets before it come first. */
			for (; next < i; next++) {
				int wrc = weld_facet(s, b, &ring[next % AHEAD]);
				if (wrc)
					return wrc;
			}
			return rc;
		}
	}
	for (; next < first + count; next++) {
		rc = weld_facet(s, b, &ring[next % AHEAD]);
		if (rc)
			return rc;
	}
	return 0;
}

/* mesh_corner_reader over a binary STL (ctx: its file descriptor): one
 * pread per run of facets, so that several threads may read at once. */
static bool read_corners(void *ctx, size_t first, size_t count, float (*corner)[3])
{
	const int fd = *(const int *)ctx;
	unsigned char raw[MESH_WELD_RUN * STL_FACET];
	size_t want = count * STL_FACET, got = 0;

	if (count > MESH_WELD_RUN)
		return false;
	while (got < want) {
		ssize_t n = pread(fd, raw + got, want - got,
				  (off_t)(binary_size((uint32_t)first) + got));
		if (n < 0 && errno == EINTR)
			continue;
		if (n <= 0)
			return false;
		got += (size_t)n;
	}
	for (size_t i = 0; i < count; i++)
		/* Bytes 0-11 are the normal, ignored; 12-47 the corners. */
		for (int k = 0; k < 3; k++)
			for (int c = 0; c < 3; c++) {
				float f = (float)get_le_float(raw + STL_FACET * i + 12 + 12 * k + 4 * c);
				if (!isfinite(f))
					return false;
				corner[3 * i + k][c] = f;
			}
	return true;
}

/*
 * Files from SPLIT_MIN facets up are read and welded by mesh_weld_read:
 * the same mesh, index for index, as welding corner by corner, without
 * an array of every corner.  One thread: each of several would read and
 * hash every corner to find its own, which on a 1M-triangle sphere took
 * twice the CPU time of one thread and, on a shared machine, more wall
 * time too.  Returns 1 when that could not be done (a facet that does not
 * read or decode, no memory, more vertices than a mesh holds): the caller
 * then reads the file in one pass, which names the first bad byte.
 */
#define SPLIT_MIN 100000u

static int read_welded(struct mio_src *s, uint32_t count, struct mesh **out)
{
	int fd = fileno(s->f);
	struct st_error werr;

	/* Out of memory or out of range: the one pass needs less memory,
	 * and names the byte where a range runs out. */
	return mesh_weld_read(read_corners, &fd, count, 1, out, &werr) == 0 ? 0 : 1;
}

int stlio_read_binary(struct mio_src *s, struct mesh **out)
{
	unsigned char head[STL_PREFIX];
	struct mesh_builder *b;
	uint32_t count;
	int rc;

	*out = NULL;
	if (!stlio_binary_size_matches(s))
		return stlio_binary_size_error(s);
	if (mio_read(s, head, sizeof(head)) != sizeof(head))
		return s->read_errno ? mio_read_error(s, s->off) : stlio_binary_size_error(s);
	count = get_le32(head + STL_HEADER);
	if (count == 0)
		return mio_err(
		    s, ST_ERR_PARSE,
		    "byte 80: binary STL header says 0 triangles; the file contains no triangles");
	if (s->f && count >= SPLIT_MIN && (rc = read_welded(s, count, out)) != 1)
		return rc;
	/* count is now bounded by the file size, so it may size the tables. */
	b = mesh_builder_new(count);
	if (!b)
		return mio_err(s, ST_ERR_NOMEM, "out of memory for %lu triangles",
			       (unsigned long)count);
	rc = read_facets(s, b, 0, count);
	if (rc) {
		mesh_builder_free(b);
		return rc;
	}
	*out = mesh_builder_finish(b);
	if (!*out)
		return mio_err(s, ST_ERR_NOMEM, "out of memory finishing the mesh");
	return 0;
}

/* ---- ASCII STL ---------------------------------------------------------- */

/* Parsing state of one ASCII STL: the reader, the builder, the facet index. */
struct ascii_stl {
	struct mio_text t;
	struct mesh_builder *b;
	size_t facet; /* index of the facet being read, from 0 */
};

/* The current line number, for messages. */
static unsigned long long line_of(const struct ascii_stl *a)
{
	return (unsigned long long)a->t.lineno;
}

/* Next keyword token (may be on a later line); fails at end of input. */
static int expect(struct ascii_stl *a, const char *kw)
{
	char shown[40];
	size_t len;
	int rc;
	char *tok = mio_next_token(&a->t, &len, &rc);

	if (!tok)
		return rc ? rc
			  : mio_err(
				a->t.s, ST_ERR_PARSE,
				"line %llu: unexpected end of file, expected '%s' (the file may be truncated)",
				line_of(a), kw);
	if (!mio_keyword(tok, kw))
		return mio_err(a->t.s, ST_ERR_PARSE, "line %llu: expected '%s', found %s",
			       line_of(a), kw, mio_tokstr(tok, shown, sizeof(shown)));
	return 0;
}

/* Three numbers on the current line after "vertex" or "facet normal". */
static int read_triple(struct ascii_stl *a, const char *what, bool finite, double v[3])
{
	char shown[40];

	for (int c = 0; c < 3; c++) {
		size_t len;
		char *tok = mio_token(&a->t, &len);

		if (!tok)
			return mio_err(a->t.s, ST_ERR_PARSE,
				       "line %llu: '%s' needs 3 numbers, found %d", line_of(a),
				       what, c);
		switch (mio_parse_double(tok, len, &v[c])) {
		case MIO_NUM_OK:
			break;
		case MIO_NUM_NONFINITE:
			if (!finite) {
				v[c] = 0.0;
				break;
			}
			return mio_err(
			    a->t.s, ST_ERR_PARSE,
			    "line %llu: facet %zu has a non-finite coordinate (NaN or infinity)",
			    line_of(a), a->facet);
		default:
			return mio_err(a->t.s, ST_ERR_PARSE,
				       "line %llu: facet %zu: %s is not a number", line_of(a),
				       a->facet, mio_tokstr(tok, shown, sizeof(shown)));
		}
	}
	return 0;
}

/* One facet after its "facet" keyword, through "endfacet". */
static int read_facet(struct ascii_stl *a)
{
	char shown[40];
	struct st_error berr;
	uint32_t idx[3];
	double v[3];
	int n = 0, rc;

	if ((rc = expect(a, "normal")) || (rc = read_triple(a, "normal", false, v)) ||
	    (rc = expect(a, "outer")) || (rc = expect(a, "loop")))
		return rc;
	for (;;) {
		size_t len;
		char *tok = mio_next_token(&a->t, &len, &rc);

		if (!tok)
			return rc ? rc
				  : mio_err(
					a->t.s, ST_ERR_PARSE,
					"line %llu: unexpected end of file inside facet %zu (the file may be truncated)",
					line_of(a), a->facet);
		if (mio_keyword(tok, "endloop"))
			break;
		if (!mio_keyword(tok, "vertex"))
			return mio_err(a->t.s, ST_ERR_PARSE,
				       "line %llu: expected 'vertex' or 'endloop', found %s",
				       line_of(a), mio_tokstr(tok, shown, sizeof(shown)));
		if (n == 3)
			return mio_err(
			    a->t.s, ST_ERR_PARSE,
			    "line %llu: facet %zu has more than 3 vertices; STL facets must be triangles",
			    line_of(a), a->facet);
		if ((rc = read_triple(a, "vertex", true, v)))
			return rc;
		if (mesh_builder_vertex(a->b, v, &idx[n], &berr))
			return mio_builder_error(a->t.s, "line", a->t.lineno, &berr);
		n++;
	}
	if (n != 3)
		return mio_err(a->t.s, ST_ERR_PARSE,
			       "line %llu: facet %zu has %d vertices; STL facets must be triangles",
			       line_of(a), a->facet, n);
	if ((rc = expect(a, "endfacet")))
		return rc;
	if (mesh_builder_triangle(a->b, idx[0], idx[1], idx[2], &berr))
		return mio_builder_error(a->t.s, "line", a->t.lineno, &berr);
	a->facet++;
	return 0;
}

/* The solid's body after "solid name": facets up to and including "endsolid". */
static int read_solid(struct ascii_stl *a)
{
	char shown[40];
	int rc;

	for (;;) {
		size_t len;
		char *tok = mio_next_token(&a->t, &len, &rc);

		if (!tok)
			return rc ? rc
				  : mio_err(
					a->t.s, ST_ERR_PARSE,
					"line %llu: unexpected end of file, 'endsolid' is missing (the file may be truncated)",
					line_of(a));
		if (mio_keyword(tok, "endsolid")) {
			a->t.pos = a->t.len; /* the name, if any */
			return 0;
		}
		if (!mio_keyword(tok, "facet"))
			return mio_err(a->t.s, ST_ERR_PARSE,
				       "line %llu: expected 'facet' or 'endsolid', found %s",
				       line_of(a), mio_tokstr(tok, shown, sizeof(shown)));
		if ((rc = read_facet(a)))
			return rc;
	}
}

int stlio_read_ascii(struct mio_src *s, struct mesh **out)
{
	struct ascii_stl *a;
	char shown[40];
	int rc;

	*out = NULL;
	a = calloc(1, sizeof(*a));
	if (!a)
		return mio_err(s, ST_ERR_NOMEM, "out of memory for the line buffer");
	mio_text_init(&a->t, s);
	/* No count in an ASCII STL: let the tables grow. */
	a->b = mesh_builder_new(0);
	if (!a->b) {
		rc = mio_err(s, ST_ERR_NOMEM, "out of memory for the mesh");
		goto out_free_state;
	}
	for (bool first = true;; first = false) {
		size_t len;
		char *tok = mio_next_token(&a->t, &len, &rc);

		if (!tok) {
			if (rc)
				goto out_free_builder;
			if (!first)
				break;
			rc = mio_err(s, ST_ERR_PARSE, "line %llu: no 'solid' in an empty text file",
				     line_of(a));
			goto out_free_builder;
		}
		if (!mio_keyword(tok, "solid")) {
			rc = mio_err(
			    s, ST_ERR_PARSE,
			    first
				? "line %llu: expected 'solid' at the start of an ASCII STL, found %s"
				: "line %llu: expected 'solid' or the end of the file after 'endsolid', found %s",
			    line_of(a), mio_tokstr(tok, shown, sizeof(shown)));
			goto out_free_builder;
		}
		a->t.pos = a->t.len; /* the solid's name, free text */
		rc = read_solid(a);
		if (rc)
			goto out_free_builder;
	}
	if (a->facet == 0) {
		rc = mio_err(s, ST_ERR_PARSE, "line %llu: the file contains no triangles",
			     line_of(a));
		goto out_free_builder;
	}
	*out = mesh_builder_finish(a->b);
	free(a);
	if (!*out)
		return mio_err(s, ST_ERR_NOMEM, "out of memory finishing the mesh");
	return 0;

out_free_builder:
	mesh_builder_free(a->b);
out_free_state:
	free(a);
	return rc;
}

/* ---- writer ------------------------------------------------------------- */

/* Unit normal of triangle abc by the right-hand rule; zero if degenerate. */
static void facet_normal(const double a[3], const double b[3], const double c[3], double n[3])
{
	double len;

	vec3_area_normal(a, b, c, n);
	len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
	for (int k = 0; k < 3; k++)
		n[k] = len > 0.0 && isfinite(len) ? n[k] / len : 0.0;
}

/* Every index in range, every used coordinate finite (and float-sized). */
static int check_mesh(const char *path, const struct mesh *m, bool binary, struct st_error *err)
{
	for (size_t i = 0; i < m->ntris; i++) {
		for (int k = 0; k < 3; k++) {
			uint32_t v = m->tris[i][k];

			if (v >= m->nverts)
				return st_error_set(
				    err, ST_ERR_ARG,
				    "%s: triangle %zu refers to vertex %lu but the mesh has %zu vertices",
				    path, i, (unsigned long)v, m->nverts);
			for (int c = 0; c < 3; c++) {
				double x = m->verts[v][c];

				if (!isfinite(x))
					return st_error_set(
					    err, ST_ERR_RANGE,
					    "%s: vertex %lu has a non-finite coordinate; nothing written",
					    path, (unsigned long)v);
				if (binary && fabs(x) > FLT_MAX)
					return st_error_set(
					    err, ST_ERR_RANGE,
					    "%s: vertex %lu has coordinate %g, beyond the float32 range of binary STL; write ASCII STL instead",
					    path, (unsigned long)v, x);
			}
		}
	}
	return 0;
}

/* Header, count and facets (normal from the rounded corners); 0 or -1. */
static int write_binary(FILE *f, const struct mesh *m)
{
	unsigned char head[STL_PREFIX], fac[STL_FACET];
	static const char title[] = "stratum binary STL";

	memset(head, ' ', STL_HEADER);
	memcpy(head, title, sizeof(title) - 1);
	put_le32(head + STL_HEADER, (uint32_t)m->ntris);
	if (fwrite(head, 1, sizeof(head), f) != sizeof(head))
		return -1;
	memset(fac, 0, sizeof(fac)); /* attribute bytes stay 0 */
	for (size_t i = 0; i < m->ntris; i++) {
		double p[3][3], n[3];

		/* The normal of the triangle as stored, i.e. after rounding. */
		for (int k = 0; k < 3; k++)
			for (int c = 0; c < 3; c++)
				p[k][c] = (float)m->verts[m->tris[i][k]][c];
		facet_normal(p[0], p[1], p[2], n);
		for (int c = 0; c < 3; c++)
			put_le_float(fac + 4 * c, (float)n[c]);
		for (int k = 0; k < 3; k++)
			for (int c = 0; c < 3; c++)
				put_le_float(fac + 12 + 12 * k + 4 * c, (float)p[k][c]);
		if (fwrite(fac, 1, sizeof(fac), f) != sizeof(fac))
			return -1;
	}
	return 0;
}

/* %.17g: every double is written with enough digits to read back exactly. */
static int write_ascii(FILE *f, const struct mesh *m)
{
	if (fputs("solid stratum\n", f) == EOF)
		return -1;
	for (size_t i = 0; i < m->ntris; i++) {
		const double *p[3];
		double n[3];

		for (int k = 0; k < 3; k++)
			p[k] = m->verts[m->tris[i][k]];
		facet_normal(p[0], p[1], p[2], n);
		if (fprintf(f, "  facet normal %.9g %.9g %.9g\n    outer loop\n", n[0], n[1],
			    n[2]) < 0)
			return -1;
		for (int k = 0; k < 3; k++)
			if (fprintf(f, "      vertex %.17g %.17g %.17g\n", p[k][0], p[k][1],
				    p[k][2]) < 0)
				return -1;
		if (fputs("    endloop\n  endfacet\n", f) == EOF)
			return -1;
	}
	return fputs("endsolid stratum\n", f) == EOF ? -1 : 0;
}

int stlio_write(const char *path, const struct mesh *m, enum meshio_format fmt,
		struct st_error *err)
{
	bool binary = fmt == MESHIO_STL_BINARY;
	struct st_file_out out;
	int rc;

	if (!path || !*path || !m)
		return st_error_set(err, ST_ERR_ARG, "meshio_write_stl: no path or no mesh");
	if (!binary && fmt != MESHIO_STL_ASCII)
		return st_error_set(err, ST_ERR_ARG,
				    "%s: can only write binary or ASCII STL, not %s", path,
				    meshio_format_name(fmt));
	if (binary && (uint64_t)m->ntris > UINT32_MAX)
		return st_error_set(
		    err, ST_ERR_RANGE,
		    "%s: %zu triangles do not fit in a binary STL (at most 4294967295); write ASCII STL instead",
		    path, m->ntris);
	if (m->ntris == 0)
		return st_error_set(err, ST_ERR_ARG,
				    "%s: the mesh has no triangles; an empty STL is not written",
				    path);
	if (!m->tris || !m->verts)
		return st_error_set(err, ST_ERR_ARG, "%s: the mesh has no tables", path);
	rc = check_mesh(path, m, binary, err);
	if (rc)
		return rc;

	if ((rc = st_file_begin(&out, path, err)))
		return rc;
	setvbuf(out.f, NULL, _IOFBF, MIO_CHUNK);
	errno = 0;
	if ((binary ? write_binary(out.f, m) : write_ascii(out.f, m)) != 0)
		return st_file_fail(&out, err);
	return st_file_commit(&out, err);
}

/*
 * meshiotest.c - the helpers of meshiotest.h.
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh.h"
#include "meshio.h"
#include "meshiotest.h"
#include "testutil.h"


/* A private copy of a scratch path (tu_path's buffers rotate). */
char *scratch(const char *name)
{
	char *p = strdup(tu_path(name));

	ck_assert_ptr_nonnull(p);
	return p;
}

struct mesh *read_path(const char *path, enum meshio_format want)
{
	struct st_error err = {0};
	struct mesh *m = NULL;
	enum meshio_format got = MESHIO_AUTO;

	ck_assert_msg(meshio_read(path, MESHIO_AUTO, &m, &got, &err) == 0, "%s", err.msg);
	ck_assert_ptr_nonnull(m);
	ck_assert_msg(got == want, "read as %s, expected %s", meshio_format_name(got),
		      meshio_format_name(want));
	return m;
}

struct mesh *read_buf(const void *data, size_t len, enum meshio_format want)
{
	struct st_error err = {0};
	struct mesh *m = NULL;
	enum meshio_format got = MESHIO_AUTO;

	ck_assert_msg(meshio_read_buffer(data, len, "buf", MESHIO_AUTO, &m, &got, &err) == 0, "%s",
		      err.msg);
	ck_assert_ptr_nonnull(m);
	ck_assert_msg(got == want, "read as %s, expected %s", meshio_format_name(got),
		      meshio_format_name(want));
	return m;
}

struct mesh *read_str(const char *text, enum meshio_format want)
{
	return read_buf(text, strlen(text), want);
}

void write_ok(const char *path, const struct mesh *m, enum meshio_format fmt)
{
	struct st_error err = {0};

	ck_assert_msg(meshio_write_stl(path, m, fmt, &err) == 0, "%s", err.msg);
}

/* Corner k of triangle i of m. */
const double *corner(const struct mesh *m, size_t i, int k)
{
	return m->verts[m->tris[i][k]];
}

/*
 * b has a's triangles in a's order with the same positions (rounded to
 * float32 first when as_float) and as many welded vertices.
 */
void assert_same(const struct mesh *a, const struct mesh *b, bool as_float)
{
	ck_assert_uint_eq(a->ntris, b->ntris);
	ck_assert_uint_eq(a->nverts, b->nverts);
	for (size_t i = 0; i < a->ntris; i++)
		for (int k = 0; k < 3; k++)
			for (int c = 0; c < 3; c++) {
				double want = corner(a, i, k)[c];
				if (as_float)
					want = (float)want;
				ck_assert_msg(corner(b, i, k)[c] == want,
					      "triangle %zu corner %d axis %d: %.17g != %.17g", i,
					      k, c, corner(b, i, k)[c], want);
			}
}

void put_le32(unsigned char *b, uint32_t u)
{
	for (int i = 0; i < 4; i++)
		b[i] = (unsigned char)(u >> (8 * i));
}

void put_float(unsigned char *b, float f)
{
	uint32_t u;

	memcpy(&u, &f, 4);
	put_le32(b, u);
}

uint32_t get_le32(const unsigned char *b)
{
	return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

float get_float(const unsigned char *b)
{
	uint32_t u = get_le32(b);
	float f;

	memcpy(&f, &u, 4);
	return f;
}

/*
 * A binary STL in buf (84 + 50 * n bytes, which the caller provides): the
 * header text, the count field `count` (may lie) and n facets whose corners
 * come from v (9 floats per facet); normals are garbage on purpose.
 */
size_t binary_stl(unsigned char *buf, const char *header, uint32_t count, const float *v,
		  size_t n)
{
	memset(buf, 0, 84 + 50 * n);
	memcpy(buf, header, strlen(header));
	put_le32(buf + 80, count);
	for (size_t i = 0; i < n; i++) {
		unsigned char *f = buf + 84 + 50 * i;
		put_float(f, 7.0f); /* a wrong normal: must be ignored */
		for (int k = 0; k < 9; k++)
			put_float(f + 12 + 4 * k, v[9 * i + k]);
	}
	return 84 + 50 * n;
}

const float two_tris[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};

/*
 * Read data as file `name` (scratch dir) and from memory under the same
 * path: both must fail with code, NULL output and the same one-line
 * message that names the file and contains every needle.
 */
void expect_fail(const char *name, const void *data, size_t len, int code,
		 const char *const *needles)
{
	char *path = scratch(name);

	tu_write(path, data, len);
	tu_expect_read_fail(path, data, len, code, needles);
	free(path);
}


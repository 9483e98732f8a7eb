/*
 * meshiotest.h - what the meshio suite's files share (check_meshio.c,
 * check_meshio_bad.c): reading from files and memory, comparing meshes,
 * building binary STL by hand, and the checks on refused input.
 */
#ifndef STRATUM_TESTS_MESHIOTEST_H
#define STRATUM_TESTS_MESHIOTEST_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "mesh.h"
#include "meshio.h"

/* Two triangles (9 floats each), a unit square at z = 0. */
extern const float two_tris[18];
/* A private copy of a scratch path (tu_path's buffers rotate). */
char *scratch(const char *name);
/* Read the file at path, or (len) bytes or a text from memory, with the
 * format found by detection, which must be want; the test fails otherwise. */
struct mesh *read_path(const char *path, enum meshio_format want);
struct mesh *read_buf(const void *data, size_t len, enum meshio_format want);
struct mesh *read_str(const char *text, enum meshio_format want);
/* Write m as STL in fmt to path; the test fails on error. */
void write_ok(const char *path, const struct mesh *m, enum meshio_format fmt);
/* Corner k of triangle i of m. */
const double *corner(const struct mesh *m, size_t i, int k);
/*
 * b has a's triangles in a's order with the same positions (rounded to
 * float32 first when as_float) and as many welded vertices.
 */
void assert_same(const struct mesh *a, const struct mesh *b, bool as_float);
/* Little-endian 32-bit words and floats, as binary STL holds them. */
void put_le32(unsigned char *b, uint32_t u);
void put_float(unsigned char *b, float f);
uint32_t get_le32(const unsigned char *b);
float get_float(const unsigned char *b);
/*
 * A binary STL in buf (84 + 50 * n bytes, which the caller provides): the
 * header text, the count field `count` (may lie) and n facets whose corners
 * come from v (9 floats per facet); normals are garbage on purpose.
 */
size_t binary_stl(unsigned char *buf, const char *header, uint32_t count, const float *v,
		  size_t n);
/*
 * Read data as file `name` (scratch dir) and from memory under the same
 * path: both must fail with code, NULL output and the same one-line
 * message that names the file and contains every needle.
 */
void expect_fail(const char *name, const void *data, size_t len, int code,
		 const char *const *needles);

#define EXPECT_FAIL(name, data, len, code, ...)                                                    \
	expect_fail(name, data, len, code, (const char *const[]){__VA_ARGS__, NULL})
#define EXPECT_FAIL_STR(name, text, code, ...)                                                     \
	EXPECT_FAIL(name, text, strlen(text), code, __VA_ARGS__)

/* One ASCII STL facet. */
#define FACET(a, b, c)                                                                             \
	"facet normal 0 0 1\nouter loop\nvertex " a "\nvertex " b "\nvertex " c                    \
	"\nendloop\nendfacet\n"

#endif

/*
 * check_meshio.c - STL/OBJ/OFF reading and STL writing (3MF: check_meshio_3mf.c): round trips of
 * generated meshes, every accepted spelling we promise, and for every kind
 * of bad input the error class and a message naming the file and the byte
 * or line.  Every bad input is read twice, from a file and from memory, and
 * must give the same message (one parser behind both).  All inputs are
 * generated here; no binary fixture files.
 */
#include <check.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

/* ---- helpers ------------------------------------------------------------ */

/* A private copy of a scratch path (tu_path's buffers rotate). */
static char *scratch(const char *name)
{
	char *p = strdup(tu_path(name));

	ck_assert_ptr_nonnull(p);
	return p;
}

static struct mesh *read_path(const char *path, enum meshio_format want)
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

static struct mesh *read_buf(const void *data, size_t len, enum meshio_format want)
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

static struct mesh *read_str(const char *text, enum meshio_format want)
{
	return read_buf(text, strlen(text), want);
}

static void write_ok(const char *path, const struct mesh *m, enum meshio_format fmt)
{
	struct st_error err = {0};

	ck_assert_msg(meshio_write_stl(path, m, fmt, &err) == 0, "%s", err.msg);
}

/* Corner k of triangle i of m. */
static const double *corner(const struct mesh *m, size_t i, int k)
{
	return m->verts[m->tris[i][k]];
}

/*
 * b has a's triangles in a's order with the same positions (rounded to
 * float32 first when as_float) and as many welded vertices.
 */
static void assert_same(const struct mesh *a, const struct mesh *b, bool as_float)
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

static void put_le32(unsigned char *b, uint32_t u)
{
	for (int i = 0; i < 4; i++)
		b[i] = (unsigned char)(u >> (8 * i));
}

static void put_float(unsigned char *b, float f)
{
	uint32_t u;

	memcpy(&u, &f, 4);
	put_le32(b, u);
}

static uint32_t get_le32(const unsigned char *b)
{
	return (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
}

static float get_float(const unsigned char *b)
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
static size_t binary_stl(unsigned char *buf, const char *header, uint32_t count, const float *v,
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

static const float two_tris[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};

/*
 * Read data as file `name` (scratch dir) and from memory under the same
 * path: both must fail with code, NULL output and the same one-line
 * message that names the file and contains every needle.
 */
static void expect_fail(const char *name, const void *data, size_t len, int code,
			const char *const *needles)
{
	char *path = scratch(name);

	tu_write(path, data, len);
	tu_expect_read_fail(path, data, len, code, needles);
	free(path);
}

#define EXPECT_FAIL(name, data, len, code, ...)                                                    \
	expect_fail(name, data, len, code, (const char *const[]){__VA_ARGS__, NULL})
#define EXPECT_FAIL_STR(name, text, code, ...)                                                     \
	EXPECT_FAIL(name, text, strlen(text), code, __VA_ARGS__)

/* One ASCII STL facet. */
#define FACET(a, b, c)                                                                             \
	"facet normal 0 0 1\nouter loop\nvertex " a "\nvertex " b "\nvertex " c                    \
	"\nendloop\nendfacet\n"

/* ---- round trips ---------------------------------------------------------- */

START_TEST(binary_round_trip)
{
	struct mesh *m = fx_torus(10.0, 3.0, 36, 18), *r;
	char *path = scratch("torus.stl");
	size_t len;
	unsigned char *raw;

	write_ok(path, m, MESHIO_STL_BINARY);
	raw = tu_slurp(path, &len);
	ck_assert_uint_eq(len, 84 + 50 * m->ntris);
	ck_assert_uint_eq(get_le32(raw + 80), m->ntris);
	r = read_path(path, MESHIO_STL_BINARY);
	assert_same(m, r, true);
	mesh_free(r);
	/* The same bytes from memory give the same mesh. */
	r = read_buf(raw, len, MESHIO_STL_BINARY);
	assert_same(m, r, true);
	mesh_free(r);
	free(raw);
	free(path);
	mesh_free(m);
}
END_TEST

START_TEST(binary_layout)
{
	struct mesh_builder *b = mesh_builder_new(0);
	const double p[3][3] = {{0, 0, 0}, {2, 0, 0}, {0, 3, 0}};
	uint32_t v[3];
	struct mesh *m;
	char *path = scratch("one.stl");
	unsigned char *raw;
	size_t len;

	for (int k = 0; k < 3; k++)
		ck_assert_int_eq(mesh_builder_vertex(b, p[k], &v[k], NULL), 0);
	ck_assert_int_eq(mesh_builder_triangle(b, v[0], v[1], v[2], NULL), 0);
	ck_assert_int_eq(mesh_builder_triangle(b, v[0], v[0], v[1], NULL), 0); /* degenerate */
	m = mesh_builder_finish(b);
	write_ok(path, m, MESHIO_STL_BINARY);
	raw = tu_slurp(path, &len);
	ck_assert_uint_eq(len, 84 + 2 * 50);
	ck_assert(!memcmp(raw, "stratum binary STL", 18));
	ck_assert_uint_eq(get_le32(raw + 80), 2);
	/* Counter-clockwise in the xy plane: normal +z, unit length. */
	ck_assert(get_float(raw + 84) == 0.0f && get_float(raw + 88) == 0.0f &&
		  get_float(raw + 92) == 1.0f);
	ck_assert(get_float(raw + 84 + 12 + 12) == 2.0f && get_float(raw + 84 + 12 + 28) == 3.0f);
	ck_assert(raw[84 + 48] == 0 && raw[84 + 49] == 0);
	/* The degenerate one gets a zero normal. */
	for (int c = 0; c < 3; c++)
		ck_assert(get_float(raw + 134 + 4 * c) == 0.0f);
	free(raw);
	free(path);
	mesh_free(m);
}
END_TEST

START_TEST(ascii_round_trip_exact)
{
	/* 2880 facets, about 700 KB: lines straddle the 64 KiB read windows. */
	struct mesh *m = fx_torus(10.0, 3.0, 80, 18), *r;
	char *path = scratch("torus-ascii.stl");
	char *raw;
	size_t len;

	write_ok(path, m, MESHIO_STL_ASCII);
	raw = tu_slurp(path, &len);
	ck_assert_uint_gt(len, 4 * 65536);
	ck_assert(!strncmp(raw, "solid stratum\n", 14));
	ck_assert_str_eq(raw + len - 17, "endsolid stratum\n");
	r = read_path(path, MESHIO_STL_ASCII);
	assert_same(m, r, false); /* bit-exact doubles */
	mesh_free(r);
	r = read_buf(raw, len, MESHIO_STL_ASCII);
	assert_same(m, r, false);
	mesh_free(r);
	free(raw);
	free(path);
	mesh_free(m);
}
END_TEST

START_TEST(write_replaces_and_keeps_mode)
{
	struct mesh *a = fx_box(0, 0, 0, 1, 1, 1), *b = fx_sphere(0, 0, 0, 5, 8, 12), *r;
	char *dir = scratch("replace"), path[600];

	ck_assert_int_eq(mkdir(dir, 0700), 0);
	snprintf(path, sizeof(path), "%s/part.stl", dir);
	umask(022);
	write_ok(path, a, MESHIO_STL_ASCII);
	{
		struct stat st;
		ck_assert_int_eq(stat(path, &st), 0);
		ck_assert_uint_eq(st.st_mode & 0777, 0644); /* not mkstemp's 0600 */
		ck_assert_int_eq(chmod(path, 0640), 0);
	}
	write_ok(path, b, MESHIO_STL_BINARY);
	{
		struct stat st;
		ck_assert_int_eq(stat(path, &st), 0);
		ck_assert_uint_eq(st.st_mode & 0777, 0640);
	}
	r = read_path(path, MESHIO_STL_BINARY);
	assert_same(b, r, true);
	ck_assert_int_eq(tu_dir_entries(dir), 1); /* no temporary left over */
	mesh_free(r);
	mesh_free(a);
	mesh_free(b);
	free(dir);
}
END_TEST

/* ---- accepted spellings ----------------------------------------------------- */

START_TEST(binary_with_solid_header)
{
	unsigned char buf[84 + 2 * 50];
	size_t len = binary_stl(buf, "solid part exported by SolidWorks", 2, two_tris, 2);
	char *path = scratch("solidworks.stl");
	struct mesh *m;

	tu_write(path, buf, len);
	m = read_path(path, MESHIO_STL_BINARY);
	ck_assert_uint_eq(m->ntris, 2);
	ck_assert_uint_eq(m->nverts, 4);
	ck_assert_uint_eq(m->tris[1][0], m->tris[0][1]); /* (1,0,0) welded */
	ck_assert(corner(m, 1, 1)[0] == 1.0 && corner(m, 1, 1)[1] == 1.0);
	mesh_free(m);
	m = read_buf(buf, len, MESHIO_STL_BINARY);
	ck_assert_uint_eq(m->ntris, 2);
	mesh_free(m);
	free(path);
}
END_TEST

START_TEST(binary_keeps_irregular_triangles)
{
	const float v[27] = {0, 0, 0, 1,     0, 0, 0, 1, 0,  /* regular */
			     1, 0, 0, 1,     0, 0, 0, 1, 0,  /* repeats a corner */
			     0, 0, 0, -0.0f, 0, 0, 0, 0, 1}; /* -0.0 welds with +0.0 */
	unsigned char buf[84 + 3 * 50];
	struct mesh *m;

	binary_stl(buf, "x", 3, v, 3);
	m = read_buf(buf, sizeof(buf), MESHIO_STL_BINARY);
	ck_assert_uint_eq(m->ntris, 3);
	ck_assert_uint_eq(m->tris[1][0], m->tris[1][1]);
	ck_assert_uint_eq(m->tris[2][0], m->tris[2][1]);
	ck_assert_uint_eq(m->nverts, 4);
	mesh_free(m);
}
END_TEST

START_TEST(ascii_spellings)
{
	/* BOM, CRLF, tabs, upper case, exponents, two solids, nameless endsolid. */
	const char *text = "\xef\xbb\xbfSOLID Part 1\r\n"
			   "  FACET NORMAL 0 0 1\r\n\tOUTER LOOP\r\n"
			   "\tVERTEX 1.5e+01 -0 +0.25\r\n\tvertex .5 5. 1E-2\r\n"
			   "\tVertex\t-2.5E+001  3  4\r\n\tENDLOOP\r\n  ENDFACET\r\n"
			   "ENDSOLID Part 1\r\n"
			   "solid\n" FACET("0 0 0", "1 0 0", "0 1 0") "endsolid\n\n";
	struct mesh *m = read_str(text, MESHIO_STL_ASCII);

	ck_assert_uint_eq(m->ntris, 2);
	ck_assert(corner(m, 0, 0)[0] == 15.0 && corner(m, 0, 0)[1] == 0.0 &&
		  corner(m, 0, 0)[2] == 0.25);
	ck_assert(corner(m, 0, 1)[0] == 0.5 && corner(m, 0, 1)[1] == 5.0 &&
		  corner(m, 0, 1)[2] == 0.01);
	ck_assert(corner(m, 0, 2)[0] == -25.0);
	ck_assert(corner(m, 1, 2)[1] == 1.0);
	mesh_free(m);
}
END_TEST

START_TEST(ascii_nonfinite_normal_is_ignored)
{
	/* Some exporters write NaN normals for slivers; normals are not used. */
	struct mesh *m = read_str("solid s\nfacet normal nan -nan inf\nouter loop\n"
				  "vertex 0 0 0\nvertex 1 0 0\nvertex 2 0 0\n"
				  "endloop\nendfacet\nendsolid s\n",
				  MESHIO_STL_ASCII);

	ck_assert_uint_eq(m->ntris, 1);
	mesh_free(m);
}
END_TEST

START_TEST(obj_polygons_and_indices)
{
	const char *text = "# exported\nmtllib scene.mtl\no thing\n"
			   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\n"
			   "vt 0 0\nvn 0 0 1\ng group\ns off\nusemtl steel\n"
			   "f 1/1/1 2/1/1 3/1/1 4/1/1\n" /* quad, a/b/c */
			   "v 0 0 1\n"
			   "f -5//1 -4//1 -1//1\n" /* relative, a//c */
			   "f 2/1 3/1 5/1\n"	   /* a/b */
			   "l 1 2\ncurv 0 1 1 2\n" /* ignored */
			   "f 1 2 3 4 5 # a pentagon\n"
			   "v 1 0 0\nf 1 6 5\n"; /* v 6 welds onto v 2 */
	static const uint32_t want[][3] = {{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {1, 2, 4},
					   {0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 1, 4}};
	struct mesh *m = read_str(text, MESHIO_OBJ);

	ck_assert_uint_eq(m->ntris, 8);
	ck_assert_uint_eq(m->nverts, 5);
	for (size_t i = 0; i < 8; i++)
		for (int k = 0; k < 3; k++)
			ck_assert_msg(m->tris[i][k] == want[i][k], "triangle %zu corner %d: %u", i,
				      k, m->tris[i][k]);
	ck_assert(corner(m, 2, 2)[2] == 1.0);
	mesh_free(m);
}
END_TEST

START_TEST(off_pentagon)
{
	const char *text = "OFF\n# a pentagon and a triangle\n\n6 2 0\n"
			   "0 0 0\n1 0 0\n1.5 1 0\n0.5 1.5 0\n-0.5 1 0\n"
			   "0 0 1 # apex\n"
			   "5 0 1 2 3 4 255 0 0\n" /* colour after the indices */
			   "3 0 1 5\n";
	static const uint32_t want[][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 1, 5}};
	struct mesh *m = read_str(text, MESHIO_OFF);

	ck_assert_uint_eq(m->ntris, 4);
	ck_assert_uint_eq(m->nverts, 6);
	for (size_t i = 0; i < 4; i++)
		for (int k = 0; k < 3; k++)
			ck_assert_uint_eq(m->tris[i][k], want[i][k]);
	ck_assert(corner(m, 0, 2)[0] == 1.5);
	mesh_free(m);
	/* COFF, counts on the header line, per-vertex colours. */
	m = read_str("COFF 3 1 0\n0 0 0 1 0 0 1\n1 0 0 1 0 0 1\n0 1 0 1 0 0 1\n3 2 1 0\n",
		     MESHIO_OFF);
	ck_assert_uint_eq(m->ntris, 1);
	ck_assert_uint_eq(m->tris[0][0], 2);
	mesh_free(m);
}
END_TEST

START_TEST(detection_and_explicit_formats)
{
	const char *obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
	char *path = scratch("really-obj.stl");
	struct st_error err = {0};
	struct mesh *m;
	enum meshio_format got;

	/* Content decides, not the extension. */
	tu_write_str(path, obj);
	m = read_path(path, MESHIO_OBJ);
	mesh_free(m);
	ck_assert_int_eq(meshio_read(path, MESHIO_OBJ, &m, &got, &err), 0);
	ck_assert_int_eq(got, MESHIO_OBJ);
	mesh_free(m);
	/* Forcing a format that does not fit is a parse error with a place. */
	ck_assert_int_eq(meshio_read(path, MESHIO_STL_BINARY, &m, NULL, &err), ST_ERR_PARSE);
	ck_assert_ptr_null(m);
	ck_assert_ptr_nonnull(strstr(err.msg, "byte"));
	ck_assert_int_eq(meshio_read(path, MESHIO_STL_ASCII, &m, NULL, &err), ST_ERR_PARSE);
	ck_assert_ptr_nonnull(strstr(err.msg, "line 1"));
	ck_assert_int_eq(meshio_read(path, MESHIO_OFF, &m, NULL, &err), ST_ERR_PARSE);
	ck_assert_ptr_nonnull(strstr(err.msg, "line 1"));
	/* An OBJ opening with a long comment block. */
	m = read_str("# one\n# two\n\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", MESHIO_OBJ);
	mesh_free(m);
	ck_assert_int_eq(meshio_read(path, (enum meshio_format)42, &m, NULL, &err), ST_ERR_ARG);
	ck_assert_int_eq(meshio_read_buffer(NULL, 5, "x", MESHIO_AUTO, &m, NULL, &err), ST_ERR_ARG);
	free(path);
}
END_TEST

START_TEST(format_names)
{
	ck_assert_str_eq(meshio_format_name(MESHIO_STL_BINARY), "binary STL");
	ck_assert_str_eq(meshio_format_name(MESHIO_STL_ASCII), "ASCII STL");
	ck_assert_str_eq(meshio_format_name(MESHIO_OBJ), "OBJ");
	ck_assert_str_eq(meshio_format_name(MESHIO_OFF), "OFF");
	ck_assert_str_eq(meshio_format_name((enum meshio_format)99), "unknown format");
}
END_TEST

/* ---- bad input: binary STL ------------------------------------------------ */

START_TEST(bad_empty_and_missing)
{
	char *missing = scratch("does-not-exist.stl");
	struct st_error err = {0};
	struct mesh *m;

	EXPECT_FAIL("empty.stl", "", 0, ST_ERR_PARSE, "empty file");
	EXPECT_FAIL_STR("blank.obj", "  \n\n\t\n", ST_ERR_PARSE, "no triangles");
	EXPECT_FAIL_STR("blank.txt", "  \n\n\t\n", ST_ERR_PARSE, "not a mesh file");
	ck_assert_int_eq(meshio_read(missing, MESHIO_AUTO, &m, NULL, &err), ST_ERR_IO);
	ck_assert_ptr_null(m);
	ck_assert_ptr_nonnull(strstr(err.msg, missing));
	ck_assert_ptr_nonnull(strstr(err.msg, "No such file"));
	/* A directory is not a mesh. */
	*strrchr(missing, '/') = '\0';
	ck_assert_int_eq(meshio_read(missing, MESHIO_AUTO, &m, NULL, &err), ST_ERR_IO);
	ck_assert_ptr_nonnull(strstr(err.msg, "directory"));
	free(missing);
}
END_TEST

START_TEST(bad_binary_counts)
{
	unsigned char buf[84 + 50 * 3];

	/* Header says 1000, two facets present. */
	binary_stl(buf, "generated", 1000, two_tris, 2);
	EXPECT_FAIL("truncated.stl", buf, 84 + 100, ST_ERR_PARSE, "byte 80", "1000 triangles",
		    "needs 50084 bytes", "has 184 bytes");
	/* About 4e9 triangles announced in a 200-byte file: nothing allocated. */
	binary_stl(buf, "generated", 0xfffffff0u, two_tris, 2);
	EXPECT_FAIL("absurd.stl", buf, 200, ST_ERR_PARSE, "byte 80", "4294967280 triangles",
		    "has 200 bytes");
	/* A valid size for zero facets is still an empty mesh. */
	binary_stl(buf, "generated", 0, two_tris, 0);
	EXPECT_FAIL("zero.stl", buf, 84, ST_ERR_PARSE, "byte 80", "no triangles");
	/* Shorter than the header. */
	EXPECT_FAIL("short.stl", buf, 50, ST_ERR_PARSE, "byte 50", "header");
	/* "solid" header but binary bytes and a wrong size: the size message. */
	binary_stl(buf, "solid exported", 3, two_tris, 2);
	EXPECT_FAIL("solid-truncated.stl", buf, 84 + 100, ST_ERR_PARSE, "byte 80", "3 triangles");
}
END_TEST

START_TEST(bad_binary_nonfinite)
{
	unsigned char buf[84 + 50 * 2];
	float v[18];

	memcpy(v, two_tris, sizeof(v));
	v[9] = NAN; /* facet 1, corner 0, x: byte 84 + 50 + 12 */
	binary_stl(buf, "generated", 2, v, 2);
	EXPECT_FAIL("nan.stl", buf, sizeof(buf), ST_ERR_PARSE, "byte 146:", "facet 1 ",
		    "non-finite");
	memcpy(v, two_tris, sizeof(v));
	v[8] = -INFINITY; /* facet 0, corner 2, z: byte 84 + 12 + 24 + 8 */
	binary_stl(buf, "generated", 2, v, 2);
	EXPECT_FAIL("inf.stl", buf, sizeof(buf), ST_ERR_PARSE, "byte 128:", "facet 0 ",
		    "non-finite");
}
END_TEST

/* ---- bad input: ASCII STL ---------------------------------------------------- */

START_TEST(bad_ascii_numbers)
{
	EXPECT_FAIL_STR("nan.stl", "solid x\n" FACET("0 0 0", "nan 0 0", "0 1 0") "endsolid x\n",
			ST_ERR_PARSE, "line 5:", "facet 0 ", "non-finite");
	EXPECT_FAIL_STR("inf.stl",
			"solid x\n" FACET("0 0 0", "1 0 0", "0 1 0")
			    FACET("0 0 0", "1 0 0", "0 -Infinity 0") "endsolid x\n",
			ST_ERR_PARSE, "line 13:", "facet 1 ", "non-finite");
	EXPECT_FAIL_STR("msvc.stl", "solid x\n" FACET("0 0 0", "1 0 0", "-1.#IND 1 0") "endsolid\n",
			ST_ERR_PARSE, "line 6:", "non-finite");
	EXPECT_FAIL_STR("overflow.stl",
			"solid x\n" FACET("0 0 0", "1 0 0", "0 1e999 0") "endsolid\n", ST_ERR_PARSE,
			"line 6:", "non-finite");
	EXPECT_FAIL_STR("garbage.stl", "solid x\n" FACET("1 2 abc", "1 0 0", "0 1 0") "endsolid\n",
			ST_ERR_PARSE, "line 4:", "'abc' is not a number");
	EXPECT_FAIL_STR("hex.stl", "solid x\n" FACET("0x1p3 0 0", "1 0 0", "0 1 0") "endsolid\n",
			ST_ERR_PARSE, "line 4:", "not a number");
	EXPECT_FAIL_STR("comma.stl", "solid x\n" FACET("0,5 0 0", "1 0 0", "0 1 0") "endsolid\n",
			ST_ERR_PARSE, "line 4:", "not a number");
	EXPECT_FAIL_STR("bigexp.stl",
			"solid x\n" FACET("1e123456 0 0", "1 0 0", "0 1 0") "endsolid\n",
			ST_ERR_PARSE, "line 4:", "not a number");
	EXPECT_FAIL_STR("short.stl", "solid x\n" FACET("1 2", "1 0 0", "0 1 0") "endsolid\n",
			ST_ERR_PARSE, "line 4:", "needs 3 numbers");
}
END_TEST

START_TEST(bad_ascii_structure)
{
	EXPECT_FAIL_STR("quad.stl",
			"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
			"vertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid x\n",
			ST_ERR_PARSE, "line 7:", "more than 3 vertices");
	EXPECT_FAIL_STR("two.stl",
			"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
			"endloop\nendfacet\nendsolid x\n",
			ST_ERR_PARSE, "line 6:", "has 2 vertices");
	EXPECT_FAIL_STR("cut.stl",
			"solid x\n" FACET("0 0 0", "1 0 0", "0 1 0") "facet normal 0 0 1\n"
								     "outer loop\nvertex 0 0 0\n",
			ST_ERR_PARSE, "line 11:", "truncated");
	EXPECT_FAIL_STR("noend.stl", "solid x\n" FACET("0 0 0", "1 0 0", "0 1 0"), ST_ERR_PARSE,
			"line 8:", "endsolid");
	EXPECT_FAIL_STR("typo.stl",
			"solid x\n" FACET("0 0 0", "1 0 0", "0 1 0") "facett\nendsolid\n",
			ST_ERR_PARSE, "line 9:", "'facett'");
	EXPECT_FAIL_STR("tail.stl",
			"solid x\n" FACET("0 0 0", "1 0 0", "0 1 0") "endsolid x\ntrailing junk\n",
			ST_ERR_PARSE, "line 10:", "'trailing'");
	EXPECT_FAIL_STR("nofacets.stl", "solid x\nendsolid x\n", ST_ERR_PARSE,
			"line 2:", "no triangles");
}
END_TEST

START_TEST(bad_text_lines)
{
	char *text = malloc(8000);
	char nul[200];
	size_t n;

	/* A 5000-byte line: rejected whole, never truncated. */
	n = (size_t)sprintf(text, "solid x\nfacet normal 0 0 1");
	memset(text + n, ' ', 5000);
	strcpy(text + n + 5000, "\nouter loop\n");
	EXPECT_FAIL_STR("long.stl", text, ST_ERR_PARSE, "line 2 ", "longer than 4096 bytes");
	/* The bound holds for comments too. */
	text[0] = '#';
	memset(text + 1, 'c', 6000);
	strcpy(text + 6001, "\nv 0 0 0\n");
	EXPECT_FAIL_STR("long.obj", text, ST_ERR_PARSE, "line 1 ", "longer than");
	/* A NUL byte after the first 84 bytes of an ASCII STL. */
	n = (size_t)sprintf(nul, "solid x\n" FACET("0 0 0", "1 0 0", "0 1 0"));
	memcpy(nul + n, "fac\0et\n", 7);
	EXPECT_FAIL("nul.stl", nul, n + 7, ST_ERR_PARSE, "line 9:", "NUL byte");
	free(text);
}
END_TEST

/* ---- bad input: OBJ and OFF ---------------------------------------------------- */

START_TEST(bad_obj)
{
	EXPECT_FAIL_STR("faces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", ST_ERR_PARSE,
			"line 4:", "vertex 9", "only 3");
	EXPECT_FAIL_STR("rel.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n", ST_ERR_PARSE,
			"line 4:", "vertex -4");
	EXPECT_FAIL_STR("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 0 1 2\n", ST_ERR_PARSE,
			"line 5:", "vertex 0");
	EXPECT_FAIL_STR("forward.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\nv 0 1 0\n", ST_ERR_PARSE,
			"line 3:", "vertex 3");
	EXPECT_FAIL_STR("corner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/x 2 3\n", ST_ERR_PARSE,
			"line 4:", "'1/x'");
	EXPECT_FAIL_STR("slashes.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", ST_ERR_PARSE,
			"line 4:", "not a face corner");
	EXPECT_FAIL_STR("edge.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", ST_ERR_PARSE,
			"line 3:", "at least 3");
	EXPECT_FAIL_STR("nan.obj", "v 0 0 0\nv nan 0 0\n", ST_ERR_PARSE, "line 2:", "non-finite");
	EXPECT_FAIL_STR("vbad.obj", "v 0 0 zero\n", ST_ERR_PARSE, "line 1:", "'zero'");
	EXPECT_FAIL_STR("vshort.obj", "v 0 0\n", ST_ERR_PARSE, "line 1:", "3 coordinates");
	EXPECT_FAIL_STR("points.obj", "# only points\nv 0 0 0\nv 1 0 0\np 1 2\n", ST_ERR_PARSE,
			"line 4:", "no triangles");
}
END_TEST

START_TEST(bad_off)
{
	EXPECT_FAIL_STR("counts.off", "OFF\n2000000000 1 0\n0 0 0\n", ST_ERR_PARSE,
			"line 2:", "2000000000 vertices", "has 25 bytes");
	EXPECT_FAIL_STR("faces.off", "OFF\n3 4000000000 0\n", ST_ERR_PARSE,
			"line 2:", "4000000000 faces");
	EXPECT_FAIL_STR("negative.off", "OFF\n-3 1 0\n", ST_ERR_PARSE, "line 2:", "OFF counts");
	EXPECT_FAIL_STR("nocounts.off", "OFF\n", ST_ERR_PARSE, "line 1:", "counts");
	EXPECT_FAIL_STR("novertex.off",
			"OFF\n# padding padding padding padding padding\n3 1 0\n0 0 0\n1 0 0\n",
			ST_ERR_PARSE, "line 5:", "2 of 3 vertices", "truncated");
	EXPECT_FAIL_STR("noface.off",
			"OFF\n# padding padding padding padding padding\n3 2 0\n0 0 0\n1 0 0\n"
			"0 1 0\n3 0 1 2\n",
			ST_ERR_PARSE, "line 7:", "1 of 2 faces");
	EXPECT_FAIL_STR("index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", ST_ERR_PARSE,
			"line 6:", "vertex 7", "has 3 vertices");
	EXPECT_FAIL_STR("short.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", ST_ERR_PARSE,
			"line 6:", "announces 4 vertices but lists 3");
	EXPECT_FAIL_STR("line.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", ST_ERR_PARSE,
			"line 6:", "at least 3");
	EXPECT_FAIL_STR("nan.off", "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", ST_ERR_PARSE,
			"line 4:", "non-finite");
	EXPECT_FAIL_STR("empty.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", ST_ERR_PARSE,
			"line 2:", "no triangles");
	EXPECT_FAIL_STR("header.off", "hello\n3 1 0\n", ST_ERR_PARSE, "line 1:", "'OFF'");
}
END_TEST

START_TEST(bad_not_a_mesh)
{
	const unsigned char png[] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 0, 0, 0, 13,
				     'I',  'H', 'D', 'R', 0,	0,    0,    1,	  0, 0, 0, 1};
	unsigned char junk[300];

	EXPECT_FAIL("picture.png", png, sizeof(png), ST_ERR_PARSE, "not a mesh file");
	EXPECT_FAIL("picture.stl", png, sizeof(png), ST_ERR_PARSE, "not a mesh file");
	EXPECT_FAIL_STR("notes.txt", "Shopping list:\n- filament\n", ST_ERR_PARSE,
			"not a mesh file");
	EXPECT_FAIL_STR("data.json", "{\"solid\": true}\n", ST_ERR_PARSE, "not a mesh file");
	for (size_t i = 0; i < sizeof(junk); i++)
		junk[i] = (unsigned char)(i * 7 + 1);
	EXPECT_FAIL("junk.bin", junk, sizeof(junk), ST_ERR_PARSE, "not a mesh file");
	/* The same bytes named .stl: reported as a binary STL of the wrong size. */
	EXPECT_FAIL("junk.stl", junk, sizeof(junk), ST_ERR_PARSE, "byte 80", "has 300 bytes");
}
END_TEST

/* ---- writer failures ---------------------------------------------------------- */

START_TEST(write_into_missing_directory)
{
	struct mesh *m = fx_box(0, 0, 0, 1, 1, 1);
	char *dir = scratch("nowhere"), path[600];
	struct st_error err = {0};

	snprintf(path, sizeof(path), "%s/sub/out.stl", dir);
	ck_assert_int_eq(meshio_write_stl(path, m, MESHIO_STL_BINARY, &err), ST_ERR_IO);
	ck_assert_ptr_nonnull(strstr(err.msg, path));
	ck_assert(!tu_file_exists(path));
	ck_assert(!tu_file_exists(dir));
	mesh_free(m);
	free(dir);
}
END_TEST

/* A write that fails half-way (file size limit) leaves the old file as it was. */
START_TEST(write_failure_keeps_old_file)
{
	struct mesh *m = fx_torus(10.0, 3.0, 60, 30);
	char *dir = scratch("full"), path[600];
	struct st_error err = {0};
	struct rlimit lim, old;
	const char *before = "the old file\n";
	size_t len;
	char *after;

	ck_assert_int_eq(mkdir(dir, 0700), 0);
	snprintf(path, sizeof(path), "%s/part.stl", dir);
	tu_write_str(path, before);
	/* Root ignores permissions but not RLIMIT_FSIZE: writes past 4 KiB fail. */
	signal(SIGXFSZ, SIG_IGN);
	ck_assert_int_eq(getrlimit(RLIMIT_FSIZE, &old), 0);
	lim = old;
	lim.rlim_cur = 4096;
	ck_assert_int_eq(setrlimit(RLIMIT_FSIZE, &lim), 0);
	ck_assert_int_eq(meshio_write_stl(path, m, MESHIO_STL_BINARY, &err), ST_ERR_IO);
	ck_assert_ptr_nonnull(strstr(err.msg, path));
	ck_assert_ptr_nonnull(strstr(err.msg, "cannot write"));
	ck_assert_int_eq(meshio_write_stl(path, m, MESHIO_STL_ASCII, &err), ST_ERR_IO);
	ck_assert_int_eq(setrlimit(RLIMIT_FSIZE, &old), 0);
	after = tu_slurp(path, &len);
	ck_assert_str_eq(after, before);
	ck_assert_int_eq(tu_dir_entries(dir), 1); /* the temporary files are gone */
	free(after);
	/* A directory in the way: rename fails, nothing else changes. */
	snprintf(path, sizeof(path), "%s/adir", dir);
	ck_assert_int_eq(mkdir(path, 0700), 0);
	ck_assert_int_eq(meshio_write_stl(path, m, MESHIO_STL_BINARY, &err), ST_ERR_IO);
	ck_assert_int_eq(tu_dir_entries(dir), 2);
	ck_assert_int_eq(tu_dir_entries(path), 0);
	mesh_free(m);
	free(dir);
}
END_TEST

START_TEST(write_refuses_bad_meshes)
{
	double verts[3][3] = {{0, 0, 0}, {1e300, 0, 0}, {0, 1, 0}};
	uint32_t tris[1][3] = {{0, 1, 2}};
	struct mesh m = {.verts = verts, .tris = tris, .nverts = 3, .ntris = 1};
	char *path = scratch("refused.stl");
	struct st_error err = {0};
	struct mesh *r;

	ck_assert_int_eq(meshio_write_stl(path, NULL, MESHIO_STL_BINARY, &err), ST_ERR_ARG);
	ck_assert_int_eq(meshio_write_stl(NULL, &m, MESHIO_STL_BINARY, &err), ST_ERR_ARG);
	ck_assert_int_eq(meshio_write_stl(path, &m, MESHIO_OBJ, &err), ST_ERR_ARG);
	/* Beyond float32: not as binary, fine (and exact) as ASCII. */
	ck_assert_int_eq(meshio_write_stl(path, &m, MESHIO_STL_BINARY, &err), ST_ERR_RANGE);
	ck_assert_ptr_nonnull(strstr(err.msg, "float32"));
	ck_assert(!tu_file_exists(path));
	write_ok(path, &m, MESHIO_STL_ASCII);
	r = read_path(path, MESHIO_STL_ASCII);
	ck_assert(corner(r, 0, 1)[0] == 1e300);
	mesh_free(r);
	verts[2][1] = NAN;
	ck_assert_int_eq(meshio_write_stl(path, &m, MESHIO_STL_ASCII, &err), ST_ERR_RANGE);
	verts[2][1] = 1;
	tris[0][2] = 3;
	ck_assert_int_eq(meshio_write_stl(path, &m, MESHIO_STL_ASCII, &err), ST_ERR_ARG);
	m.ntris = 0;
	ck_assert_int_eq(meshio_write_stl(path, &m, MESHIO_STL_ASCII, &err), ST_ERR_ARG);
	/* More facets than a binary STL can count (the tables are never read). */
	if (SIZE_MAX > UINT32_MAX) {
		struct mesh huge = {.nverts = 3, .ntris = (size_t)UINT32_MAX + 1};
		ck_assert_int_eq(meshio_write_stl(path, &huge, MESHIO_STL_BINARY, &err),
				 ST_ERR_RANGE);
	}
	free(path);
}
END_TEST

/* ---- robustness ------------------------------------------------------------- */

/* Tiny deterministic PRNG (xorshift32) so failures reproduce. */
static uint32_t next_rand(uint32_t *s)
{
	*s ^= *s << 13;
	*s ^= *s >> 17;
	*s ^= *s << 5;
	return *s;
}

/*
 * Mutated valid files of every format: each read must succeed with a sane
 * mesh or fail with a parse error and no output, never crash (run this
 * suite under `make test-asan`).
 */
START_TEST(mutations_never_crash)
{
	struct mesh *m = fx_sphere(0, 0, 0, 3, 4, 6);
	char *bpath = scratch("fz.stl"), *apath = scratch("fz-ascii.stl");
	size_t lens[4];
	unsigned char *bases[4];
	const char *obj = "# x\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0.5e1\nvt 0 0\n"
			  "f 1/1 2/1 3/1 4/1\nf -1 -2 -3\n";
	const char *off = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 5\n4 0 1 2 3 1 1 1\n3 3 2 1\n";
	uint32_t seed = 12345;

	write_ok(bpath, m, MESHIO_STL_BINARY);
	write_ok(apath, m, MESHIO_STL_ASCII);
	bases[0] = tu_slurp(bpath, &lens[0]);
	bases[1] = tu_slurp(apath, &lens[1]);
	bases[2] = (unsigned char *)strdup(obj);
	lens[2] = strlen(obj);
	bases[3] = (unsigned char *)strdup(off);
	lens[3] = strlen(off);
	for (int round = 0; round < 4000; round++) {
		int which = round % 4;
		size_t len = lens[which];
		unsigned char *buf = malloc(len);
		struct st_error err = {0};
		struct mesh *r = NULL;
		int flips = 1 + (int)(next_rand(&seed) % 4), rc;

		memcpy(buf, bases[which], len);
		for (int f = 0; f < flips; f++) {
			size_t at = next_rand(&seed) % len;
			static const char pool[] = "0123456789-+.eE \n/#nNaAfF\0\xff";
			buf[at] = next_rand(&seed) & 1
				      ? (unsigned char)next_rand(&seed)
				      : (unsigned char)pool[next_rand(&seed) % (sizeof(pool) - 1)];
		}
		if (next_rand(&seed) % 8 == 0)
			len = next_rand(&seed) % len;
		rc = meshio_read_buffer(buf, len, "fz", MESHIO_AUTO, &r, NULL, &err);
		if (rc == 0) {
			ck_assert_ptr_nonnull(r);
			ck_assert_uint_gt(r->ntris, 0);
			for (size_t i = 0; i < r->ntris; i++)
				for (int k = 0; k < 3; k++) {
					ck_assert_uint_lt(r->tris[i][k], r->nverts);
					for (int c = 0; c < 3; c++)
						ck_assert(isfinite(corner(r, i, k)[c]));
				}
			mesh_free(r);
		} else {
			ck_assert_msg(rc == ST_ERR_PARSE, "round %d: %d %s", round, rc, err.msg);
			ck_assert_ptr_null(r);
			ck_assert_msg(!strncmp(err.msg, "fz: ", 4), "%s", err.msg);
		}
		free(buf);
	}
	for (int i = 0; i < 4; i++)
		free(bases[i]);
	free(bpath);
	free(apath);
	mesh_free(m);
}
END_TEST

/* Whether a and b are the same mesh, index for index. */
static void assert_same_indexing(const struct mesh *a, const struct mesh *b)
{
	ck_assert_uint_eq(a->nverts, b->nverts);
	ck_assert_uint_eq(a->ntris, b->ntris);
	ck_assert_int_eq(memcmp(a->verts, b->verts, a->nverts * sizeof(*a->verts)), 0);
	ck_assert_int_eq(memcmp(a->tris, b->tris, a->ntris * sizeof(*a->tris)), 0);
}

/* The mesh mesh_builder_vertex makes from a binary STL's bytes, corner by
 * corner in file order: what the reader must make though it reads ahead. */
static struct mesh *weld_in_file_order(const unsigned char *data, size_t ntris)
{
	struct mesh_builder *b = mesh_builder_new(ntris);

	ck_assert_ptr_nonnull(b);
	for (size_t t = 0; t < ntris; t++) {
		uint32_t w[3];
		for (int k = 0; k < 3; k++) {
			double p[3];
			for (int c = 0; c < 3; c++) {
				float f;
				memcpy(&f, data + 84 + 50 * t + 12 + 12 * k + 4 * c, 4);
				p[c] = f;
			}
			ck_assert_int_eq(mesh_builder_vertex(b, p, &w[k], NULL), 0);
		}
		ck_assert_int_eq(mesh_builder_triangle(b, w[0], w[1], w[2], NULL), 0);
	}
	return mesh_builder_finish(b);
}

/*
 * Large binary files are decoded in two halves on two threads and welded
 * in parts on several (mesh_weld_corners); the result must be the very
 * mesh one sequential pass makes (the buffer reader is one pass), index
 * for index, and errors must still name the first bad byte.  The one-pass
 * reader reads facets a few ahead of welding them (mesh_builder_prefetch),
 * and must still weld in file order.
 */
START_TEST(binary_split_read_matches_one_pass)
{
	struct mesh *torus = fx_torus(30, 10, 400, 150); /* 120000 triangles */
	char *path = scratch("split.stl");
	struct st_error err = {0};
	struct mesh *a, *b = NULL;
	unsigned char *data;
	size_t len;
	const float nan_value = NAN;

	write_ok(path, torus, MESHIO_STL_BINARY);
	a = read_path(path, MESHIO_STL_BINARY);
	data = tu_slurp(path, &len);
	b = read_buf(data, len, MESHIO_STL_BINARY);
	assert_same_indexing(a, b);
	mesh_free(b);
	b = weld_in_file_order(data, torus->ntris);
	assert_same_indexing(a, b);
	mesh_free(a);
	mesh_free(b);

	/* A NaN in the second half only: its facet and byte are named. */
	memcpy(data + 84 + 50 * 100000 + 12, &nan_value, 4);
	tu_write(path, data, len);
	ck_assert_int_eq(meshio_read(path, MESHIO_AUTO, &a, NULL, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "byte 5000096: facet 100000 ") != NULL, "%s", err.msg);
	/* And one in each half: the earlier one is reported. */
	memcpy(data + 84 + 50 * 7 + 16, &nan_value, 4);
	tu_write(path, data, len);
	ck_assert_int_eq(meshio_read(path, MESHIO_AUTO, &a, NULL, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "byte 450: facet 7 ") != NULL, "%s", err.msg);
	free(data);
	free(path);
	mesh_free(torus);
}
END_TEST

Suite *meshio_suite(void)
{
	Suite *s = suite_create("meshio");
	TCase *io = tcase_create("round_trip");
	TCase *in = tcase_create("accepted");
	TCase *bad = tcase_create("bad_input");
	TCase *wr = tcase_create("writer");
	TCase *fz = tcase_create("robustness");

	/* The round trips write and read files of 100k facets and more (the
	 * parallel reader starts there): several seconds under ASan on a
	 * loaded machine, over Check's default 4 s. */
	tcase_set_timeout(io, 60);
	tcase_add_test(io, binary_round_trip);
	tcase_add_test(io, binary_layout);
	tcase_add_test(io, ascii_round_trip_exact);
	tcase_add_test(io, write_replaces_and_keeps_mode);
	tcase_add_test(io, binary_split_read_matches_one_pass);
	suite_add_tcase(s, io);

	tcase_add_test(in, binary_with_solid_header);
	tcase_add_test(in, binary_keeps_irregular_triangles);
	tcase_add_test(in, ascii_spellings);
	tcase_add_test(in, ascii_nonfinite_normal_is_ignored);
	tcase_add_test(in, obj_polygons_and_indices);
	tcase_add_test(in, off_pentagon);
	tcase_add_test(in, detection_and_explicit_formats);
	tcase_add_test(in, format_names);
	suite_add_tcase(s, in);

	tcase_add_test(bad, bad_empty_and_missing);
	tcase_add_test(bad, bad_binary_counts);
	tcase_add_test(bad, bad_binary_nonfinite);
	tcase_add_test(bad, bad_ascii_numbers);
	tcase_add_test(bad, bad_ascii_structure);
	tcase_add_test(bad, bad_text_lines);
	tcase_add_test(bad, bad_obj);
	tcase_add_test(bad, bad_off);
	tcase_add_test(bad, bad_not_a_mesh);
	suite_add_tcase(s, bad);

	tcase_add_test(wr, write_into_missing_directory);
	tcase_add_test(wr, write_failure_keeps_old_file);
	tcase_add_test(wr, write_refuses_bad_meshes);
	suite_add_tcase(s, wr);

	tcase_set_timeout(fz, 120);
	tcase_add_test(fz, mutations_never_crash);
	suite_add_tcase(s, fz);
	meshio_3mf_tcases(s);
	return s;
}

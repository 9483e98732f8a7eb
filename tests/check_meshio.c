/*
 * check_meshio.c - STL/OBJ/OFF reading and STL writing (3MF: check_meshio_3mf.c): round trips of
 * generated meshes and every accepted spelling we promise.  Bad input,
 * writer failures and robustness are in check_meshio_bad.c, the shared
 * readers and binary STL builder in meshiotest.c.  All inputs are
 * generated here; no binary fixture files.
 */
#include <check.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fixtures.h"
#include "meshio.h"
#include "meshiotest.h"
#include "suites.h"
#include "testutil.h"

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

	meshio_bad_tcases(s);
	meshio_3mf_tcases(s);
	return s;
}

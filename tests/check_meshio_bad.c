/*
 * check_meshio_bad.c - STL/OBJ/OFF input and STL output, part of the meshio
 * suite (check_meshio.c): for every kind of bad input the error class and a
 * message naming the file and the byte or line (each read twice, from a
 * file and from memory, with the same message: one parser behind both),
 * the writer's failures, and random mutations that must never crash.
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
#include "meshiotest.h"
#include "suites.h"
#include "testutil.h"

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

void meshio_bad_tcases(Suite *s)
{
	TCase *bad = tcase_create("bad_input");
	TCase *wr = tcase_create("writer");
	TCase *fz = tcase_create("robustness");

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
}

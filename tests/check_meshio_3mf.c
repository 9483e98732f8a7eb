/*
 * check_meshio_3mf.c - the 3MF reader, as test cases of the meshio suite:
 * PrusaSlicer's own 3MF (committed, and made afresh when prusa-slicer is
 * installed) reads to the triangles of its STL; hand-built 3MFs (libzip,
 * tests/testutil.c) for transforms, mirrors, components, units, several
 * items, parts named by p:path and the PrusaSlicer config; and every kind of
 * broken file with its class and a message naming the entry and the line,
 * read from a file and from memory alike.
 */
#include <check.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fixtures.h"
#include "meshio.h"
#include "suites.h"
#include "testutil.h"

#define CORE_NS "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"
#define PROD_NS "http://schemas.microsoft.com/3dmanufacturing/production/2015/06"
#define HEAD "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
/* A model element opening with the given attributes (unit, namespaces). */
#define MODEL(attrs) HEAD "<model " attrs " xmlns=\"" CORE_NS "\">\n"
/* One unit right tetrahedron at the origin, outward winding, as object ID. */
#define TETRA(id)                                                                           \
	"<object id=\"" id "\" type=\"model\"><mesh><vertices>\n"                           \
	"<vertex x=\"0\" y=\"0\" z=\"0\"/><vertex x=\"1\" y=\"0\" z=\"0\"/>\n"              \
	"<vertex x=\"0\" y=\"1\" z=\"0\"/><vertex x=\"0\" y=\"0\" z=\"1\"/>\n"              \
	"</vertices><triangles>\n"                                                          \
	"<triangle v1=\"0\" v2=\"2\" v3=\"1\"/><triangle v1=\"0\" v2=\"1\" v3=\"3\"/>\n"    \
	"<triangle v1=\"0\" v2=\"3\" v3=\"2\"/><triangle v1=\"1\" v2=\"2\" v3=\"3\"/>\n"    \
	"</triangles></mesh></object>\n"

/* A private copy of a scratch path (tu_path's buffers rotate). */
static char *scratch(const char *name)
{
	char *p = strdup(tu_path(name));

	ck_assert_ptr_nonnull(p);
	return p;
}

/* Read path as 3MF (detected), from the file and from memory: same mesh. */
static struct mesh *read_3mf(const char *path, struct meshio_info *info)
{
	struct st_error err = {0};
	struct meshio_info i2;
	struct mesh *m = NULL, *m2 = NULL;
	size_t len;
	void *buf = tu_slurp(path, &len);

	ck_assert_msg(meshio_read_info(path, MESHIO_AUTO, &m, info, &err) == 0, "%s", err.msg);
	ck_assert_int_eq(info->format, MESHIO_3MF);
	ck_assert_msg(meshio_read_buffer_info(buf, len, path, MESHIO_AUTO, &m2, &i2, &err) == 0,
		      "%s", err.msg);
	ck_assert_uint_eq(m->ntris, m2->ntris);
	ck_assert_uint_eq(m->nverts, m2->nverts);
	ck_assert(!memcmp(m->tris, m2->tris, m->ntris * sizeof(*m->tris)));
	ck_assert(!memcmp(m->verts, m2->verts, m->nverts * sizeof(*m->verts)));
	ck_assert_uint_eq(info->items, i2.items);
	mesh_free(m2);
	free(buf);
	return m;
}

/* Corner k of triangle t of m. */
static const double *corner(const struct mesh *m, size_t t, int k)
{
	return m->verts[m->tris[t][k]];
}

/*
 * a (a 3MF read) has b's triangles (b read from binary STL), in order, each
 * corner moved by exactly off (PrusaSlicer puts the model on the bed with
 * the item's transform; its 9 digits read back to the STL's float32, and a
 * float plus a whole lift is exact in double).
 */
static void same_triangles_moved(const struct mesh *a, const struct mesh *b, const double off[3])
{
	ck_assert_uint_eq(a->ntris, b->ntris);
	for (size_t t = 0; t < a->ntris; t++)
		for (int k = 0; k < 3; k++)
			for (int j = 0; j < 3; j++) {
				double got = corner(a, t, k)[j], want = corner(b, t, k)[j] + off[j];

				ck_assert_msg(got == want,
					      "triangle %zu corner %d axis %d: %.17g vs %.17g", t, k,
					      j, got, want);
			}
}

/* The offset between two meshes' lowest corners. */
static void bbox_offset(const struct mesh *a, const struct mesh *b, double off[3])
{
	double amin[3], amax[3], bmin[3], bmax[3];

	mesh_bbox(a, amin, amax);
	mesh_bbox(b, bmin, bmax);
	for (int j = 0; j < 3; j++)
		off[j] = amin[j] - bmin[j];
}

/* ---- PrusaSlicer's 3MF ------------------------------------------------- */

START_TEST(prusaslicer_3mf_reads_as_its_stl)
{
	/* tests/data/prusaslicer-torus-24x12.3mf: `gen_mesh torus 24 12 t.stl`, then
	 * `prusa-slicer --export-3mf t.stl` (2.5.0), which lifts it by 20 mm. */
	struct mesh *t = fx_torus(60.0, 20.0, 24, 12);
	struct mesh *stl = tu_round_trip(t, "torus24.stl", MESHIO_STL_BINARY);
	struct meshio_info info;
	struct mesh *m = read_3mf("tests/data/prusaslicer-torus-24x12.3mf", &info);
	const double lift[3] = {0, 0, 20};

	same_triangles_moved(m, stl, lift);
	ck_assert_uint_eq(m->nverts, stl->nverts);
	ck_assert_uint_eq(info.items, 1);
	ck_assert_uint_eq(info.meshes, 1);
	ck_assert_uint_eq(info.objects, 1);
	mesh_free(m);
	mesh_free(stl);
	mesh_free(t);
}
END_TEST

/* prusa-slicer ARGS on in; false (test skipped) when it is not installed. */
static bool prusa_export(const char *args, const char *in, const char *out3mf)
{
	char cmd[2048];

	if (system("command -v prusa-slicer >/dev/null 2>&1") != 0) {
		fprintf(stderr, "meshio: prusa-slicer not installed, live 3MF export skipped\n");
		return false;
	}
	snprintf(cmd, sizeof(cmd), "timeout 120 prusa-slicer --export-3mf %s -o '%s' '%s' "
		 ">/dev/null 2>&1", args, out3mf, in);
	ck_assert_msg(system(cmd) == 0, "%s failed", cmd);
	return true;
}

START_TEST(prusaslicer_live_export_and_duplicates)
{
	struct mesh *t = fx_torus(60.0, 20.0, 64, 32);
	char *in = scratch("live.stl"), *one = scratch("live.3mf"), *three = scratch("live3.3mf");
	struct mesh *stl = tu_round_trip(t, "live.stl", MESHIO_STL_BINARY), *m;
	struct meshio_info info;
	double off[3];

	if (prusa_export("", in, one)) {
		m = read_3mf(one, &info);
		bbox_offset(m, stl, off);
		same_triangles_moved(m, stl, off);
		mesh_free(m);
		/* Three instances of a box (three tori do not fit the default bed):
		 * one object, two more made of it as components. */
		struct mesh *box = fx_box(0, 0, 0, 20, 10, 5);

		mesh_free(tu_round_trip(box, "live.stl", MESHIO_STL_BINARY));
		ck_assert(prusa_export("--duplicate 3", in, three));
		m = read_3mf(three, &info);
		ck_assert_uint_eq(info.items, 3);
		ck_assert_uint_eq(info.meshes, 3);
		ck_assert_uint_eq(m->ntris, 3 * box->ntris);
		mesh_free(m);
		mesh_free(box);
	}
	mesh_free(stl);
	mesh_free(t);
	free(in);
	free(one);
	free(three);
}
END_TEST

/* ---- hand-built files -------------------------------------------------- */

/* A 3MF of model_xml as scratch file name, read; the caller frees. */
static struct mesh *read_model(const char *name, const char *model_xml, struct meshio_info *info)
{
	char *path = scratch(name);
	struct mesh *m;

	tu_write_3mf(path, model_xml);
	m = read_3mf(path, info);
	free(path);
	return m;
}

/* Is p one of m's vertices? */
static bool has_vertex(const struct mesh *m, double x, double y, double z)
{
	for (size_t i = 0; i < m->nverts; i++)
		if (m->verts[i][0] == x && m->verts[i][1] == y && m->verts[i][2] == z)
			return true;
	return false;
}

/* Signed volume, mm^3: positive for outward winding. */
static double volume(const struct mesh *m)
{
	double v = 0;

	for (size_t t = 0; t < m->ntris; t++) {
		const double *a = corner(m, t, 0), *b = corner(m, t, 1), *c = corner(m, t, 2);

		v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
		      a[2] * (b[0] * c[1] - b[1] * c[0])) /
		     6.0;
	}
	return v;
}

START_TEST(item_transform_rotates_and_moves)
{
	struct meshio_info info;
	/* Rows m00 m01 m02 / m10 .. / m20 .. / translation: x -> y, y -> -x. */
	struct mesh *m = read_model("rot.3mf",
				    MODEL("unit=\"millimeter\"") "<resources>" TETRA("1")
				    "</resources><build><item objectid=\"1\" transform=\"0 1 0 -1 0 0 "
				    "0 0 1 10 20 30\"/></build></model>",
				    &info);

	ck_assert_uint_eq(m->ntris, 4);
	ck_assert(has_vertex(m, 10, 20, 30));
	ck_assert(has_vertex(m, 10, 21, 30)); /* (1,0,0) */
	ck_assert(has_vertex(m, 9, 20, 30));  /* (0,1,0) */
	ck_assert(has_vertex(m, 10, 20, 31)); /* (0,0,1) */
	ck_assert_double_eq_tol(volume(m), 1.0 / 6.0, 1e-12);
	ck_assert_uint_eq(info.items, 1);
	mesh_free(m);
}
END_TEST

START_TEST(mirror_keeps_outward_winding)
{
	struct meshio_info info;
	struct mesh *m = read_model("mirror.3mf",
				    MODEL("") "<resources>" TETRA("1") "</resources><build><item "
				    "objectid=\"1\" transform=\"-1 0 0 0 1 0 0 0 1 0 0 0\"/></build></model>",
				    &info);

	ck_assert(has_vertex(m, -1, 0, 0));
	ck_assert_double_eq_tol(volume(m), 1.0 / 6.0, 1e-12);
	mesh_free(m);
}
END_TEST

START_TEST(components_compose_transforms)
{
	struct meshio_info info;
	/* Object 2: the tetrahedron scaled 2x, and once more moved by 5 in x;
	 * the item moves the whole by 100 in y. */
	struct mesh *m = read_model(
	    "comp.3mf",
	    MODEL("") "<resources>" TETRA("1") "<object id=\"2\"><components>"
	    "<component objectid=\"1\" transform=\"2 0 0 0 2 0 0 0 2 0 0 0\"/>"
	    "<component objectid=\"1\" transform=\"1 0 0 0 1 0 0 0 1 5 0 0\"/>"
	    "</components></object></resources>"
	    "<build><item objectid=\"2\" transform=\"1 0 0 0 1 0 0 0 1 0 100 0\"/></build></model>",
	    &info);

	ck_assert_uint_eq(m->ntris, 8);
	ck_assert(has_vertex(m, 2, 100, 0));
	ck_assert(has_vertex(m, 0, 100, 2));
	ck_assert(has_vertex(m, 6, 100, 0));
	ck_assert(has_vertex(m, 5, 101, 0));
	ck_assert_double_eq_tol(volume(m), 8.0 / 6.0 + 1.0 / 6.0, 1e-12);
	ck_assert_uint_eq(info.items, 1);
	ck_assert_uint_eq(info.meshes, 2);
	ck_assert_uint_eq(info.objects, 2);
	mesh_free(m);
}
END_TEST

START_TEST(units_convert_to_mm)
{
	static const struct {
		const char *unit;
		double mm;
	} u[] = {{"micron", 0.001}, {"millimeter", 1},	{"centimeter", 10},
		 {"inch", 25.4},    {"foot", 304.8},	{"meter", 1000}};

	for (size_t i = 0; i < sizeof(u) / sizeof(u[0]); i++) {
		char xml[2048];
		struct meshio_info info;
		struct mesh *m;

		snprintf(xml, sizeof(xml),
			 MODEL("unit=\"%s\"") "<resources>" TETRA("1") "</resources><build><item "
			 "objectid=\"1\" transform=\"1 0 0 0 1 0 0 0 1 2 0 0\"/></build></model>",
			 u[i].unit);
		m = read_model("unit.3mf", xml, &info);
		/* The translation is in the model's unit too. */
		ck_assert_msg(has_vertex(m, 3 * u[i].mm, 0, 0), "unit %s", u[i].unit);
		ck_assert_msg(has_vertex(m, 2 * u[i].mm, 0, u[i].mm), "unit %s", u[i].unit);
		mesh_free(m);
	}
}
END_TEST

START_TEST(several_items_are_separate_parts)
{
	struct meshio_info info;
	struct mesh *m = read_model(
	    "items.3mf",
	    MODEL("") "<resources>" TETRA("1") TETRA("7") "</resources><build>"
	    "<item objectid=\"1\"/>"
	    "<item objectid=\"7\" transform=\"1 0 0 0 1 0 0 0 1 10 0 0\"/>"
	    "<item objectid=\"1\" transform=\"1 0 0 0 1 0 0 0 1 20 0 0\"/>"
	    "<item objectid=\"1\" transform=\"1 0 0 0 1 0 0 0 1 30 0 0\" printable=\"0\"/>"
	    "</build></model>",
	    &info);
	struct mesh_report rep;
	struct st_error err = {0};

	ck_assert_uint_eq(m->ntris, 12);
	ck_assert_uint_eq(info.items, 3);
	ck_assert_uint_eq(info.skipped_items, 1);
	ck_assert_uint_eq(info.meshes, 3);
	ck_assert_uint_eq(info.objects, 2);
	ck_assert(!has_vertex(m, 30, 0, 0));
	ck_assert_msg(mesh_analyze(m, 1, &rep, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(rep.parts, 3);
	ck_assert(rep.printable);
	mesh_free(m);
}
END_TEST

START_TEST(production_path_parts)
{
	/* Bambu Studio's layout: the root only places components that live in
	 * another model part, named by p:path. */
	const char *names[] = {"_rels/.rels", "3D/3dmodel.model", "3D/Objects/object_1.model"};
	const char *texts[] = {
	    tu_3mf_rels,
	    MODEL("xmlns:p=\"" PROD_NS "\" requiredextensions=\"p\"")
	    "<resources><object id=\"5\"><components><component p:path=\"/3D/Objects/object_1.model\" "
	    "objectid=\"1\" transform=\"1 0 0 0 1 0 0 0 1 0 0 4\"/></components></object>"
	    "</resources><build><item objectid=\"5\"/></build></model>",
	    MODEL("") "<resources>" TETRA("1") "</resources><build/></model>"};
	char *path = scratch("bambu.3mf");
	struct meshio_info info;
	struct mesh *m;

	tu_write_zip(path, names, texts, 3);
	m = read_3mf(path, &info);
	ck_assert_uint_eq(m->ntris, 4);
	ck_assert(has_vertex(m, 0, 0, 5));
	ck_assert_uint_eq(info.objects, 2);
	mesh_free(m);
	free(path);
}
END_TEST

START_TEST(without_rels_and_extension_detects)
{
	/* No _rels/.rels: the usual model part is taken; detection is by content. */
	const char *names[] = {"3D/3dmodel.model"};
	const char *texts[] = {MODEL("") "<resources>" TETRA("1") "</resources><build><item "
			       "objectid=\"1\"/></build></model>"};
	char *path = scratch("model.bin");
	struct meshio_info info;
	struct mesh *m;

	tu_write_zip(path, names, texts, 1);
	m = read_3mf(path, &info);
	ck_assert_uint_eq(m->ntris, 4);
	ck_assert_str_eq(meshio_format_name(info.format), "3MF");
	mesh_free(m);
	free(path);
}
END_TEST

START_TEST(prusaslicer_config_text)
{
	static const char cfg[] = "; generated by PrusaSlicer 2.5.0\nlayer_height = 0.15\n";
	const char *names[] = {"_rels/.rels", "3D/3dmodel.model", "Metadata/Slic3r_PE.config"};
	const char *texts[] = {tu_3mf_rels,
			       MODEL("") "<resources>" TETRA("1") "</resources><build><item "
			       "objectid=\"1\"/></build></model>",
			       cfg};
	char *with = scratch("cfg.3mf"), *without = scratch("nocfg.3mf"), *text = NULL;
	struct st_error err = {0};

	tu_write_zip(with, names, texts, 3);
	ck_assert_msg(meshio_3mf_config(with, &text, &err) == 0, "%s", err.msg);
	ck_assert_ptr_nonnull(text);
	ck_assert_str_eq(text, cfg);
	free(text);
	tu_write_zip(without, names, texts, 2);
	text = (char *)&err;
	ck_assert_msg(meshio_3mf_config(without, &text, &err) == 0, "%s", err.msg);
	ck_assert_ptr_null(text);
	ck_assert_int_eq(meshio_3mf_config("tests/data/firmware-texts.gcode", &text, &err),
			 ST_ERR_PARSE);
	ck_assert_ptr_null(text);
	free(with);
	free(without);
}
END_TEST

/* ---- broken files ------------------------------------------------------ */

/*
 * The zip at path must fail to read with code, from the file and from
 * memory alike (tu_expect_read_fail).
 */
static void expect_fail_file(const char *path, int code, const char *const *needles)
{
	size_t len;
	void *buf = tu_slurp(path, &len);

	tu_expect_read_fail(path, buf, len, code, needles);
	free(buf);
}

/* A 3MF of model_xml that must fail as expect_fail_file says. */
static void expect_fail_model(const char *model_xml, int code, const char *const *needles)
{
	char *path = scratch("bad.3mf");

	tu_write_3mf(path, model_xml);
	expect_fail_file(path, code, needles);
	free(path);
}

#define FAIL_MODEL(xml, code, ...) expect_fail_model(xml, code, (const char *const[]){__VA_ARGS__, NULL})
#define BUILD1 "<build><item objectid=\"1\"/></build>"

START_TEST(bad_models)
{
	FAIL_MODEL(MODEL("") "<resources>" TETRA("1") "</resources>" BUILD1, ST_ERR_PARSE,
		   "3D/3dmodel.model line 10:", "not well-formed XML");
	FAIL_MODEL(MODEL("") "<resources>" TETRA("1") "</resources></model>", ST_ERR_PARSE,
		   "3D/3dmodel.model has no <build>");
	FAIL_MODEL(MODEL("") "<resources>" TETRA("1") "</resources><build></build></model>",
		   ST_ERR_PARSE, "places no triangles");
	FAIL_MODEL(MODEL("") "<resources><object id=\"1\"><mesh><vertices><vertex x=\"0\" "
		   "y=\"0\" z=\"0\"/>\n</vertices><triangles>\n<triangle v1=\"0\" v2=\"0\" "
		   "v3=\"8\"/></triangles></mesh></object></resources>" BUILD1 "</model>",
		   ST_ERR_PARSE, "line 5:", "triangle 0 of object 1 refers to vertex 8",
		   "1 vertices");
	FAIL_MODEL(MODEL("") "<resources>" TETRA("1") "</resources><build><item "
		   "objectid=\"3\"/></build></model>",
		   ST_ERR_PARSE, "build item refers to object 3, which 3D/3dmodel.model does not");
	FAIL_MODEL(MODEL("") "<resources>" TETRA("1") TETRA("1") "</resources>" BUILD1 "</model>",
		   ST_ERR_PARSE, "line 10:", "object id 1 is defined again (first on line 3)");
	FAIL_MODEL(MODEL("") "<resources><object id=\"1\"><components><component objectid=\"2\"/>"
		   "</components></object><object id=\"2\"><components><component "
		   "objectid=\"1\"/></components></object></resources>" BUILD1 "</model>",
		   ST_ERR_PARSE, "contains itself through its components");
	FAIL_MODEL(MODEL("") "<resources>" TETRA("1") "</resources><build><item objectid=\"1\" "
		   "transform=\"1 0 0 0 1 0 0 0 1 0 0\"/></build></model>",
		   ST_ERR_PARSE, "transform has 11 numbers");
	FAIL_MODEL(MODEL("") "<resources>" TETRA("1") "</resources><build><item objectid=\"1\" "
		   "transform=\"1 0 0 0 1 0 0 0 1 0 0 nan\"/></build></model>",
		   ST_ERR_PARSE, "transform number 12 'nan' is not finite");
	FAIL_MODEL(MODEL("unit=\"furlong\"") "</model>", ST_ERR_PARSE, "line 2:",
		   "unit 'furlong' is not");
	FAIL_MODEL(HEAD "<!DOCTYPE model [<!ENTITY a \"aaaa\">]>\n<model xmlns=\"" CORE_NS
		   "\"/>", ST_ERR_PARSE, "<!DOCTYPE>");
	FAIL_MODEL(MODEL("xmlns:b=\"http://schemas.microsoft.com/3dmanufacturing/beamlattice/"
			 "2017/02\" requiredextensions=\"b\"") "</model>",
		   ST_ERR_UNSUPPORTED, "requires the 3MF extension", "beamlattice");
	FAIL_MODEL(HEAD "<model xmlns=\"http://example.com/other\"/>", ST_ERR_PARSE,
		   "root element is not a 3MF <model>");
	FAIL_MODEL(MODEL("") "<resources><object id=\"1\"><mesh><vertices><vertex x=\"1e999\" "
		   "y=\"0\" z=\"0\"/></vertices></mesh></object></resources>" BUILD1 "</model>",
		   ST_ERR_PARSE, "x '1e999' is not finite");
	FAIL_MODEL(MODEL("") "<resources><object id=\"1\"/></resources>" BUILD1 "</model>",
		   ST_ERR_PARSE, "object 1 has neither <mesh> nor <components>");
	FAIL_MODEL(MODEL("") "<resources><object id=\"1\" type=\"other\"><mesh/></object>"
		   "</resources>" BUILD1 "</model>",
		   ST_ERR_PARSE, "of type other");
}
END_TEST

START_TEST(bad_containers)
{
	char *path = scratch("bad.3mf");
	const char *names[] = {"readme.txt", "3D/3dmodel.model"};
	const char *texts[] = {"hello", MODEL("") "<resources>" TETRA("1") "</resources>" BUILD1
					      "</model>"};
	unsigned char *buf;
	size_t len;

	/* Named .3mf but not a zip. */
	tu_write_str(path, "solidworks? no, plain text\n");
	expect_fail_file(path, ST_ERR_PARSE, (const char *const[]){"not start like a zip", NULL});
	/* A zip without any model part. */
	tu_write_zip(path, names, texts, 1);
	expect_fail_file(path, ST_ERR_PARSE, (const char *const[]){"not a 3MF file", NULL});
	/* Truncated: the zip's central directory is gone. */
	tu_write_zip(path, names, texts, 2);
	buf = tu_slurp(path, &len);
	tu_write(path, buf, len / 2);
	expect_fail_file(path, ST_ERR_PARSE,
			 (const char *const[]){"not a readable zip archive", NULL});
	/* The rels name a part that is not there. */
	{
		const char *n2[] = {"_rels/.rels"};
		const char *t2[] = {tu_3mf_rels};

		tu_write_zip(path, n2, t2, 1);
		expect_fail_file(path, ST_ERR_PARSE,
				 (const char *const[]){"names model part 3D/3dmodel.model", NULL});
	}
	free(buf);
	free(path);
}
END_TEST

START_TEST(zip_bomb_is_refused)
{
	/* The central directory says the model unpacks to 4 GiB: refused before
	 * a byte is inflated (the streamed count stops a lying one the same way). */
	char *path = scratch("bomb.3mf");
	const char *names[] = {"3D/3dmodel.model"};
	const char *texts[] = {MODEL("") "</model>"};
	unsigned char *buf;
	size_t len, hits = 0;

	tu_write_zip(path, names, texts, 1);
	buf = tu_slurp(path, &len);
	for (size_t i = 0; i + 46 + 16 <= len; i++)
		if (!memcmp(buf + i, "PK\x01\x02", 4) && !memcmp(buf + i + 46, "3D/3dmodel.model", 16)) {
			memset(buf + i + 24, 0xf0, 1);
			memset(buf + i + 25, 0xff, 3);
			hits++;
		}
	ck_assert_uint_eq(hits, 1);
	tu_write(path, buf, len);
	expect_fail_file(path, ST_ERR_RANGE,
			 (const char *const[]){"3D/3dmodel.model says it unpacks to 4294967280 "
					       "bytes",
					       "zip bomb", NULL});
	free(buf);
	free(path);
}
END_TEST

void meshio_3mf_tcases(Suite *s)
{
	TCase *ps = tcase_create("3mf_prusaslicer");
	TCase *hb = tcase_create("3mf_hand_built");
	TCase *bad = tcase_create("3mf_bad_input");

	tcase_set_timeout(ps, 300);
	tcase_add_test(ps, prusaslicer_3mf_reads_as_its_stl);
	tcase_add_test(ps, prusaslicer_live_export_and_duplicates);
	suite_add_tcase(s, ps);

	tcase_add_test(hb, item_transform_rotates_and_moves);
	tcase_add_test(hb, mirror_keeps_outward_winding);
	tcase_add_test(hb, components_compose_transforms);
	tcase_add_test(hb, units_convert_to_mm);
	tcase_add_test(hb, several_items_are_separate_parts);
	tcase_add_test(hb, production_path_parts);
	tcase_add_test(hb, without_rels_and_extension_detects);
	tcase_add_test(hb, prusaslicer_config_text);
	suite_add_tcase(s, hb);

	tcase_add_test(bad, bad_models);
	tcase_add_test(bad, bad_containers);
	tcase_add_test(bad, zip_bomb_is_refused);
	suite_add_tcase(s, bad);
}

/* testutil.c - scratch files and CLI runs for the Check suites. */
#include "testutil.h"
#include "fixtures.h"
#include "region.h"
#include "slicer.h"

#include <check.h>
#include <dirent.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zip.h>

static char scratch_dir[256];

void tu_scratch_init(void)
{
	const char *tmp = getenv("TMPDIR");

	snprintf(scratch_dir, sizeof(scratch_dir), "%s/stratum-test-XXXXXX", tmp ? tmp : "/tmp");
	if (!mkdtemp(scratch_dir)) {
		perror("tu_scratch_init: mkdtemp");
		exit(EXIT_FAILURE);
	}
}

void tu_scratch_cleanup(void)
{
	char cmd[300];

	snprintf(cmd, sizeof(cmd), "rm -rf '%s'", scratch_dir);
	if (scratch_dir[0] && system(cmd) != 0)
		fprintf(stderr, "could not remove %s\n", scratch_dir);
}

const char *tu_path(const char *name)
{
	static char bufs[8][512];
	static int next;
	char *buf = bufs[next++ % 8];

	ck_assert_msg(scratch_dir[0], "tu_scratch_init() was not called");
	/* The pid keeps names apart when Check runs tests in parallel forks. */
	snprintf(buf, 512, "%s/%d-%s", scratch_dir, (int)getpid(), name);
	return buf;
}

void tu_write(const char *path, const void *data, size_t len)
{
	FILE *f = fopen(path, "wb");

	ck_assert_msg(f != NULL, "cannot create %s", path);
	ck_assert(fwrite(data, 1, len, f) == len);
	ck_assert(fclose(f) == 0);
}

void tu_write_str(const char *path, const char *text)
{
	tu_write(path, text, strlen(text));
}

void *tu_slurp(const char *path, size_t *len)
{
	FILE *f = fopen(path, "rb");
	char *buf;
	long n;

	ck_assert_msg(f != NULL, "cannot open %s", path);
	ck_assert_int_eq(fseek(f, 0, SEEK_END), 0);
	n = ftell(f);
	ck_assert_int_ge(n, 0);
	rewind(f);
	buf = malloc((size_t)n + 1);
	ck_assert_ptr_nonnull(buf);
	ck_assert_uint_eq(fread(buf, 1, (size_t)n, f), (size_t)n);
	fclose(f);
	buf[n] = '\0';
	*len = (size_t)n;
	return buf;
}

void tu_expect_read_fail(const char *path, const void *data, size_t len, int code,
			 const char *const *needles)
{
	struct st_error e1 = {0}, e2 = {0};
	struct mesh *m = (struct mesh *)&e1; /* must be reset to NULL */

	ck_assert_int_eq(meshio_read(path, MESHIO_AUTO, &m, NULL, &e1), code);
	ck_assert_ptr_null(m);
	ck_assert_int_eq(e1.code, code);
	ck_assert_msg(!strncmp(e1.msg, path, strlen(path)) && e1.msg[strlen(path)] == ':',
		      "message does not start with the file name: %s", e1.msg);
	ck_assert_msg(!strchr(e1.msg, '\n'), "not one line: %s", e1.msg);
	for (size_t i = 0; needles[i]; i++)
		ck_assert_msg(strstr(e1.msg, needles[i]), "'%s' missing in: %s", needles[i],
			      e1.msg);
	m = (struct mesh *)&e2;
	ck_assert_int_eq(meshio_read_buffer(data, len, path, MESHIO_AUTO, &m, NULL, &e2), code);
	ck_assert_ptr_null(m);
	ck_assert_str_eq(e1.msg, e2.msg);
}

void tu_write_zip(const char *path, const char *const *names, const char *const *texts,
		  size_t n)
{
	int zerr = 0;
	zip_t *z = zip_open(path, ZIP_CREATE | ZIP_TRUNCATE, &zerr);

	ck_assert_msg(z != NULL, "cannot create zip %s (libzip error %d)", path, zerr);
	for (size_t i = 0; i < n; i++) {
		zip_source_t *src = zip_source_buffer(z, texts[i], strlen(texts[i]), 0);

		ck_assert_msg(src && zip_file_add(z, names[i], src, ZIP_FL_OVERWRITE) >= 0,
			      "zip %s: cannot add %s: %s", path, names[i], zip_strerror(z));
	}
	ck_assert_msg(zip_close(z) == 0, "zip %s: %s", path, zip_strerror(z));
}

void tu_zip_add(const char *path, const char *name, const char *text)
{
	int zerr = 0;
	zip_t *z = zip_open(path, 0, &zerr);
	zip_source_t *src;

	ck_assert_msg(z != NULL, "cannot open zip %s (libzip error %d)", path, zerr);
	src = zip_source_buffer(z, text, strlen(text), 0);
	ck_assert_msg(src && zip_file_add(z, name, src, ZIP_FL_OVERWRITE) >= 0,
		      "zip %s: cannot add %s: %s", path, name, zip_strerror(z));
	ck_assert_msg(zip_close(z) == 0, "zip %s: %s", path, zip_strerror(z));
}

const char tu_3mf_rels[] =
    "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
    "<Relationships xmlns=\"http://schemas.openxmlformats.org/package/2006/relationships\">\n"
    " <Relationship Target=\"/3D/3dmodel.model\" Id=\"rel0\" "
    "Type=\"http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel\"/>\n"
    "</Relationships>\n";

void tu_write_3mf(const char *path, const char *model_xml)
{
	const char *names[] = {"_rels/.rels", "3D/3dmodel.model"};
	const char *texts[] = {tu_3mf_rels, model_xml};

	tu_write_zip(path, names, texts, 2);
}

void tu_write_3mf_mesh(const char *path, const struct mesh *m)
{
	size_t cap = 256 + m->nverts * 128 + m->ntris * 64, n = 0;
	char *xml = malloc(cap);

	ck_assert_ptr_nonnull(xml);
	n += (size_t)snprintf(xml + n, cap - n,
			      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" "
			      "xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">\n"
			      "<resources><object id=\"1\" type=\"model\"><mesh><vertices>\n");
	for (size_t i = 0; i < m->nverts; i++)
		n += (size_t)snprintf(xml + n, cap - n, "<vertex x=\"%.17g\" y=\"%.17g\" z=\"%.17g\"/>\n",
				      m->verts[i][0], m->verts[i][1], m->verts[i][2]);
	n += (size_t)snprintf(xml + n, cap - n, "</vertices><triangles>\n");
	for (size_t i = 0; i < m->ntris; i++)
		n += (size_t)snprintf(xml + n, cap - n, "<triangle v1=\"%u\" v2=\"%u\" v3=\"%u\"/>\n",
				      (unsigned)m->tris[i][0], (unsigned)m->tris[i][1],
				      (unsigned)m->tris[i][2]);
	n += (size_t)snprintf(xml + n, cap - n, "</triangles></mesh></object></resources>\n"
			      "<build><item objectid=\"1\"/></build></model>\n");
	ck_assert_msg(n < cap, "tu_write_3mf_mesh: buffer too small");
	tu_write_3mf(path, xml);
	free(xml);
}

void tu_write_3mf_boxes(const char *path, const double (*cubes)[5], int n)
{
	char xml[32768];
	size_t k = 0;

	k += (size_t)snprintf(xml + k, sizeof(xml) - k,
			      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" "
			      "xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\">"
			      "<resources>\n");
	for (int i = 0; i < n; i++) {
		struct mesh *m = fx_box(0, 0, 0, cubes[i][0], cubes[i][1], cubes[i][2]);

		k += (size_t)snprintf(xml + k, sizeof(xml) - k,
				      "<object id=\"%d\" type=\"model\"><mesh><vertices>", i + 1);
		for (size_t v = 0; v < m->nverts; v++)
			k += (size_t)snprintf(xml + k, sizeof(xml) - k,
					      "<vertex x=\"%g\" y=\"%g\" z=\"%g\"/>", m->verts[v][0],
					      m->verts[v][1], m->verts[v][2]);
		k += (size_t)snprintf(xml + k, sizeof(xml) - k, "</vertices><triangles>");
		for (size_t t = 0; t < m->ntris; t++)
			k += (size_t)snprintf(xml + k, sizeof(xml) - k,
					      "<triangle v1=\"%u\" v2=\"%u\" v3=\"%u\"/>",
					      (unsigned)m->tris[t][0], (unsigned)m->tris[t][1],
					      (unsigned)m->tris[t][2]);
		k += (size_t)snprintf(xml + k, sizeof(xml) - k, "</triangles></mesh></object>\n");
		mesh_free(m);
	}
	k += (size_t)snprintf(xml + k, sizeof(xml) - k, "</resources><build>");
	for (int i = 0; i < n; i++)
		k += (size_t)snprintf(xml + k, sizeof(xml) - k,
				      "<item objectid=\"%d\" transform=\"1 0 0 0 1 0 0 0 1 %g %g 0\"/>",
				      i + 1, cubes[i][3], cubes[i][4]);
	k += (size_t)snprintf(xml + k, sizeof(xml) - k, "</build></model>\n");
	ck_assert_msg(k < sizeof(xml), "tu_write_3mf_boxes: XML too long");
	tu_write_3mf(path, xml);
}

char *tu_read_between(const char *path, char *buf, size_t cap, const char *begin,
		      const char *end)
{
	FILE *f = fopen(path, "rb");
	char *a, *b;
	size_t n;

	ck_assert_msg(f != NULL, "cannot open %s", path);
	n = fread(buf, 1, cap - 1, f);
	ck_assert_msg(n < cap - 1, "%s is larger than the test's buffer", path);
	fclose(f);
	buf[n] = '\0';
	a = strstr(buf, begin);
	ck_assert_msg(a != NULL, "%s: no '%s'", path, begin);
	a += strlen(begin);
	b = strstr(a, end);
	ck_assert_msg(b != NULL, "%s: no '%s' after '%s'", path, end, begin);
	*b = '\0';
	return a;
}

/* Run cmd through the shell, its output into out; the exit status or -1. */
static int run_shell(char *out, size_t cap, const char *cmd)
{
	FILE *p;
	size_t n = 0;
	int status;

	p = popen(cmd, "r");
	ck_assert_msg(p != NULL, "cannot run %s", cmd);
	while (cap > 1 && n < cap - 1) {
		size_t got = fread(out + n, 1, cap - 1 - n, p);
		if (got == 0)
			break;
		n += got;
	}
	if (cap)
		out[n] = '\0';
	/* Drain whatever did not fit so the child never blocks on a full pipe. */
	{
		char sink[4096];
		while (fread(sink, 1, sizeof(sink), p) > 0)
			;
	}
	status = pclose(p);
	if (!WIFEXITED(status))
		return -1;
	return WEXITSTATUS(status);
}

int tu_run(char *out, size_t cap, const char *args_fmt, ...)
{
	const char *bin = getenv("STRATUM_BIN");
	char args[2048], cmd[2300];
	va_list ap;

	va_start(ap, args_fmt);
	vsnprintf(args, sizeof(args), args_fmt, ap);
	va_end(ap);
	snprintf(cmd, sizeof(cmd), "%s %s 2>&1", bin ? bin : "build/stratum", args);
	return run_shell(out, cap, cmd);
}

int tu_sh(char *out, size_t cap, const char *cmd_fmt, ...)
{
	char cmd[4096];
	va_list ap;
	int n;

	va_start(ap, cmd_fmt);
	n = vsnprintf(cmd, sizeof(cmd) - 8, cmd_fmt, ap);
	va_end(ap);
	ck_assert_msg(n >= 0 && (size_t)n < sizeof(cmd) - 8, "command too long: %s", cmd);
	strcat(cmd, " 2>&1");
	return run_shell(out, cap, cmd);
}

int tu_marlin_log_next(FILE *log, char *line, size_t cap, long *n, const char **text)
{
	while (fgets(line, (int)cap, log)) {
		char *sp = strchr(line, ' ');

		line[strcspn(line, "\n")] = '\0';
		ck_assert_msg(sp != NULL, "simulator log line without a command: %s", line);
		if (line[0] == '-' && !strcmp(sp + 1, "M105"))
			continue;
		*n = line[0] == '-' ? -1 : strtol(line, NULL, 10);
		*text = sp + 1;
		return 1;
	}
	return 0;
}

int tu_file_exists(const char *path)
{
	struct stat st;

	return stat(path, &st) == 0;
}

size_t tu_count_role(const struct layer_paths *l, enum path_role role)
{
	size_t c = 0;

	for (size_t i = 0; i < l->n; i++)
		c += l->paths[i].role == role;
	return c;
}

double tu_path_length(const struct toolpath *p)
{
	double s = 0;

	for (size_t i = 1; i < p->n; i++)
		s += hypot((double)(p->pts[i].x - p->pts[i - 1].x),
			   (double)(p->pts[i].y - p->pts[i - 1].y));
	return s;
}

const char *tu_bin(void)
{
	return getenv("STRATUM_BIN") ? getenv("STRATUM_BIN") : "build/stratum";
}

struct mesh *tu_round_trip(const struct mesh *m, const char *name, enum meshio_format fmt)
{
	const char *path = tu_path(name);
	struct st_error err = {0};
	struct mesh *back = NULL;

	ck_assert_msg(meshio_write_stl(path, m, fmt, &err) == 0, "write %s: %s", path, err.msg);
	ck_assert_msg(meshio_read(path, MESHIO_AUTO, &back, NULL, &err) == 0, "read %s: %s", path,
		      err.msg);
	return back;
}

int tu_dir_entries(const char *dir)
{
	DIR *d = opendir(dir);
	struct dirent *e;
	int n = 0;

	ck_assert_msg(d, "cannot list %s", dir);
	while ((e = readdir(d)))
		if (strcmp(e->d_name, ".") && strcmp(e->d_name, ".."))
			n++;
	closedir(d);
	return n;
}

char *tu_gcode_mem(const struct layer_stack *st, const struct gcodew_settings *s,
		   struct gcodew_summary *sum)
{
	char *buf = NULL;
	size_t len = 0;
	struct st_error err = {0};
	FILE *fp = open_memstream(&buf, &len);
	int rc;

	ck_assert_ptr_nonnull(fp);
	rc = gcodew_write_stream(st, s, fp, sum, &err);
	ck_assert_int_eq(fclose(fp), 0);
	ck_assert_msg(rc == 0, "gcodew_write_stream failed (%d): %s", rc, err.msg);
	return buf;
}

struct tu_moves tu_read_moves(const char *text)
{
	struct tu_moves r = {0};
	size_t cap = 0;
	double x = 0, y = 0, e = 0;
	int layer = 0;
	char role[32] = "";

	for (const char *l = text; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
		size_t len = strcspn(l, "\n");
		double nx = x, ny = y, ne = e, i = 0, j = 0;
		bool has_e = false;
		bool arc = l[0] == 'G' && (l[1] == '2' || l[1] == '3') && l[2] == ' ';

		if (!strncmp(l, ";LAYER_CHANGE", 13))
			layer++;
		if (!strncmp(l, ";TYPE:", 6))
			snprintf(role, sizeof(role), "%.*s", (int)(len - 6), l + 6);
		if (!strncmp(l, "G92 E0", 6))
			e = 0;
		if (strncmp(l, "G1 ", 3) && !arc)
			continue;
		r.g1 += !arc;
		r.arcs += arc;
		for (const char *c = l + 3; c < l + len; c++) {
			double v = strtod(c + 1, NULL);
			nx = *c == 'X' ? v : nx;
			ny = *c == 'Y' ? v : ny;
			i = *c == 'I' ? v : i;
			j = *c == 'J' ? v : j;
			if (*c == 'E') {
				ne = v;
				has_e = true;
			}
		}
		if (has_e && ne > e && (arc || nx != x || ny != y) && layer > 0) {
			if (r.n == cap) {
				cap = cap ? 2 * cap : 256;
				r.m = realloc(r.m, cap * sizeof(*r.m));
				ck_assert_ptr_nonnull(r.m);
			}
			r.m[r.n] = (struct tu_move){.layer = layer, .arc = arc, .ccw = l[1] == '3',
						    .x0 = x, .y0 = y, .x1 = nx, .y1 = ny,
						    .cx = x + i, .cy = y + j, .e = ne - e};
			snprintf(r.m[r.n].role, sizeof(r.m[r.n].role), "%s", role);
			r.n++;
		}
		x = nx;
		y = ny;
		e = ne;
	}
	return r;
}

double tu_moves_e(const struct tu_moves *r, const char *role)
{
	double e = 0;

	for (size_t k = 0; k < r->n; k++)
		if (!role || !strcmp(r->m[k].role, role))
			e += r->m[k].e;
	return e;
}

struct region_report *tu_slice_region(const struct mesh *m, const char *name,
				      struct slicer_summary *sum, double *width_max)
{
	struct slicer_config c;
	struct region_opts o;
	struct region_print *p = NULL;
	struct region_report *r = NULL;
	struct st_error err = {0};
	const char *path = tu_path(name);

	slicer_config_init(&c, 0.4);
	c.threads = 1;
	ck_assert_msg(slicer_run(m, &c, path, sum, &err) == 0, "%s", err.msg);
	region_opts_init(&o);
	o.has_center = true;
	o.center_x = (c.bed.min_x + c.bed.max_x) / 2;
	o.center_y = (c.bed.min_y + c.bed.max_y) / 2;
	ck_assert_msg(region_read(path, &o, &p, &err) == 0, "%s", err.msg);
	ck_assert_msg(region_compare(m, p, &o, &r, &err) == 0, "%s", err.msg);
	ck_assert_uint_eq(r->empty_sections, 0);
	if (width_max)
		*width_max = p->width_max;
	region_print_free(p);
	return r;
}

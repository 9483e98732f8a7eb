/*
 * check_ini.c - the one ini reader (host/ini.h) as its two users see it:
 * a printer profile (profile_load_file) and the farm node's configuration
 * (node_config_load) take and refuse the same quirks at the same line, and
 * the example configuration in docs/serve.md loads as it is written.
 */
#include <check.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "ini.h"
#include "profile.h"
#include "serve/node.h"
#include "suites.h"
#include "testutil.h"

/* The node's required sections come first, so the probed lines end the file
 * in both (a last line without its line end is one of the quirks). */
static const char node_head[] = "[key a]\nkey = 0123456789abcdef\nroles = read\n"
				"[printer p]\nprofile = generic-marlin\nport = sim\n[node]\n";
#define HEAD_LINES 7 /* lines in node_head; a profile gets as many comments */

/* One quirk: the bytes after the head, and what both readers make of them. */
struct quirk {
	const char *what;
	const char *text; /* the lines probed (may hold NULs: see len) */
	size_t len;
	bool bom, crlf;	   /* a BOM before the whole file; every LF a CRLF */
	int bad_line;	   /* 0: both load; else the line (in text, from 1) both refuse */
	const char *value; /* data_dir as both read it (when they load) */
	const char *node_value; /* where the node differs: its inline ' #' and ' ;' comments
				 * (data_dir is text to a profile, which keeps them) */
};

#define Q(s) s, sizeof(s) - 1

static const struct quirk quirks[] = {
	{"plain", Q("data_dir = /d\n"), false, false, 0, "/d", NULL},
	{"no line end at the end", Q("data_dir = /d"), false, false, 0, "/d", NULL},
	{"CRLF line", Q("data_dir = /d\r\n"), false, false, 0, "/d", NULL},
	{"CRLF everywhere", Q("# c\ndata_dir = /d\n"), false, true, 0, "/d", NULL},
	{"CR at the end, no LF", Q("data_dir = /d\r"), false, false, 0, "/d", NULL},
	{"a lone CR is not a line end", Q("data_dir = /d\rx = y\n"), false, false, 0,
	 "/d\rx = y", NULL},
	{"BOM at the start", Q("data_dir = /d\n"), true, false, 0, "/d", NULL},
	{"BOM later is a bad key", Q("\xEF\xBB\xBF" "data_dir = /d\n"), false, false, 1, NULL,
	 NULL},
	{"blank lines and blanks", Q("\n \t\n\t data_dir\t=\t/d  \t\n\n"), false, false, 0, "/d",
	 NULL},
	{"comments", Q("# c\n; c\n   # indented\n\t; tab\ndata_dir = /d\n#"), false, false, 0,
	 "/d", NULL},
	{"no blanks around =", Q("data_dir=/d\n"), false, false, 0, "/d", NULL},
	{"first = splits", Q("data_dir = /d = e\n"), false, false, 0, "/d = e", NULL},
	{"# inside a value", Q("data_dir = /d#1\n"), false, false, 0, "/d#1", NULL},
	{"; after a value", Q("data_dir = /d ; x\n"), false, false, 0, "/d ; x", "/d"},
	{"blank # after a value", Q("data_dir = /d   # where\n"), false, false, 0,
	 "/d   # where", "/d"},
	{"tab # after a value", Q("data_dir = /d\t#x#y\n"), false, false, 0, "/d\t#x#y", "/d"},
	{"UTF-8 in a value", Q("data_dir = /d\xC3\xA9\n"), false, false, 0, "/d\xC3\xA9", NULL},
	{"NUL byte", Q("data_dir = /d\0x\n"), false, false, 1, NULL, NULL},
	{"NUL in a comment", Q("# ok\n# \0\n"), false, false, 2, NULL, NULL},
	{"key with '-'", Q("# c\ndata-dir = /d\n"), false, false, 2, NULL, NULL},
	{"key with a blank", Q("data dir = /d\n"), false, false, 1, NULL, NULL},
	{"no key", Q("= /d\n"), false, false, 1, NULL, NULL},
	{"no =", Q("data_dir /d\n"), false, false, 1, NULL, NULL},
	{"set twice", Q("data_dir = /d\n\ndata_dir = /e\n"), false, false, 3, NULL, NULL},
};

/* Write head + q's text to path, with q's BOM and line ends. */
static void write_probe(const char *path, const char *head, const struct quirk *q)
{
	size_t hl = strlen(head), cap = 3 + 2 * (hl + q->len), n = 0;
	char *buf = malloc(cap);

	ck_assert_ptr_nonnull(buf);
	if (q->bom) {
		memcpy(buf, "\xEF\xBB\xBF", 3);
		n = 3;
	}
	for (size_t i = 0; i < hl + q->len; i++) {
		char c = i < hl ? head[i] : q->text[i - hl];

		if (c == '\n' && q->crlf)
			buf[n++] = '\r';
		buf[n++] = c;
	}
	tu_write(path, buf, n);
	free(buf);
}

/* err names path and the line: "PATH: line N: ..." or "PATH: line N is ...". */
static void assert_at_line(const char *who, const struct quirk *q, const char *path,
			   const char *msg, int line)
{
	char want[512];
	size_t n = (size_t)snprintf(want, sizeof(want), "%s: line %d", path, line);

	ck_assert_msg(!strncmp(msg, want, n) && (msg[n] == ':' || msg[n] == ' '),
		      "%s, %s: want '%s...', got '%s'", q->what, who, want, msg);
}

/* Each quirk to both readers: the same verdict, line and value. */
START_TEST(test_profile_and_node_agree)
{
	char profile_head[2 * HEAD_LINES + 1] = "";

	for (int i = 0; i < HEAD_LINES; i++)
		strcat(profile_head, "#\n");
	for (size_t i = 0; i < sizeof(quirks) / sizeof(quirks[0]); i++) {
		const struct quirk *q = &quirks[i];
		char ppath[512], npath[512];
		struct profile *p = NULL;
		struct node_config *c = calloc(1, sizeof(*c));
		struct st_error perr = {0}, nerr = {0};
		int prc, nrc;

		ck_assert_ptr_nonnull(c);
		snprintf(ppath, sizeof(ppath), "%s", tu_path("quirk-profile.ini"));
		snprintf(npath, sizeof(npath), "%s", tu_path("quirk-node.ini"));
		write_probe(ppath, profile_head, q);
		write_probe(npath, node_head, q);
		prc = profile_load_file(ppath, &p, &perr);
		nrc = node_config_load(npath, c, &nerr);
		if (q->bad_line) {
			ck_assert_msg(prc == ST_ERR_PARSE, "%s: profile: %d %s", q->what, prc, perr.msg);
			ck_assert_msg(nrc == ST_ERR_PARSE, "%s: node: %d %s", q->what, nrc, nerr.msg);
			assert_at_line("profile", q, ppath, perr.msg, HEAD_LINES + q->bad_line);
			assert_at_line("node", q, npath, nerr.msg, HEAD_LINES + q->bad_line);
		} else {
			ck_assert_msg(prc == 0, "%s: profile: %s", q->what, perr.msg);
			ck_assert_msg(nrc == 0, "%s: node: %s", q->what, nerr.msg);
			ck_assert_str_eq(profile_get(p, "data_dir"), q->value);
			ck_assert_str_eq(c->data_dir, q->node_value ? q->node_value : q->value);
		}
		profile_free(p);
		free(c);
	}
}
END_TEST

/* The line limit is one for both: INI_LINE_MAX bytes load, one more does not. */
START_TEST(test_line_limit_agrees)
{
	char *text = malloc(INI_LINE_MAX + 8);

	ck_assert_ptr_nonnull(text);
	for (int extra = 0; extra <= 1; extra++) {
		struct quirk q = {"long comment", text, INI_LINE_MAX + (size_t)extra + 1, false, false,
				  extra ? 1 : 0, NULL, NULL};
		struct profile *p = NULL;
		struct node_config *c = calloc(1, sizeof(*c));
		struct st_error perr = {0}, nerr = {0};
		char ppath[512], npath[512];
		int prc, nrc;

		ck_assert_ptr_nonnull(c);
		text[0] = '#';
		memset(text + 1, 'x', INI_LINE_MAX - 1 + (size_t)extra);
		text[INI_LINE_MAX + extra] = '\n';
		snprintf(ppath, sizeof(ppath), "%s", tu_path("long-profile.ini"));
		snprintf(npath, sizeof(npath), "%s", tu_path("long-node.ini"));
		write_probe(ppath, "data_dir = /d\n", &q);
		write_probe(npath, "[key a]\nkey = 0123456789abcdef\nroles = read\n[printer p]\n"
				   "profile = generic-marlin\nport = sim\n[node]\ndata_dir = /d\n#\n"
				   "#\n#\n#\n#\n#\n#\n", &q);
		prc = profile_load_file(ppath, &p, &perr);
		nrc = node_config_load(npath, c, &nerr);
		if (!extra) {
			ck_assert_msg(prc == 0, "profile: %s", perr.msg);
			ck_assert_msg(nrc == 0, "node: %s", nerr.msg);
		} else {
			ck_assert_int_eq(prc, ST_ERR_PARSE);
			ck_assert_int_eq(nrc, ST_ERR_PARSE);
			assert_at_line("profile", &q, ppath, perr.msg, 2);
			assert_at_line("node", &q, npath, nerr.msg, 16);
			ck_assert_ptr_nonnull(strstr(nerr.msg, "longer than 65536 bytes"));
		}
		profile_free(p);
		free(c);
	}
	free(text);
}
END_TEST

/* The node's inline comments: on section lines too, never inside a value. */
START_TEST(test_node_inline_comments)
{
#define INLINE_HEAD                                                          \
	"[node]   # the node itself\n"                                       \
	"data_dir = /srv/a#b # a '#' after a blank starts the comment\n"     \
	"[key a] # the slicer's\n"                                           \
	"key = 0123456789#abcdef\t# keys may hold '#'\n"
#define INLINE_PRINTER "[printer p]\nprofile = generic-marlin\nport = sim\n"
	struct node_config *c = calloc(1, sizeof(*c));
	struct st_error err = {0};
	const char *path = tu_path("inline.ini");

	ck_assert_ptr_nonnull(c);
	tu_write_str(path, INLINE_HEAD "roles = read,upload#x # ... so a role may not\n"
			   INLINE_PRINTER);
	ck_assert_int_eq(node_config_load(path, c, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "line 5: roles: 'upload#x' is not a role"), "%s", err.msg);
	tu_write_str(path, INLINE_HEAD "roles = read\n" INLINE_PRINTER "[mqtt]\nhost = b\n"
			   "password = # a value cannot begin with '#'\n");
	ck_assert_int_eq(node_config_load(path, c, &err), ST_ERR_RANGE);
	ck_assert_msg(strstr(err.msg, "line 11: password: empty value"), "%s", err.msg);
	tu_write_str(path, INLINE_HEAD "roles = read, upload ; two\n" INLINE_PRINTER);
	ck_assert_msg(node_config_load(path, c, &err) == 0, "%s", err.msg);
	ck_assert_str_eq(c->data_dir, "/srv/a#b");
	ck_assert_str_eq(c->keys[0].secret, "0123456789#abcdef");
	ck_assert_uint_eq(c->keys[0].roles, NODE_ROLE_READ | NODE_ROLE_UPLOAD);
	free(c);
#undef INLINE_HEAD
#undef INLINE_PRINTER
}
END_TEST

/* A config holding API keys that its group or others can read is named
 * (node_config_exposed), and `stratum serve` warns before it starts. */
START_TEST(test_node_config_mode_warning)
{
	struct node_config *c = calloc(1, sizeof(*c));
	struct st_error err = {0};
	char path[512], out[4096], blocker[512];
	unsigned mode = 0;

	ck_assert_ptr_nonnull(c);
	snprintf(path, sizeof(path), "%s", tu_path("exposed.ini"));
	snprintf(blocker, sizeof(blocker), "%s", tu_path("not-a-dir"));
	tu_write_str(blocker, "a file where the data directory would go\n");
	/* data_dir cannot be made, so serve stops (65) right after the warning */
	snprintf(out, sizeof(out), "%sdata_dir = %s/data\n", node_head, blocker);
	tu_write_str(path, out);
	ck_assert_msg(node_config_load(path, c, &err) == 0, "%s", err.msg);
	chmod(path, 0644);
	ck_assert(node_config_exposed(path, c, &mode));
	ck_assert_uint_eq(mode, 0644);
	ck_assert_int_eq(tu_run(out, sizeof(out), "serve --config '%s'", path), 65);
	ck_assert_msg(strstr(out, "warning: ") && strstr(out, "holds API keys and can be read by "
							      "other users (mode 0644)"),
		      "%s", out);
	chmod(path, 0640);
	ck_assert(node_config_exposed(path, c, &mode));
	chmod(path, 0600);
	ck_assert(!node_config_exposed(path, c, &mode));
	ck_assert_int_eq(tu_run(out, sizeof(out), "serve --config '%s'", path), 65);
	ck_assert_msg(!strstr(out, "warning"), "%s", out);
	free(c);
}
END_TEST

/* A profile's comments after values: cut from every number, list, choice
 * and bool, kept in text (G-code and names hold ' ;' and ' #'). */
START_TEST(test_profile_inline_comments)
{
	struct profile *p = NULL;
	struct st_error err = {0};
	const char *path = tu_path("inline-profile.ini");

	tu_write_str(path, "layer_height = 0.25 ; fine\n"
			   "perimeters = 4\t# walls\n"
			   "fill_pattern = gyroid ; strong\n"
			   "fill_density = 15% # light\n"
			   "nozzle_diameter = 0.4, 0.4   # two, so two extruders\n"
			   "support_material = 1 ; on\n"
			   "bed_shape = 0x0,220x0,220x220,0x220 # square\n"
			   "start_gcode = G28 ; home all # then wait\n"
			   "printer_model = MK ; 3 # x\n");
	ck_assert_msg(profile_load_file(path, &p, &err) == 0, "%s", err.msg);
	ck_assert_double_eq_tol(p->layer_height, 0.25, 1e-12);
	ck_assert_int_eq(p->perimeters, 4);
	ck_assert_str_eq(p->fill_pattern, "gyroid");
	ck_assert_double_eq_tol(p->fill_density, 15, 1e-12);
	ck_assert_int_eq(p->extruder_count, 2);
	ck_assert(p->support_material);
	ck_assert_double_eq_tol(p->bed_max_x, 220, 1e-12);
	ck_assert_str_eq(p->start_gcode, "G28 ; home all # then wait");
	ck_assert_str_eq(p->printer_model, "MK ; 3 # x");
	ck_assert_str_eq(profile_get(p, "fill_pattern"), "gyroid"); /* the placeholder's too */
	profile_free(p);
	/* run into the value, ';' or '#' is part of it, and refused in a number */
	tu_write_str(path, "layer_height = 0.25;fine\n");
	ck_assert_int_eq(profile_load_file(path, &p, &err), ST_ERR_PARSE);
	ck_assert_msg(strstr(err.msg, "'0.25;fine' is not a number"), "%s", err.msg);
}
END_TEST

/* Every ```ini block of a doc, written out as it stands: serve.md's load as
 * node configs (a farm view's config when it starts with [farm]),
 * printers.md's as profiles.  The count guards against a
 * block that stops being one. */
START_TEST(test_doc_blocks_load)
{
	static const struct {
		const char *doc;
		bool node;
		int min;
	} docs[] = {{"docs/serve.md", true, 1}, {"docs/printers.md", false, 1}};

	for (size_t d = 0; d < sizeof(docs) / sizeof(docs[0]); d++) {
		size_t len;
		char *text = tu_slurp(docs[d].doc, &len), *b = text;
		int n = 0;

		while ((b = strstr(b, "\n```ini\n")) != NULL) {
			char *start = b + 8, *end = strstr(start, "\n```");
			const char *path = tu_path("doc-block.ini");
			struct st_error err = {0};

			ck_assert_msg(end != NULL, "%s: an ini block is not closed", docs[d].doc);
			end[1] = '\0';
			tu_write_str(path, start);
			if (docs[d].node && !strncmp(start, "[farm]", 6)) {
				struct farm_config *f = calloc(1, sizeof(*f));

				ck_assert_ptr_nonnull(f);
				ck_assert_msg(farm_config_load(path, f, &err) == 0,
					      "%s, block %d (a farm view's): %s", docs[d].doc, n + 1,
					      err.msg);
				free(f);
			} else if (docs[d].node) {
				struct node_config *c = calloc(1, sizeof(*c));

				ck_assert_ptr_nonnull(c);
				ck_assert_msg(node_config_load(path, c, &err) == 0,
					      "%s, block %d: %s", docs[d].doc, n + 1, err.msg);
				free(c);
			} else {
				struct profile *p = NULL;

				ck_assert_msg(profile_load_file(path, &p, &err) == 0,
					      "%s, block %d: %s", docs[d].doc, n + 1, err.msg);
				profile_free(p);
			}
			n++;
			b = end + 2;
		}
		ck_assert_msg(n >= docs[d].min, "%s: %d ini blocks", docs[d].doc, n);
		free(text);
	}
}
END_TEST

/* The example under "## Config" in docs/serve.md loads verbatim. */
START_TEST(test_doc_example_loads)
{
	static char doc[1 << 17];
	const char *ini = tu_read_between("docs/serve.md", doc, sizeof(doc), "## Config\n\n```ini\n",
					  "```");
	struct node_config *c = calloc(1, sizeof(*c));
	struct st_error err = {0};
	const char *path = tu_path("serve-md.ini");

	ck_assert_ptr_nonnull(c);
	tu_write_str(path, ini);
	ck_assert_msg(node_config_load(path, c, &err) == 0, "docs/serve.md's example: %s",
		      err.msg);
	ck_assert_str_eq(c->name, "farm-1");
	ck_assert_str_eq(c->listen_addr, "0.0.0.0");
	ck_assert_uint_eq(c->listen_port, 5000);
	ck_assert_str_eq(c->data_dir, "/var/lib/stratum");
	ck_assert_uint_eq(c->max_upload, 256ull << 20);
	ck_assert_uint_eq(c->nkeys, 2);
	ck_assert_str_eq(c->keys[0].secret, "2f1c0b6e9a7d4c3f8e5a");
	ck_assert_uint_eq(c->keys[0].roles, NODE_ROLE_READ | NODE_ROLE_UPLOAD);
	ck_assert_uint_eq(c->nprinters, 2);
	ck_assert_str_eq(c->printers[0].port, "/dev/ttyACM0");
	ck_assert_str_eq(c->printers[0].prefix, "/p/mk3s");
	ck_assert_str_eq(c->printers[1].prefix, "/p/bench-sim");
	ck_assert_double_eq(c->printers[1].sim_speedup, 100);
	ck_assert_str_eq(c->mqtt.host, "broker.local");
	ck_assert_str_eq(c->mqtt.username, "farm-1");
	ck_assert_str_eq(c->mqtt.client_id, "stratum-farm-1");
	ck_assert_int_eq(c->mqtt.keepalive, 30);
	ck_assert_int_eq(c->mqtt.tls, 1);
	ck_assert_str_eq(c->mqtt.tls_version, "tlsv1.2");
	ck_assert_uint_eq(c->mqtt.ndownload_hosts, 2);
	ck_assert_str_eq(c->mqtt.download_hosts[1], "10.0.0.5:8080");
	free(c);
}
END_TEST

Suite *ini_suite(void)
{
	Suite *s = suite_create("ini");
	TCase *tc = tcase_create("readers");

	/* about 20 profile and node loads: 0.6 s alone, past Check's default
	 * 4 s once on a loaded machine */
	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_profile_and_node_agree);
	tcase_add_test(tc, test_line_limit_agrees);
	tcase_add_test(tc, test_node_inline_comments);
	tcase_add_test(tc, test_doc_example_loads);
	tcase_add_test(tc, test_profile_inline_comments);
	tcase_add_test(tc, test_doc_blocks_load);
	tcase_add_test(tc, test_node_config_mode_warning);
	suite_add_tcase(s, tc);
	return s;
}

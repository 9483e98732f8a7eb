/*
 * check_octoapi.c - the OctoPrint calls of `stratum serve` beyond the
 * upload path, one test per call, checking the status codes and JSON
 * fields of OctoPrint's REST API (docs/serve.md, "OctoPrint conformance"):
 * login, current user, server, settings, files (list, one, new folder,
 * select, move, copy, delete, download), tool, bed, print head, SD card,
 * chamber, system commands, printer profiles, the key forms, HEAD and
 * OPTIONS, and /api/job's estimate, time left and filament (the push API:
 * check_octopush.c).  The node runs as a child process (servetest.h) with
 * `port = test-instant` printers, or `port = sim` where the G-code that
 * reached the printer is checked in the simulator's log.
 */
#include <check.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "servetest.h"
#include "suites.h"
#include "testutil.h"

#define CTL "X-Api-Key: " KEY_CTL
#define UP "X-Api-Key: " KEY_UP
#define RO "X-Api-Key: " KEY_READ
#define NODE_KEY_LEN 32 /* OctoPrint's API key: 32 hex digits */

/* A test-instant Prusa and a test-instant Creator Pro (two extruders). */
#define MK3S_AND_CREATOR                                                             \
	"[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n\n"          \
	"[printer cp]\nprofile = flashforge-creator-pro\nport = test-instant\n"

/* G-code that says its estimate and filament as PrusaSlicer writes them,
 * with M73 marks, and dwells so a test can hold it printing. */
static const char estimated[] =
	"M73 P0 R10\nG4 S1\nM73 P50 R5\nG4 S%d\nM73 P100 R0\n"
	"; filament used [mm] = 812.5\n; filament used [cm3] = 1.95\n"
	"; estimated printing time (normal mode) = 10m 2s\n";

static void start(struct node_proc *np, const char *printers)
{
	sv_write_config(np, printers, 8);
	sv_start(np);
}

/* Store a G-code text in folder (may be "") of mk3s without printing it. */
static void store(int port, const char *folder, const char *name, const char *text)
{
	struct resp r;

	sv_upload(port, "", KEY_UP, name, strlen(name), folder, strlen(folder), "false", text,
		  strlen(text), NULL, true, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	sv_resp_free(&r);
}

/* Whether the file exists under the node's files of printer. */
static bool stored(const struct node_proc *np, const char *printer, const char *rel)
{
	char path[1024];
	struct stat st;

	snprintf(path, sizeof(path), "%s/data/files/%s/%s", np->dir, printer, rel);
	return stat(path, &st) == 0;
}

/* A G-code text that dwells secs seconds (a job held printing). */
static char *dwell(int secs)
{
	static char text[512];

	snprintf(text, sizeof(text), estimated, secs);
	return text;
}

/* ---- who asks: login, current user, server, keys ------------------------ */

START_TEST(test_login_passive)
{
	struct node_proc np;
	struct resp r;
	json_t *perm;

	start(&np, TWO_PRINTERS);
	sv_call(np.port, "POST", "/api/login", CTL, "{\"passive\":true}", 200, &r);
	ck_assert_str_eq(sv_str(r.json, "name"), "operator");
	ck_assert(json_is_true(json_object_get(r.json, "active")));
	ck_assert(json_is_true(json_object_get(r.json, "admin")));
	ck_assert(json_is_true(json_object_get(r.json, "user")));
	ck_assert(json_object_get(r.json, "session"));
	perm = json_object_get(r.json, "permissions");
	ck_assert(json_is_array(perm) && json_array_size(perm) > 0);
	ck_assert_msg(!strstr(r.body, KEY_CTL), "the key is echoed: %s", r.body);
	sv_resp_free(&r);
	sv_call(np.port, "POST", "/api/login", RO, "{\"passive\":true}", 200, &r);
	ck_assert_str_eq(sv_str(r.json, "name"), "viewer");
	ck_assert(json_is_false(json_object_get(r.json, "admin")));
	ck_assert_msg(!strstr(r.body, "\"PRINT\""), "%s", r.body);
	sv_resp_free(&r);
	/* OctoPrint: a passive login without a user is 204; no passwords here */
	sv_expect(np.port, "POST", "/api/login", NULL, "{\"passive\":true}", 204);
	sv_expect(np.port, "POST", "/api/login", "X-Api-Key: wrong-key-000000000000",
		  "{\"passive\":true}", 204);
	sv_expect(np.port, "POST", "/api/login", NULL, "{\"user\":\"a\",\"pass\":\"b\"}", 403);
	sv_expect(np.port, "POST", "/api/login", CTL, "{}", 400);
	sv_stop(&np);
}
END_TEST

START_TEST(test_currentuser)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	sv_call(np.port, "GET", "/api/currentuser", UP, NULL, 200, &r);
	ck_assert_str_eq(sv_str(r.json, "name"), "slicer");
	ck_assert_msg(strstr(r.body, "\"FILES_UPLOAD\"") && !strstr(r.body, "\"CONTROL\""), "%s",
		      r.body);
	ck_assert(json_is_array(json_object_get(r.json, "groups")));
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/currentuser", NULL, NULL, 403);
	sv_stop(&np);
}
END_TEST

START_TEST(test_server)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	sv_call(np.port, "GET", "/api/server", RO, NULL, 200, &r);
	ck_assert_str_eq(sv_str(r.json, "version"), "1.10.0");
	ck_assert(json_is_null(json_object_get(r.json, "safemode")));
	sv_resp_free(&r);
	sv_stop(&np);
}
END_TEST

/* X-Api-Key, Authorization: Bearer and ?apikey= are the same key. */
START_TEST(test_key_forms)
{
	struct node_proc np;

	start(&np, TWO_PRINTERS);
	sv_expect(np.port, "GET", "/api/job", "Authorization: Bearer " KEY_READ, NULL, 200);
	sv_expect(np.port, "GET", "/api/job?apikey=" KEY_READ, NULL, NULL, 200);
	sv_expect(np.port, "GET", "/api/job?apikey=not-a-key-0000000000", NULL, NULL, 403);
	/* the query key has its roles, no more */
	sv_expect(np.port, "POST", "/api/job?apikey=" KEY_READ, NULL, "{\"command\":\"cancel\"}",
		  403);
	sv_stop(&np);
}
END_TEST

/* `stratum serve --new-key NAME --roles ...` (issue 20): OctoPrint's key
 * form, added to the config (mode 0600), taken in each of the three forms
 * with its roles only; a second key of the name is refused. */
START_TEST(test_new_key)
{
	struct node_proc np;
	char out[512], hdr[128], path[128], key[NODE_KEY_LEN + 1], *before, *after;
	size_t len;
	struct stat st;
	struct resp r;

	sv_write_config(&np, TWO_PRINTERS, 8);
	chmod(np.config, 0644);
	/* stdout has the key alone */
	ck_assert_int_eq(tu_sh(out, sizeof(out), "('%s' serve --config '%s' --new-key farm-app "
				  "--roles 'read, control' >'%s')", tu_bin(), np.config,
			       tu_path("key.txt")), 0);
	ck_assert_msg(strstr(out, "added [key farm-app]"), "%s", out);
	before = tu_slurp(tu_path("key.txt"), &len);
	ck_assert_msg(strlen(before) == NODE_KEY_LEN + 1 && before[NODE_KEY_LEN] == '\n' &&
		      strspn(before, "0123456789ABCDEF") == NODE_KEY_LEN, "not a key: '%s'", before);
	memcpy(key, before, NODE_KEY_LEN);
	free(before);
	key[NODE_KEY_LEN] = '\0';
	ck_assert(stat(np.config, &st) == 0);
	ck_assert_int_eq(st.st_mode & 0777, 0600);
	before = tu_slurp(np.config, &len);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "'%s' serve --config '%s' --new-key farm-app "
				  "--roles read", tu_bin(), np.config), 65);
	ck_assert_msg(strstr(out, "[key farm-app] exists already"), "%s", out);
	after = tu_slurp(np.config, &len);
	ck_assert_str_eq(before, after);
	free(before);
	free(after);
	ck_assert_int_eq(tu_sh(out, sizeof(out), "'%s' serve --config '%s' --new-key x "
				  "--roles admin", tu_bin(), np.config), 2);
	ck_assert_msg(strstr(out, "--roles: 'admin'"), "%s", out);
	sv_start(&np);
	snprintf(hdr, sizeof(hdr), "X-Api-Key: %s", key);
	sv_call(np.port, "GET", "/api/currentuser", hdr, NULL, 200, &r);
	ck_assert_str_eq(sv_str(r.json, "name"), "farm-app");
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", hdr, "{\"command\":\"cancel\"}", 409);
	snprintf(hdr, sizeof(hdr), "Authorization: Bearer %s", key);
	sv_expect(np.port, "GET", "/api/job", hdr, NULL, 200);
	snprintf(path, sizeof(path), "/api/job?apikey=%s", key);
	sv_expect(np.port, "GET", path, NULL, NULL, 200);
	/* read and control, not upload */
	sv_upload_text(np.port, "", key, "a.gcode", "G28\n", "false", &r);
	ck_assert_int_eq(r.status, 403);
	sv_resp_free(&r);
	sv_stop(&np);
}
END_TEST

/* HEAD answers GET's head; OPTIONS and a wrong method name the methods. */
START_TEST(test_head_options_405)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	sv_call(np.port, "HEAD", "/api/version", RO, NULL, 200, &r);
	ck_assert_msg(!r.body[0], "HEAD has a body: %s", r.body);
	ck_assert(sv_has_text(r.head, "Content-Type: application/json"));
	sv_resp_free(&r);
	sv_call(np.port, "OPTIONS", "/api/job", NULL, NULL, 200, &r);
	ck_assert_msg(sv_has_text(r.head, "Allow: GET, HEAD, POST, OPTIONS"), "%s", r.head);
	sv_resp_free(&r);
	sv_call(np.port, "PUT", "/api/job", CTL, "{}", 405, &r);
	ck_assert_msg(sv_has_text(r.head, "Allow: GET, HEAD, POST, OPTIONS"), "%s", r.head);
	ck_assert(json_string_value(json_object_get(r.json, "error")));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/printer/printhead", CTL, NULL, 405, &r);
	ck_assert_msg(sv_has_text(r.head, "Allow: POST, OPTIONS"), "%s", r.head);
	sv_resp_free(&r);
	sv_call(np.port, "DELETE", "/api/files/local/x.gcode", CTL, NULL, 404, &r);
	sv_resp_free(&r);
	sv_expect(np.port, "OPTIONS", "/api/no-such-call", NULL, NULL, 404);
	sv_stop(&np);
}
END_TEST

START_TEST(test_system_commands)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	sv_call(np.port, "GET", "/api/system/commands", CTL, NULL, 200, &r);
	ck_assert(json_is_array(json_object_get(r.json, "core")) &&
		  !json_array_size(json_object_get(r.json, "core")));
	ck_assert(json_is_array(json_object_get(r.json, "custom")));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/system/commands/core", CTL, NULL, 200, &r);
	ck_assert(json_is_array(r.json) && !json_array_size(r.json));
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/system/commands/other", CTL, NULL, 404);
	sv_expect(np.port, "GET", "/api/system/commands", RO, NULL, 403);
	sv_stop(&np);
}
END_TEST

/* The settings are the config file: OctoPrint's 403 for a user who may
 * not change them. */
START_TEST(test_settings_post)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	sv_call(np.port, "POST", "/api/settings", CTL, "{\"appearance\":{\"name\":\"x\"}}", 403,
		&r);
	ck_assert_msg(strstr(sv_str(r.json, "error"), "config file"), "%s", r.body);
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/settings", RO, NULL, 200, &r);
	ck_assert(json_object_get(r.json, "feature"));
	sv_resp_free(&r);
	sv_stop(&np);
}
END_TEST

START_TEST(test_printerprofile_by_id)
{
	struct node_proc np;
	struct resp r;

	start(&np, MK3S_AND_CREATOR);
	sv_call(np.port, "GET", "/p/cp/api/printerprofiles/cp", RO, NULL, 200, &r);
	ck_assert_str_eq(sv_str(r.json, "id"), "cp");
	ck_assert_int_eq(json_integer_value(json_object_get(json_object_get(r.json, "extruder"),
							   "count")), 2);
	ck_assert(json_is_object(json_object_get(r.json, "volume")));
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/printerprofiles/cp", RO, NULL, 404); /* mk3s's prefix */
	sv_expect(np.port, "GET", "/api/printerprofiles/mk3s", RO, NULL, 200);
	sv_stop(&np);
}
END_TEST

/* ---- files ----------------------------------------------------------------- */

/* The entry called name in a list, or NULL. */
static json_t *entry(json_t *list, const char *name)
{
	size_t i;
	json_t *e;

	json_array_foreach(list, i, e)
		if (!strcmp(json_string_value(json_object_get(e, "name")), name))
			return e;
	return NULL;
}

START_TEST(test_files_list)
{
	struct node_proc np;
	struct resp r;
	json_t *e, *dir, *an;
	char want[256];

	start(&np, TWO_PRINTERS);
	store(np.port, "", "top.gcode", dwell(1));
	store(np.port, "parts", "inner.gcode", "G1 X1\n");
	for (int i = 0; i < 2; i++) {
		sv_call(np.port, "GET", i ? "/api/files/local" : "/api/files", RO, NULL, 200, &r);
		ck_assert(json_integer_value(json_object_get(r.json, "free")) > 0);
		ck_assert(json_integer_value(json_object_get(r.json, "total")) > 0);
		e = entry(json_object_get(r.json, "files"), "top.gcode");
		ck_assert_msg(e, "%s", r.body);
		ck_assert_str_eq(sv_str(e, "path"), "top.gcode");
		ck_assert_str_eq(sv_str(e, "type"), "machinecode");
		ck_assert_str_eq(sv_str(e, "origin"), "local");
		snprintf(want, sizeof(want), "http://127.0.0.1:%d/api/files/local/top.gcode", np.port);
		ck_assert_str_eq(sv_str(json_object_get(e, "refs"), "resource"), want);
		snprintf(want, sizeof(want), "http://127.0.0.1:%d/downloads/files/local/top.gcode",
			 np.port);
		ck_assert_str_eq(sv_str(json_object_get(e, "refs"), "download"), want);
		an = json_object_get(e, "gcodeAnalysis");
		ck_assert_int_eq(json_integer_value(json_object_get(an, "estimatedPrintTime")), 602);
		dir = entry(json_object_get(r.json, "files"), "parts");
		ck_assert_str_eq(sv_str(dir, "type"), "folder");
		ck_assert_msg(!json_object_get(dir, "children"), "not recursive: %s", r.body);
		sv_resp_free(&r);
	}
	sv_call(np.port, "GET", "/api/files?recursive=true", RO, NULL, 200, &r);
	dir = entry(json_object_get(r.json, "files"), "parts");
	e = entry(json_object_get(dir, "children"), "inner.gcode");
	ck_assert_msg(e, "%s", r.body);
	ck_assert_str_eq(sv_str(e, "path"), "parts/inner.gcode");
	snprintf(want, sizeof(want), "http://127.0.0.1:%d/downloads/files/local/parts/inner.gcode",
		 np.port);
	ck_assert_str_eq(sv_str(json_object_get(e, "refs"), "download"), want);
	sv_resp_free(&r);
	/* a large file: the footer is read (PrusaSlicer writes its estimate there) */
	{
		size_t n = 700000, k = 0;
		char *big = malloc(n + 100);

		ck_assert(big);
		while (k + 10 < n)
			k += (size_t)sprintf(big + k, "G1 X%d\n", (int)(k % 100));
		sprintf(big + k, "; estimated printing time (normal mode) = 2h 0m 5s\n");
		store(np.port, "", "big.gcode", big);
		free(big);
	}
	sv_call(np.port, "GET", "/api/files/local/big.gcode", RO, NULL, 200, &r);
	ck_assert_int_eq(json_integer_value(json_object_get(json_object_get(r.json, "gcodeAnalysis"),
							   "estimatedPrintTime")), 7205);
	sv_resp_free(&r);
	/* the other printer's files are its own */
	sv_call(np.port, "GET", "/p/ender/api/files", RO, NULL, 200, &r);
	ck_assert_int_eq(json_array_size(json_object_get(r.json, "files")), 0);
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/files", NULL, NULL, 403);
	sv_stop(&np);
}
END_TEST

/* POST /api/files/local with foldername (and path) and no file: OctoPrint's
 * new folder, 201; 409 when it exists. */
static void new_folder(int port, const char *path, const char *name, int want, struct resp *r)
{
	char body[1024], req[2048];
	int n = snprintf(body, sizeof(body),
			 "--" BOUNDARY "\r\nContent-Disposition: form-data; name=\"foldername\"\r\n\r\n"
			 "%s\r\n--" BOUNDARY "\r\nContent-Disposition: form-data; name=\"path\"\r\n\r\n"
			 "%s\r\n--" BOUNDARY "--\r\n", name, path);
	int m = snprintf(req, sizeof(req),
			 "POST /api/files/local HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n" UP "\r\n"
			 "Connection: close\r\nContent-Length: %d\r\n"
			 "Content-Type: multipart/form-data; boundary=" BOUNDARY "\r\n\r\n%s",
			 port, n, body);

	sv_http_raw(port, req, (size_t)m, r);
	ck_assert_msg(r->status == want, "new folder %s/%s: %d, not %d: %s", path, name, r->status,
		      want, r->body);
}

START_TEST(test_folder_create)
{
	struct node_proc np;
	struct resp r;
	char want[256];

	start(&np, TWO_PRINTERS);
	new_folder(np.port, "", "parts", 201, &r);
	ck_assert_str_eq(sv_str(json_object_get(r.json, "folder"), "path"), "parts");
	snprintf(want, sizeof(want), "Location: http://127.0.0.1:%d/api/files/local/parts", np.port);
	ck_assert_msg(sv_has_text(r.head, want), "%s", r.head);
	sv_resp_free(&r);
	new_folder(np.port, "parts", "brackets", 201, &r);
	ck_assert_str_eq(sv_str(json_object_get(r.json, "folder"), "path"), "parts/brackets");
	sv_resp_free(&r);
	ck_assert(stored(&np, "mk3s", "parts/brackets"));
	new_folder(np.port, "", "parts", 409, &r);
	sv_resp_free(&r);
	new_folder(np.port, "none", "x", 409, &r);
	sv_resp_free(&r);
	new_folder(np.port, "", "..", 400, &r);
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/files/local/parts?recursive=true", RO, NULL, 200, &r);
	ck_assert_str_eq(sv_str(json_array_get(json_object_get(r.json, "children"), 0), "type"),
			 "folder");
	sv_resp_free(&r);
	sv_stop(&np);
}
END_TEST

START_TEST(test_file_get)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	store(np.port, "parts", "inner.gcode", "G1 X1\n");
	sv_call(np.port, "GET", "/api/files/local/parts/inner.gcode", RO, NULL, 200, &r);
	ck_assert_str_eq(sv_str(r.json, "name"), "inner.gcode");
	ck_assert_int_eq(json_integer_value(json_object_get(r.json, "size")), 6);
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/files/local/parts", RO, NULL, 200, &r);
	ck_assert_str_eq(sv_str(r.json, "type"), "folder");
	ck_assert(entry(json_object_get(r.json, "children"), "inner.gcode"));
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/files/local/none.gcode", RO, NULL, 404);
	sv_expect(np.port, "GET", "/api/files/local/../node.ini", RO, NULL, 404);
	sv_expect(np.port, "GET", "/api/files/local/parts/%2e%2e/%2e%2e/node.ini", RO, NULL, 404);
	sv_stop(&np);
}
END_TEST

START_TEST(test_file_select)
{
	struct node_proc np;
	struct resp r;
	json_t *queue;

	start(&np, TWO_PRINTERS);
	sv_operational(np.port, "");
	store(np.port, "", "a.gcode", dwell(3));
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP, "{\"command\":\"select\"}", 204);
	sv_call(np.port, "GET", "/api/job", RO, NULL, 200, &r);
	ck_assert_str_eq(sv_str(json_object_get(json_object_get(r.json, "job"), "file"), "name"),
			 "a.gcode");
	sv_resp_free(&r);
	/* print=true starts a print: the control role */
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP,
		  "{\"command\":\"select\",\"print\":true}", 403);
	sv_bed_clear(np.port, "", 204);
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", CTL,
		  "{\"command\":\"select\",\"print\":true}", 204);
	queue = sv_get_json(np.port, "/api/stratum/queue");
	ck_assert_int_eq(json_array_size(json_object_get(queue, "jobs")), 1);
	json_decref(queue);
	sv_wait_state(np.port, "", 1, "printing", 10);
	/* OctoPrint refuses a new selection while it prints */
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", CTL,
		  "{\"command\":\"select\",\"print\":true}", 409);
	sv_expect(np.port, "POST", "/api/files/local/none.gcode", CTL, "{\"command\":\"select\"}",
		  404);
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", CTL, "{\"command\":\"frobnicate\"}",
		  400);
	sv_stop(&np);
}
END_TEST

START_TEST(test_file_move_copy)
{
	struct node_proc np;
	struct resp r;
	char want[256];

	start(&np, TWO_PRINTERS);
	sv_operational(np.port, "");
	store(np.port, "", "a.gcode", dwell(3));
	store(np.port, "parts", "b.gcode", "G1 X2\n");
	sv_call(np.port, "POST", "/api/files/local/a.gcode", UP,
	     "{\"command\":\"copy\",\"destination\":\"parts\"}", 201, &r);
	snprintf(want, sizeof(want), "Location: http://127.0.0.1:%d/api/files/local/parts/a.gcode",
		 np.port);
	ck_assert_msg(sv_has_text(r.head, want), "%s", r.head);
	ck_assert_str_eq(sv_str(r.json, "path"), "parts/a.gcode");
	ck_assert(json_object_get(json_object_get(r.json, "refs"), "download"));
	sv_resp_free(&r);
	ck_assert(stored(&np, "mk3s", "a.gcode") && stored(&np, "mk3s", "parts/a.gcode"));
	/* onto a file that exists: 409, nothing replaced */
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP,
		  "{\"command\":\"move\",\"destination\":\"parts/b.gcode\"}", 409);
	sv_call(np.port, "POST", "/api/files/local/parts/b.gcode", UP,
	     "{\"command\":\"move\",\"destination\":\"c.gcode\"}", 201, &r);
	ck_assert_str_eq(sv_str(r.json, "name"), "c.gcode");
	sv_resp_free(&r);
	ck_assert(!stored(&np, "mk3s", "parts/b.gcode") && stored(&np, "mk3s", "c.gcode"));
	sv_expect(np.port, "POST", "/api/files/local/c.gcode", UP,
		  "{\"command\":\"move\",\"destination\":\"../c.gcode\"}", 400);
	sv_expect(np.port, "POST", "/api/files/local/c.gcode", UP,
		  "{\"command\":\"move\",\"destination\":\"c.stl\"}", 400);
	sv_expect(np.port, "POST", "/api/files/local/c.gcode", UP,
		  "{\"command\":\"move\",\"destination\":\"nofolder/c.gcode\"}", 409);
	/* a file a job prints does not move */
	sv_bed_clear(np.port, "", 204);
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", CTL,
		  "{\"command\":\"select\",\"print\":true}", 204);
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP,
		  "{\"command\":\"move\",\"destination\":\"d.gcode\"}", 409);
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP,
		  "{\"command\":\"copy\",\"destination\":\"d.gcode\"}", 201);
	sv_stop(&np);
}
END_TEST

START_TEST(test_file_delete)
{
	struct node_proc np;

	start(&np, TWO_PRINTERS);
	sv_operational(np.port, "");
	store(np.port, "", "a.gcode", dwell(3));
	store(np.port, "parts", "b.gcode", "G1 X2\n");
	sv_expect(np.port, "DELETE", "/api/files/local/parts/b.gcode", RO, NULL, 403);
	sv_expect(np.port, "DELETE", "/api/files/local/parts/b.gcode", UP, NULL, 204);
	ck_assert(!stored(&np, "mk3s", "parts/b.gcode"));
	sv_expect(np.port, "DELETE", "/api/files/local/parts/b.gcode", UP, NULL, 404);
	sv_expect(np.port, "DELETE", "/api/files/local/parts", UP, NULL, 204);
	ck_assert(!stored(&np, "mk3s", "parts"));
	/* 409 while printing that file */
	sv_bed_clear(np.port, "", 204);
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", CTL,
		  "{\"command\":\"select\",\"print\":true}", 204);
	sv_wait_state(np.port, "", 1, "printing", 10);
	sv_expect(np.port, "DELETE", "/api/files/local/a.gcode", UP, NULL, 409);
	ck_assert(stored(&np, "mk3s", "a.gcode"));
	sv_wait_state(np.port, "", 1, "done", 20);
	sv_expect(np.port, "DELETE", "/api/files/local/a.gcode", UP, NULL, 204);
	sv_stop(&np);
}
END_TEST

START_TEST(test_download)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	store(np.port, "parts", "b.gcode", "G1 X2\nG1 Y3\n");
	sv_call(np.port, "GET", "/downloads/files/local/parts/b.gcode", RO, NULL, 200, &r);
	ck_assert_str_eq(r.body, "G1 X2\nG1 Y3\n");
	ck_assert(sv_has_text(r.head, "Content-Type: application/octet-stream"));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/p/mk3s/downloads/files/local/parts/b.gcode", RO, NULL, 200, &r);
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/downloads/files/local/parts/none.gcode", RO, NULL, 404);
	sv_expect(np.port, "GET", "/downloads/files/local/parts", RO, NULL, 404);
	sv_expect(np.port, "GET", "/downloads/files/local/parts/b.gcode", NULL, NULL, 403);
	sv_stop(&np);
}
END_TEST

/* ---- printer components ------------------------------------------------------ */

START_TEST(test_printer_tool)
{
	struct node_proc np;
	struct resp r;
	json_t *t;

	start(&np, MK3S_AND_CREATOR);
	sv_operational(np.port, "");
	sv_operational(np.port, "/p/cp");
	sv_call(np.port, "GET", "/api/printer/tool", RO, NULL, 200, &r);
	ck_assert(json_is_number(json_object_get(json_object_get(r.json, "tool0"), "actual")));
	ck_assert(!json_object_get(r.json, "tool1"));
	ck_assert(!json_object_get(r.json, "bed"));
	sv_resp_free(&r);
	/* the Creator Pro has two extruders: tool1 is there */
	sv_call(np.port, "GET", "/p/cp/api/printer/tool", RO, NULL, 200, &r);
	ck_assert(json_is_object(json_object_get(r.json, "tool1")));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/p/cp/api/printer", RO, NULL, 200, &r);
	ck_assert(json_object_get(json_object_get(r.json, "temperature"), "tool1"));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/p/cp/api/printer?exclude=sd,temperature", RO, NULL, 200, &r);
	ck_assert(!json_object_get(r.json, "temperature") && !json_object_get(r.json, "sd"));
	ck_assert(json_object_get(r.json, "state"));
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":205}}", 204);
	/* the test double reaches a target at once: it was sent */
	for (int i = 0; i < 100; i++) {
		sv_call(np.port, "GET", "/api/printer/tool", RO, NULL, 200, &r);
		t = json_object_get(r.json, "tool0");
		if (json_number_value(json_object_get(t, "target")) == 205)
			break;
		sv_resp_free(&r);
		usleep(20000);
	}
	ck_assert_msg(json_number_value(json_object_get(t, "target")) == 205, "%s", r.body);
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool1\":205}}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":9999}}", 400);
	sv_expect(np.port, "POST", "/p/cp/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool1\":210}}", 204);
	sv_expect(np.port, "POST", "/p/cp/api/printer/tool", CTL,
		  "{\"command\":\"select\",\"tool\":\"tool1\"}", 204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"extrude\",\"amount\":5}", 204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"flowrate\",\"factor\":95}", 204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"flowrate\",\"factor\":300}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"offset\",\"offsets\":{\"tool0\":5}}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", UP,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":205}}", 403);
	/* not operational: 409 */
	sv_expect(np.port, "POST", "/api/connection", CTL, "{\"command\":\"disconnect\"}", 204);
	usleep(300000);
	sv_expect(np.port, "GET", "/api/printer/tool", RO, NULL, 409);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":205}}", 409);
	sv_stop(&np);
}
END_TEST

START_TEST(test_printer_bed)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	sv_operational(np.port, "");
	sv_call(np.port, "GET", "/api/printer/bed", RO, NULL, 200, &r);
	ck_assert(json_is_number(json_object_get(json_object_get(r.json, "bed"), "target")));
	ck_assert(!json_object_get(r.json, "tool0"));
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"target\",\"target\":60}",
		  204);
	/* the history: samples every 2 s, the last `limit` of them, oldest first */
	for (int i = 0; i < 80; i++) {
		json_t *h, *last;

		sv_call(np.port, "GET", "/api/printer/bed?history=true&limit=2", RO, NULL, 200, &r);
		h = json_object_get(r.json, "history");
		ck_assert_msg(json_is_array(h) && json_array_size(h) <= 2, "%s", r.body);
		last = json_array_get(h, json_array_size(h) - 1);
		if (json_number_value(json_object_get(json_object_get(last, "bed"), "target")) == 60)
			break;
		sv_resp_free(&r);
		usleep(100000);
	}
	ck_assert_msg(r.json, "no sample with the bed's target");
	ck_assert(json_integer_value(json_object_get(json_array_get(json_object_get(r.json,
											  "history"),
								    0), "time")) > 0);
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/printer/tool?history=true", RO, NULL, 200, &r);
	ck_assert(!json_object_get(json_array_get(json_object_get(r.json, "history"), 0), "bed"));
	ck_assert(json_object_get(json_array_get(json_object_get(r.json, "history"), 0), "tool0"));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	ck_assert(!json_object_get(json_object_get(r.json, "temperature"), "history"));
	sv_resp_free(&r);
	sv_call(np.port, "GET", "/api/printer?history=true&limit=1", RO, NULL, 200, &r);
	ck_assert_int_eq(json_array_size(json_object_get(json_object_get(r.json, "temperature"),
							 "history")), 1);
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"target\"}", 400);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"offset\",\"offset\":5}",
		  400);
	/* no printer of the node has a heated chamber or an SD card */
	sv_expect(np.port, "GET", "/api/printer/chamber", RO, NULL, 409);
	sv_expect(np.port, "POST", "/api/printer/chamber", CTL,
		  "{\"command\":\"target\",\"target\":40}", 409);
	sv_call(np.port, "GET", "/api/printer/sd", RO, NULL, 404, &r);
	ck_assert_str_eq(sv_str(r.json, "error"), "SD support is disabled");
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/sd", CTL, "{\"command\":\"init\"}", 404);
	sv_stop(&np);
}
END_TEST

/* Jog, home and feed rate reach the simulated Marlin printer as OctoPrint
 * sends them; refused while printing. */
START_TEST(test_printer_printhead)
{
	struct node_proc np;
	char path[600], *log = NULL;
	size_t len;

	start(&np, "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = sim\nsim_speedup = 1000\n");
	sv_operational(np.port, ""); /* the sim's boot done */
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"home\",\"axes\":[\"x\",\"y\"]}", 204);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"jog\",\"x\":10,\"y\":-5,\"speed\":3000}", 204);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"feedrate\",\"factor\":90}", 204);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"jog\",\"x\":\"far\"}", 400);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"home\",\"axes\":[\"q\"]}", 400);
	snprintf(path, sizeof(path), "%s/data/sim/mk3s.log", np.dir);
	for (int i = 0; i < 250; i++) {
		free(log);
		log = access(path, R_OK) ? NULL : tu_slurp(path, &len);
		if (log && strstr(log, "M220 S90"))
			break;
		usleep(20000);
	}
	ck_assert_msg(log && strstr(log, "G28 X0 Y0") && strstr(log, "G1 X10 Y-5 F3000") &&
		      strstr(log, "M220 S90"), "%s", log ? log : "(no log)");
	free(log);
	/* while printing, OctoPrint refuses the print head: 409 */
	sv_bed_clear(np.port, "", 204);
	ck_assert(sv_print_text(np.port, "", "long.gcode", "G4 S30\n") == 1);
	sv_wait_state(np.port, "", 1, "printing", 10);
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"home\",\"axes\":[\"z\"]}", 409);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_stop(&np);
}
END_TEST

/*
 * Commands during a print (OctoPrint queues them between the job's lines):
 * on a Marlin printer (`port = sim`) a command and a tool target posted
 * while the job streams run once each, between two lines of the job, whose
 * lines all run once and in order (the simulator's log: every line number
 * once, in order); the print head's jog and a tool select stay 409.
 */
/* The log walk of test_command_during_print: the job's lines and ours. */
struct ours_in_job {
	const char *const *ours;
	const char *job, *rest; /* the job's text, and its lines still due */
	int seen[2], inside[2];
};

static void ours_in_job_line(void *ctx, const char *text)
{
	struct ours_in_job *w = ctx;
	size_t tl = strlen(text);

	for (int i = 0; i < 2; i++) {
		if (!strcmp(text, w->ours[i])) {
			w->seen[i]++;
			/* after the first job line, before the last */
			w->inside[i] = w->rest != w->job && *w->rest;
			return;
		}
	}
	ck_assert_msg(!strncmp(w->rest, text, tl) && w->rest[tl] == '\n',
		      "the job ran '%s' where '%.40s' was due", text, w->rest);
	w->rest += tl + 1;
}

START_TEST(test_command_during_print)
{
	static const char *const ours[] = {"M117 sent during the print", "M104 S205"};
	struct node_proc np;
	struct ours_in_job w = {.ours = ours};
	char path[600], *job;
	size_t cap = 64 * 1024, len = 0;
	json_t *o;
	double pos = 0;

	job = malloc(cap);
	ck_assert(job);
	len += (size_t)snprintf(job + len, cap - len, "M117 job start\nG28\n");
	for (int k = 0; k < 160; k++)
		len += (size_t)snprintf(job + len, cap - len, "G1 X%d Y%d F60\n", 10 + k % 2, 10 + k);
	snprintf(job + len, cap - len, "M117 job end\n");
	start(&np, "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = sim\nsim_speedup = 40\n");
	sv_operational(np.port, "");
	ck_assert(sv_print_text(np.port, "", "moves.gcode", job) == 1);
	sv_wait_state(np.port, "", 1, "printing", 10);
	for (int i = 0; i < 250 && pos <= 0; i++) {
		o = sv_get_json(np.port, "/api/job");
		pos = json_number_value(json_object_get(json_object_get(o, "progress"), "filepos"));
		json_decref(o);
		usleep(20000);
	}
	ck_assert_msg(pos > 0, "the job did not start streaming");
	sv_expect(np.port, "POST", "/api/printer/command", CTL,
		  "{\"command\":\"M117 sent during the print\"}", 204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":205}}", 204);
	/* as OctoPrint: no jog, home, tool select or extrusion while printing */
	sv_expect(np.port, "POST", "/api/printer/printhead", CTL,
		  "{\"command\":\"jog\",\"x\":10}", 409);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"extrude\",\"amount\":5}", 409);
	sv_wait_state(np.port, "", 1, "done", 30);
	/* The simulator's log from the job's first line: the job whole, in
	 * order, with each command once inside it. */
	snprintf(path, sizeof(path), "%s/data/sim/mk3s.log", np.dir);
	w.job = w.rest = job;
	sv_marlin_log(path, "M117 job start", ours_in_job_line, &w);
	ck_assert_msg(!*w.rest, "the job's lines from '%.40s' did not run", w.rest);
	for (int i = 0; i < 2; i++)
		ck_assert_msg(w.seen[i] == 1 && w.inside[i], "'%s' ran %d times%s", ours[i], w.seen[i],
			      w.inside[i] ? "" : ", not between two lines of the job");
	free(job);
	sv_stop(&np);
}
END_TEST

/*
 * Temperature offsets (OctoPrint's "offset" of the tool and the bed): on a
 * Marlin printer they are reported and added to the file's targets as it
 * streams (a heater turned off stays off); test-instant printers refuse
 * them (400, test_printer_tool).
 */
START_TEST(test_temperature_offsets)
{
	struct node_proc np;
	struct resp r;
	char path[600], *log = NULL;
	json_t *temp;
	size_t len;

	start(&np, "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = sim\nsim_speedup = 1000\n");
	sv_operational(np.port, "");
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"offset\",\"offsets\":{\"tool0\":10}}", 204);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"offset\",\"offset\":-5}",
		  204);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"offset\",\"offsets\":{\"tool0\":60}}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"offset\",\"offsets\":{\"tool3\":5}}", 400);
	sv_expect(np.port, "POST", "/api/printer/tool", UP,
		  "{\"command\":\"offset\",\"offsets\":{\"tool0\":5}}", 403);
	sv_call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	temp = json_object_get(r.json, "temperature");
	ck_assert_msg(json_number_value(json_object_get(json_object_get(temp, "tool0"), "offset")) ==
			      10 &&
		      json_number_value(json_object_get(json_object_get(temp, "bed"), "offset")) ==
			      -5, "%s", r.body);
	sv_resp_free(&r);
	sv_bed_clear(np.port, "", 204);
	ck_assert(sv_print_text(np.port, "", "temps.gcode",
				"M104 S200\nM140 S60\nG1 X5 F600\nM104 S0\nM140 S0\n") == 1);
	sv_wait_state(np.port, "", 1, "done", 20);
	snprintf(path, sizeof(path), "%s/data/sim/mk3s.log", np.dir);
	log = tu_slurp(path, &len);
	ck_assert_msg(strstr(log, " M104 S210\n") && strstr(log, " M140 S55\n") &&
		      strstr(log, " M104 S0\n") && strstr(log, " M140 S0\n") &&
		      !strstr(log, " M104 S200\n") && !strstr(log, " M140 S60\n"),
		      "the offsets were not applied: %s", log);
	free(log);
	sv_stop(&np);
}
END_TEST

/*
 * The Creator Pro's second extruder (issue 20): the Sailfish driver reads
 * tool 1 too, so /api/printer/tool has its temperatures, and a target set
 * for it shows (the simulated printer heats it); a one-extruder printer
 * has no tool1.
 */
START_TEST(test_sailfish_tool1)
{
	struct node_proc np;
	struct resp r;
	json_t *t1 = NULL;
	double target = 0;

	start(&np, "[printer cp]\nprofile = flashforge-creator-pro\nport = sim\n"
		   "sim_speedup = 1000\n");
	sv_operational(np.port, "");
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool1\":150}}", 204);
	/* temperatures are read every 2 s between jobs */
	for (int i = 0; i < 300 && target != 150; i++) {
		sv_call(np.port, "GET", "/api/printer/tool", RO, NULL, 200, &r);
		t1 = json_object_get(r.json, "tool1");
		target = json_number_value(json_object_get(t1, "target"));
		if (target == 150) {
			ck_assert_msg(json_is_number(json_object_get(t1, "actual")), "%s", r.body);
			ck_assert_msg(json_number_value(json_object_get(json_object_get(r.json,
				      "tool0"), "target")) == 0, "%s", r.body);
		}
		sv_resp_free(&r);
		if (target != 150)
			usleep(20000);
	}
	ck_assert_msg(target == 150, "tool1's target never showed");
	sv_stop(&np);
}
END_TEST

/* ---- job ---------------------------------------------------------------------- */

/* /api/job: the file's estimate and filament, the time left by its M73
 * marks; flags.ready false while a job holds the printer. */
START_TEST(test_job_estimates)
{
	struct node_proc np;
	struct resp r;
	json_t *job, *prog, *fil;

	start(&np, TWO_PRINTERS);
	store(np.port, "", "a.gcode", dwell(4));
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP, "{\"command\":\"select\"}", 204);
	sv_call(np.port, "GET", "/api/job", RO, NULL, 200, &r);
	job = json_object_get(r.json, "job");
	ck_assert_int_eq(json_integer_value(json_object_get(job, "estimatedPrintTime")), 602);
	fil = json_object_get(json_object_get(job, "filament"), "tool0");
	ck_assert(json_real_value(json_object_get(fil, "length")) == 812.5);
	ck_assert(json_real_value(json_object_get(fil, "volume")) == 1.95);
	ck_assert(json_is_null(json_object_get(json_object_get(r.json, "progress"),
					       "printTimeLeft")));
	sv_resp_free(&r);
	sv_bed_clear(np.port, "", 204);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"start\"}", 204);
	sv_wait_state(np.port, "", 1, "printing", 10);
	/* past "M73 P50 R5" within the 4 s dwell */
	for (int i = 0; i < 150; i++) {
		sv_call(np.port, "GET", "/api/job", RO, NULL, 200, &r);
		prog = json_object_get(r.json, "progress");
		if (json_integer_value(json_object_get(prog, "printTimeLeft")) == 300)
			break;
		sv_resp_free(&r);
		usleep(20000);
	}
	ck_assert_msg(json_integer_value(json_object_get(prog, "printTimeLeft")) == 300, "%s",
		      r.body);
	ck_assert_str_eq(sv_str(prog, "printTimeLeftOrigin"), "estimate");
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"pause\",\"action\":\"pause\"}",
		  204);
	sv_call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	ck_assert(json_is_false(json_object_get(json_object_get(json_object_get(r.json, "state"),
								"flags"), "ready")));
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_wait_state(np.port, "", 1, "cancelled", 10);
	sv_call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	ck_assert(json_is_true(json_object_get(json_object_get(json_object_get(r.json, "state"),
							       "flags"), "ready")));
	sv_resp_free(&r);
	sv_stop(&np);
}
END_TEST

Suite *octoapi_suite(void)
{
	Suite *s = suite_create("octoapi");
	TCase *tc = tcase_create("calls");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_login_passive);
	tcase_add_test(tc, test_currentuser);
	tcase_add_test(tc, test_server);
	tcase_add_test(tc, test_key_forms);
	tcase_add_test(tc, test_new_key);
	tcase_add_test(tc, test_head_options_405);
	tcase_add_test(tc, test_system_commands);
	tcase_add_test(tc, test_settings_post);
	tcase_add_test(tc, test_printerprofile_by_id);
	tcase_add_test(tc, test_files_list);
	tcase_add_test(tc, test_folder_create);
	tcase_add_test(tc, test_file_get);
	tcase_add_test(tc, test_file_select);
	tcase_add_test(tc, test_file_move_copy);
	tcase_add_test(tc, test_file_delete);
	tcase_add_test(tc, test_download);
	tcase_add_test(tc, test_printer_tool);
	tcase_add_test(tc, test_printer_bed);
	tcase_add_test(tc, test_printer_printhead);
	tcase_add_test(tc, test_command_during_print);
	tcase_add_test(tc, test_temperature_offsets);
	tcase_add_test(tc, test_sailfish_tool1);
	tcase_add_test(tc, test_job_estimates);
	suite_add_tcase(s, tc);
	octoapi_push_tcases(s);
	octoapi_queue_tcases(s);
	octoapi_inject_tcases(s);
	return s;
}

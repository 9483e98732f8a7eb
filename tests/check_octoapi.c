/*
 * check_octoapi.c - the OctoPrint calls of `stratum serve` beyond the
 * upload path, one test per call, checking the status codes and JSON
 * fields of OctoPrint's REST API (docs/serve.md, "OctoPrint conformance"):
 * login, current user, server, settings, files (list, one, new folder,
 * select, move, copy, delete, download), tool, bed, print head, SD card,
 * chamber, system commands, printer profiles, the key forms, HEAD and
 * OPTIONS (the printer's components and /api/job's estimate, time left and
 * filament: check_octoapi_printer.c; the push API: check_octopush.c).  The node runs as a child process (servetest.h) with
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

#include "octoapitest.h"
#include "servetest.h"
#include "suites.h"
#include "testutil.h"

#define NODE_KEY_LEN 32 /* OctoPrint's API key: 32 hex digits */

/* Whether the file exists under the node's files of printer. */
static bool stored(const struct node_proc *np, const char *printer, const char *rel)
{
	char path[1024];
	struct stat st;

	snprintf(path, sizeof(path), "%s/data/files/%s/%s", np->dir, printer, rel);
	return stat(path, &st) == 0;
}

/* ---- who asks: login, current user, server, keys ------------------------ */

START_TEST(test_login_passive)
{
	struct node_proc np;
	struct resp r;
	json_t *perm;

	oa_start(&np, TWO_PRINTERS);
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

	oa_start(&np, TWO_PRINTERS);
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

	oa_start(&np, TWO_PRINTERS);
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

	oa_start(&np, TWO_PRINTERS);
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

	oa_start(&np, TWO_PRINTERS);
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

	oa_start(&np, TWO_PRINTERS);
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

	oa_start(&np, TWO_PRINTERS);
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

	oa_start(&np, MK3S_AND_CREATOR);
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

	oa_start(&np, TWO_PRINTERS);
	oa_store(np.port, "", "top.gcode", oa_dwell(1));
	oa_store(np.port, "parts", "inner.gcode", "G1 X1\n");
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
		oa_store(np.port, "", "big.gcode", big);
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

	oa_start(&np, TWO_PRINTERS);
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

	oa_start(&np, TWO_PRINTERS);
	oa_store(np.port, "parts", "inner.gcode", "G1 X1\n");
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

	oa_start(&np, TWO_PRINTERS);
	sv_operational(np.port, "");
	oa_store(np.port, "", "a.gcode", oa_dwell(3));
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

	oa_start(&np, TWO_PRINTERS);
	sv_operational(np.port, "");
	oa_store(np.port, "", "a.gcode", oa_dwell(3));
	oa_store(np.port, "parts", "b.gcode", "G1 X2\n");
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

	oa_start(&np, TWO_PRINTERS);
	sv_operational(np.port, "");
	oa_store(np.port, "", "a.gcode", oa_dwell(3));
	oa_store(np.port, "parts", "b.gcode", "G1 X2\n");
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

	oa_start(&np, TWO_PRINTERS);
	oa_store(np.port, "parts", "b.gcode", "G1 X2\nG1 Y3\n");
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
	octoapi_printer_tests(tc);
	suite_add_tcase(s, tc);
	octoapi_push_tcases(s);
	octoapi_queue_tcases(s);
	octoapi_inject_tcases(s);
	return s;
}

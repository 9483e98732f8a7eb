/*
 * check_octoapi.c - the OctoPrint calls of `stratum serve` beyond the
 * upload path (docs/serve.md, "OctoPrint conformance"): one test per call,
 * checking the status codes and JSON fields OctoPrint's REST API documents
 * (docs.octoprint.org, API 1.10): login, current user, server, files
 * (list, one, select, move, copy, delete, download), tool, bed, print head,
 * SD card, chamber, system commands, printer profiles, the key forms, HEAD
 * and OPTIONS, /api/job's estimate, time left and filament, and the push
 * API (SockJS over WebSocket, read with a wslay client).  The node
 * runs as a child process (servetest.h) with `port = test-instant`
 * printers, or `port = sim` where the G-code that reached the printer is
 * checked in the simulator's log.
 */
#include <arpa/inet.h>
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <wslay/wslay.h>
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

/* A request's answer must have status want; its JSON is kept in r. */
static void call(int port, const char *method, const char *path, const char *auth,
		 const char *body, int want, struct resp *r)
{
	sv_http(port, method, path, auth, body, r);
	ck_assert_msg(r->status == want, "%s %s: %d, not %d: %s", method, path, r->status, want,
		      r->body);
}

static const char *str(const json_t *o, const char *key)
{
	const char *s = json_string_value(json_object_get(o, key));

	ck_assert_msg(s, "no string %s in %s", key, json_dumps(o, 0));
	return s;
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
	call(np.port, "POST", "/api/login", CTL, "{\"passive\":true}", 200, &r);
	ck_assert_str_eq(str(r.json, "name"), "operator");
	ck_assert(json_is_true(json_object_get(r.json, "active")));
	ck_assert(json_is_true(json_object_get(r.json, "admin")));
	ck_assert(json_is_true(json_object_get(r.json, "user")));
	ck_assert(json_object_get(r.json, "session"));
	perm = json_object_get(r.json, "permissions");
	ck_assert(json_is_array(perm) && json_array_size(perm) > 0);
	ck_assert_msg(!strstr(r.body, KEY_CTL), "the key is echoed: %s", r.body);
	sv_resp_free(&r);
	call(np.port, "POST", "/api/login", RO, "{\"passive\":true}", 200, &r);
	ck_assert_str_eq(str(r.json, "name"), "viewer");
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
	call(np.port, "GET", "/api/currentuser", UP, NULL, 200, &r);
	ck_assert_str_eq(str(r.json, "name"), "slicer");
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
	call(np.port, "GET", "/api/server", RO, NULL, 200, &r);
	ck_assert_str_eq(str(r.json, "version"), "1.10.0");
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

/* HEAD answers GET's head; OPTIONS and a wrong method name the methods. */
START_TEST(test_head_options_405)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	call(np.port, "HEAD", "/api/version", RO, NULL, 200, &r);
	ck_assert_msg(!r.body[0], "HEAD has a body: %s", r.body);
	ck_assert(sv_has_text(r.head, "Content-Type: application/json"));
	sv_resp_free(&r);
	call(np.port, "OPTIONS", "/api/job", NULL, NULL, 200, &r);
	ck_assert_msg(sv_has_text(r.head, "Allow: GET, HEAD, POST, OPTIONS"), "%s", r.head);
	sv_resp_free(&r);
	call(np.port, "PUT", "/api/job", CTL, "{}", 405, &r);
	ck_assert_msg(sv_has_text(r.head, "Allow: GET, HEAD, POST, OPTIONS"), "%s", r.head);
	ck_assert(json_string_value(json_object_get(r.json, "error")));
	sv_resp_free(&r);
	call(np.port, "GET", "/api/printer/printhead", CTL, NULL, 405, &r);
	ck_assert_msg(sv_has_text(r.head, "Allow: POST, OPTIONS"), "%s", r.head);
	sv_resp_free(&r);
	call(np.port, "DELETE", "/api/files/local/x.gcode", CTL, NULL, 404, &r);
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
	call(np.port, "GET", "/api/system/commands", CTL, NULL, 200, &r);
	ck_assert(json_is_array(json_object_get(r.json, "core")) &&
		  !json_array_size(json_object_get(r.json, "core")));
	ck_assert(json_is_array(json_object_get(r.json, "custom")));
	sv_resp_free(&r);
	call(np.port, "GET", "/api/system/commands/core", CTL, NULL, 200, &r);
	ck_assert(json_is_array(r.json) && !json_array_size(r.json));
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/system/commands/other", CTL, NULL, 404);
	sv_expect(np.port, "GET", "/api/system/commands", RO, NULL, 403);
	sv_stop(&np);
}
END_TEST

START_TEST(test_printerprofile_by_id)
{
	struct node_proc np;
	struct resp r;

	start(&np, MK3S_AND_CREATOR);
	call(np.port, "GET", "/p/cp/api/printerprofiles/cp", RO, NULL, 200, &r);
	ck_assert_str_eq(str(r.json, "id"), "cp");
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
		call(np.port, "GET", i ? "/api/files/local" : "/api/files", RO, NULL, 200, &r);
		ck_assert(json_integer_value(json_object_get(r.json, "free")) > 0);
		ck_assert(json_integer_value(json_object_get(r.json, "total")) > 0);
		e = entry(json_object_get(r.json, "files"), "top.gcode");
		ck_assert_msg(e, "%s", r.body);
		ck_assert_str_eq(str(e, "path"), "top.gcode");
		ck_assert_str_eq(str(e, "type"), "machinecode");
		ck_assert_str_eq(str(e, "origin"), "local");
		snprintf(want, sizeof(want), "http://127.0.0.1:%d/api/files/local/top.gcode", np.port);
		ck_assert_str_eq(str(json_object_get(e, "refs"), "resource"), want);
		snprintf(want, sizeof(want), "http://127.0.0.1:%d/downloads/files/local/top.gcode",
			 np.port);
		ck_assert_str_eq(str(json_object_get(e, "refs"), "download"), want);
		an = json_object_get(e, "gcodeAnalysis");
		ck_assert_int_eq(json_integer_value(json_object_get(an, "estimatedPrintTime")), 602);
		dir = entry(json_object_get(r.json, "files"), "parts");
		ck_assert_str_eq(str(dir, "type"), "folder");
		ck_assert_msg(!json_object_get(dir, "children"), "not recursive: %s", r.body);
		sv_resp_free(&r);
	}
	call(np.port, "GET", "/api/files?recursive=true", RO, NULL, 200, &r);
	dir = entry(json_object_get(r.json, "files"), "parts");
	e = entry(json_object_get(dir, "children"), "inner.gcode");
	ck_assert_msg(e, "%s", r.body);
	ck_assert_str_eq(str(e, "path"), "parts/inner.gcode");
	snprintf(want, sizeof(want), "http://127.0.0.1:%d/downloads/files/local/parts/inner.gcode",
		 np.port);
	ck_assert_str_eq(str(json_object_get(e, "refs"), "download"), want);
	sv_resp_free(&r);
	/* the other printer's files are its own */
	call(np.port, "GET", "/p/ender/api/files", RO, NULL, 200, &r);
	ck_assert_int_eq(json_array_size(json_object_get(r.json, "files")), 0);
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/files", NULL, NULL, 403);
	sv_stop(&np);
}
END_TEST

START_TEST(test_file_get)
{
	struct node_proc np;
	struct resp r;

	start(&np, TWO_PRINTERS);
	store(np.port, "parts", "inner.gcode", "G1 X1\n");
	call(np.port, "GET", "/api/files/local/parts/inner.gcode", RO, NULL, 200, &r);
	ck_assert_str_eq(str(r.json, "name"), "inner.gcode");
	ck_assert_int_eq(json_integer_value(json_object_get(r.json, "size")), 6);
	sv_resp_free(&r);
	call(np.port, "GET", "/api/files/local/parts", RO, NULL, 200, &r);
	ck_assert_str_eq(str(r.json, "type"), "folder");
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
	json_t *jobs;

	start(&np, TWO_PRINTERS);
	store(np.port, "", "a.gcode", dwell(3));
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP, "{\"command\":\"select\"}", 204);
	call(np.port, "GET", "/api/job", RO, NULL, 200, &r);
	ck_assert_str_eq(str(json_object_get(json_object_get(r.json, "job"), "file"), "name"),
			 "a.gcode");
	sv_resp_free(&r);
	/* print=true starts a print: the control role */
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP,
		  "{\"command\":\"select\",\"print\":true}", 403);
	sv_bed_clear(np.port, "", 204);
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", CTL,
		  "{\"command\":\"select\",\"print\":true}", 204);
	jobs = json_object_get(sv_get_json(np.port, "/api/stratum/queue"), "jobs");
	ck_assert_int_eq(json_array_size(jobs), 1);
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
	store(np.port, "", "a.gcode", dwell(3));
	store(np.port, "parts", "b.gcode", "G1 X2\n");
	call(np.port, "POST", "/api/files/local/a.gcode", UP,
	     "{\"command\":\"copy\",\"destination\":\"parts\"}", 201, &r);
	snprintf(want, sizeof(want), "Location: http://127.0.0.1:%d/api/files/local/parts/a.gcode",
		 np.port);
	ck_assert_msg(sv_has_text(r.head, want), "%s", r.head);
	ck_assert_str_eq(str(r.json, "path"), "parts/a.gcode");
	ck_assert(json_object_get(json_object_get(r.json, "refs"), "download"));
	sv_resp_free(&r);
	ck_assert(stored(&np, "mk3s", "a.gcode") && stored(&np, "mk3s", "parts/a.gcode"));
	/* onto a file that exists: 409, nothing replaced */
	sv_expect(np.port, "POST", "/api/files/local/a.gcode", UP,
		  "{\"command\":\"move\",\"destination\":\"parts/b.gcode\"}", 409);
	call(np.port, "POST", "/api/files/local/parts/b.gcode", UP,
	     "{\"command\":\"move\",\"destination\":\"c.gcode\"}", 201, &r);
	ck_assert_str_eq(str(r.json, "name"), "c.gcode");
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
	call(np.port, "GET", "/downloads/files/local/parts/b.gcode", RO, NULL, 200, &r);
	ck_assert_str_eq(r.body, "G1 X2\nG1 Y3\n");
	ck_assert(sv_has_text(r.head, "Content-Type: application/octet-stream"));
	sv_resp_free(&r);
	call(np.port, "GET", "/p/mk3s/downloads/files/local/parts/b.gcode", RO, NULL, 200, &r);
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
	call(np.port, "GET", "/api/printer/tool", RO, NULL, 200, &r);
	ck_assert(json_is_number(json_object_get(json_object_get(r.json, "tool0"), "actual")));
	ck_assert(!json_object_get(r.json, "tool1"));
	ck_assert(!json_object_get(r.json, "bed"));
	sv_resp_free(&r);
	/* the Creator Pro has two extruders: tool1 is there */
	call(np.port, "GET", "/p/cp/api/printer/tool", RO, NULL, 200, &r);
	ck_assert(json_is_object(json_object_get(r.json, "tool1")));
	sv_resp_free(&r);
	call(np.port, "GET", "/p/cp/api/printer", RO, NULL, 200, &r);
	ck_assert(json_object_get(json_object_get(r.json, "temperature"), "tool1"));
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/tool", CTL,
		  "{\"command\":\"target\",\"targets\":{\"tool0\":205}}", 204);
	/* the test double reaches a target at once: it was sent */
	for (int i = 0; i < 100; i++) {
		call(np.port, "GET", "/api/printer/tool", RO, NULL, 200, &r);
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
	call(np.port, "GET", "/api/printer/bed", RO, NULL, 200, &r);
	ck_assert(json_is_number(json_object_get(json_object_get(r.json, "bed"), "target")));
	ck_assert(!json_object_get(r.json, "tool0"));
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"target\",\"target\":60}",
		  204);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"target\"}", 400);
	sv_expect(np.port, "POST", "/api/printer/bed", CTL, "{\"command\":\"offset\",\"offset\":5}",
		  400);
	/* no printer of the node has a heated chamber or an SD card */
	sv_expect(np.port, "GET", "/api/printer/chamber", RO, NULL, 409);
	sv_expect(np.port, "POST", "/api/printer/chamber", CTL,
		  "{\"command\":\"target\",\"target\":40}", 409);
	call(np.port, "GET", "/api/printer/sd", RO, NULL, 404, &r);
	ck_assert_str_eq(str(r.json, "error"), "SD support is disabled");
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
	for (int i = 0; i < 250; i++) { /* connected: the sim's boot done */
		struct resp r;

		sv_http(np.port, "GET", "/api/printer", RO, NULL, &r);
		sv_resp_free(&r);
		if (r.status == 200)
			break;
		usleep(20000);
	}
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
	call(np.port, "GET", "/api/job", RO, NULL, 200, &r);
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
		call(np.port, "GET", "/api/job", RO, NULL, 200, &r);
		prog = json_object_get(r.json, "progress");
		if (json_integer_value(json_object_get(prog, "printTimeLeft")) == 300)
			break;
		sv_resp_free(&r);
		usleep(20000);
	}
	ck_assert_msg(json_integer_value(json_object_get(prog, "printTimeLeft")) == 300, "%s",
		      r.body);
	ck_assert_str_eq(str(prog, "printTimeLeftOrigin"), "estimate");
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"pause\",\"action\":\"pause\"}",
		  204);
	call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	ck_assert(json_is_false(json_object_get(json_object_get(json_object_get(r.json, "state"),
								"flags"), "ready")));
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", CTL, "{\"command\":\"cancel\"}", 204);
	sv_wait_state(np.port, "", 1, "cancelled", 10);
	call(np.port, "GET", "/api/printer", RO, NULL, 200, &r);
	ck_assert(json_is_true(json_object_get(json_object_get(json_object_get(r.json, "state"),
							       "flags"), "ready")));
	sv_resp_free(&r);
	sv_stop(&np);
}
END_TEST

/* ---- push API ------------------------------------------------------------------ */

/* A WebSocket client of the push API (wslay does the framing and masking). */
struct ws {
	int fd;
	wslay_event_context_ptr ctx;
	char extra[4096]; /* bytes read past the handshake's answer */
	size_t extra_len, extra_off;
	bool sockjs;
	json_t *got; /* messages received, in order (SockJS frames unwrapped) */
	int frames_o, frames_h;
};

static ssize_t ws_recv(wslay_event_context_ptr ctx, uint8_t *buf, size_t len, int flags,
		       void *user)
{
	struct ws *w = user;
	ssize_t n;

	(void)flags;
	if (w->extra_off < w->extra_len) {
		n = (ssize_t)(w->extra_len - w->extra_off < len ? w->extra_len - w->extra_off : len);
		memcpy(buf, w->extra + w->extra_off, (size_t)n);
		w->extra_off += (size_t)n;
		return n;
	}
	n = recv(w->fd, buf, len, 0);
	if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK))
		wslay_event_set_error(ctx, WSLAY_ERR_WOULDBLOCK);
	else if (n <= 0)
		wslay_event_set_error(ctx, WSLAY_ERR_CALLBACK_FAILURE);
	return n > 0 ? n : -1;
}

static ssize_t ws_send(wslay_event_context_ptr ctx, const uint8_t *data, size_t len, int flags,
		       void *user)
{
	struct ws *w = user;
	ssize_t n = send(w->fd, data, len, MSG_NOSIGNAL);

	(void)flags;
	if (n < 0)
		wslay_event_set_error(ctx, errno == EAGAIN ? WSLAY_ERR_WOULDBLOCK
							   : WSLAY_ERR_CALLBACK_FAILURE);
	return n >= 0 ? n : -1;
}

static int ws_mask(wslay_event_context_ptr ctx, uint8_t *buf, size_t len, void *user)
{
	(void)ctx;
	(void)user;
	for (size_t i = 0; i < len; i++)
		buf[i] = (uint8_t)rand();
	return 0;
}

static void ws_msg(wslay_event_context_ptr ctx, const struct wslay_event_on_msg_recv_arg *arg,
		   void *user)
{
	struct ws *w = user;
	const char *t = (const char *)arg->msg;
	size_t i;
	json_t *a, *s;

	(void)ctx;
	if (arg->opcode != WSLAY_TEXT_FRAME)
		return;
	if (!w->sockjs) {
		json_array_append_new(w->got, json_loadb(t, arg->msg_length, 0, NULL));
		return;
	}
	if (arg->msg_length == 1 && t[0] == 'o')
		w->frames_o++;
	else if (arg->msg_length == 1 && t[0] == 'h')
		w->frames_h++;
	else if (arg->msg_length > 1 && t[0] == 'a' &&
		 (a = json_loadb(t + 1, arg->msg_length - 1, 0, NULL))) {
		json_array_foreach(a, i, s)
			json_array_append_new(w->got, json_loads(json_string_value(s), 0, NULL));
		json_decref(a);
	}
}

/* Open path with the WebSocket handshake; RFC 6455's sample key and accept. */
static void ws_open(struct ws *w, int port, const char *path, bool sockjs)
{
	struct sockaddr_in sa = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
	struct wslay_event_callbacks cb = {ws_recv, ws_send, ws_mask, NULL, NULL, NULL, ws_msg};
	char req[512], head[4096];
	size_t got = 0;
	char *end = NULL;
	int n;

	memset(w, 0, sizeof(*w));
	w->sockjs = sockjs;
	w->got = json_array();
	w->fd = socket(AF_INET, SOCK_STREAM, 0);
	inet_pton(AF_INET, "127.0.0.1", &sa.sin_addr);
	ck_assert(connect(w->fd, (struct sockaddr *)&sa, sizeof(sa)) == 0);
	n = snprintf(req, sizeof(req), "GET %s HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n"
		     "Upgrade: websocket\r\nConnection: Upgrade\r\n"
		     "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
		     "Sec-WebSocket-Version: 13\r\n\r\n", path, port);
	ck_assert(send(w->fd, req, (size_t)n, 0) == n);
	while (!end && got < sizeof(head) - 1) {
		ssize_t k = recv(w->fd, head + got, sizeof(head) - 1 - got, 0);

		ck_assert_msg(k > 0, "no handshake answer");
		got += (size_t)k;
		head[got] = '\0';
		end = strstr(head, "\r\n\r\n");
	}
	ck_assert_msg(!strncmp(head, "HTTP/1.1 101", 12), "%s", head);
	ck_assert_msg(sv_has_text(head, "Sec-WebSocket-Accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo="),
		      "%s", head);
	w->extra_len = got - (size_t)(end + 4 - head);
	memcpy(w->extra, end + 4, w->extra_len);
	fcntl(w->fd, F_SETFL, O_NONBLOCK);
	ck_assert(wslay_event_context_client_init(&w->ctx, &cb, w) == 0);
}

/* Send one client message (framed as SockJS's when the endpoint is). */
static void ws_say(struct ws *w, const char *json)
{
	json_t *a = json_pack("[s]", json);
	char *framed = json_dumps(a, JSON_COMPACT);
	const char *text = w->sockjs ? framed : json;
	struct wslay_event_msg m = {WSLAY_TEXT_FRAME, (const uint8_t *)text, strlen(text)};

	ck_assert(wslay_event_queue_msg(w->ctx, &m) == 0);
	free(framed);
	json_decref(a);
}

/* Run the client for up to ms; stop early once a message has key. */
static json_t *ws_until(struct ws *w, const char *key, int ms)
{
	for (int t = 0; t < ms; t += 20) {
		struct pollfd pfd = {w->fd, POLLIN | (wslay_event_want_write(w->ctx) ? POLLOUT : 0),
				     0};
		size_t i;
		json_t *m;

		poll(&pfd, 1, 20);
		if (pfd.revents & POLLIN || w->extra_off < w->extra_len)
			ck_assert_msg(wslay_event_recv(w->ctx) == 0, "the node closed the push client");
		if (wslay_event_want_write(w->ctx))
			wslay_event_send(w->ctx);
		json_array_foreach(w->got, i, m)
			if (key && json_object_get(m, key))
				return m;
	}
	return NULL;
}

static void ws_close(struct ws *w)
{
	wslay_event_context_free(w->ctx);
	close(w->fd);
	json_decref(w->got);
}

/* SockJS: info, "o", connected; auth with the login's session; history,
 * then current messages with the print's progress. */
START_TEST(test_push_sockjs)
{
	struct node_proc np;
	struct resp r;
	struct ws w;
	char auth[128];
	json_t *m, *cur;
	double completion = 0;

	start(&np, TWO_PRINTERS);
	call(np.port, "GET", "/sockjs/info", NULL, NULL, 200, &r);
	ck_assert(json_is_true(json_object_get(r.json, "websocket")));
	sv_resp_free(&r);
	call(np.port, "POST", "/api/login", CTL, "{\"passive\":true}", 200, &r);
	snprintf(auth, sizeof(auth), "{\"auth\":\"operator:%s\"}", str(r.json, "session"));
	sv_resp_free(&r);
	ws_open(&w, np.port, "/sockjs/123/abcdefgh/websocket", true);
	m = ws_until(&w, "connected", 3000);
	ck_assert_msg(m && w.frames_o == 1, "no open frame and connected message");
	ck_assert_str_eq(str(json_object_get(m, "connected"), "version"), "1.10.0");
	/* nothing but connected before auth */
	ck_assert(!ws_until(&w, "current", 1200));
	ws_say(&w, auth);
	m = ws_until(&w, "history", 3000);
	ck_assert_msg(m, "no history after auth");
	ck_assert(json_object_get(json_object_get(m, "history"), "state"));
	sv_bed_clear(np.port, "", 204);
	ck_assert(sv_print_text(np.port, "", "long.gcode", dwell(3)) == 1);
	for (int i = 0; i < 50 && completion <= 0; i++) {
		json_array_clear(w.got);
		m = ws_until(&w, "current", 2000);
		ck_assert_msg(m, "no current message");
		cur = json_object_get(m, "current");
		completion = json_number_value(json_object_get(json_object_get(cur, "progress"),
							       "completion"));
	}
	ck_assert_msg(completion > 0, "no progress in current");
	ck_assert_str_eq(str(json_object_get(cur, "state"), "text"), "Printing");
	ck_assert_str_eq(str(json_object_get(json_object_get(cur, "job"), "file"), "name"),
			 "long.gcode");
	ck_assert(json_is_array(json_object_get(cur, "temps")));
	ws_close(&w);
	sv_stop(&np);
}
END_TEST

/* The raw endpoint: plain JSON messages; a wrong session gets no state. */
START_TEST(test_push_raw)
{
	struct node_proc np;
	struct resp r;
	struct ws w;
	char auth[128];

	start(&np, TWO_PRINTERS);
	call(np.port, "POST", "/api/login", RO, "{\"passive\":true}", 200, &r);
	snprintf(auth, sizeof(auth), "{\"auth\":\"viewer:%s\"}", str(r.json, "session"));
	ck_assert_msg(!strstr(r.body, KEY_READ), "%s", r.body);
	sv_resp_free(&r);
	ws_open(&w, np.port, "/sockjs/websocket", false);
	ck_assert(ws_until(&w, "connected", 3000));
	ws_say(&w, "{\"auth\":\"viewer:0123456789abcdef0123456789abcdef\"}");
	ck_assert(!ws_until(&w, "current", 1500));
	ws_say(&w, auth);
	ck_assert(ws_until(&w, "current", 3000));
	ws_close(&w);
	/* a printer's own push API, and no upgrade without its headers */
	ws_open(&w, np.port, "/p/ender/sockjs/websocket", false);
	ck_assert(ws_until(&w, "connected", 3000));
	ws_close(&w);
	sv_expect(np.port, "GET", "/sockjs/websocket", NULL, NULL, 400);
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
	tcase_add_test(tc, test_head_options_405);
	tcase_add_test(tc, test_system_commands);
	tcase_add_test(tc, test_printerprofile_by_id);
	tcase_add_test(tc, test_files_list);
	tcase_add_test(tc, test_file_get);
	tcase_add_test(tc, test_file_select);
	tcase_add_test(tc, test_file_move_copy);
	tcase_add_test(tc, test_file_delete);
	tcase_add_test(tc, test_download);
	tcase_add_test(tc, test_printer_tool);
	tcase_add_test(tc, test_printer_bed);
	tcase_add_test(tc, test_printer_printhead);
	tcase_add_test(tc, test_job_estimates);
	tcase_add_test(tc, test_push_sockjs);
	tcase_add_test(tc, test_push_raw);
	suite_add_tcase(s, tc);
	return s;
}

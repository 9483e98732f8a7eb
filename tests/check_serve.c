/*
 * check_serve.c - `stratum serve` end to end: the node runs as a child
 * process on a loopback port and the tests speak HTTP to it over plain
 * sockets, sending requests byte for byte as PrusaSlicer's libcurl does
 * (the version check, the multipart upload: fields print, path, file, in
 * that order, curl's boundary form, X-Api-Key).  Covered: auth (403),
 * roles, oversize uploads (413, with and without Expect: 100-continue),
 * hostile file names, STL upload sliced and printed, two printers with
 * their own queues, pause/resume/cancel, kill -9 and restart with the queue
 * intact and the interrupted job marked, the bed-clear gate and config
 * errors.  Printers use `port = test-instant` (docs/serve.md).  The rest
 * of the `serve` suite: the bounds under abuse (check_serveabuse.c),
 * simulated printers and MQTT (check_servesim.c), the shared broker
 * (check_servemqtt.c) and the status page (check_servepage.c).
 */
#include <arpa/inet.h>
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <math.h>
#include <netinet/in.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <mosquitto.h>
#include <pthread.h>
#include <sqlite3.h>

#include "fixtures.h"
#include "gcode.h"
#include "meshio.h"
#include "mqtttest.h"
#include "sfcheck.h"
#include "st_clock.h"
#include "suites.h"
#include "servetest.h"
#include "testutil.h"

/* ---- tests ---------------------------------------------------------------- */

START_TEST(test_version_as_prusaslicer)
{
	struct node_proc np;
	struct resp r;
	const char *text;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_http(np.port, "GET", "/api/version", "X-Api-Key: " KEY_UP, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert_msg(sv_has_text(r.head, "Content-Type: application/json"), "%s", r.head);
	/* PrusaSlicer's test(): "api" present, "text" starting with "OctoPrint". */
	ck_assert_str_eq(json_string_value(json_object_get(r.json, "api")), "0.1");
	ck_assert(json_is_string(json_object_get(r.json, "server")));
	text = json_string_value(json_object_get(r.json, "text"));
	ck_assert(text && !strncmp(text, "OctoPrint", 9));
	sv_resp_free(&r);
	/* Bearer works as well, and under the printer's prefix. */
	sv_expect(np.port, "GET", "/p/ender/api/version", "Authorization: Bearer " KEY_READ, NULL, 200);
	sv_stop(&np);
}
END_TEST

START_TEST(test_auth)
{
	struct node_proc np;
	struct resp r;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_http(np.port, "GET", "/api/version", NULL, NULL, &r);
	ck_assert_int_eq(r.status, 403);
	ck_assert(json_is_string(json_object_get(r.json, "error")));
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/job", "X-Api-Key: " KEY_UP "x", NULL, 403);
	sv_expect(np.port, "GET", "/api/job", "X-Api-Key: upload-key-012345678", NULL, 403); /* a prefix of a key is not the key */
	sv_expect(np.port, "GET", "/api/printer", "Authorization: Bearer nope-nope-nope-nope", NULL, 403);
	/* Roles: read cannot upload; upload cannot control. */
	sv_upload_text(np.port, "", KEY_READ, "a.gcode", "G28\n", "false", &r);
	ck_assert_int_eq(r.status, 403);
	sv_resp_free(&r);
	sv_upload_text(np.port, "", NULL, "a.gcode", "G28\n", "true", &r);
	ck_assert_int_eq(r.status, 403);
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_UP, "{\"command\":\"cancel\"}", 403);
	sv_expect(np.port, "POST", "/api/printer/command", "X-Api-Key: " KEY_READ,
	     "{\"command\":\"G28\"}", 403);
	/* Nothing was stored by the refused uploads. */
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/a.gcode")));
	sv_stop(&np);
}
END_TEST

START_TEST(test_upload_as_prusaslicer)
{
	struct node_proc np;
	struct resp r;
	json_t *local;
	long long id;
	const char *gcode = "; sliced elsewhere\nM104 S215\nG28\nG1 X10 Y10 F3000\nM140 S60\n";

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_upload_text(np.port, "", KEY_UP, "part one.gcode", gcode, "true", &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	ck_assert_msg(sv_has_text(r.head, "\r\nLocation: http://127.0.0.1:"), "%s", r.head);
	ck_assert_msg(strstr(r.head, "/api/files/local/part%20one.gcode"), "%s", r.head);
	local = json_object_get(json_object_get(r.json, "files"), "local");
	ck_assert_str_eq(json_string_value(json_object_get(local, "name")), "part one.gcode");
	ck_assert_str_eq(json_string_value(json_object_get(local, "origin")), "local");
	ck_assert(json_is_string(json_object_get(json_object_get(local, "refs"), "resource")));
	ck_assert(json_is_true(json_object_get(r.json, "done")));
	ck_assert(json_is_true(json_object_get(r.json, "effectivePrint")));
	id = sv_job_of(&r);
	ck_assert(id > 0);
	sv_resp_free(&r);
	sv_wait_state(np.port, "/p/mk3s", id, "done", 10);
	/* Stored as is. */
	{
		FILE *f = fopen(tu_path("node/data/files/mk3s/part one.gcode"), "rb");
		char buf[256] = {0};

		ck_assert(f);
		ck_assert(fread(buf, 1, sizeof(buf) - 1, f) == strlen(gcode));
		fclose(f);
		ck_assert_str_eq(buf, gcode);
	}
	/* The job API names the file; the printer reports the temperatures it set. */
	sv_http(np.port, "GET", "/api/job", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert_str_eq(json_string_value(json_object_get(
				 json_object_get(json_object_get(r.json, "job"), "file"), "name")),
			 "part one.gcode");
	sv_resp_free(&r);
	sv_http(np.port, "GET", "/api/printer", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert(json_real_value(json_object_get(
			  json_object_get(json_object_get(r.json, "temperature"), "tool0"),
			  "target")) == 215);
	sv_resp_free(&r);
	/* GET /api/job always has job.file.name, null when nothing is selected. */
	sv_http(np.port, "GET", "/p/ender/api/job", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert(json_is_null(json_object_get(
		json_object_get(json_object_get(r.json, "job"), "file"), "name")));
	sv_resp_free(&r);
	/* The other OctoPrint calls slicers read; the print moved the printer,
	 * so the bed waits for an operator, and the state says so. */
	sv_http(np.port, "GET", "/api/connection", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert_str_eq(json_string_value(json_object_get(json_object_get(r.json, "current"),
							   "state")), "Waiting for bed clear");
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/settings", "X-Api-Key: " KEY_READ, NULL, 200);
	sv_http(np.port, "GET", "/api/printerprofiles", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert(json_real_value(json_object_get(json_object_get(json_object_get(json_object_get(
			  r.json, "profiles"), "mk3s"), "volume"), "width")) > 200);
	sv_resp_free(&r);
	sv_stop(&np);
}
END_TEST

/* G-code sliced for another printer is refused at upload (409, both printers
 * named, nothing stored or queued) unless the form says force=true (issue 18
 * item 8; host/guard.h). */
START_TEST(test_upload_for_another_printer)
{
	/* The Creator Pro's G-code, uploaded to the MK3S. */
	const char *gcode = "; generated by Stratum\n; printer_settings_id = flashforge-creator-pro\n"
			    "; printer_model = FFCP\n;LAYER_CHANGE\nG1 X10 Y10 F3000\n";
	/* sv_upload() writes the print field's value raw: a force field follows it */
	const char *forced = "true\r\n--" BOUNDARY "\r\nContent-Disposition: form-data; "
			     "name=\"force\"\r\n\r\ntrue";
	struct node_proc np;
	struct resp r;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_upload_text(np.port, "", KEY_UP, "ffcp.gcode", gcode, "true", &r);
	ck_assert_msg(r.status == 409, "%d %s", r.status, r.body);
	ck_assert_msg(strstr(r.body, "ffcp.gcode was sliced for printer 'flashforge-creator-pro' "
				     "(printer_model FFCP), not for 'prusa-i3-mk3s' "
				     "(printer_model MK3S)"),
		      "%s", r.body);
	sv_resp_free(&r);
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/ffcp.gcode")));
	sv_upload_text(np.port, "", KEY_UP, "ffcp.gcode", gcode, forced, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	ck_assert(sv_job_of(&r) > 0);
	sv_resp_free(&r);
	ck_assert(tu_file_exists(tu_path("node/data/files/mk3s/ffcp.gcode")));
	sv_stop(&np);
}
END_TEST

START_TEST(test_oversize)
{
	struct node_proc np;
	struct resp r;
	size_t big = (1u << 20) + 30000; /* over 1 MiB, within the multipart slack */
	size_t huge = 3u << 20;		 /* the announced body of the first request */
	char *data = malloc(huge);

	ck_assert(data);
	memset(data, ';', huge);
	data[big - 1] = '\n';
	sv_write_config(&np, TWO_PRINTERS, 1);
	sv_start(&np);
	/* curl sends Expect: 100-continue for a large body and waits: answered at once. */
	sv_upload(np.port, "", KEY_UP, "big.gcode", 9, "", 0, "false", data, huge,
	       "Expect: 100-continue\r\n", false, &r);
	ck_assert_int_eq(r.status, 413);
	sv_resp_free(&r);
	/* A body over the limit sent in full is counted and refused. */
	sv_upload(np.port, "", KEY_UP, "big.gcode", 9, "", 0, "false", data, big, NULL, true, &r);
	ck_assert_msg(r.status == 413, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/big.gcode")));
	/* Just under the limit is fine. */
	sv_upload(np.port, "", KEY_UP, "big.gcode", 9, "", 0, "false", data, 1u << 20, NULL, true,
	       &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	free(data);
	sv_stop(&np);
}
END_TEST

START_TEST(test_hostile_names)
{
	static const struct {
		const char *name;
		size_t len;
		const char *path;
		size_t path_len;
		int status;
	} cases[] = {
		{"../x.gcode", 10, "", 0, 400},
		{"/tmp/x.gcode", 12, "", 0, 400},
		{"..\\x.gcode", 10, "", 0, 400},
		{".hidden.gcode", 13, "", 0, 400},
		{"x.gcode", 7, "../..", 5, 400},
		{"x.gcode", 7, "/../../tmp", 10, 400},
		{"x.gcode", 7, "a\0b", 3, 400},
		{"x\tx.gcode", 9, "", 0, 400},
		{"x\xff.gcode", 8, "", 0, 400},	  /* not UTF-8 */
		{"\xc0\xaf.gcode", 8, "", 0, 400}, /* an overlong '/' */
		{"x.gcode", 7, "caf\xe9", 4, 400},  /* Latin-1, not UTF-8 */
		{"x.exe", 5, "", 0, 415},
		{"", 0, "", 0, 400},
	};
	char longname[400];
	struct node_proc np;
	struct resp r;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		sv_upload(np.port, "", KEY_UP, cases[i].name, cases[i].len, cases[i].path,
		       cases[i].path_len, "false", "G28\n", 4, NULL, true, &r);
		ck_assert_msg(r.status == cases[i].status, "case %zu: %d %s", i, r.status, r.body);
		ck_assert(json_is_string(json_object_get(r.json, "error")));
		sv_resp_free(&r);
	}
	memset(longname, 'a', sizeof(longname));
	memcpy(longname + sizeof(longname) - 6, ".gcode", 6);
	sv_upload(np.port, "", KEY_UP, longname, sizeof(longname), "", 0, "false", "G28\n", 4, NULL,
	       true, &r);
	ck_assert_msg(r.status == 400, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	/* Nothing landed outside the files folder or in it. */
	ck_assert(!tu_file_exists(tu_path("node/data/files/x.gcode")));
	ck_assert(!tu_file_exists(tu_path("node/data/x.gcode")));
	ck_assert(!tu_file_exists(tu_path("node/x.gcode")));
	ck_assert(!tu_file_exists(tu_path("node/data/files/mk3s/x.exe")));
	/* A folder given in path is fine when its parts are. */
	sv_upload(np.port, "", KEY_UP, "x.gcode", 7, "plates/left", 11, "false", "G28\n", 4, NULL,
	       true, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	ck_assert(tu_file_exists(tu_path("node/data/files/mk3s/plates/left/x.gcode")));
	sv_stop(&np);
}
END_TEST

START_TEST(test_stl_two_printers)
{
	struct node_proc np;
	struct resp r;
	size_t len;
	char *stl = sv_cube_stl(&len);
	long long a, b, c;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_upload(np.port, "/p/mk3s", KEY_UP, "cube.stl", 8, "", 0, "true", stl, len, NULL, true, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	a = sv_job_of(&r);
	sv_resp_free(&r);
	/* the dwell outlasts the cube's repair, slice and print under a
	 * sanitizer on a loaded machine (1.5 s did not, now and then) */
	sv_upload_text(np.port, "/p/ender", KEY_UP, "hold.gcode", "G28\nG4 P8000\nG1 X5\n", "true", &r);
	ck_assert_int_eq(r.status, 201);
	b = sv_job_of(&r);
	sv_resp_free(&r);
	/* Both printers work at once: ender holds in its dwell while mk3s slices and prints. */
	sv_wait_state(np.port, "/p/ender", b, "printing", 5);
	sv_wait_state(np.port, "/p/mk3s", a, "done", 30);
	ck_assert_str_eq(sv_job_state(np.port, "/p/ender", b, NULL), "printing");
	/* Each queue holds its own jobs only. */
	ck_assert_str_eq(sv_job_state(np.port, "/p/mk3s", b, NULL), "");
	ck_assert_str_eq(sv_job_state(np.port, "/p/ender", a, NULL), "");
	sv_wait_state(np.port, "/p/ender", b, "done", 15);
	/* The sliced G-code is the profile's (PrusaSlicer-style layer comments). */
	{
		char path[600];
		FILE *f;
		char buf[1 << 16];
		size_t n;

		snprintf(path, sizeof(path), "%s/data/sliced/job-%lld.gcode", np.dir, a);
		f = fopen(path, "r");
		ck_assert_msg(f, "no %s", path);
		n = fread(buf, 1, sizeof(buf) - 1, f);
		buf[n] = '\0';
		fclose(f);
		ck_assert(strstr(buf, ";LAYER_CHANGE"));
	}
	/* Between jobs the printer waits until the bed is cleared. */
	sv_upload_text(np.port, "/p/mk3s", KEY_UP, "next.gcode", "G28\n", "true", &r);
	c = sv_job_of(&r);
	sv_resp_free(&r);
	usleep(1500000);
	ck_assert_str_eq(sv_job_state(np.port, "/p/mk3s", c, NULL), "queued");
	sv_bed_clear(np.port, "/p/mk3s", 204);
	sv_wait_state(np.port, "/p/mk3s", c, "done", 5);
	/* A model that is no solid fails with a message, the node goes on. */
	sv_upload_text(np.port, "/p/ender", KEY_UP, "junk.stl", "solid x\nendsolid x\n", "true", &r);
	ck_assert_int_eq(r.status, 201);
	sv_wait_state(np.port, "/p/ender", sv_job_of(&r), "failed", 10);
	sv_resp_free(&r);
	free(stl);
	sv_stop(&np);
}
END_TEST

/*
 * The node slices with the job `stratum slice` runs (host/slicejob.h): the
 * G-code it prints from an uploaded STL is byte for byte what `stratum
 * slice` writes for the same model and printer profile.
 */
/* Upload body (len bytes) as name to the MK3S of a fresh node, wait for its
 * job, and check the node's G-code is what `stratum slice LOCAL` writes
 * (the same slice job, host/slicejob.c). */
static void expect_node_slice(const char *name, const char *local, const char *body, size_t len)
{
	struct node_proc np;
	struct resp r;
	char path[600], mine[600], out[4096];
	long long id;
	int rc;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_upload(np.port, "/p/mk3s", KEY_UP, name, strlen(name), "", 0, "true", body, len, NULL,
	       true, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	id = sv_job_of(&r);
	sv_resp_free(&r);
	sv_wait_state(np.port, "/p/mk3s", id, "done", 30);
	sv_stop(&np);
	snprintf(path, sizeof(path), "%s/data/sliced/job-%lld.gcode", np.dir, id);
	snprintf(mine, sizeof(mine), "%s", tu_path("slice-node.gcode"));
	rc = tu_run(out, sizeof(out), "slice %s -o %s --printer prusa-i3-mk3s >/dev/null 2>&1 && "
		    "cmp %s %s", local, mine, path, mine);
	ck_assert_msg(rc == 0, "the node's G-code is not stratum slice's (%d): %s", rc, out);
}

START_TEST(test_node_gcode_is_slice_gcode)
{
	size_t len;
	char *stl = sv_cube_stl(&len), local[600];

	snprintf(local, sizeof(local), "%s", tu_path("cube.stl"));
	expect_node_slice("cube.stl", local, stl, len);
	free(stl);
}
END_TEST

/* A 3MF with two objects uploaded to the node slices with its placement. */
START_TEST(test_node_slices_two_object_3mf)
{
	static const double plate[2][5] = {{20, 20, 5, 30, 40}, {10, 10, 5, 180, 150}};
	size_t len;
	char in[600], *body;

	snprintf(in, sizeof(in), "%s", tu_path("plate.3mf"));
	tu_write_3mf_boxes(in, plate, 2);
	body = tu_slurp(in, &len);
	expect_node_slice("plate.3mf", in, body, len);
	free(body);
}
END_TEST

/* The value of the upload's "print" field followed by the form fields of
 * pairs (name, value, ..., NULL): sv_upload() writes print as it is, so the
 * fields ride behind it as parts of their own, before the file. */
static const char *print_and_fields(char *buf, size_t cap, const char *print,
				    const char *const *pairs)
{
	size_t n = (size_t)snprintf(buf, cap, "%s", print);

	for (; pairs[0]; pairs += 2)
		n += (size_t)snprintf(buf + n, cap - n,
				      "\r\n--" BOUNDARY "\r\nContent-Disposition: form-data; "
				      "name=\"%s\"\r\n\r\n%s",
				      pairs[0], pairs[1]);
	ck_assert_uint_lt(n, cap);
	return buf;
}

/*
 * Per-job settings on the upload (issue 18 item 5): form fields spelled as
 * `stratum slice`'s options (set=KEY=VALUE, layer-height=0.3) are checked
 * at upload, kept with the job and sliced with: the node's G-code is what
 * `stratum slice --layer-height 0.3 --set perimeters=3` writes.  A bad
 * value, settings on G-code or without print=true are refused with 400.
 */
START_TEST(test_upload_settings)
{
	static const char *const good[] = {"layer-height", "0.3", "set", "perimeters=3", NULL};
	static const struct {
		const char *name, *fields[3], *print, *says;
	} bad[] = {
	    {"cube.stl", {"layer-height", "thick", NULL}, "true", "'thick' is not a number"},
	    {"cube.stl", {"set", "perimeters", NULL}, "true", "set wants KEY=VALUE"},
	    {"cube.stl", {"fill-density", "250%", NULL}, "true", "fill_density"},
	    {"cube.stl", {"layer-height", "0.3", NULL}, "false", "come with print=true"},
	    {"cube.gcode", {"layer-height", "0.3", NULL}, "true", "is sliced already"},
	};
	struct node_proc np;
	struct resp r;
	size_t len, i;
	char *stl = sv_cube_stl(&len), print[1024], path[600], mine[600], out[4096];
	long long id;
	json_t *j, *want = json_pack("[[ss][ss]]", "layer-height", "0.3", "set", "perimeters=3");
	int rc;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	for (i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		sv_upload(np.port, "/p/mk3s", KEY_UP, bad[i].name, strlen(bad[i].name), "", 0,
		       print_and_fields(print, sizeof(print), bad[i].print, bad[i].fields), stl,
		       len, NULL, true, &r);
		ck_assert_msg(r.status == 400, "%s: %d %s", bad[i].says, r.status, r.body);
		ck_assert_msg(sv_has_text(r.body, bad[i].says), "'%s' not in %s", bad[i].says, r.body);
		sv_resp_free(&r);
	}
	sv_upload(np.port, "/p/mk3s", KEY_UP, "cube.stl", 8, "", 0,
	       print_and_fields(print, sizeof(print), "true", good), stl, len, NULL, true, &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	id = sv_job_of(&r);
	sv_resp_free(&r);
	sv_wait_state(np.port, "/p/mk3s", id, "done", 30);
	sv_http(np.port, "GET", "/p/mk3s/api/stratum/queue", "X-Api-Key: " KEY_READ, NULL, &r);
	json_array_foreach(json_object_get(r.json, "jobs"), i, j)
		if (json_integer_value(json_object_get(j, "id")) == id)
			ck_assert_msg(json_equal(json_object_get(j, "settings"), want), "%s", r.body);
	sv_resp_free(&r);
	json_decref(want);
	sv_stop(&np);
	snprintf(path, sizeof(path), "%s/data/sliced/job-%lld.gcode", np.dir, id);
	snprintf(mine, sizeof(mine), "%s", tu_path("slice-cube.gcode"));
	rc = tu_run(out, sizeof(out),
		    "slice %s -o %s --printer prusa-i3-mk3s --layer-height 0.3 --set perimeters=3 "
		    ">/dev/null 2>&1 && cmp %s %s && grep -q '^; layer_height = 0.3$' %s",
		    tu_path("cube.stl"), mine, path, mine, mine);
	ck_assert_msg(rc == 0, "the node's G-code is not stratum slice's (%d): %s", rc, out);
	free(stl);
}
END_TEST

START_TEST(test_pause_resume_cancel)
{
	struct node_proc np;
	struct resp r;
	long long id;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_upload_text(np.port, "", KEY_UP, "long.gcode", "G28\nG4 P400\nG4 P400\nG4 P400\nG4 P20000\n",
		    "true", &r);
	id = sv_job_of(&r);
	sv_resp_free(&r);
	sv_wait_state(np.port, "", id, "printing", 5);
	/* Overwriting the file being printed is refused. */
	sv_upload_text(np.port, "", KEY_UP, "long.gcode", "G28\n", "false", &r);
	ck_assert_int_eq(r.status, 409);
	sv_resp_free(&r);
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL,
	     "{\"command\":\"pause\",\"action\":\"pause\"}", 204);
	ck_assert_str_eq(sv_job_state(np.port, "", id, NULL), "paused");
	usleep(300000);
	sv_http(np.port, "GET", "/api/job", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_str_eq(json_string_value(json_object_get(r.json, "state")), "Paused");
	sv_resp_free(&r);
	/* A paused print takes no command (nor does a test-instant one). */
	sv_expect(np.port, "POST", "/api/printer/command", "X-Api-Key: " KEY_CTL,
	     "{\"commands\":[\"M105\"]}", 409);
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL,
	     "{\"command\":\"pause\",\"action\":\"resume\"}", 204);
	ck_assert_str_eq(sv_job_state(np.port, "", id, NULL), "printing");
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL, "{\"command\":\"cancel\"}", 204);
	sv_wait_state(np.port, "", id, "cancelled", 5);
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL, "{\"command\":\"cancel\"}", 409); /* nothing printing */
	/* A bad command line is refused whole; a good one is accepted. */
	sv_expect(np.port, "POST", "/api/printer/command", "X-Api-Key: " KEY_CTL,
	     "{\"commands\":[\"M105\",\"G1 X1 X2\"]}", 400);
	sv_expect(np.port, "POST", "/api/printer/command", "X-Api-Key: " KEY_CTL,
	     "{\"command\":\"M105\"}", 204);
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL, "not json", 400);
	sv_stop(&np);
}
END_TEST

START_TEST(test_kill9_restart)
{
	struct node_proc np;
	struct resp r;
	long long a, b;
	bool interrupted = false;
	int st;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_upload_text(np.port, "", KEY_UP, "first.gcode", "G28\nG1 X1\nG4 S30\nG1 X2\nG1 X3\n", "true",
		    &r);
	a = sv_job_of(&r);
	sv_resp_free(&r);
	sv_upload_text(np.port, "", KEY_UP, "second.gcode", "G28\n", "true", &r);
	b = sv_job_of(&r);
	sv_resp_free(&r);
	sv_wait_state(np.port, "", a, "printing", 5);
	usleep(1200000); /* the progress ticker stores the position */
	ck_assert(kill(np.pid, SIGKILL) == 0);
	ck_assert(waitpid(np.pid, &st, 0) == np.pid);

	sv_start(&np);
	/* Same jobs; the print is marked interrupted and not restarted on its own. */
	ck_assert_str_eq(sv_job_state(np.port, "", a, &interrupted), "paused");
	ck_assert(interrupted);
	ck_assert_str_eq(sv_job_state(np.port, "", b, NULL), "queued");
	sv_http(np.port, "GET", "/api/job", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_str_eq(json_string_value(json_object_get(r.json, "state")), "Paused");
	ck_assert_str_eq(json_string_value(json_object_get(
				 json_object_get(json_object_get(r.json, "job"), "file"), "name")),
			 "first.gcode");
	ck_assert(json_integer_value(json_object_get(json_object_get(r.json, "progress"),
						     "filepos")) >= 14);
	sv_resp_free(&r);
	usleep(1200000);
	ck_assert_str_eq(sv_job_state(np.port, "", a, NULL), "paused");
	ck_assert_str_eq(sv_job_state(np.port, "", b, NULL), "queued");
	/* The bed is not clear while the interrupted part is on it. */
	sv_bed_clear(np.port, "", 409);
	/* Resume: it continues after the dwell it was in, then waits for the bed. */
	sv_expect(np.port, "POST", "/api/job", "X-Api-Key: " KEY_CTL,
	     "{\"command\":\"pause\",\"action\":\"resume\"}", 204);
	sv_wait_state(np.port, "", a, "done", 5);
	ck_assert_str_eq(sv_job_state(np.port, "", b, NULL), "queued");
	sv_bed_clear(np.port, "", 204);
	sv_wait_state(np.port, "", b, "done", 5);
	sv_stop(&np);
}
END_TEST

START_TEST(test_not_operational)
{
	struct node_proc np;
	struct resp r;

	sv_write_config(&np, "[printer real]\nprofile = generic-marlin\nport = /dev/ttyACM9\n", 8);
	sv_start(&np);
	sv_expect(np.port, "GET", "/api/printer", "X-Api-Key: " KEY_READ, NULL, 409);
	/* The worker's first attempt to open the port may still be under way
	 * (plain "Offline"); on a loaded machine that takes a while. */
	char state[64] = "";
	for (int i = 0; i < 100 && strcmp(state, "Offline after error"); i++) {
		if (i)
			usleep(100000);
		sv_http(np.port, "GET", "/p/real/api/connection", "X-Api-Key: " KEY_READ, NULL, &r);
		ck_assert_int_eq(r.status, 200);
		const char *s = json_string_value(json_object_get(json_object_get(r.json, "current"),
								  "state"));
		snprintf(state, sizeof(state), "%s", s ? s : "");
		sv_resp_free(&r);
		ck_assert_msg(!strcmp(state, "Offline") || !strcmp(state, "Offline after error"),
			      "state '%s'", state);
	}
	ck_assert_str_eq(state, "Offline after error");
	/* Uploads still queue; nothing prints until the printer is there. */
	sv_upload_text(np.port, "", KEY_UP, "wait.gcode", "G28\n", "true", &r);
	ck_assert_int_eq(r.status, 201);
	usleep(1200000);
	ck_assert_str_eq(sv_job_state(np.port, "", sv_job_of(&r), NULL), "queued");
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/nothing", "X-Api-Key: " KEY_READ, NULL, 404);
	sv_stop(&np);
}
END_TEST

START_TEST(test_config_errors)
{
	static const struct {
		const char *text, *want;
	} cases[] = {
		{"[node]\ndata_dir = d\nlisten = 1.2.3:80\n", "line 3: listen:"},
		{"[node]\ndata_dir = d\n[key a]\nkey = short\nroles = read\n", "line 4: key:"},
		{"[node]\ndata_dir = d\n[key a]\nkey = 0123456789abcdef\nroles = read, admin\n",
		 "line 5: roles:"},
		{"[node]\ndata_dir = d\nmax_upload = 5\n", "line 3: unknown key 'max_upload'"},
		{"[node]\ndata_dir = d\n[key a]\nkey = 0123456789abcdef\nroles = read\n",
		 "no [printer NAME]"},
		{"[node]\ndata_dir = d\n[printer p]\nprofile = generic-marlin\nport = sim\n",
		 "no [key NAME]"},
		{"[node]\ndata_dir = d\n[key a]\nkey = 0123456789abcdef\nroles = read\n"
		 "[printer p]\nprofile = generic-marlin\nport = sim\nprefix = /api/x\n",
		 "line 9: prefix:"},
		{"[node]\ndata_dir = d\n[key a]\nkey = 0123456789abcdef\nroles = read\n"
		 "[printer p]\nprofile = no-such-printer\nport = sim\n",
		 "[printer p]"},
		/* Beyond long long (issue 17, found by fuzzing): out of range, and
		 * no undefined float-to-integer conversion on the way. */
		{"[node]\ndata_dir = d\nmax_upload_mb = 99999999999999999999\n",
		 "line 3: max_upload_mb: 99999999999999999999 is out of range"},
		{"[node]\nslice_threads = -99999999999999999999\n",
		 "line 2: slice_threads: -99999999999999999999 is out of range"},
		{"[node]\nmax_connections = 4\n", "line 2: max_connections: 4 is out of range"},
		{"[node]\nmax_connections_per_ip = 0\n",
		 "line 2: max_connections_per_ip: 0 is out of range"},
		{"[node]\nidle_timeout_s = 3601\n", "line 2: idle_timeout_s: 3601 is out of range"},
		{"[node]\nlisten = 127.0.0.1:99999999999999999999\n",
		 "line 2: listen: '127.0.0.1:99999999999999999999': port 99999999999999999999 is "
		 "out of range"},
		{"[node]\nlisten = 127.0.0.1:65536\n", "line 2: listen: '127.0.0.1:65536': port "
							 "65536 is out of range"},
		{"[node]\ndata_dir = d\n[printer p]\nsim_speedup = 99999999999999999999\n",
		 "line 4: sim_speedup: 99999999999999999999 is out of range"},
		{"[node]\ndata_dir = d\n[mqtt]\nport = 99999999999999999999\n",
		 "line 4: port: 99999999999999999999 is out of range"},
		{"[node]\ndata_dir = d\n[mqtt]\nkeepalive = -99999999999999999999\n",
		 "line 4: keepalive: -99999999999999999999 is out of range"},
		{"[node]\ndata_dir = d\nmax_upload_mb = 2.5\n",
		 "line 3: max_upload_mb: '2.5' is not a whole number"},
	};
	char out[4096];

	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		const char *path = tu_path("bad-node.ini");
		int rc;

		tu_write_str(path, cases[i].text);
		rc = tu_run(out, sizeof(out), "serve --config %s", path);
		ck_assert_msg(rc == 65, "case %zu: exit %d: %s", i, rc, out);
		ck_assert_msg(strstr(out, cases[i].want), "case %zu: %s", i, out);
	}
	ck_assert_int_eq(tu_run(out, sizeof(out), "serve"), 2);
	ck_assert_int_eq(tu_run(out, sizeof(out), "serve --config %s", tu_path("missing.ini")), 65);
}
END_TEST

Suite *serve_suite(void)
{
	Suite *s = suite_create("serve");
	TCase *tc = tcase_create("node");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_version_as_prusaslicer);
	tcase_add_test(tc, test_auth);
	tcase_add_test(tc, test_upload_as_prusaslicer);
	tcase_add_test(tc, test_upload_for_another_printer);
	tcase_add_test(tc, test_oversize);
	tcase_add_test(tc, test_hostile_names);
	tcase_add_test(tc, test_stl_two_printers);
	tcase_add_test(tc, test_node_gcode_is_slice_gcode);
	tcase_add_test(tc, test_node_slices_two_object_3mf);
	tcase_add_test(tc, test_upload_settings);
	tcase_add_test(tc, test_pause_resume_cancel);
	tcase_add_test(tc, test_kill9_restart);
	tcase_add_test(tc, test_not_operational);
	tcase_add_test(tc, test_config_errors);
	suite_add_tcase(s, tc);
	serve_abuse_tcases(s);
	serve_sim_tcases(s);
	serve_mqtt_tcases(s);
	serve_page_tcases(s);
	return s;
}

/*
 * check_farm.c - the farm view (`stratum farm`, docs/serve.md "The farm
 * view"): its config, then a mosquitto broker on loopback with two nodes of
 * two test-instant printers each (farm-a and farm-b: an Ender-3 and an
 * MK3S on each) and the farm view on it, whose JSON shows all four printers
 * with their nodes' links, whose job call hands a file to the first idle
 * printer of a profile (and refuses when none is; farm-b through the URL
 * the farm's config pins for it), and whose page shows
 * both nodes in headless Chromium without a JavaScript error.
 */
#include <check.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "browser.h"
#include "mqtttest.h"
#include "serve/node.h"
#include "servetest.h"
#include "suites.h"
#include "testutil.h"

#define FARM_KEY_A "farm-key-of-node-a-0123"
#define FARM_KEY_B "farm-key-of-node-b-0123"
#define ENDER "creality-ender-3"
#define MK3S "prusa-i3-mk3s"

/* A broker, two nodes and the farm view on it. */
struct farm_env {
	pid_t broker;
	int broker_port;
	struct node_proc node[2], farm;
};

/* np's files in the scratch folder dir, its config text. */
static void write_proc(struct node_proc *np, const char *dir, const char *text)
{
	snprintf(np->dir, sizeof(np->dir), "%s", tu_path(dir));
	mkdir(np->dir, 0700);
	snprintf(np->config, sizeof(np->config), "%s/%s.ini", np->dir, dir);
	snprintf(np->log, sizeof(np->log), "%s/%s.log", np->dir, dir);
	tu_write_str(np->config, text);
	chmod(np->config, 0600);
}

/* GET /api/farm with the read key. */
static json_t *farm_state(int port)
{
	struct resp r;
	json_t *o;

	sv_http(port, "GET", "/api/farm", "X-Api-Key: " KEY_READ, NULL, &r);
	ck_assert_msg(r.status == 200, "GET /api/farm: %d %s", r.status, r.body);
	o = json_incref(r.json);
	sv_resp_free(&r);
	return o;
}

/* Printer name of node number i in the farm's JSON, or NULL. */
static json_t *farm_printer(json_t *farm, size_t i, const char *name)
{
	json_t *p;
	size_t k;

	json_array_foreach(json_object_get(json_array_get(json_object_get(farm, "nodes"), i),
					   "printers"), k, p)
		if (!strcmp(json_string_value(json_object_get(p, "name")), name))
			return p;
	return NULL;
}

/* Wait up to 10 s for the farm to show `idle` idle printers of 4. */
static json_t *wait_farm(int port, int idle)
{
	json_t *o = NULL;

	for (int i = 0; i < 100; i++) {
		json_decref(o);
		o = farm_state(port);
		if (json_integer_value(json_object_get(o, "printers")) == 4 &&
		    json_integer_value(json_object_get(o, "idle")) == idle)
			return o;
		usleep(100000);
	}
	ck_abort_msg("the farm did not show 4 printers, %d idle: %s", idle,
		     json_dumps(o, JSON_COMPACT));
	return NULL;
}

/* Wait up to 10 s for node number i to be shown offline. */
static json_t *wait_offline(int port, size_t i)
{
	json_t *o = NULL;

	for (int k = 0; k < 100; k++) {
		json_decref(o);
		o = farm_state(port);
		if (json_is_false(json_object_get(json_array_get(json_object_get(o, "nodes"), i),
						  "online")))
			return o;
		usleep(100000);
	}
	ck_abort_msg("node %zu is not shown offline: %s", i, json_dumps(o, JSON_COMPACT));
	return NULL;
}

static void farm_up(struct farm_env *e)
{
	static const char *const names[2] = {"a", "b"}, *const keys[2] = {FARM_KEY_A, FARM_KEY_B};
	char text[2048], dir[16];

	e->broker_port = free_port();
	e->broker = anon_broker_start(e->broker_port);
	for (int i = 0; i < 2; i++) {
		snprintf(text, sizeof(text),
			 "[node]\nname = farm-%s\nlisten = 127.0.0.1:0\ndata_dir = data\n"
			 "[key operator]\nkey = " KEY_CTL "\nroles = read, upload, control\n"
			 "[key slicer]\nkey = " KEY_UP "\nroles = read, upload\n"
			 "[key viewer]\nkey = " KEY_READ "\nroles = read\n"
			 "[key farm]\nkey = %s\nroles = read, upload\n" TWO_PRINTERS
			 "[mqtt]\nhost = 127.0.0.1\nport = %d\nkeepalive = 5\n",
			 names[i], keys[i], e->broker_port);
		snprintf(dir, sizeof(dir), "node-%s", names[i]);
		write_proc(&e->node[i], dir, text);
		sv_start(&e->node[i]);
	}
	snprintf(text, sizeof(text),
		 "[farm]\nname = test-farm\nlisten = 127.0.0.1:0\nmax_upload_mb = 8\n"
		 "[key viewer]\nkey = " KEY_READ "\nroles = read\n"
		 "[key dispatcher]\nkey = " KEY_UP "\nroles = read, upload\n"
		 "[remote farm-a]\nkey = " FARM_KEY_A "\n[remote farm-b]\nkey = " FARM_KEY_B "\n"
		 "url = http://localhost:%d\n"
		 "[mqtt]\nhost = 127.0.0.1\nport = %d\nkeepalive = 5\n", e->node[1].port,
		 e->broker_port);
	write_proc(&e->farm, "farm", text);
	sv_start_cmd(&e->farm, "farm");
}

/* Stop what farm_up started and a test did not stop (pid 0). */
static void farm_down(struct farm_env *e)
{
	sv_stop(&e->farm);
	for (int i = 1; i >= 0; i--)
		if (e->node[i].pid)
			sv_stop(&e->node[i]);
	broker_stop(e->broker);
}

/* POST /api/farm/jobs: profile and a G-code file name with text, as a
 * browser's form sends them, with the key header auth (or NULL). */
static void send_job(int port, const char *auth, const char *profile, const char *name,
		     const char *text, struct resp *r)
{
	char body[4096], req[8192];
	int n = snprintf(body, sizeof(body),
			 "--" BOUNDARY "\r\nContent-Disposition: form-data; name=\"profile\"\r\n\r\n"
			 "%s\r\n--" BOUNDARY "\r\nContent-Disposition: form-data; name=\"file\"; "
			 "filename=\"%s\"\r\nContent-Type: application/octet-stream\r\n\r\n%s\r\n--"
			 BOUNDARY "--\r\n", profile, name, text);
	int m = snprintf(req, sizeof(req),
			 "POST /api/farm/jobs HTTP/1.1\r\nHost: 127.0.0.1:%d\r\n%s%s"
			 "Content-Type: multipart/form-data; boundary=" BOUNDARY "\r\n"
			 "Content-Length: %d\r\nConnection: close\r\n\r\n%s",
			 port, auth ? auth : "", auth ? "\r\n" : "", n, body);

	sv_http_raw(port, req, (size_t)m, r);
}

/* The config: [farm] takes the HTTP keys of [node] and node_key, [remote
 * NODE] the farm's key on that node and its URL; a node's sections are
 * refused. */
START_TEST(test_farm_config)
{
	static const struct {
		const char *text, *want;
	} cases[] = {
		{"[farm]\ndata_dir = d\n", "line 2: unknown key 'data_dir' in [farm] (node_key, "
					   "name, listen, max_upload_mb"},
		{"[node]\n", "line 1: unknown section [node] (farm, key NAME, remote NODE, mqtt)"},
		{"[printer p]\n", "unknown section [printer p] (farm, key NAME, remote NODE, mqtt)"},
		{"[remote farm-1]\n", "[remote farm-1] needs key ="},
		{"[remote farm-1]\nkey = short\n", "line 2: key: 5 bytes; an API key has 16 to 128"},
		{"[remote x]\nkey = " FARM_KEY_A "\n[remote x]\n", "line 3: [remote x] given twice"},
		{"[remote x]\nurl = farm-1:5000\n", "line 2: url: 'farm-1:5000' is not a URL"},
	};
	struct farm_config *c = calloc(1, sizeof(*c));
	struct node_config *n = calloc(1, sizeof(*n));
	struct st_error err = {0};
	const char *path = tu_path("farm.ini");
	char text[1024];

	ck_assert(c && n);
	for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); i++) {
		snprintf(text, sizeof(text), "%s[key k]\nkey = " KEY_READ "\nroles = read\n",
			 cases[i].text);
		tu_write_str(path, text);
		ck_assert_msg(farm_config_load(path, c, &err) != 0, "%s loads", cases[i].text);
		ck_assert_msg(strstr(err.msg, cases[i].want), "%s: %s", cases[i].text, err.msg);
	}
	tu_write_str(path, "[farm]\nname = north\nnode_key = " FARM_KEY_A "\nlisten = 0.0.0.0:5100\n"
			   "[key k]\nkey = " KEY_READ "\nroles = read\n"
			   "[remote farm-2]\nkey = " FARM_KEY_B "\nurl = https://farm-2.lan:5000\n"
			   "[mqtt]\nhost = broker\n");
	ck_assert_msg(farm_config_load(path, c, &err) == 0, "%s", err.msg);
	ck_assert_str_eq(c->node_key, FARM_KEY_A);
	ck_assert_str_eq(c->remotes[0].name, "farm-2");
	ck_assert_str_eq(c->remotes[0].key, FARM_KEY_B);
	ck_assert_str_eq(c->remotes[0].url, "https://farm-2.lan:5000");
	ck_assert_str_eq(c->base.mqtt.client_id, "stratum-farm-north");
	ck_assert_uint_eq(c->base.listen_port, 5100);
	/* and a node's config takes neither node_key nor [remote] */
	tu_write_str(path, "[node]\ndata_dir = d\nnode_key = " FARM_KEY_A "\n");
	ck_assert(node_config_load(path, n, &err) != 0);
	ck_assert_msg(strstr(err.msg, "line 3: unknown key 'node_key' in [node]"), "%s", err.msg);
	free(c);
	free(n);
}
END_TEST

/* Both nodes' printers in one JSON; jobs to the first idle printer of a
 * profile; refusals when none is idle, for no such profile, without a key. */
START_TEST(test_farm_api_and_jobs)
{
	struct farm_env e;
	struct resp r;
	json_t *farm, *p, *q;
	char path[128];
	long long busy;

	if (!have_broker("test_farm_api_and_jobs"))
		return;
	farm_up(&e);
	farm = wait_farm(e.farm.port, 4);
	for (size_t i = 0; i < 2; i++) {
		json_t *node = json_array_get(json_object_get(farm, "nodes"), i);
		char url[64];

		/* farm-a as it announces itself, farm-b where the farm's config pins it */
		snprintf(url, sizeof(url), "http://%s:%d", i ? "localhost" : "127.0.0.1",
			 e.node[i].port);
		ck_assert_str_eq(sv_str(node, "name"), i ? "farm-b" : "farm-a");
		ck_assert(json_is_true(json_object_get(node, "online")));
		ck_assert_str_eq(sv_str(node, "url"), url);
		p = farm_printer(farm, i, "ender");
		ck_assert_ptr_nonnull(p);
		ck_assert_str_eq(sv_str(p, "profile"), ENDER);
		ck_assert_str_eq(sv_str(p, "state"), "Operational");
		ck_assert(strstr(sv_str(p, "url"), "/p/ender"));
		ck_assert(json_is_true(json_object_get(p, "bedClear")));
		ck_assert_ptr_nonnull(json_object_get(json_object_get(p, "temperature"), "tool0"));
		ck_assert_str_eq(sv_str(farm_printer(farm, i, "mk3s"), "profile"), MK3S);
	}
	json_decref(farm);
	/* farm-a's Ender prints, 12 minutes left by its M73: the farm shows it */
	busy = sv_print_text(e.node[0].port, "/p/ender", "hold.gcode",
			     "M73 P0 R12\nM104 S205\nG4 P20000\nM73 P100 R0\n");
	sv_wait_state(e.node[0].port, "/p/ender", busy, "printing", 10);
	farm = wait_farm(e.farm.port, 3);
	p = farm_printer(farm, 0, "ender");
	ck_assert_str_eq(sv_str(p, "state"), "Printing");
	ck_assert_str_eq(sv_str(json_object_get(p, "job"), "name"), "hold.gcode");
	ck_assert_int_eq(json_integer_value(json_object_get(json_object_get(p, "progress"),
							    "printTimeLeft")), 720);
	json_decref(farm);

	/* an Ender job: farm-a's is busy, so farm-b's takes it */
	send_job(e.farm.port, "X-Api-Key: " KEY_UP, ENDER, "part.gcode", "G28\nG4 P20000\n", &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	ck_assert_str_eq(sv_str(r.json, "node"), "farm-b");
	ck_assert_str_eq(sv_str(r.json, "printer"), "ender");
	snprintf(path, sizeof(path), "/p/ender/api/stratum/queue/%lld",
		 (long long)json_integer_value(json_object_get(r.json, "job")));
	sv_resp_free(&r);
	q = sv_get_json(e.node[1].port, path);
	ck_assert_str_eq(sv_str(q, "name"), "part.gcode");
	json_decref(q);
	/* no Ender is idle now, even before farm-b publishes its state */
	send_job(e.farm.port, "X-Api-Key: " KEY_UP, ENDER, "part2.gcode", "G28\n", &r);
	ck_assert_msg(r.status == 409, "%d %s", r.status, r.body);
	ck_assert_msg(strstr(sv_str(r.json, "error"), "no printer with the profile "
			     "'creality-ender-3' is idle (2 of them"), "%s", r.body);
	sv_resp_free(&r);
	/* an MK3S job: the first node's; the next goes on to farm-b */
	send_job(e.farm.port, "X-Api-Key: " KEY_UP, MK3S, "mk.gcode", "G28\n", &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	ck_assert_str_eq(sv_str(r.json, "node"), "farm-a");
	ck_assert_str_eq(sv_str(r.json, "printer"), "mk3s");
	sv_resp_free(&r);
	send_job(e.farm.port, "X-Api-Key: " KEY_UP, MK3S, "mk2.gcode", "G28\n", &r);
	ck_assert_msg(r.status == 201, "%d %s", r.status, r.body);
	ck_assert_str_eq(sv_str(r.json, "node"), "farm-b");
	sv_resp_free(&r);
	/* farm-b stops: still listed, offline, its printers neither idle nor as they were */
	sv_stop(&e.node[1]);
	e.node[1].pid = 0;
	farm = wait_offline(e.farm.port, 1);
	ck_assert_int_eq(json_integer_value(json_object_get(farm, "printers")), 4);
	ck_assert_str_eq(sv_str(farm_printer(farm, 1, "mk3s"), "state"), "Offline");
	json_decref(farm);
	send_job(e.farm.port, "X-Api-Key: " KEY_UP, "no-such-printer", "x.gcode", "G28\n", &r);
	ck_assert_msg(r.status == 404, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	send_job(e.farm.port, "X-Api-Key: " KEY_UP, MK3S, "x.txt", "G28\n", &r);
	ck_assert_msg(r.status == 415, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	/* the node's key model: read cannot send jobs, no key reads nothing */
	send_job(e.farm.port, "X-Api-Key: " KEY_READ, MK3S, "x.gcode", "G28\n", &r);
	ck_assert_msg(r.status == 403, "%d %s", r.status, r.body);
	sv_resp_free(&r);
	sv_expect(e.farm.port, "GET", "/api/farm", NULL, NULL, 403);
	sv_expect(e.farm.port, "GET", "/api/farm", "X-Api-Key: " KEY_CTL, NULL, 403);
	farm_down(&e);
}
END_TEST

/* The farm view bounds a slow client as a node does (header_timeout_s,
 * min_body_rate): a header or a job's body trickled one byte every 250 ms
 * loses its connection after 1 s, though idle_timeout_s (3 s) never runs
 * out.  No broker is needed: the page and the API answer without one. */
START_TEST(test_farm_slow_client)
{
	static const char *const head[2] = {
		"GET /api/farm HTTP/1.1\r\nHost: x\r\nX-Api-Key: " KEY_READ "\r\n",
		"POST /api/farm/jobs HTTP/1.1\r\nHost: x\r\nX-Api-Key: " KEY_UP "\r\n"
		"Content-Type: multipart/form-data; boundary=" BOUNDARY "\r\n"
		"Content-Length: 100000\r\n\r\n--" BOUNDARY "\r\n"};
	struct node_proc farm;
	char text[1024];
	double closed_at[2];
	json_t *o;

	snprintf(text, sizeof(text),
		 "[farm]\nname = test-farm\nlisten = 127.0.0.1:0\nidle_timeout_s = 3\n"
		 "header_timeout_s = 1\nmin_body_rate = 1000\n"
		 "[key viewer]\nkey = " KEY_READ "\nroles = read\n"
		 "[key dispatcher]\nkey = " KEY_UP "\nroles = read, upload\n"
		 "[mqtt]\nhost = 127.0.0.1\nport = %d\nkeepalive = 5\n", free_port());
	write_proc(&farm, "farm-slow", text);
	sv_start_cmd(&farm, "farm");
	sv_trickle(farm.port, head, closed_at, 2.8);
	ck_assert_msg(closed_at[0] > 0.8 && closed_at[0] < 2.0,
		      "a header trickled kept its connection (closed at %.1f s)", closed_at[0]);
	ck_assert_msg(closed_at[1] > 0.8 && closed_at[1] < 2.0,
		      "a body trickled kept its connection (closed at %.1f s)", closed_at[1]);
	o = farm_state(farm.port);
	ck_assert(json_is_array(json_object_get(o, "nodes")));
	json_decref(o);
	sv_stop(&farm);
}
END_TEST

/* The page shows both nodes' printers from one page, with no JS error. */
START_TEST(test_farm_page)
{
	struct farm_env e;
	struct browser b;
	struct resp r;
	char url[200], *text;
	json_t *v;

	if (!have_broker("test_farm_page"))
		return;
	if (!browser_path()) {
		printf("farm: page test skipped: no chromium (make check installs it)\n");
		return;
	}
	farm_up(&e);
	json_decref(wait_farm(e.farm.port, 4));
	sv_http(e.farm.port, "GET", "/", NULL, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert(strstr(r.body, "api/farm"));
	sv_resp_free(&r);
	browser_open(&b, tu_path("chromium-profile"));
	snprintf(url, sizeof(url), "http://127.0.0.1:%d/#key=%s", e.farm.port, KEY_READ);
	browser_go(&b, url);
	v = browser_until(&b, "document.querySelectorAll('tr[data-printer]').length === 4", 10);
	json_decref(v);
	text = browser_text(&b, "Array.prototype.map.call(document.querySelectorAll("
				"'tr[data-printer]'), function (t) { return t.getAttribute("
				"'data-printer') + ':' + t.children[2].textContent; }).join(' ')", 5);
	ck_assert_str_eq(text, "farm-a/mk3s:Operational (idle) farm-a/ender:Operational (idle) "
			       "farm-b/mk3s:Operational (idle) farm-b/ender:Operational (idle)");
	free(text);
	/* each node's name links to its own page */
	snprintf(url, sizeof(url), "http://localhost:%d/", e.node[1].port);
	text = browser_text(&b, "document.querySelector('h2[data-node=farm-b] a').href", 5);
	ck_assert_str_eq(text, url);
	free(text);
	ck_assert_msg(!b.errors, "the page raised %d JavaScript errors, first %s", b.errors,
		      b.first_error);
	browser_close(&b);
	farm_down(&e);
}
END_TEST

Suite *farm_suite(void)
{
	Suite *s = suite_create("farm");
	TCase *tc = tcase_create("farm");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_farm_config);
	tcase_add_test(tc, test_farm_api_and_jobs);
	tcase_add_test(tc, test_farm_page);
	tcase_add_test(tc, test_farm_slow_client);
	suite_add_tcase(s, tc);
	return s;
}

/*
 * check_servepage.c - the status page as an operator's console
 * (docs/serve.md, "Status page"), part of the serve suite: loaded in
 * headless Chromium (tests/browser.h) from a node of two test-instant
 * printers, it must show what the API knows (time left, a failed job's
 * reason, the temperature chart), and its buttons and upload form must act
 * through the API, with no JavaScript error on the way.  Skipped with a
 * message when chromium is not installed (make check installs it).
 */
#include <check.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "browser.h"
#include "servetest.h"
#include "suites.h"
#include "testutil.h"

#define ROW(printer, sel) "document.querySelector('tr[data-printer=" printer "] " sel "')"
/* The text of the first element matching sel in printer's row, or ''. */
#define ROW_TEXT(printer, sel) "(" ROW(printer, sel) " || {}).textContent || ''"
/* The operator's message once it is about what (a regular expression). */
#define MSG_ABOUT(what) \
	"/" what "/.test(document.getElementById('msg').textContent) && " \
	"document.getElementById('msg').textContent"
/* Click button b (an expression) times times once it is there, in one turn
 * of the page's event loop (the page asks for a second click to cancel a
 * print or confirm the bed clear). */
#define CLICK_WHEN_THERE(b, times) \
	"(function (b) { if (!b) return false;" \
	" for (var i = 0; i < " times "; i++) b.click(); return true; })(" b ")"
#define CLICK_TWICE(b) CLICK_WHEN_THERE(b, "2")

/* The name of mk3s's next queued job. */
static const char *first_waiting(int port)
{
	static char name[100];
	json_t *q = sv_get_json(port, "/api/stratum/queue");

	snprintf(name, sizeof(name), "%s",
		 sv_str(json_array_get(json_object_get(q, "waiting"), 0), "name"));
	json_decref(q);
	return name;
}

/* Click the button that sel_fmt, with %lld for the job id, selects. */
static void click_job(struct browser *b, const char *sel_fmt, long long id)
{
	char sel[300], js[400];

	snprintf(sel, sizeof(sel), sel_fmt, id);
	snprintf(js, sizeof(js), CLICK_WHEN_THERE("%s", "1"), sel);
	json_decref(browser_until(b, js, 5));
}

/* Start a browser on the page of np with key; false (test skipped) without
 * chromium. */
static bool open_page(struct browser *b, const struct node_proc *np, const char *key)
{
	char url[200];

	if (!browser_path()) {
		printf("serve: status page browser test skipped: no chromium (make check installs "
		       "it)\n");
		return false;
	}
	browser_open(b, tu_path("chromium-profile"));
	snprintf(url, sizeof(url), "http://127.0.0.1:%d/#key=%s", np->port, key);
	browser_go(b, url);
	json_decref(browser_until(b, "document.body.getAttribute('data-updates')", 10));
	return true;
}

/* Wait up to 10 s for the string expr to be non-empty in the page; it must
 * contain needle. */
static void expect_text(struct browser *b, const char *expr, const char *needle)
{
	char *text = browser_text(b, expr, 10);

	ck_assert_msg(strstr(text, needle), "%s: \"%s\" has no \"%s\"", expr, text, needle);
	free(text);
}

/* The page itself needs no key (it holds no data); the data does. */
START_TEST(test_page_needs_key_for_data)
{
	struct node_proc np;
	struct resp r;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	sv_http(np.port, "GET", "/", NULL, NULL, &r);
	ck_assert_int_eq(r.status, 200);
	ck_assert(sv_has_text(r.head, "Content-Type: text/html"));
	ck_assert(strstr(r.body, "api/stratum/node"));
	sv_resp_free(&r);
	sv_expect(np.port, "GET", "/api/stratum/node", NULL, NULL, 403);
	sv_stop(&np);
}
END_TEST

/* With a read key: state, queue, time left, a failure's reason, the chart; no buttons. */
START_TEST(test_page_shows)
{
	struct node_proc np;
	struct browser b;
	struct resp r;
	json_t *q, *v;
	const char *why;
	long long bad;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	/* mk3s: a job failed on a bad line (before moving: the bed stays clear) */
	bad = sv_print_text(np.port, "", "bad.gcode", "G28\nG1 X1.2.3\n");
	sv_wait_state(np.port, "", bad, "failed", 10);
	/* ender: printing, 12 minutes left by the file's M73 */
	sv_upload_text(np.port, "/p/ender", KEY_UP, "hold.gcode",
		       "M73 P0 R12\nM104 S205\nG4 P20000\nM73 P100 R0\n", "true", &r);
	sv_wait_state(np.port, "/p/ender", sv_job_of(&r), "printing", 10);
	sv_resp_free(&r);
	if (!open_page(&b, &np, KEY_READ)) {
		sv_stop(&np);
		return;
	}
	expect_text(&b, "document.getElementById('node').textContent", "test-node");
	expect_text(&b, ROW_TEXT("ender", "td.progress .left"), "12 min left");
	expect_text(&b, ROW_TEXT("ender", "td.job"), "hold.gcode (printing)");
	expect_text(&b, ROW_TEXT("ender", "td.tool"), "205 °C");
	/* the reason the node recorded, under the printer's state */
	q = sv_get_json(np.port, "/api/stratum/queue");
	why = sv_str(json_array_get(json_object_get(q, "jobs"), 0), "error");
	expect_text(&b, ROW_TEXT("mk3s", "td.state .reason"), "failed: ");
	expect_text(&b, ROW_TEXT("mk3s", "td.state .reason"), why);
	json_decref(q);
	/* the chart: samples of the last minutes, drawn */
	v = browser_until(&b,
			  "(function (c) {"
			  " if (!c || !+c.getAttribute('data-points')) return 0;"
			  " var d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data, n = 0;"
			  " for (var i = 3; i < d.length; i += 4) if (d[i]) n++;"
			  " return n;"
			  "})(" ROW("ender", "canvas") ")",
			  10);
	ck_assert_int_gt(json_integer_value(v), 50);
	json_decref(v);
	/* a read key gets no buttons and no upload form */
	v = browser_eval(&b, "document.querySelectorAll('button[data-action]').length");
	ck_assert_int_eq(json_integer_value(v), 0);
	json_decref(v);
	v = browser_eval(&b, "document.getElementById('upload').hidden");
	ck_assert(json_is_true(v));
	json_decref(v);
	ck_assert_msg(!b.errors, "the page raised %d JavaScript errors, first %s", b.errors,
		      b.first_error);
	browser_close(&b);
	sv_stop(&np);
}
END_TEST

/* With a control key: pause, resume, cancel, the queue, bed clear and the
 * upload form act through the API. */
START_TEST(test_page_acts)
{
	struct node_proc np;
	struct browser b;
	struct resp r;
	long long hold, next, later, requeued;
	json_t *q, *v;

	sv_write_config(&np, TWO_PRINTERS, 8);
	sv_start(&np);
	/* mk3s: a print that moved it is done, the next waits for the bed */
	sv_wait_state(np.port, "", sv_print_text(np.port, "", "moved.gcode", "G28\nG1 X5\n"), "done",
		      10);
	next = sv_print_text(np.port, "", "next.gcode", "G28\n");
	sv_upload_text(np.port, "/p/ender", KEY_UP, "hold.gcode", "M104 S205\nG4 P20000\n", "true",
		       &r);
	hold = sv_job_of(&r);
	sv_resp_free(&r);
	sv_wait_state(np.port, "/p/ender", hold, "printing", 10);
	if (!open_page(&b, &np, KEY_CTL)) {
		sv_stop(&np);
		return;
	}
	expect_text(&b, "(" ROW("mk3s", "td.state") " || {}).firstChild.nodeValue",
		    "Waiting for bed clear");
	expect_text(&b, ROW_TEXT("mk3s", "td.bed"), "not confirmed clear");
	expect_text(&b, ROW_TEXT("mk3s", "td.queue li"), "#2 next.gcode");
	/* only what the state allows: no pause on a printer waiting for its bed */
	v = browser_eval(&b, "!!" ROW("mk3s", "button[data-action=pause]"));
	ck_assert(json_is_false(v));
	json_decref(v);

	/* Pause and resume the running job, each as the API then reports it. */
	json_decref(browser_until(&b, CLICK_WHEN_THERE(ROW("ender", "button[data-action=pause]"),
						       "1"), 5));
	sv_wait_state(np.port, "/p/ender", hold, "paused", 5);
	json_decref(browser_until(&b, CLICK_WHEN_THERE(ROW("ender", "button[data-action=resume]"),
						       "1"), 5));
	sv_wait_state(np.port, "/p/ender", hold, "printing", 5);

	/* Cancel the running job: two clicks, then the API says cancelled. */
	json_decref(browser_until(&b, CLICK_TWICE(ROW("ender", "button[data-action=cancel]")), 5));
	sv_wait_state(np.port, "/p/ender", hold, "cancelled", 10);
	expect_text(&b, MSG_ABOUT("cancel"), "cancel: done");

	/* The queue: move a job up, cancel one, requeue it (a new job, last). */
	later = sv_print_text(np.port, "", "later.gcode", "G28\n");
	click_job(&b, ROW("mk3s", "li[data-job=\"%lld\"] button[data-action=move-up]"), later);
	expect_text(&b, MSG_ABOUT("move"), "move-up: done");
	ck_assert_str_eq(first_waiting(np.port), "later.gcode");
	click_job(&b, ROW("mk3s", "td.queue li[data-job=\"%lld\"] button[data-action=cancel-queued]"),
		  next);
	sv_wait_state(np.port, "", next, "cancelled", 5);
	click_job(&b, ROW("mk3s", "td.recent li[data-job=\"%lld\"] button[data-action=requeue]"),
		  next);
	expect_text(&b, MSG_ABOUT("requeue"), "requeue: done");
	q = sv_get_json(np.port, "/api/stratum/queue");
	ck_assert_str_eq(sv_str(json_array_get(json_object_get(q, "waiting"), 1), "name"),
			 "next.gcode");
	requeued = json_integer_value(json_object_get(json_array_get(json_object_get(q, "waiting"),
								     1), "id"));
	json_decref(q);

	/* Confirm the bed clear: the first queued job prints (and homes: the
	 * requeued one waits for the next confirmation). */
	json_decref(
		browser_until(&b, CLICK_TWICE(ROW("mk3s", "button[data-action=bed-clear]")), 5));
	sv_wait_state(np.port, "", later, "done", 10);
	ck_assert_str_eq(sv_job_state(np.port, "", requeued, NULL), "queued");

	/* Upload to ender and print: the form posts the multipart upload. */
	json_decref(browser_eval(&b, "(function () {"
				     " var t = new DataTransfer();"
				     " t.items.add(new File(['M104 S200\\n'], 'up.gcode'));"
				     " document.getElementById('upfile').files = t.files;"
				     " document.getElementById('upprinter').selectedIndex = 1;"
				     " document.getElementById('upprint').checked = true;"
				     " document.getElementById('upsend').click();"
				     " return true; })()"));
	expect_text(&b, MSG_ABOUT("Upload"), "Upload of up.gcode: done");
	q = sv_get_json(np.port, "/p/ender/api/stratum/queue");
	ck_assert_str_eq(sv_str(json_array_get(json_object_get(q, "jobs"), 0), "name"), "up.gcode");
	json_decref(q);
	sv_expect(np.port, "GET", "/p/ender/api/files/local/up.gcode", "X-Api-Key: " KEY_READ, NULL,
		  200);
	/* A file over the node's limit (8 MiB here) is refused before it is sent. */
	json_decref(browser_eval(&b, "(function () {"
				     " var t = new DataTransfer();"
				     " t.items.add(new File([new Uint8Array(9 << 20)], 'big.gcode'));"
				     " document.getElementById('upfile').files = t.files;"
				     " document.getElementById('upsend').click();"
				     " return true; })()"));
	expect_text(&b, MSG_ABOUT("big.gcode"),
		    "big.gcode is larger than the node’s limit of 8388608 bytes");
	sv_expect(np.port, "GET", "/p/ender/api/files/local/big.gcode", "X-Api-Key: " KEY_READ,
		  NULL, 404);
	ck_assert_msg(!b.errors, "the page raised %d JavaScript errors, first %s", b.errors,
		      b.first_error);
	browser_close(&b);
	sv_stop(&np);
}
END_TEST

void serve_page_tcases(Suite *s)
{
	TCase *tc = tcase_create("page");

	tcase_set_timeout(tc, 60);
	tcase_add_test(tc, test_page_needs_key_for_data);
	tcase_add_test(tc, test_page_shows);
	tcase_add_test(tc, test_page_acts);
	suite_add_tcase(s, tc);
}

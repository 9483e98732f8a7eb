/*
 * browser.c - headless Chromium over the DevTools protocol on a pipe
 * (browser.h).  Each call sends one command and reads messages until its
 * answer comes, counting the page's JavaScript errors from the events that
 * arrive meanwhile.
 */
#include <check.h>
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "browser.h"

#define ANSWER_SECS 30 /* a command's answer; loading a page included */

const char *browser_path(void)
{
	static const char *const browsers[] = {"/usr/bin/chromium", "/usr/bin/chromium-browser",
					       "/usr/bin/google-chrome"};

	for (size_t i = 0; i < sizeof(browsers) / sizeof(browsers[0]); i++)
		if (!access(browsers[i], X_OK))
			return browsers[i];
	return NULL;
}

static void note_error(struct browser *b, const char *what, const char *text)
{
	if (!b->errors++)
		snprintf(b->first_error, sizeof(b->first_error), "%s: %s", what,
			 text ? text : "(no text)");
}

/* An event: count what the page reported as an error.  A failed request
 * (a 409 the page asked for and showed) is the network's, not the script's. */
static void on_event(struct browser *b, const char *method, json_t *params)
{
	if (!strcmp(method, "Runtime.exceptionThrown")) {
		json_t *d = json_object_get(params, "exceptionDetails");
		json_t *ex = json_object_get(d, "exception");

		note_error(b, "exception", json_string_value(json_object_get(
						   ex ? ex : d, ex ? "description" : "text")));
	} else if (!strcmp(method, "Runtime.consoleAPICalled")) {
		const char *type = json_string_value(json_object_get(params, "type"));
		json_t *arg = json_array_get(json_object_get(params, "args"), 0);

		if (type && !strcmp(type, "error"))
			note_error(b, "console.error",
				   json_string_value(json_object_get(arg, "value")));
	} else if (!strcmp(method, "Log.entryAdded")) {
		json_t *e = json_object_get(params, "entry");
		const char *level = json_string_value(json_object_get(e, "level"));
		const char *source = json_string_value(json_object_get(e, "source"));

		if (level && !strcmp(level, "error") && !(source && !strcmp(source, "network")))
			note_error(b, "log", json_string_value(json_object_get(e, "text")));
	}
}

/* Read until the answer to id arrives; its "result" (the caller decrefs). */
static json_t *wait_answer(struct browser *b, int id)
{
	time_t end = time(NULL) + ANSWER_SECS;

	for (;;) {
		char *nul = b->len ? memchr(b->buf, '\0', b->len) : NULL;

		if (nul) {
			size_t used = (size_t)(nul - b->buf) + 1;
			json_t *m = json_loadb(b->buf, used - 1, 0, NULL);
			json_t *mid = json_object_get(m, "id");
			json_t *res = NULL;

			memmove(b->buf, b->buf + used, b->len - used);
			b->len -= used;
			ck_assert_msg(m, "the browser sent a message that is not JSON");
			if (mid && json_integer_value(mid) == id) {
				json_t *err = json_object_get(m, "error");

				ck_assert_msg(!err, "browser command %d: %s", id,
					      json_string_value(json_object_get(err, "message")));
				res = json_incref(json_object_get(m, "result"));
				json_decref(m);
				return res;
			}
			if (json_is_string(json_object_get(m, "method")))
				on_event(b, json_string_value(json_object_get(m, "method")),
					 json_object_get(m, "params"));
			json_decref(m);
			continue;
		}
		struct pollfd pfd = {.fd = b->from, .events = POLLIN};
		int left = (int)(end - time(NULL));
		ssize_t n;

		ck_assert_msg(left > 0, "the browser did not answer command %d in %d s", id,
			      ANSWER_SECS);
		if (poll(&pfd, 1, left * 1000) <= 0)
			continue;
		if (b->len + 65536 > b->cap) {
			b->cap = 2 * b->cap + 65536;
			b->buf = realloc(b->buf, b->cap);
			ck_assert(b->buf);
		}
		n = read(b->from, b->buf + b->len, 65536);
		ck_assert_msg(n > 0, "the browser closed its pipe");
		b->len += (size_t)n;
	}
}

/* Send method with params (stolen; NULL: none), to the page's session when
 * page is true; its result (the caller decrefs). */
static json_t *command(struct browser *b, bool page, const char *method, json_t *params)
{
	json_t *m = json_pack("{s:i,s:s,s:o}", "id", ++b->next_id, "method", method, "params",
			      params ? params : json_object());
	char *text;
	size_t len, off = 0;

	if (page)
		json_object_set_new(m, "sessionId", json_string(b->session));
	text = json_dumps(m, JSON_COMPACT);
	ck_assert(text);
	len = strlen(text) + 1; /* the NUL ends the message */
	while (off < len) {
		ssize_t n = write(b->to, text + off, len - off);

		ck_assert_msg(n > 0 || errno == EINTR, "writing to the browser: %s",
			      strerror(errno));
		if (n > 0)
			off += (size_t)n;
	}
	free(text);
	json_decref(m);
	return wait_answer(b, b->next_id);
}

void browser_open(struct browser *b, const char *profile)
{
	int to[2], from[2];
	char dir[600];
	json_t *r;

	memset(b, 0, sizeof(*b));
	ck_assert(browser_path());
	ck_assert(!pipe(to) && !pipe(from));
	snprintf(dir, sizeof(dir), "--user-data-dir=%s", profile);
	b->pid = fork();
	ck_assert(b->pid >= 0);
	if (!b->pid) {
		int null = open("/dev/null", O_WRONLY);

		/* fd 3: commands in, fd 4: answers out (moved clear of 3 and 4 first) */
		int in = fcntl(to[0], F_DUPFD, 10), out = fcntl(from[1], F_DUPFD, 10);

		dup2(in, 3);
		dup2(out, 4);
		dup2(null, 1);
		dup2(null, 2);
		for (int fd = 5; fd < 64; fd++)
			close(fd);
		execl(browser_path(), browser_path(), "--headless", "--no-sandbox", "--disable-gpu",
		      "--no-first-run", "--remote-debugging-pipe", "--window-size=1500,900", dir,
		      "about:blank", (char *)NULL);
		_exit(127);
	}
	close(to[0]);
	close(from[1]);
	b->to = to[1];
	b->from = from[0];
	signal(SIGPIPE, SIG_IGN);
	r = command(b, false, "Target.createTarget", json_pack("{s:s}", "url", "about:blank"));
	json_t *a = command(b, false, "Target.attachToTarget",
			    json_pack("{s:O,s:b}", "targetId", json_object_get(r, "targetId"),
				      "flatten", 1));
	snprintf(b->session, sizeof(b->session), "%s",
		 json_string_value(json_object_get(a, "sessionId")));
	json_decref(r);
	json_decref(a);
	ck_assert(b->session[0]);
	json_decref(command(b, true, "Runtime.enable", NULL));
	json_decref(command(b, true, "Log.enable", NULL));
	json_decref(command(b, true, "Page.enable", NULL));
}

void browser_close(struct browser *b)
{
	int status;

	json_decref(command(b, false, "Browser.close", NULL));
	close(b->to);
	close(b->from);
	for (int i = 0; i < 100 && waitpid(b->pid, &status, WNOHANG) == 0; i++)
		usleep(50000);
	if (waitpid(b->pid, &status, WNOHANG) == 0) {
		kill(b->pid, SIGKILL);
		waitpid(b->pid, &status, 0);
	}
	free(b->buf);
	b->buf = NULL;
}

void browser_go(struct browser *b, const char *url)
{
	json_decref(command(b, true, "Page.navigate", json_pack("{s:s}", "url", url)));
	json_decref(browser_until(b, "document.readyState === 'complete'", 10));
}

json_t *browser_eval(struct browser *b, const char *expr)
{
	json_t *r = command(b, true, "Runtime.evaluate",
			    json_pack("{s:s,s:b,s:b}", "expression", expr, "awaitPromise", 1,
				      "returnByValue", 1));
	json_t *ex = json_object_get(r, "exceptionDetails"), *v;

	ck_assert_msg(!ex, "%s: %s", expr,
		      json_string_value(json_object_get(json_object_get(ex, "exception"),
							"description")));
	v = json_object_get(json_object_get(r, "result"), "value");
	v = json_incref(v ? v : json_null());
	json_decref(r);
	return v;
}

json_t *browser_until(struct browser *b, const char *expr, int secs)
{
	size_t cap = strlen(expr) + 300;
	char *js = malloc(cap);
	json_t *v;
	int n;

	ck_assert(js);
	n = snprintf(js, cap,
			 "new Promise(function (done) {"
			 " var end = Date.now() + %d;"
			 " (function again() {"
			 "  var v = (function () { return (%s); })();"
			 "  if (v || Date.now() > end) done(v); else setTimeout(again, 100);"
			 " })();"
			 "})",
			 secs * 1000, expr);
	ck_assert(n > 0 && (size_t)n < cap);
	v = browser_eval(b, js);
	free(js);
	ck_assert_msg(json_is_true(v) || (v && !json_is_false(v) && !json_is_null(v) &&
					  !(json_is_string(v) && !*json_string_value(v)) &&
					  !(json_is_integer(v) && !json_integer_value(v))),
		      "not in %d s: %s", secs, expr);
	return v;
}

char *browser_text(struct browser *b, const char *expr, int secs)
{
	json_t *v = browser_until(b, expr, secs);
	char *s;

	ck_assert_msg(json_is_string(v), "not a string: %s", expr);
	s = strdup(json_string_value(v));
	json_decref(v);
	return s;
}

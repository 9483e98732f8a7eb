/*
 * browser.h - headless Chromium driven by the test suites over the Chrome
 * DevTools Protocol on a pipe (--remote-debugging-pipe: JSON messages, each
 * ended by a NUL byte, written to the browser's fd 3 and read from its fd 4),
 * so a test can load a page, run script in it (click its buttons, wait for
 * what it shows) and count the JavaScript errors it raised.  Debian's
 * chromium (TEST_PACKAGES); no WebSocket, no second process.
 */
#ifndef STRATUM_TESTS_BROWSER_H
#define STRATUM_TESTS_BROWSER_H

#include <jansson.h>
#include <stdbool.h>
#include <sys/types.h>

struct browser {
	pid_t pid;
	int to, from;	    /* our ends of the browser's fd 3 and fd 4 */
	char *buf;	    /* bytes read and not yet split into messages */
	size_t len, cap;
	int next_id;
	char session[128];  /* the page's session of the flat protocol */
	int errors;	    /* uncaught exceptions, console.error, script log errors */
	char first_error[512];
};

/* browser_path - the chromium binary, or NULL when none is installed. */
const char *browser_path(void);
/* browser_open - start a headless browser on one blank page (fails the test
 * when it does not answer); profile is a fresh directory for its profile. */
void browser_open(struct browser *b, const char *profile);
/* browser_close - close the browser and reap it. */
void browser_close(struct browser *b);
/* browser_go - load url in the page and wait until it has loaded. */
void browser_go(struct browser *b, const char *url);
/* browser_eval - the value of a JavaScript expression in the page (a
 * promise is awaited); the caller decrefs.  An exception fails the test. */
json_t *browser_eval(struct browser *b, const char *expr);
/* browser_until - wait up to secs for expr to be truthy in the page (polled
 * in the page every 100 ms); its last value (the caller decrefs). */
json_t *browser_until(struct browser *b, const char *expr, int secs);
/* browser_text - browser_until expr is a non-empty string; a malloc'd copy. */
char *browser_text(struct browser *b, const char *expr, int secs);

#endif /* STRATUM_TESTS_BROWSER_H */

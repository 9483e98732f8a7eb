/*
 * check_console.c - `stratum console` and `stratum send --command`: the
 * built-in words as G-code (host/console.h), the console driven through a
 * pseudo-terminal (line editing, history, Ctrl-C) and as a script on stdin,
 * on both simulators and on a pty port; send --command printing the
 * firmware's replies, and refusing a Sailfish printer.
 */
#include <check.h>
#include <errno.h>
#include <jansson.h>
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "console.h"
#include "printer.h"
#include "suites.h"
#include "testutil.h"

#define MARLIN "prusa-i3-mk3s"
#define SAILFISH "flashforge-creator-pro"

static char out[1 << 16];

/* ---- the words ---- */

static const struct console_heat heat = {215, 60};

/* text reads as kind with the lines given (NULL-terminated). */
static void expect(const char *text, enum console_kind kind, const char *const *lines)
{
	struct console_cmd c;
	size_t n = 0;

	console_read(text, &heat, &c);
	ck_assert_msg(c.kind == kind, "'%s': kind %d, not %d (%s)", text, c.kind, kind, c.msg);
	for (; lines && lines[n]; n++) {
		ck_assert_uint_lt(n, c.n);
		ck_assert_msg(!strcmp(c.line[n], lines[n]), "'%s' line %zu: '%s', not '%s'", text,
			      n, c.line[n], lines[n]);
	}
	if (kind == CONSOLE_BUILTIN)
		ck_assert_uint_eq(c.n, n);
}

START_TEST(builtins_are_gcode)
{
	expect("home", CONSOLE_BUILTIN, (const char *[]){"G28", NULL});
	expect("  HOME x y", CONSOLE_BUILTIN, (const char *[]){"G28 X Y", NULL});
	expect("jog z -0.5", CONSOLE_BUILTIN,
	       (const char *[]){"G91", "G1 Z-0.500 F600", "G90", NULL});
	expect("jog X 10", CONSOLE_BUILTIN, (const char *[]){"G91", "G1 X10.000 F3000", "G90", NULL});
	expect("preheat PETG", CONSOLE_BUILTIN, (const char *[]){"M104 S240", "M140 S80", NULL});
	expect("preheat pla", CONSOLE_BUILTIN, (const char *[]){"M104 S210", "M140 S60", NULL});
	expect("preheat", CONSOLE_BUILTIN, (const char *[]){"M104 S215", "M140 S60", NULL});
	expect("cooldown", CONSOLE_BUILTIN, (const char *[]){"M104 S0", "M140 S0", NULL});
	expect("motors off", CONSOLE_BUILTIN, (const char *[]){"M84", NULL});
	expect("M115", CONSOLE_GCODE, NULL);
	expect("g28 x", CONSOLE_GCODE, NULL);
	expect("", CONSOLE_EMPTY, NULL);
	expect("   ; a note", CONSOLE_EMPTY, NULL);
	expect("help", CONSOLE_HELP, NULL);
	expect("quit", CONSOLE_QUIT, NULL);
	expect("exit", CONSOLE_QUIT, NULL);
}
END_TEST

/* What tells the two apart without a dialect switch in host/. */
START_TEST(marlin_has_text_replies_sailfish_not)
{
	ck_assert(printer_marlin_ops.text_replies);
	ck_assert(!printer_sailfish_ops.text_replies);
}
END_TEST

START_TEST(builtins_used_wrongly_are_refused)
{
	const char *bad[] = {"jog q 5",   "jog x",	     "jog x 0",	     "jog x 5000",
			     "jog x five", "home w",	     "home x x",     "home x y z x",
			     "preheat nylon", "preheat pla abs", "cooldown now", "motors on",
			     "quit now"};

	for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); i++) {
		struct console_cmd c;

		console_read(bad[i], &heat, &c);
		ck_assert_msg(c.kind == CONSOLE_BAD && c.msg[0], "'%s' was taken (kind %d)", bad[i],
			      c.kind);
	}
}
END_TEST

/* ---- send --command ---- */

/* `stratum sim --dialect marlin` in the background on a link, then
 * "stratum ARGS" with that link for PORT (a %s in args); exit status. */
static int with_marlin_sim(const char *args_fmt)
{
	char link[512], args[1024];

	snprintf(link, sizeof(link), "%s", tu_path("console-tty"));
	snprintf(args, sizeof(args), args_fmt, link);
	return tu_sh(out, sizeof(out),
		     "%s sim --dialect marlin --speedup 1000 --link %s >/dev/null 2>&1 & P=$!; "
		     "for i in $(seq 50); do [ -e %s ] && break; sleep 0.1; done; "
		     "%s %s; r=$?; kill $P; wait $P; exit $r",
		     tu_bin(), link, link, tu_bin(), args);
}

START_TEST(send_command_prints_the_replies)
{
	int rc = with_marlin_sim("send --command M115 --command M114 --port %s --printer " MARLIN
				 " 2>&1");
	const char *fw = strstr(out, "FIRMWARE_NAME:"), *pos = strstr(out, "X:");

	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert_msg(fw && pos && fw < pos, "M115 then M114 replies: %s", out);
	ck_assert_msg(strstr(fw, "\nok"), "no ok line after M115: %s", out);
}
END_TEST

START_TEST(send_command_json)
{
	json_error_t je;
	json_t *o, *r;
	int rc = with_marlin_sim("send --json --command M115 --command 'M117 hello' --port %s "
				 "--printer " MARLIN " 2>/dev/null");

	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	o = json_loads(out, 0, &je);
	ck_assert_msg(o != NULL, "bad JSON (%s): %s", je.text, out);
	ck_assert(json_is_true(json_object_get(o, "ok")));
	r = json_object_get(o, "replies");
	ck_assert_uint_eq(json_array_size(r), 2);
	ck_assert_str_eq(json_string_value(json_object_get(json_array_get(r, 0), "command")),
			 "M115");
	ck_assert_str_eq(json_string_value(json_object_get(json_array_get(r, 1), "command")),
			 "M117 hello");
	ck_assert_uint_ge(json_array_size(json_object_get(json_array_get(r, 0), "reply")), 2);
	json_decref(o);
}
END_TEST

/* A bad line is found before the port is opened: nothing sent, exit 65
 * (the port does not exist, which would be 69). */
START_TEST(send_command_bad_line_sends_nothing)
{
	int rc = tu_run(out, sizeof(out), "send --command M115 --command 'G1 X1*999' --port "
					  "/nonexistent/tty --printer " MARLIN);

	ck_assert_msg(rc == 65, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "nothing was sent"), "%s", out);
}
END_TEST

START_TEST(send_command_refuses_sailfish)
{
	int rc = tu_run(out, sizeof(out), "send --command M115 --port sim --printer " SAILFISH);

	ck_assert_msg(rc == 2, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "binary packets") && strstr(out, "stratum console"), "%s", out);
	rc = tu_run(out, sizeof(out), "send --command M115 FILE.gcode --port sim --printer " MARLIN);
	ck_assert_msg(rc == 2 && strstr(out, "not both"), "exit %d: %s", rc, out);
}
END_TEST

/* ---- the console as a script ---- */

START_TEST(console_script_homes_and_shows_replies)
{
	const char *log = tu_path("console-marlin.log");
	char *text;
	size_t len;
	int rc = tu_sh(out, sizeof(out),
		       "printf 'home\\nM115\\njog x 5\\nquit\\nM84\\n' | %s console --printer " MARLIN
		       " --sim-log %s 2>&1", tu_bin(), log);
	const char *g28 = strstr(out, "> G28");

	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert_msg(g28 && strstr(g28, "\nok"), "no ok after G28: %s", out);
	ck_assert_msg(strstr(out, "> M115") && strstr(out, "FIRMWARE_NAME:"), "%s", out);
	ck_assert_msg(strstr(out, "> G1 X5.000 F3000"), "%s", out);
	ck_assert_msg(!strstr(out, "> M84"), "a line after quit was sent: %s", out);
	text = tu_slurp(log, &len);
	ck_assert_msg(strstr(text, " G28\n") && strstr(text, " G1 X5.000 F3000\n"), "log: %s", text);
	free(text);
}
END_TEST

/* The first refused line ends a script: exit 65, nothing after it sent. */
START_TEST(console_script_stops_at_a_refused_line)
{
	int rc = tu_sh(out, sizeof(out),
		       "printf 'jog q 5\\nhome\\n' | %s console --printer " MARLIN " 2>&1", tu_bin());

	ck_assert_msg(rc == 65, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "usage: jog") && !strstr(out, "> G28"), "%s", out);
}
END_TEST

/* A real port: `stratum sim` on a pty, the console on its path. */
START_TEST(console_on_a_pty_port)
{
	int rc = with_marlin_sim("console --printer " MARLIN " --port %s 2>&1 <<'EOF'\n"
				 "M114\ncooldown\nEOF");

	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "X:") && strstr(out, "> M140 S0"), "%s", out);
}
END_TEST

/* Sailfish sends no text: the built-ins translate to X3G, the sim runs
 * them and the console shows the temperatures it polls.  The printer
 * queues commands, so the script waits before it ends (the built-in
 * simulator stops with the console). */
START_TEST(console_sailfish_script)
{
	const char *log = tu_path("console-sailfish.log");
	char *text;
	size_t len;
	int rc = tu_sh(out, sizeof(out),
		       "(printf 'home\\npreheat PLA\\n'; sleep 3; printf 'cooldown\\n'; sleep 1) | "
		       "%s console --printer " SAILFISH " --sim-log %s 2>&1", tu_bin(), log);

	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "no text replies") && strstr(out, "> M104 S210"), "%s", out);
	ck_assert_msg(strstr(out, "T:210.0 /210.0"), "no temperature report: %s", out);
	text = tu_slurp(log, &len);
	ck_assert_msg(strstr(text, "find axes") && strstr(text, "136 tool action tool=0 cmd=3 len=2 "
						  "value=210\n"), "log: %s", text);
	free(text);
}
END_TEST

/* ---- the console on a terminal ---- */

/* Read fd into buf (appending at *len) until needle is in buf from `from`
 * on or ms pass; where it is, or NULL. */
static const char *read_until(int fd, char *buf, size_t cap, size_t *len, size_t from,
			      const char *needle, int ms)
{
	struct timespec t0;

	clock_gettime(CLOCK_MONOTONIC, &t0);
	for (;;) {
		struct pollfd p = {fd, POLLIN, 0};
		struct timespec t;
		const char *at = strstr(buf + from, needle);
		long left;

		if (at)
			return at;
		clock_gettime(CLOCK_MONOTONIC, &t);
		left = ms - ((t.tv_sec - t0.tv_sec) * 1000 + (t.tv_nsec - t0.tv_nsec) / 1000000);
		if (left <= 0 || poll(&p, 1, (int)left) <= 0)
			return NULL;
		ssize_t n = read(fd, buf + *len, cap - 1 - *len);
		if (n <= 0)
			return NULL;
		*len += (size_t)n;
		buf[*len] = '\0';
	}
}

/* The console on a new terminal, its state directory dir; the child's pid. */
static pid_t console_on_pty(int *master, const char *dir, const char *log)
{
	pid_t pid = forkpty(master, NULL, NULL, NULL);

	ck_assert_int_ge(pid, 0);
	if (pid == 0) {
		setenv("STRATUM_STATE_DIR", dir, 1);
		setenv("TERM", "xterm", 1);
		execl(tu_bin(), "stratum", "console", "--printer", MARLIN, "--sim-log", log,
		      (char *)NULL);
		_exit(127);
	}
	return pid;
}

static int wait_exit(pid_t pid)
{
	int st = 0;

	for (int i = 0; i < 100; i++) {
		if (waitpid(pid, &st, WNOHANG) == pid)
			return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
		usleep(100000);
	}
	kill(pid, SIGKILL);
	waitpid(pid, &st, 0);
	return -2;
}

START_TEST(console_terminal_home_history_quit)
{
	const char *dir = tu_path("console-state"), *log = tu_path("console-pty.log");
	char hist[600];
	size_t len = 0;
	int master, rc;
	pid_t pid = console_on_pty(&master, dir, log);
	const char *at;
	char *text;

	out[0] = '\0';
	at = read_until(master, out, sizeof(out), &len, 0, MARLIN "> ", 20000);
	ck_assert_msg(at != NULL, "no prompt: %s", out);
	ck_assert_int_eq(write(master, "home\r", 5), 5);
	at = read_until(master, out, sizeof(out), &len, 0, "> G28", 10000);
	ck_assert_msg(at != NULL, "home was not sent as G28: %s", out);
	ck_assert_msg(read_until(master, out, sizeof(out), &len, (size_t)(at - out), "ok", 10000),
		      "no ok after G28: %s", out);
	ck_assert_int_eq(write(master, "quit\r", 5), 5);
	rc = wait_exit(pid);
	close(master);
	ck_assert_msg(rc == 0, "exit %d: %s", rc, out);
	snprintf(hist, sizeof(hist), "%s/console/history", dir);
	text = tu_slurp(hist, &len);
	ck_assert_msg(strstr(text, "home") && strstr(text, "quit"), "history: %s", text);
	free(text);
	text = tu_slurp(log, &len);
	ck_assert_msg(strstr(text, " G28\n"), "log: %s", text);
	free(text);
}
END_TEST

/* Ctrl-C at the prompt: a safe stop (M104/M140 S0, M84 in the log), exit 130. */
START_TEST(console_terminal_ctrl_c_stops_safely)
{
	const char *dir = tu_path("console-state2"), *log = tu_path("console-pty2.log");
	size_t len = 0;
	int master, rc;
	pid_t pid = console_on_pty(&master, dir, log);
	char *text;

	out[0] = '\0';
	ck_assert_msg(read_until(master, out, sizeof(out), &len, 0, MARLIN "> ", 20000),
		      "no prompt: %s", out);
	ck_assert_int_eq(write(master, "\003", 1), 1);
	read_until(master, out, sizeof(out), &len, 0, "stopped safely", 10000);
	rc = wait_exit(pid);
	close(master);
	ck_assert_msg(rc == 130, "exit %d: %s", rc, out);
	ck_assert_msg(strstr(out, "stopped safely"), "%s", out);
	text = tu_slurp(log, &len);
	ck_assert_msg(strstr(text, " M104 S0\n") && strstr(text, " M84\n"), "log: %s", text);
	free(text);
}
END_TEST

Suite *console_suite(void)
{
	Suite *s = suite_create("console");
	TCase *words = tcase_create("words"), *send = tcase_create("send_command");
	TCase *script = tcase_create("script"), *term = tcase_create("terminal");

	tcase_add_test(words, builtins_are_gcode);
	tcase_add_test(words, builtins_used_wrongly_are_refused);
	tcase_add_test(words, marlin_has_text_replies_sailfish_not);
	tcase_add_test(send, send_command_prints_the_replies);
	tcase_add_test(send, send_command_json);
	tcase_add_test(send, send_command_bad_line_sends_nothing);
	tcase_add_test(send, send_command_refuses_sailfish);
	tcase_add_test(script, console_script_homes_and_shows_replies);
	tcase_add_test(script, console_script_stops_at_a_refused_line);
	tcase_add_test(script, console_on_a_pty_port);
	tcase_add_test(script, console_sailfish_script);
	tcase_add_test(term, console_terminal_home_history_quit);
	tcase_add_test(term, console_terminal_ctrl_c_stops_safely);
	tcase_set_timeout(send, 60);
	tcase_set_timeout(script, 60);
	tcase_set_timeout(term, 60);
	suite_add_tcase(s, words);
	suite_add_tcase(s, send);
	suite_add_tcase(s, script);
	suite_add_tcase(s, term);
	return s;
}

/*
 * cmd_console.c - `stratum console [--port P] --printer NAME`: a terminal
 * to the printer through serial/printer.h (docs/printing.md "The
 * console").  Every line the firmware sends is shown as it arrives (the
 * printer's trace hook, read between keystrokes by printer_poll); the
 * built-in words (host/console.h) become G-code, any other line is sent as
 * typed.
 *
 * On a terminal, lines are edited with GNU readline in
 * callback mode, so printer output can be written above the prompt while a
 * line is being typed; the history is kept in the state directory.  Without
 * a terminal, stdin is a script: each line is echoed as "> LINE", and the
 * first refused line ends it (exit 65) so a script never runs on past a
 * mistake.  Ctrl-C stops the printer safely and exits 130; quit and EOF
 * leave it as it is.
 */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/select.h>
#include <unistd.h>
/* after stdio.h, which readline's headers use */
#include <readline/history.h>
#include <readline/readline.h>

#include "commands.h"
#include "console.h"
#include "journal.h"
#include "printer.h"
#include "printer_profile.h"
#include "profile.h"
#include "send.h"
#include "st_append.h"
#include "st_error.h"

#define CONSOLE_CMD "stratum console"
#define CONSOLE_TICK_MS 100	   /* how often the link is read while waiting for a key */
#define CONSOLE_HISTORY_MAX 1000   /* lines kept */
#define CONSOLE_SCRIPT_LINE 4096   /* longest script line */

struct console_args {
	const char *port, *printer, *sim_log;
	long baud;
	double speedup;
};

/* One console session. */
struct console {
	struct printer *pr;
	const struct printer_ops *ops;
	struct console_heat heat;
	volatile sig_atomic_t *stop;
	bool tty;    /* stdin and stdout are terminals: line editing */
	bool live;   /* show the printer's lines (not the greeting at connect) */
	bool prompt_shown; /* readline's prompt and line are on screen */
	bool quit;
	int status;
	char history[JOURNAL_PATH_MAX]; /* "" when none */
	char in[CONSOLE_SCRIPT_LINE];	/* script mode: bytes of a line not ended yet */
	size_t nin;
};

/* The one session the readline line handler reaches (it takes no context). */
static struct console *console_now;

static int console_parse(int argc, char **argv, struct console_args *a)
{
	const struct cmd_opt opts[] = {
	    CMD_OPT_PRINTER_NAME(&a->printer),
	    CMD_OPT_PORT_OR_SIM(&a->port),
	    CMD_OPT_BAUD(&a->baud),
	    CMD_OPT_SPEEDUP(&a->speedup),
	    CMD_OPT_SIM_LOG(&a->sim_log),
	};
	const struct cmd_spec spec = {
	    .cmd = CONSOLE_CMD, CMD_TABLE(opts), .col = 18,
	    .head = "usage: stratum console --printer NAME [--port PATH|auto|tcp://HOST:PORT|sim]\n"
		    "                       [--baud N] [--speedup K] [--sim-log FILE]\n"
		    "A terminal to the printer: every line the firmware sends (replies,\n"
		    "temperature reports) is shown as it arrives.  Built in: home, jog AXIS MM,\n"
		    "preheat [PLA|PETG|ABS|ASA|TPU|PC], cooldown, motors off, help, quit; any\n"
		    "other line goes to the printer as G-code (translated to X3G for Sailfish\n"
		    "printers, which send no text: their temperatures are shown instead).\n"
		    "On a terminal lines are edited and kept in a history (console/history in\n"
		    "the state directory, ~/.local/state/stratum unless $XDG_STATE_HOME or\n"
		    "$STRATUM_STATE_DIR say otherwise); otherwise stdin is a script, each line\n"
		    "echoed as '> LINE', and the first refused line ends it (exit 65).\n",
	    .tail = "quit or Ctrl-D leaves the printer as it is; Ctrl-C stops it safely (heaters\n"
		    "and motors off, once the command running has been answered) and exits 130.\n"
		    "Exit status: 0, 2 usage, 65 a script line refused, 69 printer unavailable\n"
		    "or lost, 1 a firmware error in a script.\n"};
	int rc;

	memset(a, 0, sizeof(*a));
	a->speedup = CMD_SIM_SPEEDUP;
	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc;
	if (!a->printer)
		return cmd_refuse(
		    &spec, "no printer given; add --printer NAME ('stratum printers' lists them)");
	return 0;
}

/* Write one line of output, above the prompt when it is on screen. */
static void console_show(struct console *c, const char *line, size_t len)
{
	if (c->prompt_shown)
		fputs("\r\033[K", stdout);
	fprintf(stdout, "%.*s\n", (int)len, line);
	fflush(stdout);
	if (c->prompt_shown)
		rl_forced_update_display();
}

/* The printer's trace: every line from the firmware, as it arrives. */
static void console_trace(void *ctx, const char *dir, const char *line)
{
	struct console *c = ctx;

	if (c->live && dir[0] == '<')
		console_show(c, line, strcspn(line, "\r\n"));
}

/* A script line failed: end the script with status. */
static void console_fail(struct console *c, int status)
{
	if (!c->tty) {
		c->quit = true;
		c->status = status;
	}
}

/* Send one G-code line; a lost link ends the session. */
static void console_send(struct console *c, const char *line, bool echo)
{
	struct st_error err = {0};
	int rc;

	if (echo) {
		char shown[CONSOLE_LINE_MAX + 8];
		int n = snprintf(shown, sizeof(shown), "> %s", line);

		console_show(c, shown, n > 0 && (size_t)n < sizeof(shown) ? (size_t)n
									     : sizeof(shown) - 1);
	}
	if (!(rc = printer_command(c->pr, line, NULL, 0, &err)))
		return;
	fprintf(stderr, CONSOLE_CMD ": %s\n", err.msg);
	if (rc == ST_ERR_IO) {
		c->quit = true;
		c->status = ST_EXIT_UNAVAILABLE;
	} else {
		console_fail(c, rc == ST_ERR_PARSE ? ST_EXIT_DATAERR : ST_EXIT_FAILURE);
	}
}

/* One line typed or read from the script. */
static void console_line(struct console *c, const char *text)
{
	struct console_cmd cmd;

	console_read(text, &c->heat, &cmd);
	switch (cmd.kind) {
	case CONSOLE_EMPTY:
		break;
	case CONSOLE_HELP:
		console_help(&c->heat, stdout);
		break;
	case CONSOLE_QUIT:
		c->quit = true;
		break;
	case CONSOLE_BAD:
		fprintf(stderr, CONSOLE_CMD ": %s\n", cmd.msg);
		console_fail(c, ST_EXIT_DATAERR);
		break;
	case CONSOLE_GCODE:
		console_send(c, text, !c->tty);
		break;
	case CONSOLE_BUILTIN:
		for (size_t i = 0; i < cmd.n && !c->quit; i++)
			console_send(c, cmd.line[i], true);
		break;
	}
	fflush(stdout);
}

/* readline's line handler: NULL at Ctrl-D. */
static void console_on_line(char *line)
{
	struct console *c = console_now;

	c->prompt_shown = false;
	if (!line) {
		fputc('\n', stdout);
		c->quit = true;
		return;
	}
	if (line[strspn(line, " \t")]) {
		add_history(line);
		if (c->history[0] && write_history(c->history)) {
			fprintf(stderr, CONSOLE_CMD ": cannot write the history %s; going on "
						    "without it\n", c->history);
			c->history[0] = '\0';
		}
	}
	console_line(c, line);
	free(line);
	c->prompt_shown = !c->quit; /* readline shows the next prompt */
}

/* Script mode: the bytes stdin has, line by line; at EOF the last line. */
static void console_read_script(struct console *c)
{
	ssize_t got = read(STDIN_FILENO, c->in + c->nin, sizeof(c->in) - 1 - c->nin);
	char *nl;

	if (got < 0 && errno == EINTR)
		return;
	if (got <= 0) {
		c->in[c->nin] = '\0';
		if (c->nin)
			console_line(c, c->in);
		c->quit = true;
		return;
	}
	c->nin += (size_t)got;
	c->in[c->nin] = '\0';
	while (!c->quit && (nl = memchr(c->in, '\n', c->nin))) {
		size_t len = (size_t)(nl - c->in) + 1;

		*nl = '\0';
		if (nl > c->in && nl[-1] == '\r')
			nl[-1] = '\0';
		console_line(c, c->in);
		memmove(c->in, c->in + len, c->nin - len + 1);
		c->nin -= len;
	}
	if (!c->quit && c->nin == sizeof(c->in) - 1) {
		fprintf(stderr, CONSOLE_CMD ": a line of the script is longer than %d bytes\n",
			CONSOLE_SCRIPT_LINE - 1);
		console_fail(c, ST_EXIT_DATAERR);
	}
}

/* Temperatures of a printer that sends no text, when poll read them. */
static void console_temps(struct console *c, const struct printer_progress *t)
{
	char line[96] = "";

	if (t->tool)
		st_appendf(line, sizeof(line), "T:%.1f /%.1f", t->tool_actual, t->tool_target);
	if (t->bed)
		st_appendf(line, sizeof(line), "%sB:%.1f /%.1f", line[0] ? " " : "", t->bed_actual,
			   t->bed_target);
	if (line[0])
		console_show(c, line, strlen(line));
}

/* Keys or script lines until quit, Ctrl-C or a lost link. */
static void console_loop(struct console *c)
{
	while (!c->quit && !*c->stop) {
		struct printer_progress t = {0};
		struct timeval tv = {0, CONSOLE_TICK_MS * 1000};
		struct st_error err = {0};
		fd_set rd;
		int n;

		FD_ZERO(&rd);
		FD_SET(STDIN_FILENO, &rd);
		n = select(STDIN_FILENO + 1, &rd, NULL, NULL, &tv);
		if (n < 0 && errno != EINTR) {
			fprintf(stderr, CONSOLE_CMD ": reading the terminal: %s\n", strerror(errno));
			c->status = ST_EXIT_SOFTWARE;
			return;
		}
		if (n > 0 && c->tty)
			rl_callback_read_char();
		else if (n > 0)
			console_read_script(c);
		if (c->quit || *c->stop)
			break;
		if (printer_poll(c->pr, &t, &err)) {
			fprintf(stderr, CONSOLE_CMD ": %s\n", err.msg);
			c->status = ST_EXIT_UNAVAILABLE;
			return;
		}
		if (!c->ops->text_replies)
			console_temps(c, &t);
	}
}

/* Line editing and the history file (in the state directory, journal.h). */
static void console_edit_start(struct console *c, const char *prompt)
{
	struct st_error err = {0};
	char dir[JOURNAL_PATH_MAX - 16];

	rl_catch_signals = 0; /* Ctrl-C is ours: a safe stop */
	rl_readline_name = "stratum";
	rl_initialize();
	using_history();
	stifle_history(CONSOLE_HISTORY_MAX);
	if (journal_state_dir(dir, sizeof(dir), "console", "console history", &err))
		fprintf(stderr, CONSOLE_CMD ": %s; no history is kept\n", err.msg);
	else
		snprintf(c->history, sizeof(c->history), "%s/history", dir);
	if (c->history[0])
		read_history(c->history); /* none yet is fine */
	console_now = c;
	rl_callback_handler_install(prompt, console_on_line);
	c->prompt_shown = true;
}

static void console_edit_end(struct console *c)
{
	fputs("\r\033[K", stdout); /* readline showed a prompt after the last line */
	rl_callback_handler_remove();
	c->prompt_shown = false;
	console_now = NULL;
}

/* Open the printer of o on port; 0 or the exit status after a message. */
static int console_open(struct console *c, const struct console_args *a,
			struct printer_options o, const char *port)
{
	struct st_error err = {0};
	char firmware[96] = "";
	int rc;

	o.sim_speedup = a->speedup;
	o.sim_log = a->sim_log;
	o.trace = console_trace;
	o.trace_ctx = c;
	if ((rc = printer_open(c->ops, &o, &c->pr, &err)))
		return cmd_fail(CONSOLE_CMD, send_exit_for_open(rc), "%s", err.msg);
	printer_describe(c->pr, firmware, sizeof(firmware));
	fprintf(stderr, CONSOLE_CMD ": %s on %s%s; 'help' lists the built-ins, 'quit' leaves\n",
		firmware, port, c->ops->text_replies ? "" : " (no text replies: temperatures shown)");
	c->live = true;
	return 0;
}

int cmd_console(int argc, char **argv)
{
	struct console_args a;
	struct console *c = NULL;
	struct profile *prof = NULL;
	struct printer_options o;
	struct st_error err = {0};
	char *port_auto = NULL, prompt[140];
	const char *port;
	int status, rc;

	if ((status = console_parse(argc, argv, &a)))
		return status < 0 ? ST_EXIT_OK : status;
	if ((rc = profile_find(a.printer, &prof, &err)))
		return cmd_fail(CONSOLE_CMD, profile_exit_status(rc), "%s", err.msg);
	port = a.port ? a.port : "sim";
	if (!(c = calloc(1, sizeof(*c)))) {
		status = cmd_fail(CONSOLE_CMD, ST_EXIT_SOFTWARE, "out of memory");
		goto out_profile;
	}
	if ((status = printer_profile_cli(CONSOLE_CMD, prof, &port, a.baud, false, &port_auto, &o,
					  &c->ops)))
		goto out_console;
	c->heat = (struct console_heat){prof->temperature[0], prof->bed_temperature};
	c->tty = isatty(STDIN_FILENO) && isatty(STDOUT_FILENO);
	c->stop = send_catch_signals();
	if ((status = console_open(c, &a, o, port)))
		goto out_console;
	snprintf(prompt, sizeof(prompt), "%s> ", a.printer);
	if (c->tty)
		console_edit_start(c, prompt);
	console_loop(c);
	if (c->tty)
		console_edit_end(c);
	status = c->status;
	if (*c->stop) {
		if (printer_safe_stop(c->pr, &err))
			fprintf(stderr, CONSOLE_CMD ": %s\n", err.msg);
		else
			fprintf(stderr, CONSOLE_CMD ": stopped safely: heaters and motors off\n");
		status = ST_EXIT_INTERRUPTED;
	}
	printer_close(c->pr);
out_console:
	free(c);
out_profile:
	profile_free(prof);
	free(port_auto);
	return status;
}

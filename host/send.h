/*
 * send.h - what `stratum send` (host/cmd_send.c) and `stratum print`
 * (host/cmd_print.c) share on top of serial/printer.h: the stop flag
 * Ctrl-C sets, the progress line, exit statuses and the one-line JSON
 * report.
 */
#ifndef STRATUM_HOST_SEND_H
#define STRATUM_HOST_SEND_H

#include <jansson.h>
#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "printer.h"

/*
 * send_catch_signals - SIGINT/SIGTERM set the flag returned (STYLE rule 10
 * exception: the one stop flag); the drivers poll it and stop safely.
 */
volatile sig_atomic_t *send_catch_signals(void);

/* send_warning - printer_warn_fn printing "CMD: FILE:LINE: warning: MSG" (ctx = CMD). */
void send_warning(void *ctx, const char *path, uint64_t line, const char *msg);

/* Exit statuses: of a failed printer_check, a failed printer_open, and a
 * stream (printer_stream's rc and result). */
int send_exit_for_check(int rc);
int send_exit_for_open(int rc);
int send_exit_for(const struct printer_result *res, int rc);

/*
 * send_safe_stop - when res asks for it, stop pr safely and say so on
 * stderr ("CMD: stopped safely: ..."); true when it was asked.
 */
bool send_safe_stop(const char *cmd, struct printer *pr, const struct printer_result *res);

/* Progress state: a redrawn line on a terminal, a line per 10 % otherwise
 * (host/send_progress.c). */
struct send_progress {
	const char *cmd; /* plain lines' prefix, SEND_CMD unless changed after start */
	const char *tag; /* the line's "[send]", likewise */
	bool tty;
	double t0;	 /* st_mono_s() */
	int last_decile; /* plain mode: last 10 % step printed */
	size_t width;	 /* characters of the redrawn line */
	size_t layers;	 /* layers of the file, 0 unknown */
	/* The print's time estimate, set before each show: est_total > 0 makes
	 * the ETA follow it (progress_eta) rather than the line rate. */
	double est_total, est_done; /* estimated printing seconds: all, done */
	double pace0;	 /* estimated s per wall s before one is measured (the
			  * simulator's speed-up, else 1) */
	double t_moving; /* st_mono_s() when est_done first grew, 0 not yet */
};

/* send_progress_start - decide tty or lines, start the clock. */
void send_progress_start(struct send_progress *p);

/*
 * send_progress_line - the line for v at time now in at most cols - 1
 * characters: percent, layer N/M (counted from 1, as PrusaSlicer and
 * OctoPrint show them; v->layer is 0-based), lines, temperatures, elapsed
 * time and ETA as h:mm:ss, fields left out from the least wanted when the
 * terminal is narrow.  Returns its length.
 */
size_t send_progress_line(struct send_progress *p, const struct printer_progress *v, double now,
			  size_t cols, char *out, size_t cap);

/* send_progress_show - draw v (redrawn line or a line per 10 %). */
void send_progress_show(struct send_progress *p, const struct printer_progress *v);

/* send_progress_end - end the redrawn line so the report starts clean. */
void send_progress_end(struct send_progress *p);

/* send_report_emit - print o as one line on stdout; frees o. */
void send_report_emit(json_t *o);

/* `stratum send --command LINE` (repeatable): the lines, in order. */
#define SEND_COMMANDS_MAX 64
struct send_commands {
	const char *line[SEND_COMMANDS_MAX];
	size_t n;
};

/* send_command_add - the --command reader (struct cmd_opt.read): false when
 * v is empty or the list is full. */
bool send_command_add(const char *v, void *dest);

/*
 * send_commands_run - `stratum send --command`: check every line, open the
 * printer of ops and o, send the lines one by one and print the firmware's
 * reply to each on stdout (one JSON object with json; printer and port name
 * the printer there).  A printer whose firmware sends no text
 * (ops->text_replies false) is refused before it is opened: exit 2.
 * Returns the exit status, after a message on stderr (host/send_command.c).
 */
int send_commands_run(const struct send_commands *c, const struct printer_ops *ops,
		      const struct printer_options *o, const char *printer, const char *port,
		      bool json);

#endif /* STRATUM_HOST_SEND_H */

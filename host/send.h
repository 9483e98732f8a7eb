/*
 * send.h - what the two halves of `stratum send` share (host/ only): the
 * options, the stop flag Ctrl-C sets, the progress line and the final
 * report.  host/cmd_send.c holds these and the Marlin path;
 * host/send_sailfish.c streams to Sailfish printers over S3G.
 */
#ifndef STRATUM_HOST_SEND_H
#define STRATUM_HOST_SEND_H

#include <jansson.h>
#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "profile.h"

#define SEND_CMD "stratum send"

/* What a Sailfish job did, for a caller that reports it itself. */
struct send_result {
	bool ok;
	uint64_t done, total;	/* commands confirmed (or skipped), of total */
	uint64_t lines;		/* G-code lines done (G-code input) */
	long layer;		/* layer of the last command taken, -1 unknown */
	uint64_t retries;
	double seconds;
	char firmware[32];
	double tool_actual, tool_target, bed_actual, bed_target; /* degC, last reported */
};

struct send_args {
	const char *file, *port, *printer;
	bool json;
	long baud; /* 0 = the profile's */
	const char *cmd;	    /* message prefix; NULL = SEND_CMD */
	struct send_result *result; /* set: filled instead of printing the report */
	/* Sailfish G-code only, for a resume (stratum print): start reading at
	 * byte offset, and translate the G-code lines of preamble ('\n' after
	 * each) first with the same translator; lines then count from offset */
	int64_t offset;
	const char *preamble;
	/* called as the stream goes with what is done so far (may be NULL) */
	void (*progress)(void *ctx, const struct send_result *r);
	void *progress_ctx;
};

/*
 * send_catch_signals - SIGINT/SIGTERM set the flag returned (STYLE rule 10
 * exception: the one stop flag); the drivers poll it and stop safely.
 */
volatile sig_atomic_t *send_catch_signals(void);

/* What the progress line shows, from either driver's status. */
struct send_view {
	const char *unit;	 /* "line" (Marlin) or "command" (Sailfish) */
	uint64_t done, total;	 /* of unit */
	long layer;		 /* -1 unknown */
	bool tool, bed;		 /* the temperatures below are known */
	double tool_actual, tool_target, bed_actual, bed_target; /* degC */
	bool paused;
};

struct marlin_status;

/* send_view_marlin - the Marlin driver's status as a view of lines:
 * done = acknowledged, layer and temperatures as reported. */
void send_view_marlin(const struct marlin_status *st, uint64_t total, struct send_view *v);

/* Progress state: a redrawn line on a terminal, a line per 10 % otherwise. */
struct send_progress {
	const char *cmd; /* plain lines' prefix, SEND_CMD unless changed after start */
	const char *tag; /* the bar's "[send]", likewise */
	bool tty;
	double t0;	 /* monotonic s */
	int last_decile; /* plain mode: last 10 % step printed */
	size_t width;	 /* characters of the redrawn line */
};

/* send_now - monotonic clock, seconds. */
double send_now(void);

/* send_progress_start - decide tty or lines, start the clock. */
void send_progress_start(struct send_progress *p);

/* send_progress_show - draw v (redrawn line or a line per 10 %). */
void send_progress_show(struct send_progress *p, const struct send_view *v);

/* send_progress_end - end the redrawn line so the report starts clean. */
void send_progress_end(struct send_progress *p);

/* The figures both report forms share. */
struct send_summary {
	bool ok;
	const char *error;	  /* why the job stopped, NULL if ok */
	const char *protocol;	  /* "marlin" or "sailfish" */
	const char *firmware;	  /* what the firmware called itself */
	const char *unit;	  /* "lines" or "commands" in the text report */
	uint64_t done;		  /* of unit, acknowledged by the printer */
	uint64_t resends, errors, unknown_commands;
	uint64_t bytes;		  /* bytes of acknowledged commands as sent */
	uint64_t bytes_written;	  /* every byte written */
	double seconds;
	long baud;
};

/*
 * send_report_json - the JSON report's shared keys (ok, file, port,
 * printer, protocol, firmware, resends, errors, unknown_commands, seconds,
 * bytes, bytes_written, bytes_per_s, baud, link_fraction, error); the
 * caller adds its own and passes it to send_report_emit.  NULL on NOMEM.
 */
json_t *send_report_json(const struct send_args *a, const struct send_summary *s);

/* send_report_emit - print o as one line on stdout; frees o. */
void send_report_emit(json_t *o);

/*
 * send_report_text - the text report: "sent FILE: N unit in S s", then
 * detail (the protocol's counters, one line, may be NULL), then rates and
 * the link fraction.
 */
void send_report_text(const struct send_args *a, const struct send_summary *s,
		      const char *detail);

/* send_has_ext - true when path ends in ext (".x3g"), any case. */
bool send_has_ext(const char *path, const char *ext);

/*
 * send_sailfish - the Sailfish half of cmd_send (host/send_sailfish.c):
 * FILE (G-code translated on the fly, or X3G) to the S3G printer on the
 * port.  prof is a sailfish profile.  Returns the exit status.
 */
int send_sailfish(const struct send_args *a, const struct profile *prof);

#endif /* STRATUM_HOST_SEND_H */

/*
 * marlin.h - the Marlin text-protocol driver over a struct xport
 * (docs/architecture.md item 6, docs/protocols.md section 1, docs/streaming.md).
 *
 * Every command goes out as "N<n> <cmd>*<cs>"; replies drive a window of
 * commands in flight:
 *
 *  - bytes: the bytes of unacknowledged lines, except the oldest `bufsize`
 *    ones (they sit in the firmware's command queue, out of its RX ring),
 *    stay below the RX ring size (character counting, like grbl's
 *    stream.py);
 *  - slots: `bufsize` is the firmware's BUFSIZE, taken from the options or
 *    learnt from ADVANCED_OK replies ("ok N.. P.. B.."); 0 = unknown, and
 *    then only the RX ring bounds the window;
 *  - with neither known, one command is in flight at a time.
 *
 * "Resend: k" rewinds to line k (the "ok" after it belongs to the request);
 * the copies already on the way are counted until the firmware has
 * answered for them, so repeated requests caused by them do not rewind
 * again.  Line numbers make the firmware execute each line exactly once
 * whatever the host resends.  busy/temperature lines extend time-outs; a
 * fatal "Error:" (kill, thermal runaway, MINTEMP/MAXTEMP) stops the job and
 * is never answered with a resend.
 *
 * One thread drives a handle.  marlin_request_* only store a
 * volatile sig_atomic_t, so they may be called from a signal handler (via a
 * pointer the caller keeps) or another thread.  Library code: nothing is
 * printed; no globals.
 */
#ifndef STRATUM_SERIAL_MARLIN_H
#define STRATUM_SERIAL_MARLIN_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "gcode.h"
#include "st_error.h"
#include "xport.h"

/* Longest command text marlin_submit takes (bytes): Marlin keeps 95 bytes
 * of a line (MAX_CMD_SIZE 96), and "N<8 digits> " plus "*255" go around it. */
#define MARLIN_CMD_MAX 81
/* Hot ends whose temperatures are kept. */
#define MARLIN_MAX_TOOLS 8

/* Options; marlin_options_init fills the defaults. */
struct marlin_options {
	unsigned rx_buffer;	/* firmware RX ring (bytes); 0 = unknown; default 128 */
	unsigned bufsize;	/* firmware command slots; 0 = unknown/learn; default 0 */
	bool expect_reset;	/* opening reset the board: wait for "start" first */
	int boot_wait_ms;	/* longest wait for "start" with expect_reset; default 5000 */
	int connect_timeout_ms; /* longest wait for M110/M115 answers; default 15000 */
	int retry_ms;		/* connect: re-send M110/M115 after this silence; default 2000 */
	int probe_ms;		/* no reply to lines in flight for this long: re-send; default 3000 */
	int dead_ms;		/* not one byte for this long: printer not answering; default 30000 */
	int dead_blocking_ms;	/* the same while G28/M109/M400... runs; default 600000 */
	int autoreport_s;	/* M155 S<n> when AUTOREPORT_TEMP; 0 = leave it; default 2 */
	/* Optional traffic log: dir is "<" (from the printer) or ">" (to it). */
	void (*trace)(void *ctx, const char *dir, const char *line);
	void *trace_ctx;
};

/* What M115 and the replies told about the firmware. */
struct marlin_caps {
	bool m115;		   /* a FIRMWARE_NAME line was seen */
	char firmware_name[64];	   /* "Marlin 2.1.2 (...)" */
	char machine_type[64];
	int extruder_count;	   /* 0 = not reported */
	bool advanced_ok;	   /* Cap:ADVANCED_OK:1 or an "ok N.. P.. B.." reply */
	bool emergency_parser;	   /* Cap:EMERGENCY_PARSER:1 */
	bool autoreport_temp;	   /* Cap:AUTOREPORT_TEMP:1 */
	bool host_action_commands; /* Cap:HOST_ACTION_COMMANDS:1 */
	bool prompt_support;	   /* Cap:PROMPT_SUPPORT:1 */
	bool eeprom, sdcard, thermal_protection, arcs, progress;
};

/* Why a job ended early (status.fail). */
enum marlin_fail {
	MARLIN_FAIL_NONE = 0,
	MARLIN_FAIL_LINK,      /* unplugged, reset, not answering, protocol broken */
	MARLIN_FAIL_FIRMWARE,  /* kill(), thermal runaway, MINTEMP/MAXTEMP */
	MARLIN_FAIL_CANCELLED, /* marlin_request_cancel or the stop flag */
	MARLIN_FAIL_PRINTER_CANCEL, /* //action:cancel from the printer */
};

/* One heater as the firmware last reported it. */
struct marlin_temp {
	bool present;
	double actual, target; /* degC */
};

/* Counters and the latest printer state; plain value, copy freely. */
struct marlin_status {
	uint64_t submitted;	 /* commands handed to marlin_submit */
	uint64_t acked;		 /* of those, acknowledged by the firmware */
	uint64_t transmitted;	 /* numbered lines written, resends included */
	uint64_t resends;	 /* lines written again (Resend requests and probes) */
	uint64_t resend_requests; /* "Resend:" lines received */
	uint64_t line_errors;	 /* checksum / line-number "Error:" lines */
	uint64_t other_errors;	 /* other non-fatal "Error:" lines */
	uint64_t unknown_commands; /* "echo:Unknown command" warnings */
	uint64_t busy;		 /* "echo:busy:" keep-alives */
	uint64_t bytes_written;	 /* every byte written to the port */
	uint64_t bytes_acked;	 /* numbered-line bytes (newline included) of acked commands */
	uint64_t stray_oks;	 /* "ok" with nothing in flight */
	long first_n;		 /* line number of the first submitted command, 0 none */
	long last_acked_n;	 /* line number of the last acknowledged command */
	uint64_t last_acked_src; /* caller's source line of it (marlin_submit) */
	long layer;		 /* layer of the last acknowledged command, -1 unknown */
	double z;		 /* its layer height, NAN unknown */
	struct marlin_temp tool[MARLIN_MAX_TOOLS];
	struct marlin_temp bed, chamber;
	bool heating_wait;	 /* the last report ended in W: (M109/M190 waiting) */
	bool paused;		 /* //action:pause or marlin_request_pause */
	enum marlin_fail fail;
	char last_warning[128];	 /* last "echo:Unknown command..." line */
	char fail_msg[256];	 /* why the job ended early */
};

/* Opaque driver. */
struct marlin;

/* marlin_options_init - fill o with the defaults listed above. */
void marlin_options_init(struct marlin_options *o);

/*
 * marlin_new - a driver over x, which stays the caller's (not closed by
 * marlin_free).  opts NULL = defaults; copied.  Returns 0, ST_ERR_ARG or
 * ST_ERR_NOMEM; *out NULL on error.
 */
int marlin_new(struct xport *x, const struct marlin_options *opts, struct marlin **out,
	       struct st_error *err);

/* marlin_free - free the driver; NULL is safe.  Does not close the port. */
void marlin_free(struct marlin *m);

/*
 * marlin_connect - wait out the boot banner ("start", with expect_reset),
 * synchronise line numbers (M110 N0), read M115 into the capabilities and,
 * with AUTOREPORT_TEMP and autoreport_s > 0, send M155 S<autoreport_s>.
 * Returns 0, or ST_ERR_IO (port failed, printer not answering within
 * connect_timeout_ms) / ST_ERR_INTERNAL (firmware reported a fatal error),
 * err naming the port and what to check.
 */
int marlin_connect(struct marlin *m, struct st_error *err);

/* marlin_caps - the capabilities learnt so far (owned by m). */
const struct marlin_caps *marlin_caps(const struct marlin *m);

/*
 * marlin_submit - queue one command for sending.
 * @cmd: a cleaned command (gcode_line.text): printable ASCII, no ';', at
 *       most MARLIN_CMD_MAX bytes.
 * @src_line: the caller's source line (file line), reported back in status.
 * @layer, @z: the layer it belongs to (-1 / NAN when unknown).
 * Returns 1 queued, 0 the queue is full (call marlin_step, then again), or
 * ST_ERR_ARG (bad or too long cmd; err says which) / ST_ERR_IO (the job has
 * failed: status.fail says why).
 */
int marlin_submit(struct marlin *m, const char *cmd, uint64_t src_line, long layer, double z,
		  struct st_error *err);

/*
 * marlin_submit_next - marlin_submit of a command that is not the job's
 * (src 0), ahead of every submitted job command not yet written (after
 * earlier such commands, in order): the next numbered line, written even
 * while paused.  An operator's command during a print goes in there,
 * between two job lines, instead of after the queue's MARLIN_QUEUE.
 * Returns 0 when marlin_next_room is 0.
 */
int marlin_submit_next(struct marlin *m, const char *cmd, struct st_error *err);

/* marlin_next_room - how many more marlin_submit_next takes now. */
size_t marlin_next_room(const struct marlin *m);

/*
 * marlin_step - write what the window allows, then wait at most timeout_ms
 * (>= 0) for replies and handle them, time-outs included.  Returns 0, or
 * ST_ERR_IO when the job failed (status.fail and err say why: link,
 * firmware, cancel).
 */
int marlin_step(struct marlin *m, int timeout_ms, struct st_error *err);

/* marlin_idle - true when every submitted command has been acknowledged. */
bool marlin_idle(const struct marlin *m);

/* marlin_drained - true when every line written has been acknowledged (lines
 * still queued may wait: what a pause holds back). */
bool marlin_drained(const struct marlin *m);

/* marlin_can_submit - true when marlin_submit has room for one more. */
bool marlin_can_submit(const struct marlin *m);

/* marlin_pending - commands submitted but not yet acknowledged. */
size_t marlin_pending(const struct marlin *m);

/* marlin_status - copy the counters and printer state into *out. */
void marlin_status(const struct marlin *m, struct marlin_status *out);

/*
 * marlin_emergency - send M112, M108 or M410 (cmd) ahead of everything: as
 * raw bytes past the window when the firmware has EMERGENCY_PARSER,
 * otherwise as the next numbered line before queued ones.  Returns 0,
 * ST_ERR_ARG (not an emergency command) or ST_ERR_IO.
 */
int marlin_emergency(struct marlin *m, const char *cmd, struct st_error *err);

/*
 * Requests, safe from a signal handler or another thread: pause stops new
 * lines (resends still go) until resume; cancel ends the job at the next
 * marlin_step with MARLIN_FAIL_CANCELLED.
 */
void marlin_request_pause(struct marlin *m);
void marlin_request_resume(struct marlin *m);
void marlin_request_cancel(struct marlin *m);

/*
 * marlin_safe_stop - docs/protocols.md "A safe cancel": drop the commands not
 * yet sent, M410 past the queue (EMERGENCY_PARSER; M108 too when a heat
 * wait runs), then M104 S0, M140 S0, M107, M84, waiting at most
 * timeout_ms for them.  Works after a cancel; does nothing useful after a
 * link failure.  On success the cancelled job is over: status.fail is NONE
 * again and the driver takes the next job on the same link (read the
 * status before, to report why the job ended).  Returns 0 or ST_ERR_IO.
 */
int marlin_safe_stop(struct marlin *m, int timeout_ms, struct st_error *err);

/* ---- reply parsing, exposed for tests and other hosts ---- */

/* What a reply line is. */
enum marlin_reply_kind {
	MARLIN_REPLY_OTHER = 0,
	MARLIN_REPLY_OK,	 /* "ok", "ok N.. P.. B..", "ok T:..." */
	MARLIN_REPLY_RESEND,	 /* "Resend: k" or "rs k" */
	MARLIN_REPLY_LINE_ERROR, /* Error: checksum / line number / no checksum */
	MARLIN_REPLY_FATAL,	 /* Error: halted, kill, thermal runaway, MINTEMP/MAXTEMP */
	MARLIN_REPLY_ERROR,	 /* any other "Error:" */
	MARLIN_REPLY_BUSY,	 /* "echo:busy: ..." */
	MARLIN_REPLY_UNKNOWN_CMD, /* "echo:Unknown command..." */
	MARLIN_REPLY_TEMP,	 /* a temperature report without ok */
	MARLIN_REPLY_START,	 /* "start": the board (re)booted */
	MARLIN_REPLY_ACTION,	 /* "//action:NAME ..." */
	MARLIN_REPLY_FIRMWARE,	 /* "FIRMWARE_NAME:..." */
	MARLIN_REPLY_CAP,	 /* "Cap:NAME:0|1" */
};

/* Fields of a parsed reply; which are set depends on the kind. */
struct marlin_reply {
	enum marlin_reply_kind kind;
	bool has_n, has_p, has_b; /* ok N<n> P<p> B<b> */
	long n, p, b;
	long resend;		  /* RESEND: the line asked for */
	bool has_temps;		  /* OK or TEMP carried a report */
	char action[32];	  /* ACTION: "pause", "resume", "cancel" ... */
};

/*
 * marlin_parse_reply - classify one reply line (no line ending) and fill
 * r; temperatures found in it go into st (may be NULL), Cap/FIRMWARE_NAME
 * lines into caps (may be NULL).  Never fails: unknown lines are OTHER.
 */
enum marlin_reply_kind marlin_parse_reply(const char *line, size_t len, struct marlin_reply *r,
					  struct marlin_status *st, struct marlin_caps *caps);

/* marlin_fail_name - "link", "firmware", "cancelled", "printer-cancel" or "none". */
const char *marlin_fail_name(enum marlin_fail f);

#endif /* STRATUM_SERIAL_MARLIN_H */

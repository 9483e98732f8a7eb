/*
 * marlin_impl.h - the Marlin driver's state and what its parts share:
 * marlin.c (lifecycle, queue, transmit, replies, timers, stop),
 * marlin_window.c (the window, acks, Resend, probes), marlin_connect.c
 * (the handshake) and marlin_reply.c (reply parsing).  Private to
 * serial/marlin*.c; the interface is marlin.h.
 *
 * Line numbers are given when a command is first written, so emergency
 * commands can jump the queue.  hist[] keeps every written line by number
 * for Resend; pend[] holds submitted commands not yet written.
 *
 *   n_acked < ... < n_send <= n_next
 *   (n_acked, n_send)  written in this epoch, not yet acknowledged
 *   [n_send, n_next)   written before a rewind, to be written again
 */
#ifndef STRATUM_SERIAL_MARLIN_IMPL_H
#define STRATUM_SERIAL_MARLIN_IMPL_H

#include <signal.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "marlin.h"

#define MARLIN_HIST 1024	/* written lines kept for Resend (power of two) */
#define MARLIN_QUEUE 256	/* submitted commands waiting to be written */
#define MARLIN_NEXT 32		/* marlin_submit_next's lines waiting, beyond the queue */
#define MARLIN_RING (MARLIN_QUEUE + MARLIN_NEXT) /* the pend ring holds both */
#define MARLIN_MAX_INFLIGHT 512 /* lines in flight, whatever the buffers say */
#define MARLIN_PRIO 8		/* emergency/stop commands ahead of the queue */
#define MARLIN_PHANTOMS 8	/* unnumbered emergency lines awaiting their ok */
#define MARLIN_LINE_CAP 100	/* "N<n> <cmd>*<cs>\n" + NUL; Marlin keeps 95 */
#define MARLIN_RX_MAX 1024	/* longest reply line kept (bytes) */
#define MARLIN_WRITE_MS 5000	/* bound on one write to the port */
#define MARLIN_BREAK_REPEAT_S 2.0 /* safe stop: M108 again while the same wait runs */
#define MARLIN_M105_PROBE "\nM105\n" /* the lost-ok probe; the window keeps room for it */
#define MARLIN_M105_MAX 2	/* its copies awaiting their "ok T:" */
#define MARLIN_M105_FAST_S 0.05 /* shortest silence before one (s) */
#define MARLIN_M105_AGAIN_S 0.25 /* another while one is unanswered, after (s) */
#define MARLIN_BUSY_HOLD_S 2.5	/* busy/W: seen this recently: the firmware is alive (s) */

/* One numbered line as written. */
struct marlin_entry {
	long n;		 /* its number; 0 = slot never used */
	uint16_t len;	 /* bytes of text, newline included */
	bool job;	 /* submitted by the caller (counted in status) */
	bool blocking;	 /* its ok may take long (gcode_is_blocking) */
	bool heat_wait;	 /* M109/M190...: M108 ends it */
	uint64_t src;
	long layer;
	double z;
	double t_sent;	 /* when written first (s); 0 once written again */
	char text[MARLIN_LINE_CAP];
};

/* An unnumbered M105 written as a probe: its "ok T:" comes once every
 * command queued before it has run, so it acknowledges every line written
 * before it, if nothing went wrong since (docs/streaming.md "The window"). */
struct marlin_m105 {
	long after;	/* lines up to this one were written before it */
	uint64_t marks;	/* errors, Resends and unknown commands when written */
	double t;	/* when (s) */
	bool valid;	/* false: its answer may be another's, acknowledges nothing */
	bool after_taken; /* the firmware had said it has line `after` */
};

/* An unnumbered emergency line (M108, M410): the emergency parser acts on
 * it at once, but Marlin also queues it, so it sits in the RX ring until
 * it runs and earns an ok. */
struct marlin_phantom {
	long after;	/* written after this line */
	uint16_t len;	/* bytes, newline included */
};

/* A command not yet written. */
struct marlin_pend {
	char cmd[MARLIN_CMD_MAX + 1];
	bool job, blocking, heat_wait;
	bool next;	/* marlin_submit_next's: written even while paused */
	uint64_t src;
	long layer;
	double z;
};

struct marlin {
	struct xport *x;
	struct marlin_options o;
	struct marlin_caps caps;
	struct marlin_status st;

	struct marlin_entry *hist;
	long n_next, n_send, n_acked, n_max_sent;
	long last_tx_n;		/* number of the line written last */
	long n_taken;		/* the firmware has every line up to this one
				 * (a "Resend: k" says k - 1): out of its RX ring */
	long n_acked_hi;	/* highest line ever acknowledged (an un-ack may
				 * have to be undone) */
	bool probed;		/* a probe went out and nothing answered since */
	bool talks_blocked;	/* busy/W: reports seen: it talks while it waits */

	struct marlin_pend *pend;
	size_t pend_head, pend_count;
	size_t next_count;	/* of pend, marlin_submit_next's lines, at its head */
	struct marlin_pend prio[MARLIN_PRIO];
	size_t prio_count;

	/* Copies written before a rewind whose fate is unknown: they occupy
	 * the firmware's RX ring until it answers for them. */
	uint16_t ghost[MARLIN_MAX_INFLIGHT];
	size_t ghost_head, ghost_n, ghost_bytes;
	size_t stale_left;	/* further "Resend: rewind_k" they may cause */
	long rewind_k;
	bool rewinding;
	unsigned silent_probes;	/* probes nothing answered since the last reply */
	struct marlin_m105 m105[MARLIN_M105_MAX]; /* oldest first */
	size_t m105_n;
	bool m105_spent;	/* a probe's answer acknowledged nothing new: the
				 * older probe's turn (until something moves) */
	size_t m105_late;	/* answers that may still come for probes no longer
				 * awaited: none is written meanwhile (for probe_ms) */
	double t_m105_late;
	size_t m105_gone_bytes;	/* probes given up, perhaps still in the RX ring */
	long m105_gone_after;	/* ... until a line after this one is acknowledged */
	unsigned skip_ok;	/* oks that belong to Resend requests */
	struct marlin_phantom phantom[MARLIN_PHANTOMS]; /* oldest first */
	size_t phantom_n, phantom_bytes;
	double t_busy;		/* last busy or heat-wait report (s) */
	unsigned bufsize_learnt; /* largest ADVANCED_OK B<n>: BUFSIZE - 1 */
	long queued;		/* lines after n_acked surely in the firmware's queue */
	double rtt;		/* smoothed write-to-ok time of clean lines (s) */
	double cwnd;		/* lines the window may hold: halved by each
				 * rewind, grown by each ack (docs/streaming.md) */
	long broken_n;		/* safe stop: the heat wait M108 was sent for */
	double t_broken;	/* when (s) */

	double t_progress;	/* last reply showing the firmware works on us */
	double t_rx;		/* last byte received (or first line in flight) */
	char rx[MARLIN_RX_MAX + 1];
	size_t rx_len;
	bool connected, dead, cancelled, stopping;

	volatile sig_atomic_t req_pause, req_resume, req_cancel;
};

static inline struct marlin_entry *marlin_hist_entry(struct marlin *m, long n)
{
	return &m->hist[(unsigned long)n % MARLIN_HIST];
}

/* marlin.c */

/* Seconds on the transport's clock (xport_clock_s). */
double marlin_now_s(struct marlin *m);
/* Where the job stands, for messages: "the last line acknowledged was ...". */
void marlin_where(const struct marlin *m, char *buf, size_t cap);
/* End the job: record why (first reason wins) and fill err; ST_ERR_IO. */
int marlin_fail(struct marlin *m, enum marlin_fail why, struct st_error *err, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));
/* The error a failed driver keeps returning. */
int marlin_failed_err(const struct marlin *m, struct st_error *err);
/* Pass a line (dir ">" or "<") to the trace callback, if any. */
void marlin_trace(struct marlin *m, const char *dir, const char *text, size_t len);
/* Write raw bytes; a failure ends the job as a link failure. */
int marlin_write(struct marlin *m, const char *buf, size_t len, struct st_error *err);
/* Read and handle replies for at most timeout_ms; bytes read (0 on
 * time-out) or < 0. */
int marlin_read(struct marlin *m, int timeout_ms, struct st_error *err);
/* Queue a driver command (M155, the stop sequence) ahead of job lines. */
void marlin_push_prio(struct marlin *m, const char *cmd);

/* marlin_window.c */

/* An ADVANCED_OK ok (N or B): learn the capability and BUFSIZE - 1. */
void marlin_learn_b(struct marlin *m, const struct marlin_reply *r);
/* May a line of len bytes go out now? */
bool marlin_window_open(const struct marlin *m, size_t len);
/* Account lines (n_acked, n] as acknowledged. */
void marlin_ack_through(struct marlin *m, long n);
/* "Resend: k": rewind (or fail if k cannot be resent). */
int marlin_resend(struct marlin *m, long k, struct st_error *err);
/* Is a blocking command (G28, M109, M400 ...) among the lines in flight? */
bool marlin_blocking_inflight(const struct marlin *m);
/* Nothing answered for a while: an M105 probe, a newline, or one line
 * written again (blocking: a long command may be running). */
int marlin_probe(struct marlin *m, double now, bool blocking, struct st_error *err);
/* An emergency line of len bytes was written: it awaits its ok. */
void marlin_phantom_push(struct marlin *m, size_t len);
/* The oldest emergency line has its ok (or surely ran). */
void marlin_phantom_pop(struct marlin *m);
/* An "ok T:" reply: the answer to an M105 probe?  Then it acknowledges
 * what it can and true is returned. */
bool marlin_m105_answer(struct marlin *m);
/* An "Unknown command" echo of (line, len): a fragment of a damaged line
 * (whose ok is no line's) rather than a line in flight?  A spoilt probe is
 * then no longer awaited. */
bool marlin_unknown_fragment(struct marlin *m, const char *line, size_t len);

#endif /* STRATUM_SERIAL_MARLIN_IMPL_H */

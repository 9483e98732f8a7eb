/*
 * s3g_stream.c - streaming a build to a Sailfish printer (s3g.h): flow
 * control on the firmware's buffer, reset detection, and the resolver
 * that settles a lost reply to an action packet from build statistics.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "s3g_int.h"

/* ---- streaming ---------------------------------------------------------- */

#define S3G_HIST_MASK (S3G_STREAM_HISTORY - 1)
#define S3G_NOISY_S 1.0 /* after a fault, baseline before each packet this long (s) */
_Static_assert((S3G_STREAM_HISTORY & S3G_HIST_MASK) == 0, "history must be a power of two");

/* What the stream knows for settling lost replies and spotting resets.
 * Commands are pulled one at a time, so the lengths and codes of the last
 * S3G_STREAM_HISTORY are kept by index: those still queued in the
 * firmware are always among them (a buffer of capacity bytes holds at most
 * capacity / 2 commands). */
struct s3g_stream_ctx {
	size_t n;		/* commands expected, 0 unknown */
	size_t cur;		/* index of the packet in flight */
	long base;		/* index of the last confirmed build start (153), -1 none */
	/* The first command still queued is base + 1 + line + shift: shift
	 * counts commands the firmware's line count does not (skipped ones,
	 * and a packet damaged past CRC-8 that ran as another number of
	 * commands), measured at the last baseline (s3g_rebase). */
	long shift;
	bool shift_known;	/* false: the last baseline found bytes queued that
				 * no run of our commands adds up to */
	double noisy_until;	/* a fault this recent: baseline before each packet */
	uint32_t capacity;	/* largest free space seen (bytes) */
	bool seen_running;	/* build statistics said running after our 153 */
	bool running_before;	/* a build ran when the stream began */
	uint32_t last_line;
	double next_stats, next_temps;
	bool stats_due;		/* check now (after a time-out) */
	/* framing (s3g_frame_builds): our own 153 and 154 around the source's */
	enum { FRAME_UNDECIDED, FRAME_NONE, FRAME_STARTED, FRAME_ENDED } frame;
	bool held;		/* the source's first command waits behind our 153 */
	struct s3g_cmd held_cmd;
	uint8_t last_code;	/* of the source's last command */
	uint8_t frame_cmd[S3G_MAX_PAYLOAD];
	uint8_t len[S3G_STREAM_HISTORY];  /* by index & S3G_HIST_MASK */
	uint8_t code[S3G_STREAM_HISTORY];
};

/* The last confirmed command, for messages. */
static void s3g_last_desc(const struct s3g_stream_ctx *c, char *buf, size_t cap)
{
	char of[32] = "";
	if (c->n)
		snprintf(of, sizeof(of), " of %zu", c->n);
	if (c->cur == 0)
		snprintf(buf, cap, "before the first command was confirmed");
	else
		snprintf(buf, cap, "after command %zu%s (code %u, %s) was confirmed", c->cur, of,
			 c->code[(c->cur - 1) & S3G_HIST_MASK],
			 s3g_command_name(c->code[(c->cur - 1) & S3G_HIST_MASK]));
}

/* Build statistics: remember the build running; a reboot shows as state
 * "none" or a line number going backwards.  Returns 0 or ST_ERR_IO. */
static int s3g_check_reset(struct s3g *s, struct s3g_stream_ctx *c, struct s3g_build_stats *out,
			   struct st_error *err)
{
	struct s3g_build_stats b;
	char last[160];
	int rc = s3g_get_build_stats(s, &b, err);
	if (rc)
		return rc;
	c->next_stats = s3g_now(s) + s->o.stats_ms / 1000.0;
	c->stats_due = false;
	if (out)
		*out = b;
	bool running = b.state == S3G_BUILD_RUNNING || b.state == S3G_BUILD_PAUSED;
	if (c->seen_running && running && b.line < c->last_line) {
		/* a running build counting from 0 again: a build start ran, and
		 * only a packet damaged past CRC-8 brings one mid-stream (a
		 * reboot answers "none" until a build starts): the count is
		 * off until the next re-count */
		c->shift_known = false;
		c->stats_due = true;
		s->st.drifts++;
	} else if (c->seen_running && b.state == S3G_BUILD_NONE) {
		s3g_last_desc(c, last, sizeof(last));
		return s3g_why(s, S3G_FAIL_LINK,
			       st_error_set(err, ST_ERR_IO,
					    "the printer reset during the print: it answers as "
					    "freshly booted (build state %u, line %u, was line %u) "
					    "%s; home it and start the print again",
					    b.state, b.line, c->last_line, last));
	}
	if (running && c->base >= 0) {
		c->seen_running = true;
		c->last_line = b.line;
	}
	return 0;
}

/* A stable snapshot: free space, build statistics, free space again until
 * both free-space readings agree (nothing ran in between).  An empty
 * buffer needs no second reading: Sailfish counts a command as it takes
 * it out of the buffer, so with none queued (and none sent since) the
 * count cannot move.  Returns 0, 1 if it never settled, or an error. */
static int s3g_snapshot(struct s3g *s, struct s3g_stream_ctx *c, uint32_t *free_bytes,
			struct s3g_build_stats *b, struct st_error *err)
{
	uint32_t f2 = 0;
	int rc;

	for (int tries = 0; tries < 50; tries++) {
		if ((rc = s3g_get_buffer_free(s, free_bytes, err)) ||
		    (rc = s3g_check_reset(s, c, b, err)))
			return rc;
		if (*free_bytes == c->capacity)
			return 0;
		if ((rc = s3g_get_buffer_free(s, &f2, err)))
			return rc;
		if (*free_bytes == f2)
			return 0;
	}
	return 1;
}

/*
 * Measure shift at a definite point: every command before cur was
 * answered (or settled), cur not yet sent.  The bytes queued are then the
 * tail of our commands before cur, which tells the first one still queued
 * whatever the line count says; the line count against it is the shift.
 * A packet CRC-8 let through damaged can run as more or fewer commands
 * than one (docs/reliability.md, "Fault matrix"): the shift absorbs that
 * here, before a lost reply needs the count.  Returns 0 or an error.
 */
static int s3g_rebase(struct s3g *s, struct s3g_stream_ctx *c, struct st_error *err)
{
	struct s3g_build_stats b;
	uint32_t f = 0;
	int rc;

	if (c->base < 0)
		return 0;
	if ((rc = s3g_snapshot(s, c, &f, &b, err)) < 0)
		return rc;
	bool running = b.state == S3G_BUILD_RUNNING || b.state == S3G_BUILD_PAUSED;
	if (rc > 0 || !running || f > c->capacity) {
		c->shift_known = rc == 0 && !running ? c->shift_known : false;
		return 0;
	}
	uint64_t queued = c->capacity - f, sum = 0;
	size_t first = c->cur, lowest = (size_t)c->base + 1;
	while (first > lowest && c->cur - first < S3G_STREAM_HISTORY - 1 &&
	       (sum < queued || c->len[(first - 1) & S3G_HIST_MASK] == 0)) {
		first--;
		sum += c->len[first & S3G_HIST_MASK];
	}
	if (sum != queued) {
		c->shift_known = false;
		return 0;
	}
	long shift = (long)first - (c->base + 1) - (long)b.line;
	if (c->shift_known && shift != c->shift)
		s->st.drifts++;
	c->shift = shift;
	c->shift_known = true;
	return 0;
}

/* Settle a lost reply to command cur (see s3g.h "Exactly once"). */
static enum s3g_lost s3g_decide(struct s3g *s, void *ctx, struct st_error *err, int *rc)
{
	struct s3g_stream_ctx *c = ctx;
	struct s3g_build_stats b;
	uint32_t f1 = 0;

	*rc = s3g_check_reset(s, c, &b, err);
	if (*rc)
		return S3G_LOST_RESEND;
	bool running = b.state == S3G_BUILD_RUNNING || b.state == S3G_BUILD_PAUSED;
	bool starting = c->base < 0 && c->code[c->cur & S3G_HIST_MASK] == 153;
	bool ending = c->base >= 0 && c->code[c->cur & S3G_HIST_MASK] == 154;
	if ((c->base < 0 && !starting) || (!running && !starting && !ending) ||
	    c->capacity == 0 || (c->base >= 0 && !c->shift_known))
		goto unknown;
	int snap = s3g_snapshot(s, c, &f1, &b, err);
	if (snap < 0) {
		*rc = snap;
		return S3G_LOST_RESEND;
	}
	if (snap > 0 || f1 > c->capacity)
		goto unknown;
	running = b.state == S3G_BUILD_RUNNING || b.state == S3G_BUILD_PAUSED;
	if (ending && !running) {
		/* the build end ran: the build is finished, the buffer empty,
		 * and its last line count takes in every command after our
		 * build start, the build end included */
		if (b.state == S3G_BUILD_FINISHED && f1 == c->capacity &&
		    (long)b.line + c->shift == (long)c->cur - c->base) {
			s->st.resolved++;
			return S3G_LOST_QUEUED;
		}
		goto unknown;
	}
	if (starting) {
		/* the build start itself: no line count yet, but with no build
		 * before ours, running means it ran, and the bytes queued say
		 * whether it waits in the buffer (the only packet not yet run) */
		uint64_t queued = c->capacity - f1;
		if (c->running_before)
			goto unknown;
		if ((running && queued == 0) || (!running && queued == c->len[c->cur & S3G_HIST_MASK])) {
			s->st.resolved++;
			return S3G_LOST_QUEUED;
		}
		if (!running && queued == 0) {
			s->st.resolved++;
			return S3G_LOST_RESEND;
		}
		goto unknown;
	}
	{
		long at = c->base + 1 + (long)b.line + c->shift; /* first command still queued */
		size_t first = at < 0 ? 0 : (size_t)at;
		uint64_t queued = c->capacity - f1, without = 0;
		if (at < 0)
			goto unknown;
		if (first == c->cur + 1) { /* already taken out and counted */
			s->st.resolved++;
			return S3G_LOST_QUEUED;
		}
		if (first > c->cur + 1 || c->cur - first >= S3G_STREAM_HISTORY)
			goto unknown;
		for (size_t i = first; i < c->cur; i++)
			without += c->len[i & S3G_HIST_MASK];
		if (queued == without + c->len[c->cur & S3G_HIST_MASK]) {
			s->st.resolved++;
			return S3G_LOST_QUEUED;
		}
		if (queued == without) {
			s->st.resolved++;
			return S3G_LOST_RESEND;
		}
	}
unknown:
	s->st.dup_risk++;
	return S3G_LOST_RESEND;
}

void s3g_frame_builds(struct s3g *s, const char *name)
{
	if (s)
		snprintf(s->frame_name, sizeof(s->frame_name), "%s", name ? name : "");
}

/* The next command: the source's, or a framing 153 before its first and a
 * 154 after its last (s3g_frame_builds); *own says which.  Returns as an
 * s3g_source_fn. */
static int s3g_pull(struct s3g *s, struct s3g_stream_ctx *c, s3g_source_fn next, void *src,
		    struct s3g_cmd *k, bool *own, struct st_error *err)
{
	*own = false;
	if (c->held) {
		c->held = false;
		*k = c->held_cmd;
		c->last_code = k->payload[0];
		return 1;
	}
	if (c->frame == FRAME_ENDED)
		return 0;
	int rc = next(src, k, err);
	if (rc > 0 && k->payload && k->len)
		c->last_code = k->payload[0];
	if (c->frame == FRAME_UNDECIDED) {
		c->frame = FRAME_NONE;
		if (rc > 0 && s->frame_name[0] && k->payload && k->len && k->payload[0] != 153) {
			size_t l = strlen(s->frame_name);
			c->held_cmd = *k;
			c->held = true;
			c->frame = FRAME_STARTED;
			memset(c->frame_cmd, 0, 5); /* code, then uint32 steps 0 as GPX writes */
			c->frame_cmd[0] = 153;
			memcpy(c->frame_cmd + 5, s->frame_name, l + 1);
			*k = (struct s3g_cmd){c->frame_cmd, (uint8_t)(l + 6)};
			*own = true;
			return 1;
		}
	}
	if (rc == 0 && c->frame == FRAME_STARTED) {
		c->frame = FRAME_ENDED;
		if (c->last_code == 154)
			return 0;
		c->frame_cmd[0] = 154;
		c->frame_cmd[1] = 0;
		*k = (struct s3g_cmd){c->frame_cmd, 2};
		*own = true;
		return 1;
	}
	return rc;
}

/* Refresh temperatures for the status, then call the progress callback. */
static void s3g_report(struct s3g *s, double t0, s3g_progress_fn progress, void *ctx)
{
	s->st.elapsed_s = s3g_now(s) - t0;
	if (progress)
		progress(ctx, &s->st);
}

/* ST_ERR_ARG unless k is one whole action command of at most 32 bytes. */
static int s3g_check_cmd(const struct s3g_cmd *k, size_t i, struct st_error *err)
{
	int want = k->payload && k->len ? s3g_action_length(k->payload, k->len) : -1;
	if (!k->payload || k->len == 0 || k->len > S3G_MAX_PAYLOAD || want != k->len)
		return st_error_set(err, ST_ERR_ARG,
				    "S3G stream command %zu (code %u, %u bytes) is not one "
				    "whole action command of at most %d bytes",
				    i, k->payload && k->len ? k->payload[0] : 0u, k->len,
				    S3G_MAX_PAYLOAD);
	return 0;
}

/* Wait until the packet of len bytes fits the printer's buffer: only poll
 * while it cannot.  Returns 0 (also when *stop was set: status says so) or
 * an error. */
static int s3g_wait_room(struct s3g *s, struct s3g_stream_ctx *c, uint32_t *free_est,
			 uint8_t len, double t0, double *next_report, s3g_progress_fn progress,
			 void *ctx, volatile sig_atomic_t *stop, struct st_error *err)
{
	double now = s3g_now(s), idle_since = now;
	uint32_t seen = *free_est;
	struct s3g_temps temps;
	char last[160];
	int rc;

	while (*free_est < len) {
		if (stop && *stop) {
			s->st.interrupted = true;
			return 0;
		}
		s3g_sleep_ms(s, s->o.poll_ms);
		if ((rc = s3g_get_buffer_free(s, free_est, err)))
			return rc;
		if (*free_est > c->capacity)
			c->capacity = *free_est;
		now = s3g_now(s);
		if (*free_est != seen) {
			seen = *free_est;
			idle_since = now;
		}
		if (now >= c->next_stats) {
			if ((rc = s3g_check_reset(s, c, NULL, err)))
				return rc;
			/* heating counts as progress: waits block the buffer */
			int before = s->st.tool_temp + s->st.platform_temp;
			if (s3g_get_temps(s, &temps, NULL) == 0 &&
			    temps.tool + temps.platform != before)
				idle_since = now;
		}
		if (progress && now >= *next_report) {
			s3g_report(s, t0, progress, ctx);
			*next_report = now + 0.1;
		}
		if ((now - idle_since) * 1000.0 > s->o.overflow_deadline_ms) {
			s3g_last_desc(c, last, sizeof(last));
			return s3g_why(s, S3G_FAIL_PRINTER,
				       st_error_set(err, ST_ERR_IO,
						    "the printer's command buffer stayed full for %d "
						    "ms with no progress %s",
						    s->o.overflow_deadline_ms, last));
		}
	}
	return 0;
}

/* Poll until the printer is idle (or *stop). */
static int s3g_wait_done(struct s3g *s, struct s3g_stream_ctx *c, double t0, double *next_report,
			 s3g_progress_fn progress, void *ctx, volatile sig_atomic_t *stop,
			 struct st_error *err)
{
	struct s3g_temps temps;
	bool done = false;
	int rc;

	while (!done) {
		if (stop && *stop) {
			s->st.interrupted = true;
			break;
		}
		if ((rc = s3g_is_finished(s, &done, err)))
			return rc;
		double now = s3g_now(s);
		if (now >= c->next_stats || done) {
			if ((rc = s3g_check_reset(s, c, NULL, err)))
				return rc;
			s3g_get_temps(s, &temps, NULL);
		}
		if (progress && now >= *next_report) {
			s3g_report(s, t0, progress, ctx);
			*next_report = now + 0.1;
		}
		if (!done)
			s3g_sleep_ms(s, 20);
	}
	return 0;
}

int s3g_stream_pull(struct s3g *s, s3g_source_fn next, void *src, size_t total,
		    s3g_progress_fn progress, void *ctx, volatile sig_atomic_t *stop,
		    struct s3g_status *st, struct st_error *err)
{
	struct s3g_stream_ctx *c;
	struct s3g_resolver res;
	uint8_t resp[S3G_MAX_PAYLOAD];
	size_t rlen;
	uint32_t free_est = 0;
	double t0 = s3g_now(s), next_report = t0;
	struct s3g_temps temps;
	char last[160];
	int rc = 0;

	if (!s || !next)
		return st_error_set(err, ST_ERR_ARG, "s3g_stream: NULL argument");
	c = calloc(1, sizeof(*c));
	if (!c)
		return st_error_set(err, ST_ERR_NOMEM, "S3G stream: out of memory");
	c->n = total;
	c->base = -1;
	res = (struct s3g_resolver){s3g_decide, c};
	s->st.total = total;
	s->st.confirmed = s->st.skipped = 0;
	s->st.interrupted = false;
	s->st.fail = S3G_FAIL_NONE;
	if ((rc = s3g_get_buffer_free(s, &free_est, err)))
		goto out;
	c->capacity = free_est;
	{
		struct s3g_build_stats b0;
		if ((rc = s3g_check_reset(s, c, &b0, err)))
			goto out;
		c->running_before = b0.state == S3G_BUILD_RUNNING || b0.state == S3G_BUILD_PAUSED;
	}
	for (c->cur = 0;; c->cur++) {
		struct s3g_cmd k;
		bool own;
		double now = s3g_now(s);
		if (stop && *stop) {
			s->st.interrupted = true;
			break;
		}
		rc = s3g_pull(s, c, next, src, &k, &own, err);
		if (rc == 0)
			break;
		if (rc > 0)
			rc = s3g_check_cmd(&k, c->cur, err);
		if (rc < 0) {
			s->st.fail = S3G_FAIL_SOURCE;
			goto out;
		}
		c->len[c->cur & S3G_HIST_MASK] = k.len;
		c->code[c->cur & S3G_HIST_MASK] = k.payload[0];
		if (c->base >= 0 && (now < c->noisy_until || c->stats_due)) {
			/* a fault just now: a damaged packet may have run as
			 * something else; count again before the next can be lost */
			if ((rc = s3g_rebase(s, c, err)))
				goto out;
		} else if (c->stats_due || now >= c->next_stats) {
			if ((rc = s3g_check_reset(s, c, NULL, err)))
				goto out;
		}
		if (now >= c->next_temps) {
			c->next_temps = now + s->o.stats_ms / 1000.0;
			s3g_get_temps(s, &temps, NULL);
		}
		if (progress && now >= next_report) {
			s3g_report(s, t0, progress, ctx);
			next_report = now + 0.1;
		}
		rc = s3g_wait_room(s, c, &free_est, k.len, t0, &next_report, progress, ctx, stop,
				   err);
		if (rc || s->st.interrupted)
			goto out;
		uint64_t lost = s->st.timeouts + s->st.garbled, overflows = s->st.overflows;
		uint64_t faults = s->st.retries + s->st.errors + lost;
		rc = s3g_send(s, k.payload, k.len, resp, sizeof(resp), &rlen, &res, err);
		if (rc < 0) {
			char inner[256];
			snprintf(inner, sizeof(inner), "%s", err ? err->msg : "");
			s3g_last_desc(c, last, sizeof(last));
			st_error_set(err, rc, "%s (%s)", inner, last);
			goto out;
		}
		if (s->st.timeouts + s->st.garbled != lost)
			c->stats_due = true;
		if (s->st.retries + s->st.errors + s->st.timeouts + s->st.garbled != faults)
			c->noisy_until = s3g_now(s) + S3G_NOISY_S;
		if (s->st.overflows != overflows || rc == 1)
			free_est = 0; /* our count was off: ask again before the next */
		else if (free_est >= k.len)
			free_est -= k.len;
		if (rc == 0 && resp[0] == S3G_RC_UNSUPPORTED) {
			s->st.skipped++;
			/* not queued, never a line: the commands after it sit one
			 * further from the line count */
			c->len[c->cur & S3G_HIST_MASK] = 0;
			c->shift++;
		} else {
			if (!own) {
				s->st.confirmed++;
				s->st.action_bytes += k.len;
			}
			if (k.payload[0] == 153) {
				c->base = (long)c->cur;
				c->seen_running = false;
				c->last_line = 0;
				c->shift = 0;
				c->shift_known = true;
			}
		}
		rc = 0;
	}
	if (!s->st.interrupted && s->o.wait_finished)
		rc = s3g_wait_done(s, c, t0, &next_report, progress, ctx, stop, err);
out:
	if (rc < 0 && err && !strstr(err->msg, "confirmed")) {
		char inner[256];
		snprintf(inner, sizeof(inner), "%s", err->msg);
		s3g_last_desc(c, last, sizeof(last));
		st_error_set(err, rc, "%s (%s)", inner, last);
	}
	free(c);
	s->st.elapsed_s = s3g_now(s) - t0;
	if (progress)
		progress(ctx, &s->st);
	if (st)
		*st = s->st;
	return rc;
}

/* The source over an array, for s3g_stream. */
struct s3g_array_src {
	const struct s3g_cmd *cmds;
	size_t n, next;
};

static int s3g_array_next(void *src, struct s3g_cmd *cmd, struct st_error *err)
{
	struct s3g_array_src *a = src;
	(void)err;
	if (a->next >= a->n)
		return 0;
	*cmd = a->cmds[a->next++];
	return 1;
}

int s3g_stream(struct s3g *s, const struct s3g_cmd *cmds, size_t n, s3g_progress_fn progress,
	       void *ctx, volatile sig_atomic_t *stop, struct s3g_status *st,
	       struct st_error *err)
{
	struct s3g_array_src a = {cmds, n, 0};
	int rc;

	if (!s || (!cmds && n))
		return st_error_set(err, ST_ERR_ARG, "s3g_stream: NULL argument");
	/* all checked before the first packet: a bad array sends nothing */
	for (size_t i = 0; i < n; i++)
		if ((rc = s3g_check_cmd(&cmds[i], i, err)))
			return rc;
	return s3g_stream_pull(s, s3g_array_next, &a, n, progress, ctx, stop, st, err);
}

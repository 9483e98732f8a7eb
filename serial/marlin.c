/*
 * marlin.c - Marlin text-protocol driver (see marlin.h, docs/streaming.md):
 * lifecycle, the command queue, transmit, reply handling, time-outs and the
 * safe stop; files are streamed by printer_marlin.c (printer.h).  The window
 * and Resend accounting are in marlin_window.c, the handshake in
 * marlin_connect.c, reply parsing in marlin_reply.c; their shared state in
 * marlin_impl.h.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "marlin_impl.h"

double marlin_now_s(struct marlin *m)
{
	return xport_clock_s(m->x);
}

void marlin_options_init(struct marlin_options *o)
{
	memset(o, 0, sizeof(*o));
	o->rx_buffer = 128;
	o->boot_wait_ms = 5000;
	o->connect_timeout_ms = 15000;
	o->retry_ms = 2000;
	o->probe_ms = 3000;
	o->dead_ms = 30000;
	o->dead_blocking_ms = 600000;
	o->autoreport_s = 2;
}

const char *marlin_fail_name(enum marlin_fail f)
{
	switch (f) {
	case MARLIN_FAIL_LINK: return "link";
	case MARLIN_FAIL_FIRMWARE: return "firmware";
	case MARLIN_FAIL_CANCELLED: return "cancelled";
	case MARLIN_FAIL_PRINTER_CANCEL: return "printer-cancel";
	default: return "none";
	}
}

int marlin_new(struct xport *x, const struct marlin_options *opts, struct marlin **out,
	       struct st_error *err)
{
	struct marlin *m;
	if (out)
		*out = NULL;
	if (!x || !out)
		return st_error_set(err, ST_ERR_ARG, "marlin_new: no port or no out pointer");
	m = calloc(1, sizeof(*m));
	if (!m)
		return st_error_set(err, ST_ERR_NOMEM, "Marlin driver: out of memory");
	if (opts)
		m->o = *opts;
	else
		marlin_options_init(&m->o);
	if (m->o.rx_buffer > 1u << 20 || m->o.bufsize > 4096 || m->o.boot_wait_ms < 0 ||
	    m->o.connect_timeout_ms <= 0 || m->o.retry_ms <= 0 || m->o.probe_ms <= 0 ||
	    m->o.dead_ms <= 0 || m->o.dead_blocking_ms <= 0 || m->o.autoreport_s < 0 ||
	    m->o.autoreport_s > 60) {
		free(m);
		return st_error_set(err, ST_ERR_ARG, "Marlin driver: an option is out of range");
	}
	m->hist = calloc(MARLIN_HIST, sizeof(*m->hist));
	m->pend = calloc(MARLIN_RING, sizeof(*m->pend));
	if (!m->hist || !m->pend) {
		free(m->hist);
		free(m->pend);
		free(m);
		return st_error_set(err, ST_ERR_NOMEM, "Marlin driver: out of memory");
	}
	m->x = x;
	m->cwnd = MARLIN_MAX_INFLIGHT;
	m->n_next = m->n_send = 1;
	m->st.layer = -1;
	m->st.z = NAN;
	*out = m;
	return 0;
}

void marlin_free(struct marlin *m)
{
	if (!m)
		return;
	free(m->hist);
	free(m->pend);
	free(m);
}

const struct marlin_caps *marlin_caps(const struct marlin *m)
{
	return &m->caps;
}

void marlin_status(const struct marlin *m, struct marlin_status *out)
{
	*out = m->st;
	out->paused = m->st.paused;
}

bool marlin_idle(const struct marlin *m)
{
	return m->pend_count == 0 && m->prio_count == 0 && m->n_acked + 1 >= m->n_next;
}

bool marlin_drained(const struct marlin *m)
{
	return m->prio_count == 0 && m->n_acked + 1 >= m->n_next;
}

size_t marlin_pending(const struct marlin *m)
{
	return m->pend_count + m->prio_count + (size_t)(m->n_next - 1 - m->n_acked);
}

bool marlin_can_submit(const struct marlin *m)
{
	return m->pend_count < MARLIN_QUEUE;
}

size_t marlin_next_room(const struct marlin *m)
{
	return MARLIN_NEXT - m->next_count;
}

void marlin_request_pause(struct marlin *m)
{
	m->req_pause = 1;
}

void marlin_request_resume(struct marlin *m)
{
	m->req_resume = 1;
}

void marlin_request_cancel(struct marlin *m)
{
	m->req_cancel = 1;
}

void marlin_where(const struct marlin *m, char *buf, size_t cap)
{
	if (m->st.acked == 0)
		snprintf(buf, cap, "before any line of the job was acknowledged");
	else
		snprintf(buf, cap, "the last line acknowledged was line %llu of the file (N%ld)",
			 (unsigned long long)m->st.last_acked_src, m->st.last_acked_n);
}

int marlin_fail(struct marlin *m, enum marlin_fail why, struct st_error *err, const char *fmt, ...)
{
	if (m->st.fail == MARLIN_FAIL_NONE) {
		va_list ap;
		va_start(ap, fmt);
		vsnprintf(m->st.fail_msg, sizeof(m->st.fail_msg), fmt, ap);
		va_end(ap);
		m->st.fail = why;
	}
	if (why == MARLIN_FAIL_CANCELLED)
		m->cancelled = true;
	else
		m->dead = true;
	return st_error_set(err, ST_ERR_IO, "%s", m->st.fail_msg);
}

int marlin_failed_err(const struct marlin *m, struct st_error *err)
{
	return st_error_set(err, ST_ERR_IO, "%s", m->st.fail_msg);
}

void marlin_trace(struct marlin *m, const char *dir, const char *text, size_t len)
{
	char buf[MARLIN_RX_MAX + 1];
	if (!m->o.trace)
		return;
	if (len > MARLIN_RX_MAX)
		len = MARLIN_RX_MAX;
	memcpy(buf, text, len);
	while (len && (buf[len - 1] == '\n' || buf[len - 1] == '\r'))
		len--;
	buf[len] = '\0';
	m->o.trace(m->o.trace_ctx, dir, buf);
}

/* A read or write on the port failed (what: "reading from"/"writing to"):
 * the job ends as a link failure, a hang-up named as such. */
static int marlin_port_failed(struct marlin *m, const char *what, const struct st_error *e,
			      struct st_error *err)
{
	char where[160];
	marlin_where(m, where, sizeof(where));
	if (xport_is_gone(m->x))
		return marlin_fail(m, MARLIN_FAIL_LINK, err,
				   "the port %s closed (printer unplugged or switched off); %s",
				   xport_describe(m->x), where);
	return marlin_fail(m, MARLIN_FAIL_LINK, err, "%s %s failed: %s; %s", what,
			   xport_describe(m->x), e->msg, where);
}

/* Write raw bytes; a failure ends the job as a link failure. */
int marlin_write(struct marlin *m, const char *buf, size_t len, struct st_error *err)
{
	struct st_error e = {0};
	if (!len)
		return 0;
	if (xport_write_all(m->x, buf, len, MARLIN_WRITE_MS, NULL, &e))
		return marlin_port_failed(m, "writing to", &e, err);
	m->st.bytes_written += len;
	return 0;
}

/* Take the next command to number: emergency/stop ones first. */
static bool marlin_next_cmd(struct marlin *m, struct marlin_pend *out, bool take)
{
	if (m->prio_count) {
		*out = m->prio[0];
		if (take)
			memmove(m->prio, m->prio + 1, --m->prio_count * sizeof(m->prio[0]));
		return true;
	}
	if (!m->pend_count || (m->st.paused && !m->pend[m->pend_head].next))
		return false;
	*out = m->pend[m->pend_head];
	if (take) {
		m->pend_head = (m->pend_head + 1) % MARLIN_RING;
		m->pend_count--;
		m->next_count -= out->next;
	}
	return true;
}

/* Write every line the window allows, in one write. */
static int marlin_transmit(struct marlin *m, struct st_error *err)
{
	char buf[8192];
	size_t len = 0;
	/* nothing written is unacknowledged: a probe's rewrite (n_send moved
	 * back) is not a fresh start and must not restart the dead-link clock */
	bool was_empty = m->n_max_sent <= m->n_acked;

	for (;;) {
		struct marlin_entry *e;
		if (m->n_send < m->n_next) {
			e = marlin_hist_entry(m, m->n_send);
			if (!marlin_window_open(m, e->len))
				break;
			m->st.resends++;
			e->t_sent = 0;
		} else {
			struct marlin_pend p;
			char text[MARLIN_LINE_CAP];
			if (m->n_next - m->n_acked >= MARLIN_HIST - 16 || !marlin_next_cmd(m, &p, false))
				break;
			int k = gcode_format_numbered(text, sizeof(text) - 1, m->n_next, p.cmd);
			if (k <= 0)
				return marlin_fail(m, MARLIN_FAIL_LINK, err,
						   "internal: cannot number command '%s'", p.cmd);
			text[k++] = '\n';
			if (!marlin_window_open(m, (size_t)k))
				break;
			marlin_next_cmd(m, &p, true);
			e = marlin_hist_entry(m, m->n_next);
			e->n = m->n_next;
			e->len = (uint16_t)k;
			memcpy(e->text, text, (size_t)k);
			e->job = p.job;
			e->blocking = p.blocking;
			e->heat_wait = p.heat_wait;
			e->src = p.src;
			e->layer = p.layer;
			e->z = p.z;
			e->t_sent = marlin_now_s(m);
			if (p.job && !m->st.first_n)
				m->st.first_n = e->n;
			m->n_next++;
		}
		if (len + e->len > sizeof(buf)) {
			if (marlin_write(m, buf, len, err))
				return ST_ERR_IO;
			len = 0;
		}
		memcpy(buf + len, e->text, e->len);
		len += e->len;
		marlin_trace(m, ">", e->text, e->len);
		m->last_tx_n = e->n;
		if (e->n > m->n_max_sent)
			m->n_max_sent = e->n;
		m->n_send++;
		m->st.transmitted++;
	}
	if (len && was_empty) {
		/* the clocks start when something is in flight again */
		m->t_rx = m->t_progress = marlin_now_s(m);
	}
	return marlin_write(m, buf, len, err);
}

/* Handle one reply line. */
static int marlin_handle(struct marlin *m, const char *line, size_t len, double now,
			 struct st_error *err)
{
	struct marlin_reply r;
	char where[160];
	enum marlin_reply_kind kind = marlin_parse_reply(line, len, &r, &m->st, &m->caps);

	marlin_trace(m, "<", line, len);
	switch (kind) {
	case MARLIN_REPLY_OK: {
		/* before skip_ok: the ok after a Resend is a bare "ok"; a
		 * probe's answer that acknowledged nothing is no progress */
		long acked = m->n_acked;
		m->probed = false;
		if (r.has_temps && marlin_m105_answer(m)) {
			if (m->n_acked != acked)
				m->t_progress = now;
			break;
		}
		m->t_progress = now;
		m->probed = false;
		if (m->skip_ok) {
			m->skip_ok--;
			break;
		}
		marlin_learn_b(m, &r);
		if (r.has_n) {
			if (r.n > m->n_acked && r.n < m->n_next && r.n <= m->n_max_sent) {
				marlin_ack_through(m, r.n);
				if (r.has_b)
					m->queued = (long)m->bufsize_learnt > r.b
							    ? (long)m->bufsize_learnt - r.b
							    : 0;
			} else {
				m->st.stray_oks++;
			}
			break;
		}
		if (m->caps.advanced_ok && !r.has_temps) {
			/* ADVANCED_OK numbers every ok of a numbered line (M105
			 * answers "ok T:..." instead): this one belongs to an
			 * unnumbered line, ours or a fragment the firmware took */
			if (m->phantom_n)
				marlin_phantom_pop(m);
			else
				m->st.stray_oks++;
			break;
		}
		if (m->phantom_n && m->n_acked >= m->phantom[0].after) {
			marlin_phantom_pop(m);
			break;
		}
		if (m->n_acked + 1 < m->n_next && m->n_acked + 1 <= m->n_max_sent)
			marlin_ack_through(m, m->n_acked + 1);
		else
			m->st.stray_oks++;
		break;
	}
	case MARLIN_REPLY_RESEND:
		m->t_progress = now;
		m->skip_ok++;
		m->st.resend_requests++;
		if (m->connected) {
			int rc = marlin_resend(m, r.resend, err);
			m->probed = false;
			return rc;
		}
		break;
	case MARLIN_REPLY_LINE_ERROR:
		m->st.line_errors++;
		break;
	case MARLIN_REPLY_FATAL: {
		char msg[120];
		size_t n = len < sizeof(msg) - 1 ? len : sizeof(msg) - 1;
		memcpy(msg, line, n);
		msg[n] = '\0';
		marlin_where(m, where, sizeof(where));
		return marlin_fail(m, MARLIN_FAIL_FIRMWARE, err,
				   "the printer stopped with \"%s\"; %s", msg, where);
	}
	case MARLIN_REPLY_ERROR:
		m->st.other_errors++;
		break;
	case MARLIN_REPLY_BUSY:
		m->st.busy++;
		m->t_progress = m->t_busy = now;
		m->probed = false;
		m->talks_blocked = true;
		break;
	case MARLIN_REPLY_UNKNOWN_CMD: {
		size_t n = len < sizeof(m->st.last_warning) - 1 ? len : sizeof(m->st.last_warning) - 1;
		memcpy(m->st.last_warning, line, n);
		m->st.last_warning[n] = '\0';
		m->st.unknown_commands++;
		/* a fragment's ok comes next; with ADVANCED_OK it has no N */
		if (marlin_unknown_fragment(m, line, len) && !m->caps.advanced_ok)
			m->skip_ok++;
		break;
	}
	case MARLIN_REPLY_TEMP:
		if (m->st.heating_wait || marlin_blocking_inflight(m)) {
			m->t_progress = now;
			m->probed = false;
			m->talks_blocked = m->talks_blocked || m->st.heating_wait;
			if (m->st.heating_wait)
				m->t_busy = now;
		}
		break;
	case MARLIN_REPLY_START:
		if (m->connected) {
			marlin_where(m, where, sizeof(where));
			return marlin_fail(m, MARLIN_FAIL_LINK, err,
					   "the printer restarted during the job (it sent its boot "
					   "banner \"start\") and lost its state; %s", where);
		}
		break;
	case MARLIN_REPLY_ACTION:
		if (!strcmp(r.action, "pause") || !strcmp(r.action, "paused")) {
			m->st.paused = true;
		} else if (!strcmp(r.action, "resume") || !strcmp(r.action, "resumed")) {
			m->st.paused = false;
		} else if (!strcmp(r.action, "cancel")) {
			marlin_where(m, where, sizeof(where));
			m->pend_count = m->next_count = 0;
			return marlin_fail(m, MARLIN_FAIL_PRINTER_CANCEL, err,
					   "the printer cancelled the job (//action:cancel); %s", where);
		}
		break;
	default:
		break;
	}
	return 0;
}

/* Split received bytes into lines and handle them. */
static int marlin_feed(struct marlin *m, const char *buf, size_t n, double now,
		       struct st_error *err)
{
	for (size_t i = 0; i < n; i++) {
		char c = buf[i];
		if (c == '\n' || c == '\r') {
			if (m->rx_len) {
				int rc = marlin_handle(m, m->rx, m->rx_len, now, err);
				m->rx_len = 0;
				if (rc)
					return rc;
			}
		} else if (m->rx_len < MARLIN_RX_MAX) {
			m->rx[m->rx_len++] = c;
		}
	}
	return 0;
}

/* Read for at most timeout_ms; returns bytes handled (0 on time-out) or <0. */
int marlin_read(struct marlin *m, int timeout_ms, struct st_error *err)
{
	char buf[4096];
	struct st_error e = {0};
	int n = xport_read(m->x, buf, sizeof(buf), timeout_ms, &e);
	if (n < 0)
		return marlin_port_failed(m, "reading from", &e, err);
	if (n == 0)
		return 0;
	double now = marlin_now_s(m);
	m->t_rx = now;
	int rc = marlin_feed(m, buf, (size_t)n, now, err);
	return rc ? rc : n;
}

/* Time-outs: re-send what seems lost, give up on a silent printer. */
static int marlin_timers(struct marlin *m, double now, struct st_error *err)
{
	char where[160];
	if (m->n_max_sent <= m->n_acked && m->n_send - 1 <= m->n_acked)
		return 0; /* nothing in flight */
	bool blocking = marlin_blocking_inflight(m);
	/* a firmware that sends busy or W: reports while it waits
	 * (HOST_KEEPALIVE) falls silent only when it hangs */
	double dead = (blocking && !m->talks_blocked ? m->o.dead_blocking_ms : m->o.dead_ms) /
		      1000.0;
	if (now - m->t_rx > dead) {
		marlin_where(m, where, sizeof(where));
		return marlin_fail(m, MARLIN_FAIL_LINK, err,
				   "the printer on %s stopped answering (nothing for %.0f s); %s",
				   xport_describe(m->x), now - m->t_rx, where);
	}
	/* After a rewind, copies the firmware flushed never answer: when the
	 * replies stop for several round trips, the ones still counted as
	 * "on the way" are gone, and so is our resent line (flushed by one of
	 * their errors).  Write it again without waiting for probe_ms.  Not
	 * after a probe: a stalled firmware would get a window of copies.
	 * Without a rewind, 8 round trips of silence (at least
	 * MARLIN_M105_FAST_S) send the M105 probe, whose answer counts oks
	 * that were lost; a blocking command in flight may have finished
	 * with its ok lost, so that probe goes out then too. */
	double quiet = m->o.probe_ms / 1000.0;
	double fast = m->rtt > 0 && 8 * m->rtt < quiet ? 8 * m->rtt : quiet;
	if (m->rewinding)
		quiet = fast < 0.02 ? 0.02 : fast;
	else
		quiet = fast < MARLIN_M105_FAST_S ? MARLIN_M105_FAST_S : fast;
	if (now - m->t_progress > quiet)
		return marlin_probe(m, now, blocking, err);
	return 0;
}

/* marlin_submit, at the end of the queue or (first) at its head. */
static int submit(struct marlin *m, const char *cmd, uint64_t src_line, long layer, double z,
		  bool first, struct st_error *err)
{
	struct gcode_line g;
	size_t len = cmd ? strlen(cmd) : 0;
	if (m->dead || m->cancelled)
		return marlin_failed_err(m, err);
	if (!len || len > MARLIN_CMD_MAX)
		return st_error_set(err, ST_ERR_ARG,
				    "command '%.40s%s' is %zu bytes; Marlin takes 1 to %d "
				    "(MAX_CMD_SIZE 96 with line number and checksum)",
				    cmd ? cmd : "", len > 40 ? "..." : "", len, MARLIN_CMD_MAX);
	if (gcode_parse(cmd, len, 0, &g, err))
		return ST_ERR_ARG;
	if (first ? !marlin_next_room(m) : !marlin_can_submit(m))
		return 0;
	size_t slot = (m->pend_head + m->pend_count) % MARLIN_RING;
	if (first) {
		/* after the earlier next lines not yet written, in their order */
		m->pend_head = (m->pend_head + MARLIN_RING - 1) % MARLIN_RING;
		for (size_t i = 0; i < m->next_count; i++)
			m->pend[(m->pend_head + i) % MARLIN_RING] =
				m->pend[(m->pend_head + i + 1) % MARLIN_RING];
		slot = (m->pend_head + m->next_count++) % MARLIN_RING;
	}
	struct marlin_pend *p = &m->pend[slot];
	memcpy(p->cmd, cmd, len + 1);
	p->job = true;
	p->next = first;
	p->blocking = gcode_is_blocking(g.kind);
	p->heat_wait = g.kind == GCODE_KIND_TEMP_WAIT || g.kind == GCODE_KIND_USER_WAIT;
	p->src = src_line;
	p->layer = layer;
	p->z = z;
	m->pend_count++;
	m->st.submitted++;
	return 1;
}

int marlin_submit(struct marlin *m, const char *cmd, uint64_t src_line, long layer, double z,
		  struct st_error *err)
{
	return submit(m, cmd, src_line, layer, z, false, err);
}

int marlin_submit_next(struct marlin *m, const char *cmd, struct st_error *err)
{
	return submit(m, cmd, 0, -1, NAN, true, err);
}

/* Queue a driver command (M155, the stop sequence) ahead of job lines. */
void marlin_push_prio(struct marlin *m, const char *cmd)
{
	struct marlin_pend *p;
	if (m->prio_count == MARLIN_PRIO)
		return;
	size_t n = strlen(cmd);
	if (n > MARLIN_CMD_MAX)
		n = MARLIN_CMD_MAX; /* only our own short commands come here */
	p = &m->prio[m->prio_count++];
	memset(p, 0, sizeof(*p));
	memcpy(p->cmd, cmd, n);
	p->cmd[n] = '\0';
	p->layer = -1;
	p->z = NAN;
}

int marlin_step(struct marlin *m, int timeout_ms, struct st_error *err)
{
	double end = marlin_now_s(m) + (timeout_ms > 0 ? timeout_ms : 0) / 1000.0;
	int rc;

	if (m->dead || (m->cancelled && !m->stopping))
		return marlin_failed_err(m, err);
	if (m->req_cancel && !m->stopping) {
		char where[160];
		m->req_cancel = 0;
		marlin_where(m, where, sizeof(where));
		return marlin_fail(m, MARLIN_FAIL_CANCELLED, err, "the job was cancelled; %s",
				   where);
	}
	if (m->req_pause) {
		m->req_pause = 0;
		m->st.paused = true;
	}
	if (m->req_resume) {
		m->req_resume = 0;
		m->st.paused = false;
	}
	for (;;) {
		if ((rc = marlin_transmit(m, err)))
			return rc;
		double left = end - marlin_now_s(m);
		rc = marlin_read(m, left > 0 ? (int)(left * 1000.0 + 0.5) : 0, err);
		if (rc < 0)
			return rc;
		if ((rc = marlin_timers(m, marlin_now_s(m), err)))
			return rc;
		if (marlin_now_s(m) >= end || m->pend_count < MARLIN_QUEUE / 2)
			break;
	}
	return marlin_transmit(m, err);
}

int marlin_emergency(struct marlin *m, const char *cmd, struct st_error *err)
{
	struct gcode_line g;
	if (!cmd || gcode_parse(cmd, strlen(cmd), 0, &g, NULL) || g.letter != 'M' ||
	    (g.number != 112 && g.number != 108 && g.number != 410))
		return st_error_set(err, ST_ERR_ARG, "'%s' is not M112, M108 or M410",
				    cmd ? cmd : "");
	if (m->dead)
		return marlin_failed_err(m, err);
	if (m->caps.emergency_parser) {
		char buf[GCODE_LINE_MAX + 2];
		int k = snprintf(buf, sizeof(buf), "%s\n", g.text);
		/* Marlin also queues the unnumbered line, which earns an ok */
		if (g.number != 112)
			marlin_phantom_push(m, (size_t)k);
		marlin_trace(m, ">", buf, (size_t)k);
		return marlin_write(m, buf, (size_t)k, err);
	}
	marlin_push_prio(m, g.text);
	return marlin_transmit(m, err);
}

/* The printer confirmed the safe stop: the cancelled job is over and the
 * link takes the next one (a long-lived connection, as the farm node's). */
static void marlin_job_over(struct marlin *m)
{
	m->stopping = false;
	m->cancelled = false;
	m->req_cancel = 0;
	m->req_pause = 0;
	m->req_resume = 0;
	m->st.paused = false;
	m->st.fail = MARLIN_FAIL_NONE;
	m->st.fail_msg[0] = '\0';
}

/*
 * During the safe stop: when the oldest line not yet acknowledged is a
 * heat or user wait (the command the firmware runs, or the next it will
 * run once the one before ends), break it with M108.  Marlin's M108 ends
 * only the wait that runs when it arrives, and each M109/M190 starts its
 * own, so every queued wait needs its own M108, sent once it is the head
 * (M190 then M109, every slicer's start G-code).  Sent again every
 * MARLIN_BREAK_REPEAT_S while the same wait stays at the head, in case it
 * arrived before the wait began (docs/streaming.md "Stopping").
 */
static int marlin_break_wait(struct marlin *m, struct st_error *err)
{
	long head = m->n_acked + 1;
	double now = marlin_now_s(m);
	if (!m->caps.emergency_parser || head >= m->n_next || head > m->n_max_sent)
		return 0;
	const struct marlin_entry *e = marlin_hist_entry(m, head);
	if (e->n != head || !e->heat_wait)
		return 0;
	if (m->broken_n == head && now - m->t_broken < MARLIN_BREAK_REPEAT_S)
		return 0;
	m->broken_n = head;
	m->t_broken = now;
	return marlin_emergency(m, "M108", err);
}

int marlin_safe_stop(struct marlin *m, int timeout_ms, struct st_error *err)
{
	double end = marlin_now_s(m) + timeout_ms / 1000.0;
	if (m->dead)
		return marlin_failed_err(m, err);
	m->stopping = true;
	m->pend_count = m->next_count = 0;
	m->st.paused = false;
	m->broken_n = 0;
	if (marlin_break_wait(m, err) ||
	    (m->caps.emergency_parser && marlin_emergency(m, "M410", err)))
		return ST_ERR_IO;
	marlin_push_prio(m, "M104 S0");
	marlin_push_prio(m, "M140 S0");
	marlin_push_prio(m, "M107");
	marlin_push_prio(m, "M84");
	while (!marlin_idle(m)) {
		double left = end - marlin_now_s(m);
		if (left <= 0)
			return st_error_set(err, ST_ERR_IO,
					    "the printer did not confirm heaters and motors off "
					    "within %d s", timeout_ms / 1000);
		int rc = marlin_step(m, left < 0.05 ? (int)(left * 1000) : 50, err);
		if (rc || (rc = marlin_break_wait(m, err)))
			return rc;
	}
	marlin_job_over(m);
	return 0;
}

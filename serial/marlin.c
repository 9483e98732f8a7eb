/*
 * marlin.c - Marlin text-protocol driver (see marlin.h, docs/streaming.md).
 *
 * Line numbers are given when a command is first written, so emergency
 * commands can jump the queue.  hist[] keeps every written line by number
 * for Resend; pend[] holds submitted commands not yet written.
 *
 *   n_acked < ... < n_send <= n_next
 *   (n_acked, n_send)  written in this epoch, not yet acknowledged
 *   [n_send, n_next)   written before a rewind, to be written again
 */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "marlin.h"

#define MARLIN_HIST 1024	/* written lines kept for Resend (power of two) */
#define MARLIN_QUEUE 256	/* submitted commands waiting to be written */
#define MARLIN_MAX_INFLIGHT 512 /* lines in flight, whatever the buffers say */
#define MARLIN_PRIO 8		/* emergency/stop commands ahead of the queue */
#define MARLIN_PHANTOMS 8	/* unnumbered emergency lines awaiting their ok */
#define MARLIN_LINE_CAP 100	/* "N<n> <cmd>*<cs>\n" + NUL; Marlin keeps 95 */
#define MARLIN_RX_MAX 1024	/* longest reply line kept (bytes) */
#define MARLIN_WRITE_MS 5000	/* bound on one write to the port */

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

/* A command not yet written. */
struct marlin_pend {
	char cmd[MARLIN_CMD_MAX + 1];
	bool job, blocking, heat_wait;
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

	struct marlin_pend *pend;
	size_t pend_head, pend_count;
	struct marlin_pend prio[MARLIN_PRIO];
	size_t prio_count;

	/* Copies written before a rewind whose fate is unknown: they occupy
	 * the firmware's RX ring until it answers for them. */
	uint16_t ghost[MARLIN_MAX_INFLIGHT];
	size_t ghost_head, ghost_n, ghost_bytes;
	size_t stale_left;	/* further "Resend: rewind_k" they may cause */
	long rewind_k;
	bool rewinding;
	unsigned skip_ok;	/* oks that belong to Resend requests */
	long phantom[MARLIN_PHANTOMS]; /* unnumbered lines: written after line n */
	size_t phantom_n;
	unsigned bufsize_learnt;
	double rtt;		/* smoothed write-to-ok time of clean lines (s) */

	double t_progress;	/* last reply showing the firmware works on us */
	double t_rx;		/* last byte received (or first line in flight) */
	char rx[MARLIN_RX_MAX + 1];
	size_t rx_len;
	bool connected, dead, cancelled, stopping;

	volatile sig_atomic_t req_pause, req_resume, req_cancel;
};

/* Monotonic clock, seconds. */
static double mono_s(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
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
	m->pend = calloc(MARLIN_QUEUE, sizeof(*m->pend));
	if (!m->hist || !m->pend) {
		free(m->hist);
		free(m->pend);
		free(m);
		return st_error_set(err, ST_ERR_NOMEM, "Marlin driver: out of memory");
	}
	m->x = x;
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

size_t marlin_pending(const struct marlin *m)
{
	return m->pend_count + m->prio_count + (size_t)(m->n_next - 1 - m->n_acked);
}

bool marlin_can_submit(const struct marlin *m)
{
	return m->pend_count < MARLIN_QUEUE;
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

/* Where the job stands, for messages: "after file line L (N<n>)". */
static void marlin_where(const struct marlin *m, char *buf, size_t cap)
{
	if (m->st.acked == 0)
		snprintf(buf, cap, "before any line of the job was acknowledged");
	else
		snprintf(buf, cap, "the last line acknowledged was line %llu of the file (N%ld)",
			 (unsigned long long)m->st.last_acked_src, m->st.last_acked_n);
}

/* End the job: record why (first reason wins) and fill err. */
static int marlin_fail(struct marlin *m, enum marlin_fail why, struct st_error *err,
		       const char *fmt, ...) __attribute__((format(printf, 4, 5)));
static int marlin_fail(struct marlin *m, enum marlin_fail why, struct st_error *err,
		       const char *fmt, ...)
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

/* The error a failed driver keeps returning. */
static int marlin_failed_err(const struct marlin *m, struct st_error *err)
{
	return st_error_set(err, ST_ERR_IO, "%s", m->st.fail_msg);
}

/* ---- reply parsing ---- */

/* Case-insensitive substring test on (s, len). */
static bool has_ci(const char *s, size_t len, const char *needle)
{
	size_t k = strlen(needle);
	for (size_t i = 0; i + k <= len; i++) {
		size_t j = 0;
		while (j < k && tolower((unsigned char)s[i + j]) == tolower((unsigned char)needle[j]))
			j++;
		if (j == k)
			return true;
	}
	return false;
}

static bool starts(const char *s, size_t len, const char *prefix)
{
	size_t k = strlen(prefix);
	return len >= k && !memcmp(s, prefix, k);
}

/* A whole non-negative decimal at p (< end); false if none. */
static bool read_long(const char *p, const char *end, long *v, const char **after)
{
	long x = 0;
	const char *q = p;
	while (q < end && *q == ' ')
		q++;
	if (q >= end || !isdigit((unsigned char)*q))
		return false;
	while (q < end && isdigit((unsigned char)*q) && x < 1000000000000L)
		x = x * 10 + (*q++ - '0');
	*v = x;
	if (after)
		*after = q;
	return true;
}

/* A number token [p, end) through the project's number reader. */
static bool read_num(const char *p, const char *end, double *v)
{
	return end > p && gcode_read_number(p, (size_t)(end - p), v, NULL) == 0;
}

/* Parse "T:210.00 /210.00 B:60.0 /60.0 T0:.. C:.. @:0 W:?" into st; true
 * if any heater was found. */
static bool parse_temps(const char *s, size_t len, struct marlin_status *st)
{
	const char *p = s, *end = s + len;
	bool any = false, wait = false;
	while (p < end) {
		while (p < end && *p == ' ')
			p++;
		const char *t = p;
		while (p < end && *p != ' ')
			p++;
		const char *colon = memchr(t, ':', (size_t)(p - t));
		if (!colon)
			continue;
		struct marlin_temp *h = NULL;
		size_t nl = (size_t)(colon - t);
		if (nl == 1 && t[0] == 'T') {
			h = &st->tool[0];
		} else if (nl >= 2 && t[0] == 'T' && isdigit((unsigned char)t[1])) {
			long i;
			if (read_long(t + 1, colon, &i, NULL) && i < MARLIN_MAX_TOOLS)
				h = &st->tool[i];
		} else if (nl == 1 && t[0] == 'B') {
			h = &st->bed;
		} else if (nl == 1 && t[0] == 'C') {
			h = &st->chamber;
		} else if (nl == 1 && t[0] == 'W') {
			wait = true;
			continue;
		}
		if (!h || !read_num(colon + 1, p, &h->actual))
			continue;
		h->present = true;
		any = true;
		/* the target follows as " /210.00" */
		const char *q = p;
		while (q < end && *q == ' ')
			q++;
		if (q < end && *q == '/') {
			const char *e = ++q;
			while (e < end && *e != ' ')
				e++;
			if (read_num(q, e, &h->target))
				p = e;
		}
	}
	if (any)
		st->heating_wait = wait;
	return any;
}

/* Does (s, len) look like a temperature report ("T:", "T0:", "B:" first)? */
static bool looks_like_temps(const char *s, size_t len)
{
	while (len && *s == ' ') {
		s++;
		len--;
	}
	if (len >= 2 && (s[0] == 'T' || s[0] == 'B' || s[0] == 'C') && s[1] == ':')
		return true;
	return len >= 3 && s[0] == 'T' && isdigit((unsigned char)s[1]) && s[2] == ':';
}

/* Copy the text after key up to stop (or the end) into out. */
static void copy_field(const char *s, size_t len, const char *key, const char *stop, char *out,
		       size_t cap)
{
	size_t k = strlen(key);
	for (size_t i = 0; i + k <= len; i++) {
		if (memcmp(s + i, key, k))
			continue;
		const char *b = s + i + k, *e = s + len;
		for (const char *q = b; stop && q + strlen(stop) <= s + len; q++)
			if (!memcmp(q, stop, strlen(stop))) {
				e = q;
				break;
			}
		size_t n = (size_t)(e - b);
		if (n >= cap)
			n = cap - 1;
		memcpy(out, b, n);
		out[n] = '\0';
		return;
	}
}

/* Apply one "Cap:NAME:v" line to caps. */
static void parse_cap(const char *s, size_t len, struct marlin_caps *caps)
{
	static const struct {
		const char *name;
		size_t off;
	} tab[] = {
		{"ADVANCED_OK", offsetof(struct marlin_caps, advanced_ok)},
		{"EMERGENCY_PARSER", offsetof(struct marlin_caps, emergency_parser)},
		{"AUTOREPORT_TEMP", offsetof(struct marlin_caps, autoreport_temp)},
		{"HOST_ACTION_COMMANDS", offsetof(struct marlin_caps, host_action_commands)},
		{"PROMPT_SUPPORT", offsetof(struct marlin_caps, prompt_support)},
		{"EEPROM", offsetof(struct marlin_caps, eeprom)},
		{"SDCARD", offsetof(struct marlin_caps, sdcard)},
		{"THERMAL_PROTECTION", offsetof(struct marlin_caps, thermal_protection)},
		{"ARCS", offsetof(struct marlin_caps, arcs)},
		{"PROGRESS", offsetof(struct marlin_caps, progress)},
	};
	const char *name = s + 4, *end = s + len;
	const char *colon = memchr(name, ':', (size_t)(end - name));
	if (!colon || colon + 1 >= end)
		return;
	size_t nl = (size_t)(colon - name);
	bool on = colon[1] == '1';
	for (size_t i = 0; i < sizeof(tab) / sizeof(tab[0]); i++)
		if (strlen(tab[i].name) == nl && !memcmp(tab[i].name, name, nl)) {
			bool *f = (bool *)((char *)caps + tab[i].off);
			/* ADVANCED_OK seen in a reply stays known whatever M115 says */
			*f = i == 0 ? (*f || on) : on;
		}
}

enum marlin_reply_kind marlin_parse_reply(const char *line, size_t len, struct marlin_reply *r,
					  struct marlin_status *st, struct marlin_caps *caps)
{
	struct marlin_status dummy;
	memset(r, 0, sizeof(*r));
	if (!st) {
		memset(&dummy, 0, sizeof(dummy));
		st = &dummy;
	}
	while (len && (line[len - 1] == '\r' || line[len - 1] == ' ' || line[len - 1] == '\n'))
		len--;
	const char *end = line + len;

	if (starts(line, len, "ok") && (len == 2 || line[2] == ' ')) {
		r->kind = MARLIN_REPLY_OK;
		if (looks_like_temps(line + 2, len - 2)) {
			r->has_temps = parse_temps(line + 2, len - 2, st);
			return r->kind;
		}
		for (const char *p = line + 2; p < end;) {
			while (p < end && *p == ' ')
				p++;
			if (p >= end)
				break;
			char c = *p;
			long v;
			const char *after;
			if ((c == 'N' || c == 'P' || c == 'B') && read_long(p + 1, end, &v, &after) &&
			    (after == end || *after == ' ')) {
				if (c == 'N') {
					r->has_n = true;
					r->n = v;
				} else if (c == 'P') {
					r->has_p = true;
					r->p = v;
				} else {
					r->has_b = true;
					r->b = v;
				}
				p = after;
			} else {
				while (p < end && *p != ' ')
					p++;
			}
		}
		return r->kind;
	}
	if (starts(line, len, "Resend:") || starts(line, len, "rs ")) {
		const char *p = line + (line[0] == 'R' ? 7 : 3);
		while (p < end && (*p == ' ' || *p == 'N'))
			p++;
		if (read_long(p, end, &r->resend, NULL)) {
			r->kind = MARLIN_REPLY_RESEND;
			return r->kind;
		}
		return r->kind = MARLIN_REPLY_OTHER;
	}
	if (starts(line, len, "Error:") || starts(line, len, "!!")) {
		if (has_ci(line, len, "checksum mismatch") || has_ci(line, len, "line number") ||
		    has_ci(line, len, "no checksum"))
			r->kind = MARLIN_REPLY_LINE_ERROR;
		else if (has_ci(line, len, "halted") || has_ci(line, len, "kill") ||
			 has_ci(line, len, "thermal runaway") || has_ci(line, len, "mintemp") ||
			 has_ci(line, len, "maxtemp") || has_ci(line, len, "heating failed") ||
			 has_ci(line, len, "thermal malfunction") ||
			 has_ci(line, len, "printer stopped") || starts(line, len, "!!"))
			r->kind = MARLIN_REPLY_FATAL;
		else
			r->kind = MARLIN_REPLY_ERROR;
		return r->kind;
	}
	if (starts(line, len, "echo:busy:") || starts(line, len, "busy:"))
		return r->kind = MARLIN_REPLY_BUSY;
	if (starts(line, len, "echo:Unknown command") || starts(line, len, "echo: Unknown command"))
		return r->kind = MARLIN_REPLY_UNKNOWN_CMD;
	if (len == 5 && !memcmp(line, "start", 5))
		return r->kind = MARLIN_REPLY_START;
	if (starts(line, len, "//action:")) {
		const char *p = line + 9, *e = p;
		while (e < end && *e != ' ')
			e++;
		size_t n = (size_t)(e - p);
		if (n >= sizeof(r->action))
			n = sizeof(r->action) - 1;
		memcpy(r->action, p, n);
		r->action[n] = '\0';
		return r->kind = MARLIN_REPLY_ACTION;
	}
	if (starts(line, len, "FIRMWARE_NAME:")) {
		if (caps) {
			caps->m115 = true;
			copy_field(line, len, "FIRMWARE_NAME:", " SOURCE_CODE_URL:",
				   caps->firmware_name, sizeof(caps->firmware_name));
			if (has_ci(caps->firmware_name, strlen(caps->firmware_name),
				   " PROTOCOL_VERSION:"))
				copy_field(line, len, "FIRMWARE_NAME:", " PROTOCOL_VERSION:",
					   caps->firmware_name, sizeof(caps->firmware_name));
			copy_field(line, len, "MACHINE_TYPE:", " EXTRUDER_COUNT:",
				   caps->machine_type, sizeof(caps->machine_type));
			/* (line, len) need not end in a NUL: search within len only */
			const char *ec = NULL;
			for (size_t i = 0; !ec && i + 15 <= len; i++)
				if (!memcmp(line + i, "EXTRUDER_COUNT:", 15))
					ec = line + i;
			long v;
			if (ec && read_long(ec + 15, end, &v, NULL) && v < 64)
				caps->extruder_count = (int)v;
		}
		return r->kind = MARLIN_REPLY_FIRMWARE;
	}
	if (starts(line, len, "Cap:")) {
		if (caps)
			parse_cap(line, len, caps);
		return r->kind = MARLIN_REPLY_CAP;
	}
	if (looks_like_temps(line, len) && parse_temps(line, len, st)) {
		r->has_temps = true;
		return r->kind = MARLIN_REPLY_TEMP;
	}
	return r->kind = MARLIN_REPLY_OTHER;
}

/* ---- the window ---- */

static struct marlin_entry *entry(struct marlin *m, long n)
{
	return &m->hist[(unsigned long)n % MARLIN_HIST];
}

static void ghost_clear(struct marlin *m)
{
	m->ghost_head = m->ghost_n = m->ghost_bytes = 0;
	m->stale_left = 0;
	m->rewinding = false;
}

static void ghost_push(struct marlin *m, uint16_t len)
{
	if (m->ghost_n == MARLIN_MAX_INFLIGHT)
		return;
	m->ghost[(m->ghost_head + m->ghost_n++) % MARLIN_MAX_INFLIGHT] = len;
	m->ghost_bytes += len;
}

static void ghost_pop(struct marlin *m)
{
	if (!m->ghost_n)
		return;
	m->ghost_bytes -= m->ghost[m->ghost_head];
	m->ghost_head = (m->ghost_head + 1) % MARLIN_MAX_INFLIGHT;
	m->ghost_n--;
}

/* Command slots of the firmware we may count on (0 = unknown). */
static unsigned marlin_slots(const struct marlin *m)
{
	return m->o.bufsize ? m->o.bufsize : m->bufsize_learnt;
}

/*
 * May a line of len bytes go out now?  The oldest `slots` lines in flight
 * have left the RX ring for the command queue (Marlin reads the ring only
 * while a slot is free, and answers "ok" only when the command is done);
 * the rest, plus copies written before a rewind, must fit in the ring.
 */
static bool marlin_window_open(const struct marlin *m, size_t len)
{
	long inflight = m->n_send - 1 - m->n_acked;
	unsigned slots = marlin_slots(m);
	size_t bytes;

	if (inflight <= 0)
		return true; /* one in flight always */
	if (inflight >= MARLIN_MAX_INFLIGHT)
		return false;
	if (!m->o.rx_buffer)
		return slots && (unsigned long)inflight < slots;
	bytes = m->ghost_bytes;
	if ((unsigned long)inflight >= slots)
		bytes += len;
	for (long n = m->n_acked + 1 + (long)slots; n < m->n_send; n++)
		bytes += m->hist[(unsigned long)n % MARLIN_HIST].len;
	return bytes + 1 <= m->o.rx_buffer; /* AVR rings hold size - 1 bytes */
}

static void trace(struct marlin *m, const char *dir, const char *text, size_t len)
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
static int marlin_write(struct marlin *m, const char *buf, size_t len, struct st_error *err)
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
	if (!m->pend_count || m->st.paused)
		return false;
	*out = m->pend[m->pend_head];
	if (take) {
		m->pend_head = (m->pend_head + 1) % MARLIN_QUEUE;
		m->pend_count--;
	}
	return true;
}

/* Write every line the window allows, in one write. */
static int marlin_transmit(struct marlin *m, struct st_error *err)
{
	char buf[8192];
	size_t len = 0;
	bool was_empty = m->n_send - 1 <= m->n_acked;

	for (;;) {
		struct marlin_entry *e;
		if (m->n_send < m->n_next) {
			e = entry(m, m->n_send);
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
			e = entry(m, m->n_next);
			e->n = m->n_next;
			e->len = (uint16_t)k;
			memcpy(e->text, text, (size_t)k);
			e->job = p.job;
			e->blocking = p.blocking;
			e->heat_wait = p.heat_wait;
			e->src = p.src;
			e->layer = p.layer;
			e->z = p.z;
			e->t_sent = mono_s();
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
		trace(m, ">", e->text, e->len);
		m->last_tx_n = e->n;
		if (e->n > m->n_max_sent)
			m->n_max_sent = e->n;
		m->n_send++;
		m->st.transmitted++;
	}
	if (len && was_empty) {
		/* the clocks start when something is in flight again */
		m->t_rx = m->t_progress = mono_s();
	}
	return marlin_write(m, buf, len, err);
}

/* Account lines (n_acked, n] as acknowledged. */
static void marlin_ack_through(struct marlin *m, long n)
{
	struct marlin_entry *last = entry(m, n);
	if (last->n == n && last->t_sent > 0 && !last->blocking) {
		double sample = mono_s() - last->t_sent;
		m->rtt = m->rtt > 0 ? 0.875 * m->rtt + 0.125 * sample : sample;
	}
	for (long k = m->n_acked + 1; k <= n; k++) {
		struct marlin_entry *e = entry(m, k);
		if (e->n != k || !e->job)
			continue;
		m->st.acked++;
		m->st.bytes_acked += e->len;
		m->st.last_acked_n = k;
		m->st.last_acked_src = e->src;
		m->st.layer = e->layer;
		m->st.z = e->z;
	}
	m->n_acked = n;
	if (m->n_send <= n)
		m->n_send = n + 1;
	if (m->rewinding && n >= m->rewind_k)
		ghost_clear(m); /* a copy after the rewind got through: the old ones are gone */
}

/* Undo the accounting of lines (n, n_acked]: the firmware says it never
 * took them (an "ok" we counted belonged to something else). */
static void marlin_unack_to(struct marlin *m, long n)
{
	for (long k = n + 1; k <= m->n_acked; k++) {
		struct marlin_entry *e = entry(m, k);
		if (e->n != k || !e->job || !m->st.acked)
			continue;
		m->st.acked--;
		m->st.bytes_acked -= e->len;
	}
	m->n_acked = n;
}

/* "Resend: k": the firmware has taken every line before k, none after. */
static int marlin_resend(struct marlin *m, long k, struct st_error *err)
{
	char where[160];
	if (k < 1 || k > m->n_max_sent + 1 || entry(m, k)->n != k || k < m->n_acked - 8) {
		if (k == m->n_max_sent + 1 && k == m->n_next) {
			/* the next line, never written: nothing to rewind */
			ghost_clear(m);
			return 0;
		}
		marlin_where(m, where, sizeof(where));
		return marlin_fail(m, MARLIN_FAIL_LINK, err,
				   "the printer asked for line N%ld again, which this job %s "
				   "(was the printer reset?); %s",
				   k, k > m->n_max_sent ? "never sent" : "no longer keeps", where);
	}
	if (m->rewinding && k == m->rewind_k && m->stale_left > 0) {
		/* caused by a copy written before our rewind: already handled */
		m->stale_left--;
		ghost_pop(m);
		return 0;
	}
	ghost_clear(m);
	if (k - 1 < m->n_acked)
		marlin_unack_to(m, k - 1);
	for (long n = k; n < m->n_send; n++)
		ghost_push(m, entry(m, n)->len);
	m->stale_left = m->ghost_n ? m->ghost_n - 1 : 0;
	ghost_pop(m); /* the copy that caused this request has been read */
	m->rewinding = true;
	m->rewind_k = k;
	m->n_send = k;
	return 0;
}

/* Is a blocking command (G28, M109, M400 ...) among the lines in flight? */
static bool marlin_blocking_inflight(const struct marlin *m)
{
	long hi = m->n_max_sent < m->n_next ? m->n_max_sent : m->n_next - 1;
	for (long n = m->n_acked + 1; n <= hi; n++)
		if (m->hist[(unsigned long)n % MARLIN_HIST].blocking)
			return true;
	return false;
}

/* Handle one reply line. */
static int marlin_handle(struct marlin *m, const char *line, size_t len, double now,
			 struct st_error *err)
{
	struct marlin_reply r;
	char where[160];
	enum marlin_reply_kind kind = marlin_parse_reply(line, len, &r, &m->st, &m->caps);

	trace(m, "<", line, len);
	switch (kind) {
	case MARLIN_REPLY_OK:
		m->t_progress = now;
		if (m->skip_ok) {
			m->skip_ok--;
			break;
		}
		if (r.has_n || r.has_b)
			m->caps.advanced_ok = true;
		if (r.has_b && (unsigned)r.b + 1 > m->bufsize_learnt && r.b < 4096)
			m->bufsize_learnt = (unsigned)r.b + 1;
		if (r.has_n) {
			if (r.n > m->n_acked && r.n < m->n_next && r.n <= m->n_max_sent)
				marlin_ack_through(m, r.n);
			else
				m->st.stray_oks++;
			break;
		}
		if (m->caps.advanced_ok && !r.has_temps) {
			/* ADVANCED_OK numbers every ok of a numbered line (M105
			 * answers "ok T:..." instead): this one belongs to an
			 * unnumbered line, ours or a fragment the firmware took */
			if (m->phantom_n)
				memmove(m->phantom, m->phantom + 1,
					--m->phantom_n * sizeof(m->phantom[0]));
			else
				m->st.stray_oks++;
			break;
		}
		if (m->phantom_n && m->n_acked >= m->phantom[0]) {
			memmove(m->phantom, m->phantom + 1, --m->phantom_n * sizeof(m->phantom[0]));
			break;
		}
		if (m->n_acked + 1 < m->n_next && m->n_acked + 1 <= m->n_max_sent)
			marlin_ack_through(m, m->n_acked + 1);
		else
			m->st.stray_oks++;
		break;
	case MARLIN_REPLY_RESEND:
		m->t_progress = now;
		m->skip_ok++;
		m->st.resend_requests++;
		if (m->connected)
			return marlin_resend(m, r.resend, err);
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
		m->t_progress = now;
		break;
	case MARLIN_REPLY_UNKNOWN_CMD: {
		size_t n = len < sizeof(m->st.last_warning) - 1 ? len : sizeof(m->st.last_warning) - 1;
		memcpy(m->st.last_warning, line, n);
		m->st.last_warning[n] = '\0';
		m->st.unknown_commands++;
		break;
	}
	case MARLIN_REPLY_TEMP:
		if (m->st.heating_wait || marlin_blocking_inflight(m))
			m->t_progress = now;
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
			m->pend_count = 0;
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
static int marlin_read(struct marlin *m, int timeout_ms, struct st_error *err)
{
	char buf[4096];
	struct st_error e = {0};
	int n = xport_read(m->x, buf, sizeof(buf), timeout_ms, &e);
	if (n < 0)
		return marlin_port_failed(m, "reading from", &e, err);
	if (n == 0)
		return 0;
	double now = mono_s();
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
	double dead = (blocking ? m->o.dead_blocking_ms : m->o.dead_ms) / 1000.0;
	if (now - m->t_rx > dead) {
		marlin_where(m, where, sizeof(where));
		return marlin_fail(m, MARLIN_FAIL_LINK, err,
				   "the printer on %s stopped answering (nothing for %.0f s); %s",
				   xport_describe(m->x), now - m->t_rx, where);
	}
	/* After a rewind, copies the firmware flushed never answer: when the
	 * replies stop for several round trips, the ones still counted as
	 * "on the way" are gone, and so is our resent line (flushed by one of
	 * their errors).  Write it again without waiting for probe_ms. */
	double quiet = m->o.probe_ms / 1000.0;
	if (m->rewinding && m->rtt > 0 && 8 * m->rtt < quiet)
		quiet = 8 * m->rtt < 0.02 ? 0.02 : 8 * m->rtt;
	if (!blocking && now - m->t_progress > quiet) {
		/* A line's end was lost and nothing followed to expose it: end
		 * any fragment and write everything unacknowledged again.
		 * Copies the firmware already has are dropped or answered with
		 * a Resend that puts us right. */
		ghost_clear(m);
		m->skip_ok = 0;
		m->n_send = m->n_acked + 1;
		m->t_progress = now;
		if (marlin_write(m, "\n", 1, err))
			return ST_ERR_IO;
	}
	return 0;
}

int marlin_submit(struct marlin *m, const char *cmd, uint64_t src_line, long layer, double z,
		  struct st_error *err)
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
	if (!marlin_can_submit(m))
		return 0;
	struct marlin_pend *p = &m->pend[(m->pend_head + m->pend_count) % MARLIN_QUEUE];
	memcpy(p->cmd, cmd, len + 1);
	p->job = true;
	p->blocking = gcode_is_blocking(g.kind);
	p->heat_wait = g.kind == GCODE_KIND_TEMP_WAIT || g.kind == GCODE_KIND_USER_WAIT;
	p->src = src_line;
	p->layer = layer;
	p->z = z;
	m->pend_count++;
	m->st.submitted++;
	return 1;
}

/* Queue a driver command (M155, the stop sequence) ahead of job lines. */
static void marlin_push_prio(struct marlin *m, const char *cmd)
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
	double end = mono_s() + (timeout_ms > 0 ? timeout_ms : 0) / 1000.0;
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
		double left = end - mono_s();
		rc = marlin_read(m, left > 0 ? (int)(left * 1000.0 + 0.5) : 0, err);
		if (rc < 0)
			return rc;
		if ((rc = marlin_timers(m, mono_s(), err)))
			return rc;
		if (mono_s() >= end || m->pend_count < MARLIN_QUEUE / 2)
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
		if (g.number != 112 && m->phantom_n < MARLIN_PHANTOMS)
			m->phantom[m->phantom_n++] = m->last_tx_n;
		trace(m, ">", buf, (size_t)k);
		return marlin_write(m, buf, (size_t)k, err);
	}
	marlin_push_prio(m, g.text);
	return marlin_transmit(m, err);
}

int marlin_safe_stop(struct marlin *m, int timeout_ms, struct st_error *err)
{
	double end = mono_s() + timeout_ms / 1000.0;
	if (m->dead)
		return marlin_failed_err(m, err);
	m->stopping = true;
	m->pend_count = 0;
	m->st.paused = false;
	if (m->caps.emergency_parser) {
		bool heat = false;
		for (long n = m->n_acked + 1; n < m->n_next; n++)
			heat = heat || entry(m, n)->heat_wait;
		if ((heat && marlin_emergency(m, "M108", err)) || marlin_emergency(m, "M410", err))
			return ST_ERR_IO;
	}
	marlin_push_prio(m, "M104 S0");
	marlin_push_prio(m, "M140 S0");
	marlin_push_prio(m, "M107");
	marlin_push_prio(m, "M84");
	while (!marlin_idle(m)) {
		double left = end - mono_s();
		if (left <= 0)
			return st_error_set(err, ST_ERR_IO,
					    "the printer did not confirm heaters and motors off "
					    "within %d s; switch it off by hand", timeout_ms / 1000);
		int rc = marlin_step(m, left < 0.05 ? (int)(left * 1000) : 50, err);
		if (rc)
			return rc;
	}
	return 0;
}

/* Handle replies until the line has been quiet for quiet_ms (at most
 * max_ms in all). */
static int marlin_wait_quiet(struct marlin *m, int quiet_ms, int max_ms, struct st_error *err)
{
	double end = mono_s() + max_ms / 1000.0;
	while (mono_s() < end) {
		int rc = marlin_read(m, quiet_ms, err);
		if (rc <= 0)
			return rc;
	}
	return 0;
}

int marlin_connect(struct marlin *m, struct st_error *err)
{
	double t0 = mono_s(), end = t0 + m->o.connect_timeout_ms / 1000.0;
	char buf[2 * MARLIN_LINE_CAP + 2];
	int rc;

	m->connected = false;
	if (m->o.expect_reset) {
		/* The bootloader must see no bytes: wait for the banner, then
		 * for the rest of it. */
		double boot_end = t0 + m->o.boot_wait_ms / 1000.0;
		while (mono_s() < boot_end) {
			double last = m->t_rx;
			rc = marlin_read(m, 100, err);
			if (rc < 0)
				return rc;
			if (rc == 0 && last > t0)
				break; /* something came, then 100 ms of quiet */
		}
	}
	for (int attempt = 0; mono_s() < end; attempt++) {
		int k = 0;
		buf[k++] = '\n'; /* ends any fragment left in the firmware's line */
		rc = gcode_format_numbered(buf + k, sizeof(buf) - (size_t)k - 2, 0, "M110 N0");
		if (rc <= 0)
			return st_error_set(err, ST_ERR_INTERNAL, "cannot format M110");
		k += rc;
		buf[k++] = '\n';
		rc = gcode_format_numbered(buf + k, sizeof(buf) - (size_t)k - 2, 1, "M115");
		if (rc <= 0)
			return st_error_set(err, ST_ERR_INTERNAL, "cannot format M115");
		k += rc;
		buf[k++] = '\n';
		trace(m, ">", buf + 1, (size_t)k - 1);
		if ((rc = marlin_write(m, buf, (size_t)k, err)))
			return rc;
		/* Answer: ok (M110), FIRMWARE_NAME, Cap lines, ok (M115). */
		bool fw = false, done = false;
		double until = mono_s() + m->o.retry_ms / 1000.0;
		if (until > end)
			until = end;
		while (!done && mono_s() < until) {
			double left = until - mono_s();
			char b[1024];
			struct st_error e = {0};
			int n = xport_read(m->x, b, sizeof(b), (int)(left * 1000.0) + 1, &e);
			if (n < 0)
				return st_error_set(err, ST_ERR_IO, "%s: %s", xport_describe(m->x),
						    e.msg);
			double now = mono_s();
			if (n > 0)
				m->t_rx = now;
			for (int i = 0; i < n && !done; i++) {
				char c = b[i];
				if (c != '\n' && c != '\r') {
					if (m->rx_len < MARLIN_RX_MAX)
						m->rx[m->rx_len++] = c;
					continue;
				}
				if (!m->rx_len)
					continue;
				struct marlin_reply r;
				char text[MARLIN_RX_MAX + 1];
				size_t tl = m->rx_len;
				memcpy(text, m->rx, tl);
				text[tl] = '\0';
				m->rx_len = 0;
				trace(m, "<", text, tl);
				enum marlin_reply_kind kind =
					marlin_parse_reply(text, tl, &r, &m->st, &m->caps);
				if (kind == MARLIN_REPLY_FIRMWARE) {
					fw = true;
				} else if (kind == MARLIN_REPLY_OK) {
					if (r.has_n || r.has_b)
						m->caps.advanced_ok = true;
					if (r.has_b && r.b < 4096 &&
					    (unsigned)r.b + 1 > m->bufsize_learnt)
						m->bufsize_learnt = (unsigned)r.b + 1;
					done = fw;
				} else if (kind == MARLIN_REPLY_FATAL) {
					return st_error_set(err, ST_ERR_INTERNAL,
							    "the printer on %s reports a fatal error: "
							    "\"%.100s\"; fix it and reset the printer",
							    xport_describe(m->x), text);
				} else if (kind == MARLIN_REPLY_RESEND) {
					until = now; /* out of step: try again */
				}
				/* "start" may be an old banner still in the pipe:
				 * let the attempt be answered or time out. */
			}
		}
		if (!done)
			continue;
		/* Answers to an earlier attempt may follow; they must not count
		 * as acks, and if one of them reset the line numbers (an M110
		 * read after our M115), start over. */
		if (attempt > 0) {
			uint64_t seen = m->st.resend_requests;
			if ((rc = marlin_wait_quiet(m, 200, m->o.retry_ms, err)))
				return rc;
			if (m->st.resend_requests != seen)
				continue;
		}
		m->st.resend_requests = 0;
		m->skip_ok = 0;
		m->st.stray_oks = 0;
		m->n_next = m->n_send = 2;
		m->n_acked = m->n_max_sent = m->last_tx_n = 1;
		entry(m, 0)->n = 0;
		entry(m, 1)->n = 0; /* not resendable: connect lines are not kept */
		m->connected = true;
		m->t_rx = m->t_progress = mono_s();
		if (m->caps.autoreport_temp && m->o.autoreport_s > 0) {
			char cmd[32];
			snprintf(cmd, sizeof(cmd), "M155 S%d", m->o.autoreport_s);
			marlin_push_prio(m, cmd);
			while (!marlin_idle(m)) {
				if (mono_s() > end)
					return st_error_set(err, ST_ERR_IO,
							    "the printer on %s did not acknowledge "
							    "M155 within %d s",
							    xport_describe(m->x),
							    m->o.connect_timeout_ms / 1000);
				if ((rc = marlin_step(m, 50, err)))
					return rc;
			}
		}
		return 0;
	}
	return st_error_set(err, ST_ERR_IO,
			    "no answer from a Marlin printer on %s within %d s; check that it is "
			    "switched on and that the baud rate matches its firmware",
			    xport_describe(m->x), m->o.connect_timeout_ms / 1000);
}

int marlin_stream_file(struct marlin *m, struct gcode_reader *r, const char *name,
		       marlin_progress_fn progress, void *ctx, volatile sig_atomic_t *stop,
		       struct st_error *err)
{
	struct gcode_line g;
	long layer = -1;
	double z = NAN, t_cb = 0;
	bool eof = false;
	int rc;

	if (!name)
		name = "<input>";
	for (;;) {
		if (stop && *stop)
			marlin_request_cancel(m);
		while (!eof && marlin_can_submit(m) && !m->dead && !m->cancelled) {
			rc = gcode_reader_next(r, 0, &g, err);
			if (rc == 0) {
				eof = true;
				break;
			}
			if (rc < 0)
				return rc;
			long l;
			double zz;
			enum gcode_layer_mark mark = gcode_layer_comment(&g, &l, &zz);
			if (mark == GCODE_LAYER_START) {
				layer = l >= 0 ? l : layer + 1;
				if (!isnan(zz))
					z = zz;
			} else if (mark == GCODE_LAYER_Z) {
				z = zz;
			}
			if (g.kind == GCODE_KIND_HOST_ONLY || g.text_len == 0)
				continue;
			uint64_t src = gcode_reader_line(r);
			if (g.text_len > MARLIN_CMD_MAX)
				return st_error_set(err, ST_ERR_ARG,
						    "%s: line %llu: the command is %zu bytes long; "
						    "Marlin takes at most %d (shorten it)",
						    name, (unsigned long long)src, g.text_len,
						    MARLIN_CMD_MAX);
			rc = marlin_submit(m, g.text, src, layer, z, err);
			if (rc < 0)
				return rc;
		}
		if (eof && marlin_idle(m))
			break;
		if ((rc = marlin_step(m, 50, err)))
			return rc;
		double now = mono_s();
		if (progress && now - t_cb >= 0.2) {
			t_cb = now;
			progress(ctx, &m->st, gcode_reader_bytes(r));
		}
	}
	if (progress)
		progress(ctx, &m->st, gcode_reader_bytes(r));
	return 0;
}

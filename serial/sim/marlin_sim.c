/*
 * marlin_sim.c - simulated Marlin 2.1 firmware over a pty (see marlin_sim.h).
 *
 * One thread, one poll() loop.  Bytes the host writes go "onto the wire"
 * (a staging buffer standing for the adapter and cable) and reach the RX
 * ring one byte time (10 bits / baud) after another, starting when the host
 * wrote them: an idle link banks no capacity, as a UART does not.  The
 * "firmware" takes bytes out of the ring into the current line only while
 * a command-queue slot is free, as Marlin's get_serial_commands does, so a
 * host that over-fills the ring loses bytes.  Reply lines are paced the same
 * way and reach the host when their last byte has crossed the link.
 * The executor and heaters are in marlin_sim_exec.c.
 */
#define _GNU_SOURCE /* ppoll: the link's byte times are well under 1 ms */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <stdarg.h>
#include <pthread.h>
#include <pty.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "marlin_sim_int.h"

/* Monotonic wall clock in seconds. */
static double sim_now(void)
{
	return sim_clock();
}

/* xorshift64* step: uniform double in [0, 1). */
static double sim_rand(struct sim_marlin *s)
{
	return sim_rand01(&s->rng);
}

void sim_marlin_options_init(struct sim_marlin_options *o)
{
	memset(o, 0, sizeof(*o));
	o->rx_buffer = 128;
	o->bufsize = 4;
	o->speedup = 1.0;
	o->baud = 115200;
	o->boot_s = 1.5;
}

/* Append one reply line (newline added) to the TX buffer. */
void msim_send(struct sim_marlin *s, const char *text)
{
	size_t n = strlen(text);
	if (s->unplugged)
		return;
	if (s->o.reply_loss_p > 0 && !strncmp(text, "ok", 2) && sim_rand(s) < s->o.reply_loss_p)
		return;
	if (s->tx_len + n + 1 > SIM_TX_MAX)
		return; /* host not reading at all: drop, as a UART would block */
	char *p = st_grow(s->tx, &s->tx_cap, s->tx_len + n + 1, 1);
	if (!p)
		return;
	s->tx = p;
	struct sim_txmark *m = st_grow(s->marks, &s->marks_cap, s->marks_n + 1, sizeof(*m));
	if (!m)
		return;
	s->marks = m;
	memcpy(s->tx + s->tx_len, text, n);
	s->tx[s->tx_len + n] = '\n';
	s->tx_len += n + 1;
	s->marks[s->marks_n].end = s->tx_len;
	s->marks[s->marks_n].ready = sim_now() + s->o.latency_ms / 1000.0;
	s->marks_n++;
}

/* printf-style msim_send. */
void msim_sendf(struct sim_marlin *s, const char *fmt, ...)
{
	char buf[512];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(buf, sizeof(buf), fmt, ap);
	va_end(ap);
	msim_send(s, buf);
}

/* Send the boot banner and ignore input for the boot time. */
void msim_boot(struct sim_marlin *s, double now)
{
	msim_send(s, "start");
	msim_send(s, "echo:Marlin 2.1.2 (Stratum simulator)");
	msim_send(s, "echo: Last Updated: 2023-03-20 | Author: (Stratum, sim)");
	msim_send(s, "echo: Compiled: Stratum simulator");
	msim_sendf(s, "echo: Free Memory: 2797  PlannerBufferBytes: %u", SIM_PLANNER * 77u);
	msim_send(s, "echo:Hardcoded Default Settings Loaded");
	s->boot_until = now + s->o.boot_s / s->o.speedup;
}

/* Forget everything volatile, as a board reset does. */
void msim_reset_state(struct sim_marlin *s)
{
	s->rx_len = 0;
	s->line_len = 0;
	s->line_comment = false;
	s->ep_len = 0;
	s->ep_over = false;
	s->q_head = s->q_count = 0;
	s->last_n = 0;
	s->planner_n = 0;
	memset(s->pos, 0, sizeof(s->pos));
	s->rel_xyz = s->rel_e = false;
	s->feed = 25.0;
	s->blk = SIM_BLK_NONE;
	s->wait_cancel = false;
	s->heater[0].target = s->heater[1].target = 0;
	s->autoreport_s = 0;
}

static int sim_thread_run(void *sim, volatile sig_atomic_t *stop);

int sim_marlin_new(const struct sim_marlin_options *opts, struct sim_marlin **out,
		   struct st_error *err)
{
	struct sim_marlin *s;
	int rc;

	if (out)
		*out = NULL;
	if (!out)
		return st_error_set(err, ST_ERR_ARG, "sim_marlin_new: out is NULL");
	s = calloc(1, sizeof(*s));
	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "simulated Marlin: out of memory");
	if (opts)
		s->o = *opts;
	else
		sim_marlin_options_init(&s->o);
	s->master = s->slave = -1;
	if (s->o.rx_buffer < 8 || s->o.rx_buffer > 65536 || s->o.bufsize < 1 ||
	    s->o.bufsize > 1024 || !(s->o.speedup > 0) || s->o.speedup > 1e6 ||
	    s->o.baud < 300 || s->o.baud > 100000000 || !(s->o.corrupt_p >= 0) ||
	    s->o.corrupt_p > 1 || !(s->o.drop_p >= 0) || s->o.drop_p > 1 ||
	    !(s->o.reply_loss_p >= 0) || s->o.reply_loss_p > 1 ||
	    !(s->o.boot_s >= 0) || !(s->o.freeze_s >= 0) || s->o.latency_ms > 60000) {
		rc = st_error_set(err, ST_ERR_ARG,
				  "simulated Marlin: an option is out of range (rx buffer 8-65536 "
				  "bytes, bufsize 1-1024, speedup > 0, baud 300-100000000, "
				  "probabilities 0-1, latency <= 60000 ms)");
		goto out_free;
	}
	s->rng = s->o.seed ? s->o.seed : 0x9e3779b97f4a7c15ull;
	s->rx = malloc(s->o.rx_buffer);
	s->q = calloc(s->o.bufsize, sizeof(*s->q));
	if (!s->rx || !s->q) {
		rc = st_error_set(err, ST_ERR_NOMEM, "simulated Marlin: out of memory");
		goto out_free;
	}
	if (sim_pty_open(&s->master, &s->slave, s->slave_path) < 0) {
		rc = st_error_set(err, ST_ERR_IO, "simulated Marlin: cannot open a pseudo-terminal: %s",
				  strerror(errno));
		goto out_free;
	}
	if (s->o.log_path) {
		s->log = fopen(s->o.log_path, "w");
		if (!s->log) {
			rc = st_error_set(err, ST_ERR_IO,
					  "simulated Marlin: cannot create log file '%s': %s",
					  s->o.log_path, strerror(errno));
			goto out_close_pty;
		}
		s->own_log = true;
	} else {
		s->log = s->o.log_fp;
	}
	s->o.log_path = NULL;
	s->heater[0] = (struct sim_heater){SIM_AMBIENT, 0, 2.0, 1.0};
	s->heater[1] = (struct sim_heater){SIM_AMBIENT, 0, 0.5, 0.3};
	msim_reset_state(s);
	s->t_prev = sim_now();
	msim_boot(s, s->t_prev);
	s->th.run = sim_thread_run;
	s->th.sim = s;
	*out = s;
	return 0;

out_close_pty:
	close(s->master);
	close(s->slave);
out_free:
	free(s->rx);
	free(s->q);
	free(s);
	return rc;
}

const char *sim_marlin_slave_path(const struct sim_marlin *sim)
{
	return sim->slave_path;
}

bool sim_marlin_unplugged(const struct sim_marlin *sim)
{
	return sim->unplugged;
}

bool sim_marlin_halted(const struct sim_marlin *sim)
{
	return sim->halted;
}

bool sim_marlin_frozen(const struct sim_marlin *sim)
{
	return sim->frozen;
}

long sim_marlin_answered_line(const struct sim_marlin *sim)
{
	return atomic_load(&sim->answered_n);
}

double sim_marlin_machine_s(const struct sim_marlin *sim)
{
	return (double)atomic_load(&sim->machine_us) / 1e6;
}

uint64_t sim_marlin_dropped_bytes(const struct sim_marlin *sim)
{
	return sim->dropped;
}

/* Free planner blocks at time now (finished blocks are retired). */
size_t msim_planner_free(struct sim_marlin *s, double now)
{
	size_t k = 0;
	for (size_t i = 0; i < s->planner_n; i++)
		if (s->planner_end[i] > now)
			s->planner_end[k++] = s->planner_end[i];
	s->planner_n = k;
	return SIM_PLANNER - k;
}

/* Seconds one byte takes on the link (start, 8 data and stop bits). */
static double sim_byte_s(const struct sim_marlin *s)
{
	return 10.0 / s->o.baud;
}

/* "ok", or Marlin's ADVANCED_OK form. */
void msim_ok(struct sim_marlin *s, const struct sim_cmd *c, double now)
{
	if (!s->o.advanced_ok) {
		msim_send(s, "ok");
		return;
	}
	size_t pf = msim_planner_free(s, now);
	size_t bf = s->o.bufsize - s->q_count;
	if (c && c->has_n)
		msim_sendf(s, "ok N%ld P%zu B%zu", c->n, pf, bf);
	else
		msim_sendf(s, "ok P%zu B%zu", pf, bf);
}

/*
 * Marlin 2.1's gcode_line_error + flush_and_request_resend: the error, the
 * RX ring read empty ("clear out the RX buffer": lines behind the bad one
 * that are already in the ring are lost without a word; keep_rx_on_error
 * keeps them, to be answered one by one), "Resend:" and a plain "ok"
 * (STR_OK, never the ADVANCED_OK form).  The command queue is kept: the
 * lines before the bad one run and earn their oks, so the firmware is
 * ahead of what the host has seen acknowledged.
 */
static void sim_line_error(struct sim_marlin *s, const char *what)
{
	s->rx_flush = !s->o.keep_rx_on_error;
	msim_sendf(s, "Error:%s, Last Line: %ld", what, s->last_n);
	msim_sendf(s, "Resend: %ld", s->last_n + 1);
	msim_send(s, "ok");
}

/* Temperature report as print_heater_states writes it (leading space). */
void msim_temp_string(const struct sim_marlin *s, char *buf, size_t cap)
{
	snprintf(buf, cap, " T:%.2f /%.2f B:%.2f /%.2f @:0 B@:0", s->heater[0].temp,
		 s->heater[0].target, s->heater[1].temp, s->heater[1].target);
}

/* Read a decimal number like strtol, without locale or errno games. */
static long sim_read_long(const char *p, const char *end)
{
	long v = 0;
	bool neg = false;
	if (p < end && (*p == '-' || *p == '+'))
		neg = *p++ == '-';
	while (p < end && *p >= '0' && *p <= '9' && v < 100000000000L)
		v = v * 10 + (*p++ - '0');
	return neg ? -v : v;
}

/* Check one complete line the way queue.cpp does and queue it. */
static void sim_accept_line(struct sim_marlin *s)
{
	char *cmd = s->line;
	size_t len = s->line_len;
	struct sim_cmd *c;
	bool has_n = false;
	long n = 0;

	while (len && (cmd[len - 1] == ' ' || cmd[len - 1] == '\t'))
		len--;
	while (len && (*cmd == ' ' || *cmd == '\t')) {
		cmd++;
		len--;
	}
	if (!len)
		return;
	cmd[len] = '\0';
	char *star = strrchr(cmd, '*');
	if (*cmd == 'N') {
		const char *npos = cmd;
		char *m110 = strstr(cmd, "M110");
		if (m110) {
			char *n2 = strchr(m110 + 4, 'N');
			if (n2)
				npos = n2;
		}
		n = sim_read_long(npos + 1, cmd + len);
		if (s->o.spoil_number_at > 0 && n == s->o.spoil_number_at && n == s->last_n + 1 &&
		    !s->number_spoilt) {
			s->number_spoilt = true;
			n = s->last_n;
		}
		if (n != s->last_n + 1 && !m110) {
			/* A duplicate sent before the host saw our Resend: Marlin
			 * 2.1 drops last-1 and last silently (no error, no ok). */
			if (n == s->last_n || n == s->last_n - 1)
				return;
			sim_line_error(s, "Line Number is not Last Line Number+1");
			return;
		}
		if (!star) {
			sim_line_error(s, "No Checksum with line number");
			return;
		}
		long want = sim_read_long(star + 1, cmd + len);
		if (gcode_checksum(cmd, (size_t)(star - cmd)) != want) {
			sim_line_error(s, "checksum mismatch");
			return;
		}
		s->last_n = n;
		has_n = true;
		n = sim_read_long(cmd + 1, cmd + len);
	} else if (star) {
		sim_line_error(s, "No Line Number with checksum");
		return;
	}

	c = &s->q[(s->q_head + s->q_count) % s->o.bufsize];
	memset(c, 0, sizeof(*c));
	c->has_n = has_n;
	c->n = n;
	{
		/* the command text without N prefix and checksum, for messages */
		const char *p = cmd, *e = star ? star : cmd + len;
		if (*p == 'N') {
			p++;
			while (p < e && ((*p >= '0' && *p <= '9') || *p == '-'))
				p++;
			while (p < e && *p == ' ')
				p++;
		}
		size_t k = (size_t)(e - p);
		while (k && p[k - 1] == ' ')
			k--;
		memcpy(c->raw, p, k);
		c->raw[k] = '\0';
	}
	/* Parse the text without N and checksum, as Marlin's parser skips
	 * "N[-]digits": printcore numbers its M110 line N-1, which our
	 * parser (rightly, for files) refuses as a line number. */
	c->parsed = gcode_parse(c->raw, strlen(c->raw), 0, &c->g, NULL) == 0;
	s->q_count++;
}

/* Marlin's emergency parser: act on M108/M112/M410 as the line arrives. */
static void sim_emergency(struct sim_marlin *s, double now)
{
	const char *p = s->ep, *e = s->ep + s->ep_len;
	(void)now;
	if (s->ep_over)
		return;
	while (p < e && *p == ' ')
		p++;
	if (p < e && *p == 'N') {
		p++;
		while (p < e && *p >= '0' && *p <= '9')
			p++;
		while (p < e && *p == ' ')
			p++;
	}
	if (e - p < 4 || p[0] != 'M')
		return;
	if (e - p > 4 && p[4] != ' ' && p[4] != '*')
		return;
	if (!memcmp(p, "M112", 4)) {
		s->halted = true;
		s->heater[0].target = s->heater[1].target = 0;
		s->planner_n = 0;
		msim_send(s, "Error:Printer halted. kill() called!");
	} else if (!memcmp(p, "M108", 4)) {
		s->wait_cancel = true;
	} else if (!memcmp(p, "M410", 4)) {
		s->planner_n = 0;
	}
}

/* One byte off the wire into the RX ring (faults, emergency parser). */
static void sim_rx_byte(struct sim_marlin *s, uint8_t b, double now)
{
	if (s->o.drop_p > 0 && sim_rand(s) < s->o.drop_p) {
		s->dropped++;
		return;
	}
	if (s->o.corrupt_p > 0 && sim_rand(s) < s->o.corrupt_p)
		b ^= (uint8_t)(1u << (unsigned)(sim_rand(s) * 8));
	if (now < s->boot_until || s->halted)
		return;
	if (b == '\n' || b == '\r') {
		sim_emergency(s, now);
		s->ep_len = 0;
		s->ep_over = false;
	} else if (s->ep_len < sizeof(s->ep)) {
		s->ep[s->ep_len++] = (char)b;
	} else {
		s->ep_over = true;
	}
	if (s->halted)
		return;
	if (s->rx_len >= s->o.rx_buffer) {
		s->dropped++; /* ring full: the byte is lost, as on a real board */
		return;
	}
	s->rx[s->rx_len++] = b;
}

/* Is the newline ending the line so far one that lose_newline_at loses? */
static bool sim_newline_lost(struct sim_marlin *s)
{
	if (!s->line_len || s->line[0] != 'N')
		return false;
	long n = sim_read_long(s->line + 1, s->line + s->line_len);
	for (size_t k = 0; k < SIM_MARLIN_CUTS; k++)
		if (s->o.lose_newline_at[k] > 0 && s->o.lose_newline_at[k] == n &&
		    !s->newline_lost[k]) {
			s->newline_lost[k] = true;
			return true;
		}
	return false;
}

/* Is the line so far the one whose '*' star_to_newline_at turns into a
 * newline?  Then it ends there, and what followed the '*' goes to tail. */
static bool sim_star_cut(struct sim_marlin *s, char *tail, size_t *tail_len)
{
	if (s->star_cut || s->o.star_to_newline_at <= 0 || !s->line_len || s->line[0] != 'N' ||
	    sim_read_long(s->line + 1, s->line + s->line_len) != s->o.star_to_newline_at)
		return false;
	char *star = memchr(s->line, '*', s->line_len);
	if (!star)
		return false;
	s->star_cut = true;
	*tail_len = s->line_len - (size_t)(star + 1 - s->line);
	memcpy(tail, star + 1, *tail_len);
	s->line_len = (size_t)(star - s->line);
	return true;
}

/* Move bytes from the RX ring into lines while a queue slot is free and no
 * command blocks: Marlin reads serial input in its main loop, between
 * commands, not in the idle() a waiting command spins in. */
void msim_serial_commands(struct sim_marlin *s)
{
	size_t i = 0;
	if (s->blk != SIM_BLK_NONE || s->frozen)
		return;
	while (i < s->rx_len && s->q_count < s->o.bufsize && !s->halted) {
		char ch = (char)s->rx[i++];
		if (ch == '\n' || ch == '\r') {
			char tail[SIM_MAX_CMD];
			size_t tail_len = 0;
			if (!s->line_comment && sim_newline_lost(s))
				continue;
			if (!s->line_comment && sim_star_cut(s, tail, &tail_len)) {
				/* the line errs; the digits after it, a byte time
				 * or more behind, come after the error emptied the
				 * ring, and end as a line of their own */
				sim_accept_line(s);
				memcpy(s->line, tail, tail_len);
				s->line_len = tail_len;
			}
			if (!s->line_comment || s->line_len)
				sim_accept_line(s);
			s->line_len = 0;
			s->line_comment = false;
			if (s->rx_flush) {
				s->rx_flush = false;
				i = s->rx_len;
			}
			continue;
		}
		if (ch == ';')
			s->line_comment = true;
		if (s->line_comment)
			continue;
		if (s->line_len < SIM_MAX_CMD - 1)
			s->line[s->line_len++] = ch;
	}
	memmove(s->rx, s->rx + i, s->rx_len - i);
	s->rx_len -= i;
}

/* Write one execution-log line. */
static int sim_flush_tx(struct sim_marlin *s, double now, double *wake)
{
	const double byte_s = sim_byte_s(s);
	size_t limit = s->tx_off, k = 0;
	double t = s->out_t;
	for (; k < s->marks_n; k++) {
		double start = s->marks[k].ready > t ? s->marks[k].ready : t;
		double end = start + (double)(s->marks[k].end - limit) * byte_s;
		if (end > now) {
			if (end < *wake)
				*wake = end;
			break;
		}
		t = end;
		limit = s->marks[k].end;
	}
	if (limit > s->tx_off) {
		ssize_t w = write(s->master, s->tx + s->tx_off, limit - s->tx_off);
		if (w < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
			return ST_ERR_IO;
		if (w > 0) {
			s->tx_off += (size_t)w;
			s->out_t = t; /* a short write (host not reading) keeps the rest */
		}
	}
	k = 0;
	while (k < s->marks_n && s->marks[k].end <= s->tx_off)
		k++;
	if (k) {
		memmove(s->marks, s->marks + k, (s->marks_n - k) * sizeof(*s->marks));
		s->marks_n -= k;
	}
	if (s->tx_off == s->tx_len) {
		s->tx_off = s->tx_len = 0;
		s->marks_n = 0;
	} else if (s->tx_off > 65536) {
		memmove(s->tx, s->tx + s->tx_off, s->tx_len - s->tx_off);
		for (size_t i = 0; i < s->marks_n; i++)
			s->marks[i].end -= s->tx_off;
		s->tx_len -= s->tx_off;
		s->tx_off = 0;
	}
	return 0;
}

/* Hand the bytes on the wire that have arrived by now to the RX ring, each
 * one byte time after the one before; lower *wake to when the next line
 * end (or the last staged byte) will have arrived. */
static void sim_wire_deliver(struct sim_marlin *s, double now, double *wake)
{
	const double byte_s = sim_byte_s(s);
	size_t i = 0, j;
	while (i < s->wire_len && s->in_t + byte_s <= now) {
		s->in_t += byte_s;
		sim_rx_byte(s, s->wire[i++], s->in_t);
		/* The firmware runs short commands and empties the ring far
		 * faster than bytes arrive, so a late loop (a loaded test
		 * machine) delivering a batch must not overflow a ring the
		 * real board would have drained: run what was due by then. */
		if (s->rx_len >= s->o.rx_buffer) {
			msim_execute(s, s->in_t);
			msim_serial_commands(s);
		}
	}
	memmove(s->wire, s->wire + i, s->wire_len - i);
	s->wire_len -= i;
	for (j = 0; j < s->wire_len; j++)
		if (s->wire[j] == '\n' || s->wire[j] == '\r')
			break;
	if (s->wire_len) {
		double due = s->in_t + (double)(j < s->wire_len ? j + 1 : s->wire_len) * byte_s;
		if (due < *wake)
			*wake = due;
	}
}

int sim_marlin_run(struct sim_marlin *s, volatile sig_atomic_t *stop, struct st_error *err)
{
	if (!stop && s->o.unplug_at_line <= 0)
		return st_error_set(err, ST_ERR_ARG, "sim_marlin_run: no stop flag");
	s->t_prev = sim_now();
	while (!(stop && *stop) && !s->unplugged) {
		double now = sim_now(), dt = now - s->t_prev;
		s->t_prev = now;
		bool busy = s->tx_len > s->tx_off || s->q_count || s->rx_len || s->wire_len ||
			    s->planner_n || s->blk != SIM_BLK_NONE ||
			    s->heater[0].temp != SIM_AMBIENT || s->heater[1].temp != SIM_AMBIENT ||
			    s->autoreport_s > 0;
		/* motion, heaters and timers are checked every millisecond while
		 * anything runs; link events wake the loop exactly */
		double wake = now + (busy ? 0.001 : 0.020);

		if (s->frozen && now >= s->thaw_at) {
			/* The stall is over.  What the host wrote meanwhile is all
			 * there (a stalled board's UART, or a stopped process's
			 * pty, kept it) and is read before the next command runs,
			 * as Marlin's loop reads its ring before it runs one. */
			double arrived = 0;
			s->frozen = false;
			if (sim_wait_input(s->master, true, now, s->wire, &s->wire_len,
					   sizeof(s->wire), &arrived))
				return st_error_set(err, ST_ERR_IO, "simulated Marlin: poll failed: %s",
						    strerror(errno));
			s->in_t = now - (double)s->wire_len * sim_byte_s(s);
		}
		if (s->frozen) {
			/* a hung board: the UART still fills the kernel's buffer
			 * but nothing is read, run or answered */
			size_t none = 0;
			uint8_t sink[1];
			if (sim_wait_input(s->master, false, now + 0.020, sink, &none, 0, NULL))
				return st_error_set(err, ST_ERR_IO, "simulated Marlin: poll failed: %s",
						    strerror(errno));
			continue;
		}
		sim_wire_deliver(s, now, &wake);
		msim_physics(s, now, dt);
		msim_serial_commands(s);
		msim_execute(s, now);
		msim_serial_commands(s);
		if (s->unplugged)
			break;
		if (sim_flush_tx(s, now, &wake))
			return st_error_set(err, ST_ERR_IO, "simulated Marlin: writing to the pty failed: %s",
					    strerror(errno));

		double arrived = 0;
		size_t before = s->wire_len;
		if (sim_wait_input(s->master, true, wake, s->wire, &s->wire_len,
				   sizeof(s->wire), &arrived))
			return st_error_set(err, ST_ERR_IO, "simulated Marlin: poll failed: %s",
					    strerror(errno));
		if (s->wire_len > before && !before && s->in_t < arrived)
			s->in_t = arrived; /* idle link: these bytes start now */
	}
	if (s->unplugged)
		sim_pty_close(&s->master, &s->slave);
	return 0;
}

/* The event loop as sim_thread runs it. */
static int sim_thread_run(void *sim, volatile sig_atomic_t *stop)
{
	return sim_marlin_run(sim, stop, NULL);
}

int sim_marlin_start_thread(struct sim_marlin *s, struct st_error *err)
{
	return sim_thread_start(&s->th, "simulated Marlin", err);
}

int sim_marlin_stop(struct sim_marlin *s)
{
	return sim_thread_stop(&s->th);
}

void sim_marlin_free(struct sim_marlin *s)
{
	if (!s)
		return;
	sim_marlin_stop(s);
	sim_pty_close(&s->master, &s->slave);
	if (s->own_log && s->log)
		fclose(s->log);
	free(s->rx);
	free(s->q);
	free(s->tx);
	free(s->marks);
	free(s);
}

/*
 * sailfish_sim.c - simulated Sailfish firmware over a pty (see
 * sailfish_sim.h).
 *
 * One thread, one poll() loop, built like marlin_sim.c: bytes the host
 * writes wait "on the wire" and reach the packet reader one byte time
 * (10 bits / baud) apart; replies reach the host when their last byte has
 * crossed.  The packet reader is the firmware's byte-wise state machine,
 * fed as each byte arrives (the UART interrupt); the "host slice" that
 * answers a finished or failed packet runs only while no reply is going
 * out, as runHostSlice returns early while out.isSending().  The command
 * processor and heaters are in sailfish_sim_exec.c.
 */
#define _GNU_SOURCE /* ppoll */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <pthread.h>
#include <pty.h>
#include <stdlib.h>
#include <string.h>
#include <termios.h>
#include <time.h>
#include <unistd.h>

#include "sailfish_sim_int.h"

static double sf_now(void)
{
	return sim_clock();
}

/* xorshift64*: uniform double in [0, 1). */
static double sf_rand(struct sim_sailfish *s)
{
	return sim_rand01(&s->rng);
}

static void sf_wr16(uint8_t *p, uint16_t v)
{
	p[0] = (uint8_t)v;
	p[1] = (uint8_t)(v >> 8);
}

static void sf_wr32(uint8_t *p, uint32_t v)
{
	for (int i = 0; i < 4; i++)
		p[i] = (uint8_t)(v >> (8 * i));
}

void sim_sailfish_options_init(struct sim_sailfish_options *o)
{
	memset(o, 0, sizeof(*o));
	o->buffer_size = S3G_BUFFER_SIZE;
	o->speedup = 1.0;
	o->baud = 115200;
	o->boot_s = 2.0;
}

/* Reset the packet reader (Packet::reset). */
static void sf_in_reset(struct sim_sailfish *s)
{
	s->ps = SF_PS_START;
	s->perr = SF_E_NONE;
	s->plen = s->pexp = s->pcrc = 0;
}

/* Packet::error: reset, then remember why. */
static void sf_in_error(struct sim_sailfish *s, int e)
{
	sf_in_reset(s);
	s->perr = e;
}

/* Heaters off, planner and command buffer empty: what Motherboard and
 * command resets leave. */
static void sf_machine_reset(struct sim_sailfish *s)
{
	s->cb_head = s->cb_len = 0;
	s->planner_n = 0;
	s->mode = SF_READY;
	s->paused = false;
	for (int i = 0; i < 3; i++)
		s->heater[i].target = 0;
}

/* Power-on state: everything volatile forgotten, build state "none". */
void sfsim_hard_reset(struct sim_sailfish *s, double now)
{
	sf_machine_reset(s);
	sf_in_reset(s);
	s->timer_on = false;
	s->tx_len = s->tx_off = 0;
	s->soft_reset_pending = false;
	memset(s->pos, 0, sizeof(s->pos));
	s->tool = 0;
	s->build_state = S3G_BUILD_NONE;
	s->line = s->last_line = 0;
	s->build_name[0] = '\0';
	s->boot_until = now + s->o.boot_s / s->o.speedup;
	s->resets++;
}

static int sf_thread_run(void *sim, volatile sig_atomic_t *stop);

int sim_sailfish_new(const struct sim_sailfish_options *opts, struct sim_sailfish **out,
		     struct st_error *err)
{
	struct sim_sailfish *s;
	int rc;

	if (out)
		*out = NULL;
	if (!out)
		return st_error_set(err, ST_ERR_ARG, "sim_sailfish_new: out is NULL");
	s = calloc(1, sizeof(*s));
	if (!s)
		return st_error_set(err, ST_ERR_NOMEM, "simulated Sailfish: out of memory");
	if (opts)
		s->o = *opts;
	else
		sim_sailfish_options_init(&s->o);
	s->master = s->slave = -1;
	if (s->o.buffer_size < 64 || s->o.buffer_size > 65536 || !(s->o.speedup > 0) ||
	    s->o.speedup > 1e6 || s->o.baud < 300 || s->o.baud > 100000000 ||
	    !(s->o.corrupt_p >= 0) || s->o.corrupt_p > 1 || !(s->o.drop_p >= 0) ||
	    s->o.drop_p > 1 || !(s->o.reply_corrupt_p >= 0) || s->o.reply_corrupt_p > 1 ||
	    !(s->o.boot_s >= 0) || s->o.latency_ms > 60000) {
		rc = st_error_set(err, ST_ERR_ARG,
				  "simulated Sailfish: an option is out of range (buffer 64-65536 "
				  "bytes, speedup > 0, baud 300-100000000, probabilities 0-1, "
				  "latency <= 60000 ms)");
		goto out_free;
	}
	s->rng = s->o.seed ? s->o.seed : 0x9e3779b97f4a7c15ull;
	s->cb = malloc(s->o.buffer_size);
	if (!s->cb) {
		rc = st_error_set(err, ST_ERR_NOMEM, "simulated Sailfish: out of memory");
		goto out_free;
	}
	if (sim_pty_open(&s->master, &s->slave, s->slave_path) < 0) {
		rc = st_error_set(err, ST_ERR_IO,
				  "simulated Sailfish: cannot open a pseudo-terminal: %s",
				  strerror(errno));
		goto out_free;
	}
	if (s->o.log_path) {
		s->log = fopen(s->o.log_path, "w");
		if (!s->log) {
			rc = st_error_set(err, ST_ERR_IO,
					  "simulated Sailfish: cannot create log file '%s': %s",
					  s->o.log_path, strerror(errno));
			goto out_close_pty;
		}
		s->own_log = true;
	} else {
		s->log = s->o.log_fp;
	}
	s->o.log_path = NULL;
	s->heater[0] = (struct sf_heater){SF_AMBIENT, 0, 3.0, 1.0};
	s->heater[1] = (struct sf_heater){SF_AMBIENT, 0, 3.0, 1.0};
	s->heater[2] = (struct sf_heater){SF_AMBIENT, 0, 0.8, 0.3};
	sfsim_hard_reset(s, sf_now());
	s->resets = 0;
	s->boot_until = 0; /* powered on before the host opened the port */
	s->th.run = sf_thread_run;
	s->th.sim = s;
	*out = s;
	return 0;

out_close_pty:
	close(s->master);
	close(s->slave);
out_free:
	free(s->cb);
	free(s);
	return rc;
}

const char *sim_sailfish_slave_path(const struct sim_sailfish *sim)
{
	return sim->slave_path;
}

bool sim_sailfish_unplugged(const struct sim_sailfish *sim)
{
	return sim->unplugged;
}

uint64_t sim_sailfish_executed(const struct sim_sailfish *sim)
{
	return sim->seq;
}

double sim_sailfish_machine_s(const struct sim_sailfish *sim)
{
	return (double)atomic_load(&sim->machine_us) / 1e6;
}

uint64_t sim_sailfish_undetected(const struct sim_sailfish *sim)
{
	return sim->undetected;
}

unsigned sim_sailfish_resets(const struct sim_sailfish *sim)
{
	return sim->resets;
}

/* Queue one reply packet (payload[0] is the response code). */
static void sf_reply(struct sim_sailfish *s, const uint8_t *payload, size_t n, double now)
{
	uint8_t pkt[S3G_MAX_PACKET];
	int len = s3g_encode(payload, n, pkt, sizeof(pkt), NULL);
	if (len < 0 || s->unplugged)
		return;
	if (s->tx_len + (size_t)len > SF_TX_MAX)
		return;
	uint8_t *tx = st_grow(s->tx, &s->tx_cap, s->tx_len + (size_t)len, 1);
	if (!tx)
		return;
	s->tx = tx;
	for (int i = 0; i < len; i++)
		if (s->o.reply_corrupt_p > 0 && sf_rand(s) < s->o.reply_corrupt_p)
			pkt[i] ^= (uint8_t)(1u << (unsigned)(sf_rand(s) * 8));
	memcpy(s->tx + s->tx_len, pkt, (size_t)len);
	s->tx_len += (size_t)len;
	s->tx_ready = now + s->o.latency_ms / 1000.0;
}

static void sf_reply_code(struct sim_sailfish *s, uint8_t code, double now)
{
	sf_reply(s, &code, 1, now);
}

/* The UART interrupt: one byte into the packet reader (InPacket). */
static void sf_rx_byte(struct sim_sailfish *s, uint8_t b, double now)
{
	bool hit = false;
	if (s->o.drop_p > 0 && sf_rand(s) < s->o.drop_p) {
		s->rx_hit = true;
		return;
	}
	if (s->o.corrupt_p > 0 && sf_rand(s) < s->o.corrupt_p) {
		b ^= (uint8_t)(1u << (unsigned)(sf_rand(s) * 8));
		hit = s->rx_hit = true;
	}
	if (now < s->boot_until)
		return;
	switch (s->ps) {
	case SF_PS_START:
		if (b == S3G_START) {
			s->ps = SF_PS_LEN;
			s->rx_hit = hit;
		} else {
			sf_in_error(s, SF_E_NOISE);
		}
		break;
	case SF_PS_LEN:
		if (b <= S3G_MAX_PAYLOAD) {
			s->pexp = b;
			s->ps = b == 0 ? SF_PS_CRC : SF_PS_PAYLOAD;
		} else {
			sf_in_error(s, SF_E_LENGTH);
		}
		break;
	case SF_PS_PAYLOAD:
		s->pcrc = s3g_crc_update(s->pcrc, b);
		s->payload[s->plen++] = b;
		if (s->plen >= s->pexp)
			s->ps = SF_PS_CRC;
		break;
	case SF_PS_CRC:
		if (s->pcrc == b) {
			s->ps = SF_PS_LAST;
			s->undetected += s->rx_hit;
			if (s->plen && (s->payload[0] & 0x80) &&
			    ++s->good_actions == s->o.crc_escape_at)
				s->payload[0] = s->o.crc_escape_code ? s->o.crc_escape_code
								    : s->payload[0] ^ 0x80;
			else if (s->plen && !(s->payload[0] & 0x80) &&
				 ++s->good_queries == s->o.query_escape_at)
				s->payload[0] = s->o.query_escape_code;
		} else {
			sf_in_error(s, SF_E_CRC);
		}
		break;
	default: /* a finished packet not yet taken: the byte is lost */
		break;
	}
}

/* Command buffer: free bytes, peek, pop. */
static size_t sf_cb_free(const struct sim_sailfish *s)
{
	return s->o.buffer_size - s->cb_len;
}

size_t sfsim_cb_peek(const struct sim_sailfish *s, uint8_t *out, size_t n)
{
	if (n > s->cb_len)
		n = s->cb_len;
	for (size_t i = 0; i < n; i++)
		out[i] = s->cb[(s->cb_head + i) % s->o.buffer_size];
	return n;
}

void sfsim_cb_pop(struct sim_sailfish *s, size_t n)
{
	s->cb_head = (s->cb_head + n) % s->o.buffer_size;
	s->cb_len -= n;
}

/* Planner blocks still running at now (finished ones retired). */
size_t sfsim_planner_used(struct sim_sailfish *s, double now)
{
	size_t k = 0;
	for (size_t i = 0; i < s->planner_n; i++)
		if (s->planner_end[i] > now)
			s->planner_end[k++] = s->planner_end[i];
	s->planner_n = k;
	return k;
}

static bool sf_is_finished(struct sim_sailfish *s, double now)
{
	return sfsim_planner_used(s, now) == 0 && s->cb_len == 0 && s->mode == SF_READY;
}

/* Answer a query packet (Host.cc processQueryPacket). */
static void sf_query(struct sim_sailfish *s, const uint8_t *p, size_t n, double now)
{
	uint8_t r[S3G_MAX_PAYLOAD] = {S3G_RC_OK};
	size_t k = 1;
	switch (p[0]) {
	case S3G_Q_VERSION:
		sf_wr16(r + 1, n >= 3 && sf_rd16(p + 1) < 39 ? 0 : SF_FW_VERSION);
		k = 3;
		break;
	case S3G_Q_INIT:
		break;
	case S3G_Q_BUFFER_FREE:
		sf_wr32(r + 1, (uint32_t)sf_cb_free(s));
		k = 5;
		break;
	case S3G_Q_CLEAR_BUFFER:
	case S3G_Q_ABORT:
	case S3G_Q_RESET:
		/* Host.cc: reset after the reply has gone out */
		s->soft_reset_pending = true;
		break;
	case S3G_Q_PAUSE:
		s->paused = !s->paused;
		if (s->build_state == S3G_BUILD_RUNNING || s->build_state == S3G_BUILD_PAUSED)
			s->build_state = s->paused ? S3G_BUILD_PAUSED : S3G_BUILD_RUNNING;
		break;
	case S3G_Q_TOOL_QUERY: {
		int t = n >= 2 && p[1] == 1 ? 1 : 0;
		struct sf_heater *h = &s->heater[t], *b = &s->heater[2];
		uint8_t cmd = n >= 3 ? p[2] : 0xFF;
		k = 3;
		switch (cmd) {
		case S3G_TQ_VERSION: sf_wr16(r + 1, SF_FW_VERSION); break;
		case S3G_TQ_TEMP: sf_wr16(r + 1, (uint16_t)(int16_t)lround(h->temp)); break;
		case S3G_TQ_TARGET: sf_wr16(r + 1, (uint16_t)(int16_t)lround(h->target)); break;
		case S3G_TQ_PLATFORM_TEMP: sf_wr16(r + 1, (uint16_t)(int16_t)lround(b->temp)); break;
		case S3G_TQ_PLATFORM_TARGET:
			sf_wr16(r + 1, (uint16_t)(int16_t)lround(b->target));
			break;
		case S3G_TQ_TOOL_READY:
			r[1] = fabs(h->temp - h->target) <= SF_READY_BAND;
			k = 2;
			break;
		case S3G_TQ_PLATFORM_READY:
			r[1] = fabs(b->temp - b->target) <= SF_READY_BAND;
			k = 2;
			break;
		default:
			k = 1;
			break;
		}
		break;
	}
	case S3G_Q_IS_FINISHED:
		r[1] = sf_is_finished(s, now);
		k = 2;
		break;
	case S3G_Q_BUILD_NAME: {
		size_t l = strlen(s->build_name);
		memcpy(r + 1, s->build_name, l + 1);
		k = l + 2;
		break;
	}
	case S3G_Q_POSITION_EXT:
		for (int i = 0; i < 5; i++)
			sf_wr32(r + 1 + 4 * i, (uint32_t)s->pos[i]);
		sf_wr16(r + 21, 0);
		k = 23;
		break;
	case S3G_Q_EXTENDED_STOP:
		if (n >= 2 && (p[1] & 1))
			s->planner_n = 0;
		if (n >= 2 && (p[1] & 2)) {
			s->cb_head = s->cb_len = 0;
			s->mode = SF_READY;
		}
		r[1] = 0;
		k = 2;
		break;
	case S3G_Q_BOARD_STATUS:
		r[1] = 0;
		k = 2;
		break;
	case S3G_Q_BUILD_STATS: {
		bool live = s->build_state == S3G_BUILD_RUNNING || s->build_state == S3G_BUILD_PAUSED;
		double secs = live ? (now - s->build_t0) * s->o.speedup : 0;
		r[1] = s->build_state;
		r[2] = (uint8_t)((long)(secs / 3600) & 0xFF);
		r[3] = (uint8_t)((long)(secs / 60) % 60);
		sf_wr32(r + 4, live ? s->line : s->last_line);
		sf_wr32(r + 8, 0);
		k = 12;
		break;
	}
	case S3G_Q_ADVANCED_VERSION:
		sf_wr16(r + 1, SF_FW_VERSION);
		sf_wr16(r + 3, 0);
		r[5] = SF_VARIANT;
		r[6] = 0;
		sf_wr16(r + 7, 0);
		k = 9;
		break;
	default:
		r[0] = S3G_RC_UNSUPPORTED;
		break;
	}
	sf_reply(s, r, k, now);
}

/* runHostSlice: answer a failed or finished packet, time out a stalled
 * one.  Runs only while no reply is on its way out. */
static void sf_host_slice(struct sim_sailfish *s, double now)
{
	if (s->tx_off < s->tx_len)
		return;
	if (s->soft_reset_pending) {
		s->soft_reset_pending = false;
		if (s->build_state == S3G_BUILD_RUNNING || s->build_state == S3G_BUILD_PAUSED) {
			s->build_state = S3G_BUILD_CANCELED;
			s->last_line = s->line;
		}
		sf_machine_reset(s);
		s->timer_on = false;
		return;
	}
	if (s->ps != SF_PS_START && s->ps != SF_PS_LAST) {
		if (!s->timer_on) {
			s->timer_on = true;
			s->timer_start = now;
		} else if (now - s->timer_start >= S3G_PACKET_TIMEOUT_MS / 1000.0) {
			sf_in_error(s, SF_E_TIMEOUT);
		}
	}
	if (s->perr != SF_E_NONE) {
		static const uint8_t code[] = {
			[SF_E_NOISE] = S3G_RC_GENERIC_ERROR, [SF_E_LENGTH] = S3G_RC_QUERY_TOO_BIG,
			[SF_E_CRC] = S3G_RC_CRC_MISMATCH, [SF_E_TIMEOUT] = S3G_RC_PACKET_TIMEOUT};
		s->timer_on = false;
		sf_reply_code(s, code[s->perr], now);
		sf_in_reset(s);
	} else if (s->ps == SF_PS_LAST) {
		s->timer_on = false;
		if (s->plen >= 1 && (s->payload[0] & 0x80)) {
			if (sf_cb_free(s) >= s->plen) {
				for (size_t i = 0; i < s->plen; i++)
					s->cb[(s->cb_head + s->cb_len + i) % s->o.buffer_size] =
						s->payload[i];
				s->cb_len += s->plen;
				sf_reply_code(s, S3G_RC_OK, now);
			} else {
				sf_reply_code(s, S3G_RC_BUFFER_OVERFLOW, now);
			}
		} else if (s->plen >= 1) {
			sf_query(s, s->payload, s->plen, now);
		} else {
			sf_reply_code(s, S3G_RC_UNSUPPORTED, now);
		}
		sf_in_reset(s);
	}
}

/* Append a move of dur simulated seconds behind the planned ones. */
static int sf_flush_tx(struct sim_sailfish *s, double now, double *wake)
{
	const double byte_s = 10.0 / s->o.baud;
	if (s->tx_off >= s->tx_len)
		return 0;
	double start = s->tx_ready > s->out_t ? s->tx_ready : s->out_t;
	size_t n = 0;
	while (s->tx_off + n < s->tx_len && start + (double)(n + 1) * byte_s <= now)
		n++;
	if (n) {
		ssize_t w = write(s->master, s->tx + s->tx_off, n);
		if (w < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)
			return ST_ERR_IO;
		if (w > 0) {
			s->tx_off += (size_t)w;
			s->out_t = start + (double)w * byte_s;
		}
	}
	if (s->tx_off >= s->tx_len) {
		s->tx_off = s->tx_len = 0;
	} else {
		double next = (s->tx_ready > s->out_t ? s->tx_ready : s->out_t) + byte_s;
		if (next < *wake)
			*wake = next;
	}
	return 0;
}

/* Hand the bytes on the wire that have arrived by now to the reader. */
static void sf_wire_deliver(struct sim_sailfish *s, double now, double *wake)
{
	const double byte_s = 10.0 / s->o.baud;
	size_t i = 0;
	while (i < s->wire_len && s->in_t + byte_s <= now) {
		s->in_t += byte_s;
		sf_rx_byte(s, s->wire[i++], s->in_t);
		/* the firmware's host slice answers within microseconds when
		 * no reply is going out: let it see this packet first */
		if ((s->ps == SF_PS_LAST || s->perr != SF_E_NONE) && s->tx_off >= s->tx_len)
			break;
	}
	memmove(s->wire, s->wire + i, s->wire_len - i);
	s->wire_len -= i;
	if (s->wire_len) {
		double due = s->in_t + byte_s;
		if (due < *wake)
			*wake = due;
	}
}

int sim_sailfish_run(struct sim_sailfish *s, volatile sig_atomic_t *stop, struct st_error *err)
{
	if (!stop && s->o.unplug_at <= 0)
		return st_error_set(err, ST_ERR_ARG, "sim_sailfish_run: no stop flag");
	s->t_prev = sf_now();
	while (!(stop && *stop) && !s->unplugged) {
		double now = sf_now(), dt = now - s->t_prev;
		s->t_prev = now;
		bool busy = s->tx_len > s->tx_off || s->cb_len || s->wire_len || s->planner_n ||
			    s->mode != SF_READY || s->ps != SF_PS_START ||
			    s->heater[0].temp != SF_AMBIENT || s->heater[1].temp != SF_AMBIENT ||
			    s->heater[2].temp != SF_AMBIENT;
		double wake = now + (busy ? 0.001 : 0.020);

		sf_wire_deliver(s, now, &wake);
		sf_host_slice(s, now);
		sfsim_physics(s, dt);
		sfsim_commands(s, now);
		if (s->unplugged)
			break;
		if (sf_flush_tx(s, now, &wake))
			return st_error_set(err, ST_ERR_IO,
					    "simulated Sailfish: writing to the pty failed: %s",
					    strerror(errno));
		if (s->tx_off >= s->tx_len && (s->ps == SF_PS_LAST || s->perr != SF_E_NONE ||
					       s->soft_reset_pending))
			wake = now; /* the host slice has work */

		double arrived = 0;
		size_t before = s->wire_len;
		if (sim_wait_input(s->master, true, wake, s->wire, &s->wire_len,
				   sizeof(s->wire), &arrived))
			return st_error_set(err, ST_ERR_IO, "simulated Sailfish: poll failed: %s",
					    strerror(errno));
		if (s->wire_len > before && !before && s->in_t < arrived)
			s->in_t = arrived; /* idle link: these bytes start now */
	}
	if (s->unplugged)
		sim_pty_close(&s->master, &s->slave);
	return 0;
}

/* The event loop as sim_thread runs it. */
static int sf_thread_run(void *sim, volatile sig_atomic_t *stop)
{
	return sim_sailfish_run(sim, stop, NULL);
}

int sim_sailfish_start_thread(struct sim_sailfish *s, struct st_error *err)
{
	return sim_thread_start(&s->th, "simulated Sailfish", err);
}

int sim_sailfish_stop(struct sim_sailfish *s)
{
	return sim_thread_stop(&s->th);
}

void sim_sailfish_free(struct sim_sailfish *s)
{
	if (!s)
		return;
	sim_sailfish_stop(s);
	sim_pty_close(&s->master, &s->slave);
	if (s->own_log && s->log)
		fclose(s->log);
	free(s->cb);
	free(s->tx);
	free(s);
}

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

#include "gcode.h"
#include "marlin_sim.h"
#include "sim_util.h"
#include "st_grow.h"

#define SIM_MAX_CMD 96		/* Marlin MAX_CMD_SIZE (bytes, NUL included) */
#define SIM_PLANNER 16		/* Marlin BLOCK_BUFFER_SIZE */
#define SIM_TX_MAX (1u << 20)	/* TX backlog cap (bytes) */
#define SIM_AMBIENT 25.0	/* room temperature (degC) */
#define SIM_ACCEL 1000.0	/* default acceleration (mm/s^2) */
#define SIM_HOME_S 5.0		/* simulated G28 duration (s) */
#define SIM_KEEPALIVE_S 2.0	/* HOST_KEEPALIVE interval (wall s) */

/* A command waiting in (or running from) the queue. */
struct sim_cmd {
	bool has_n;
	long n;
	bool parsed;		/* gcode_parse accepted it */
	struct gcode_line g;
	char raw[SIM_MAX_CMD];	/* command text, for "Unknown command" */
};

/* What the command at the queue head is waiting for. */
enum sim_block {
	SIM_BLK_NONE = 0,
	SIM_BLK_PLANNER_SLOT, /* G0/G1 with the planner full */
	SIM_BLK_SYNC_TIMED,   /* planner empty, then wait dur (G4, G28, M400) */
	SIM_BLK_HEAT,	      /* M109 / M190 */
	SIM_BLK_BUSY,	      /* busy_at_line: held for busy_s wall seconds */
};

/* A reply line in the TX buffer: ends at byte end, may go out at ready. */
struct sim_txmark {
	size_t end;
	double ready;
};

struct sim_heater {
	double temp, target;	 /* degC */
	double heat_rate, cool_rate; /* degC per simulated s */
};

struct sim_marlin {
	struct sim_marlin_options o;
	int master, slave;
	char slave_path[128];
	FILE *log;
	bool own_log;
	uint64_t rng;

	double t_prev;		/* last loop time (wall s) */
	uint8_t wire[4096];	/* bytes written by the host, still crossing the link */
	size_t wire_len;
	double in_t;		/* when the last byte delivered from wire arrived (wall s) */
	double out_t;		/* when the last reply byte written finished crossing (wall s) */
	double boot_until;	/* input ignored before this (wall s) */

	uint8_t *rx;		/* RX ring as a linear buffer */
	size_t rx_len;
	bool rx_flush;		/* a line error asks to empty the ring */
	uint64_t dropped;

	char line[SIM_MAX_CMD];	/* line being assembled from the RX ring */
	size_t line_len;
	bool line_comment;
	char ep[32];		/* emergency parser's view of the current line */
	size_t ep_len;
	bool ep_over;

	struct sim_cmd *q;	/* command queue ring */
	size_t q_head, q_count;
	long last_n;

	double planner_end[SIM_PLANNER]; /* end times of planned blocks (wall s) */
	size_t planner_n;
	double pos[4];		/* X Y Z E (mm) */
	bool rel_xyz, rel_e;
	double feed;		/* mm/s */

	enum sim_block blk;
	bool blk_synced;
	double blk_dur, blk_until;
	int blk_heater;		/* 0 hotend, 1 bed */
	bool blk_heat_both;	/* R: wait for cooling too */
	double next_temp_report, next_busy;
	bool wait_cancel;

	struct sim_heater heater[2];
	double autoreport_s, next_autoreport;

	char *tx;
	size_t tx_len, tx_off, tx_cap;
	struct sim_txmark *marks;
	size_t marks_n, marks_cap;

	bool halted, unplugged;
	bool frozen;		/* freeze_at_line ran: no byte in or out any more */
	bool number_spoilt;	/* spoil_number_at happened */
	double thaw_at;		/* when a freeze_s stall ends (sim_now) */

	struct sim_thread th;
};

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
static void sim_send(struct sim_marlin *s, const char *text)
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

/* printf-style sim_send. */
static void sim_sendf(struct sim_marlin *s, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));
static void sim_sendf(struct sim_marlin *s, const char *fmt, ...)
{
	char buf[512];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(buf, sizeof(buf), fmt, ap);
	va_end(ap);
	sim_send(s, buf);
}

/* Send the boot banner and ignore input for the boot time. */
static void sim_boot(struct sim_marlin *s, double now)
{
	sim_send(s, "start");
	sim_send(s, "echo:Marlin 2.1.2 (Stratum simulator)");
	sim_send(s, "echo: Last Updated: 2023-03-20 | Author: (Stratum, sim)");
	sim_send(s, "echo: Compiled: Stratum simulator");
	sim_sendf(s, "echo: Free Memory: 2797  PlannerBufferBytes: %u", SIM_PLANNER * 77u);
	sim_send(s, "echo:Hardcoded Default Settings Loaded");
	s->boot_until = now + s->o.boot_s / s->o.speedup;
}

/* Forget everything volatile, as a board reset does. */
static void sim_reset_state(struct sim_marlin *s)
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
	sim_reset_state(s);
	s->t_prev = sim_now();
	sim_boot(s, s->t_prev);
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

uint64_t sim_marlin_dropped_bytes(const struct sim_marlin *sim)
{
	return sim->dropped;
}

/* Free planner blocks at time now (finished blocks are retired). */
static size_t sim_planner_free(struct sim_marlin *s, double now)
{
	size_t k = 0;
	for (size_t i = 0; i < s->planner_n; i++)
		if (s->planner_end[i] > now)
			s->planner_end[k++] = s->planner_end[i];
	s->planner_n = k;
	return SIM_PLANNER - k;
}

/* "ok", or Marlin's ADVANCED_OK form. */
static void sim_ok(struct sim_marlin *s, const struct sim_cmd *c, double now)
{
	if (!s->o.advanced_ok) {
		sim_send(s, "ok");
		return;
	}
	size_t pf = sim_planner_free(s, now);
	size_t bf = s->o.bufsize - s->q_count;
	if (c && c->has_n)
		sim_sendf(s, "ok N%ld P%zu B%zu", c->n, pf, bf);
	else
		sim_sendf(s, "ok P%zu B%zu", pf, bf);
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
	sim_sendf(s, "Error:%s, Last Line: %ld", what, s->last_n);
	sim_sendf(s, "Resend: %ld", s->last_n + 1);
	sim_send(s, "ok");
}

/* Temperature report as print_heater_states writes it (leading space). */
static void sim_temp_string(const struct sim_marlin *s, char *buf, size_t cap)
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
		sim_send(s, "Error:Printer halted. kill() called!");
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

/* Move bytes from the RX ring into lines while a queue slot is free and no
 * command blocks: Marlin reads serial input in its main loop, between
 * commands, not in the idle() a waiting command spins in. */
static void sim_serial_commands(struct sim_marlin *s)
{
	size_t i = 0;
	if (s->blk != SIM_BLK_NONE || s->frozen)
		return;
	while (i < s->rx_len && s->q_count < s->o.bufsize && !s->halted) {
		char ch = (char)s->rx[i++];
		if (ch == '\n' || ch == '\r') {
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
static void sim_log(struct sim_marlin *s, const struct sim_cmd *c)
{
	if (!s->log)
		return;
	if (c->has_n)
		fprintf(s->log, "%ld %s\n", c->n, c->parsed ? c->g.text : c->raw);
	else
		fprintf(s->log, "- %s\n", c->parsed ? c->g.text : c->raw);
	fflush(s->log);
}

/* Trapezoid move time (simulated s) for distance d (mm) at speed v (mm/s). */
static double sim_move_time(double d, double v)
{
	if (d <= 0 || v <= 0)
		return 0;
	if (d >= v * v / SIM_ACCEL)
		return d / v + v / SIM_ACCEL;
	return 2.0 * sqrt(d / SIM_ACCEL);
}

/* Plan a G0/G1/G2/G3 into the planner (a free block is guaranteed). */
static void sim_plan_move(struct sim_marlin *s, const struct gcode_line *g, double now)
{
	static const char axes[4] = {'X', 'Y', 'Z', 'E'};
	double v, d2 = 0, de = 0;
	if (gcode_word_value(g, 'F', &v) && v > 0)
		s->feed = v / 60.0;
	for (int a = 0; a < 4; a++) {
		double target = s->pos[a];
		bool rel = a == 3 ? s->rel_e : s->rel_xyz;
		if (gcode_word_value(g, axes[a], &v))
			target = rel ? s->pos[a] + v : v;
		double dd = target - s->pos[a];
		if (a < 3)
			d2 += dd * dd;
		else
			de = fabs(dd);
		s->pos[a] = target;
	}
	double d = d2 > 0 ? sqrt(d2) : de;
	double dur = sim_move_time(d, s->feed) / s->o.speedup;
	if (dur <= 0)
		return;
	double start = now;
	for (size_t i = 0; i < s->planner_n; i++)
		if (s->planner_end[i] > start)
			start = s->planner_end[i];
	s->planner_end[s->planner_n++] = start + dur;
}

/* M115 capability report. */
static void sim_m115(struct sim_marlin *s)
{
	static const char *const caps[] = {
		"SERIAL_XON_XOFF:0", "BINARY_FILE_TRANSFER:0", "EEPROM:0", "VOLUMETRIC:1",
		"AUTOREPORT_POS:0", "AUTOREPORT_TEMP:1", "PROGRESS:0", "PRINT_JOB:1",
		"AUTOLEVEL:0", "RUNOUT:0", "Z_PROBE:0", "LEVELING_DATA:0",
		"BUILD_PERCENT:0", "SOFTWARE_POWER:0", "TOGGLE_LIGHTS:0",
		"CASE_LIGHT_BRIGHTNESS:0", "EMERGENCY_PARSER:1", "HOST_ACTION_COMMANDS:1",
		"PROMPT_SUPPORT:0", "SDCARD:0", "REPEAT:0", "SD_WRITE:0",
		"AUTOREPORT_SD_STATUS:0", "LONG_FILENAME:0", "THERMAL_PROTECTION:1",
		"MOTION_MODES:0", "ARCS:1", "BABYSTEPPING:0", "CHAMBER_TEMPERATURE:0",
		"COOLER_TEMPERATURE:0", "MEATPACK:0",
	};
	if (s->o.no_firmware_name)
		return; /* the ok alone */
	sim_send(s, "FIRMWARE_NAME:Marlin 2.1.2 (Stratum simulator) "
		    "SOURCE_CODE_URL:github.com/MarlinFirmware/Marlin PROTOCOL_VERSION:1.0 "
		    "MACHINE_TYPE:Stratum Simulated Printer EXTRUDER_COUNT:1 "
		    "UUID:cede2a2f-41a2-4748-9b12-c55c62f367ff");
	for (size_t i = 0; i < sizeof(caps) / sizeof(caps[0]); i++)
		sim_sendf(s, "Cap:%s", caps[i]);
	sim_sendf(s, "Cap:ADVANCED_OK:%d", s->o.advanced_ok ? 1 : 0);
}

/* Start the queue-head command.  Returns true when it is finished. */
static bool sim_exec_start(struct sim_marlin *s, struct sim_cmd *c, double now)
{
	const struct gcode_line *g = &c->g;
	double v;
	char buf[160];

	if (!c->parsed || g->letter == 0) {
		if (c->raw[0])
			sim_sendf(s, "echo:Unknown command: \"%s\"", c->raw);
		return true;
	}
	if (g->letter == 'G') {
		switch (g->number) {
		case 0: case 1: case 2: case 3:
			if (sim_planner_free(s, now) == 0) {
				s->blk = SIM_BLK_PLANNER_SLOT;
				return false;
			}
			sim_plan_move(s, g, now);
			return true;
		case 4:
			s->blk_dur = 0;
			if (gcode_word_value(g, 'P', &v))
				s->blk_dur = v / 1000.0;
			if (gcode_word_value(g, 'S', &v))
				s->blk_dur = v;
			s->blk_dur /= s->o.speedup;
			s->blk = SIM_BLK_SYNC_TIMED;
			s->blk_synced = false;
			return false;
		case 28:
			memset(s->pos, 0, 3 * sizeof(s->pos[0]));
			s->blk_dur = SIM_HOME_S / s->o.speedup;
			s->blk = SIM_BLK_SYNC_TIMED;
			s->blk_synced = false;
			return false;
		case 90: s->rel_xyz = false; s->rel_e = false; return true;
		case 91: s->rel_xyz = true; s->rel_e = true; return true;
		case 92:
			for (int a = 0; a < 4; a++)
				if (gcode_word_value(g, "XYZE"[a], &v))
					s->pos[a] = v;
			return true;
		case 20: case 21: case 29: case 80:
			return true;
		default:
			break;
		}
	} else if (g->letter == 'M') {
		switch (g->number) {
		case 104: case 109: case 140: case 190: {
			int h = (g->number == 140 || g->number == 190) ? 1 : 0;
			bool wait = g->number == 109 || g->number == 190;
			bool r = false;
			if (gcode_word_value(g, 'S', &v)) {
				s->heater[h].target = v;
			} else if (gcode_word_value(g, 'R', &v)) {
				s->heater[h].target = v;
				r = true;
			}
			if (!wait)
				return true;
			s->blk = SIM_BLK_HEAT;
			s->blk_heater = h;
			s->blk_heat_both = r;
			s->wait_cancel = false;
			s->next_temp_report = now + 1.0 / s->o.speedup;
			return false;
		}
		case 105:
			sim_temp_string(s, buf, sizeof(buf));
			sim_sendf(s, "ok%s", buf);
			return true;
		case 110:
			if (!c->has_n && gcode_word_value(g, 'N', &v))
				s->last_n = (long)v;
			return true;
		case 114:
			sim_sendf(s, "X:%.2f Y:%.2f Z:%.2f E:%.2f Count X:0 Y:0 Z:0", s->pos[0],
				  s->pos[1], s->pos[2], s->pos[3]);
			return true;
		case 115:
			sim_m115(s);
			return true;
		case 155:
			s->autoreport_s = gcode_word_value(g, 'S', &v) && v > 0 ? v : 0;
			s->next_autoreport = now + s->autoreport_s;
			return true;
		case 400:
			s->blk_dur = 0;
			s->blk = SIM_BLK_SYNC_TIMED;
			s->blk_synced = false;
			return false;
		case 82: s->rel_e = false; return true;
		case 83: s->rel_e = true; return true;
		case 17: case 18: case 84: case 106: case 107: case 108: case 112: case 410:
		case 73: case 117: case 118: case 201: case 203: case 204: case 205: case 220:
		case 221: case 302: case 500: case 501: case 502: case 503: case 900: case 876:
			return true;
		default:
			break;
		}
	} else if (g->letter == 'T' && g->number == 0) {
		return true;
	}
	sim_sendf(s, "echo:Unknown command: \"%s\"", c->raw);
	return true;
}

/* Is the blocked head command done? */
static bool sim_exec_poll(struct sim_marlin *s, struct sim_cmd *c, double now)
{
	switch (s->blk) {
	case SIM_BLK_PLANNER_SLOT:
		if (sim_planner_free(s, now) == 0)
			return false;
		sim_plan_move(s, &c->g, now);
		return true;
	case SIM_BLK_SYNC_TIMED:
		if (!s->blk_synced) {
			if (sim_planner_free(s, now) < SIM_PLANNER)
				return false;
			s->blk_synced = true;
			s->blk_until = now + s->blk_dur;
		}
		return now >= s->blk_until;
	case SIM_BLK_BUSY:
		return now >= s->blk_until;
	case SIM_BLK_HEAT: {
		struct sim_heater *h = &s->heater[s->blk_heater];
		if (s->wait_cancel)
			return true;
		bool done = s->blk_heat_both ? fabs(h->temp - h->target) < 1.0
					     : h->temp >= h->target - 1.0;
		if (done)
			return true;
		if (now >= s->next_temp_report) {
			char buf[160];
			sim_temp_string(s, buf, sizeof(buf));
			sim_sendf(s, "%s W:?", buf);
			s->next_temp_report = now + 1.0 / s->o.speedup;
		}
		return false;
	}
	default:
		return true;
	}
}

/* Run queued commands as far as they go at time now. */
static void sim_execute(struct sim_marlin *s, double now)
{
	while (s->q_count && !s->halted && !s->unplugged) {
		struct sim_cmd *c = &s->q[s->q_head];
		bool done;
		if (s->blk == SIM_BLK_NONE) {
			if (c->has_n && s->o.freeze_at_line > 0 && c->n == s->o.freeze_at_line &&
			    !s->thaw_at) {
				/* hangs before running it; after a stall it runs */
				s->frozen = true;
				s->thaw_at = s->o.freeze_s > 0 ? now + s->o.freeze_s : INFINITY;
				return;
			}
			sim_log(s, c);
			if (c->has_n && s->o.unplug_at_line > 0 && c->n == s->o.unplug_at_line) {
				s->unplugged = true;
				return;
			}
			if (c->has_n && s->o.reset_at_line > 0 && c->n == s->o.reset_at_line) {
				sim_reset_state(s);
				s->tx_len = s->tx_off = s->marks_n = 0;
				sim_boot(s, now);
				return;
			}
			s->next_busy = now + SIM_KEEPALIVE_S;
			if (c->has_n && s->o.busy_at_line > 0 && c->n == s->o.busy_at_line) {
				s->blk = SIM_BLK_BUSY;
				s->blk_until = now + s->o.busy_s;
				done = false;
			} else {
				done = sim_exec_start(s, c, now);
			}
		} else {
			done = sim_exec_poll(s, c, now);
		}
		if (!done) {
			if (now >= s->next_busy) {
				sim_send(s, "echo:busy: processing");
				s->next_busy = now + SIM_KEEPALIVE_S;
			}
			return;
		}
		s->blk = SIM_BLK_NONE;
		if (!(c->parsed && c->g.letter == 'M' && c->g.number == 105))
			sim_ok(s, c, now);
		s->q_head = (s->q_head + 1) % s->o.bufsize;
		s->q_count--;
		sim_serial_commands(s); /* the main loop reads input between commands */
	}
}

/* Heaters move toward their targets; M155 auto-reports. */
static void sim_physics(struct sim_marlin *s, double now, double dt)
{
	for (int i = 0; i < 2; i++) {
		struct sim_heater *h = &s->heater[i];
		double goal = h->target > SIM_AMBIENT ? h->target : SIM_AMBIENT;
		double step = dt * s->o.speedup * (goal > h->temp ? h->heat_rate : h->cool_rate);
		if (fabs(goal - h->temp) <= step)
			h->temp = goal;
		else
			h->temp += goal > h->temp ? step : -step;
	}
	if (s->autoreport_s > 0 && now >= s->next_autoreport && !s->halted) {
		char buf[160];
		sim_temp_string(s, buf, sizeof(buf));
		sim_send(s, buf);
		s->next_autoreport = now + s->autoreport_s;
	}
}

/* Write the reply lines whose last byte has crossed the link by now (each
 * starts when it is ready and the line before it is through); lower *wake
 * to when the next one will have. */
static int sim_flush_tx(struct sim_marlin *s, double now, double *wake)
{
	const double byte_s = 10.0 / s->o.baud;
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
	const double byte_s = 10.0 / s->o.baud;
	size_t i = 0, j;
	while (i < s->wire_len && s->in_t + byte_s <= now) {
		s->in_t += byte_s;
		sim_rx_byte(s, s->wire[i++], s->in_t);
		/* The firmware empties the ring while a queue slot is free far
		 * faster than bytes arrive, so a late loop delivering a batch
		 * must not overflow a ring the real board would have drained. */
		if (s->rx_len >= s->o.rx_buffer)
			sim_serial_commands(s);
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
			/* the stall is over: what came meanwhile is read at once */
			s->frozen = false;
			s->in_t = now;
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
		sim_physics(s, now, dt);
		sim_serial_commands(s);
		sim_execute(s, now);
		sim_serial_commands(s);
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

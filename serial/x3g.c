/*
 * x3g.c - G-code to X3G translation and X3G decoding (x3g.h).
 *
 * The numbers follow GPX 2.6.8 (markwal/GPX src/gpx/gpx.c), the translator
 * every Sailfish user has, so that our files match `gpx -m fcp` command for
 * command; where GPX does something only a serial link makes sense of
 * (writing query commands such as M105 into a file) we warn instead.
 */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "x3g.h"

/* Axis bits, as S3G's axes bitfields and GPX's word flags use them. */
enum {
	BIT_X = 1u << 0,
	BIT_Y = 1u << 1,
	BIT_Z = 1u << 2,
	BIT_A = 1u << 3,
	BIT_B = 1u << 4,
	BITS_XYZ = 0x07,
	BITS_AXES = 0x1f,
	/* other words of a line */
	BIT_E = 1u << 5,
	BIT_F = 1u << 6,
	BIT_P = 1u << 8,
	BIT_R = 1u << 10,
	BIT_S = 1u << 11,
	BIT_T = 1u << 14,
};

#define AX_A 3
#define AX_B 4
#define NOZZLE_MAX 280u	   /* GPX clamps nozzle targets here (C) */
#define WAIT_FOREVER 0xffffu /* GPX MAX_TIMEOUT: wait timeouts when no P (s) */
#define OUT_CAP 1024	   /* bytes one line can produce, with room to spare */

enum prog_state { PROG_READY, PROG_RUNNING, PROG_ENDED };

struct x3g_translator {
	struct x3g_machine m;
	enum x3g_flavor flavor;
	char build_name[X3G_BUILD_NAME_MAX + 1];
	unsigned mask;	   /* axes the machine has */
	unsigned known;	   /* axes whose position we know */
	double cur[5];	   /* position, mm */
	double tgt[5];	   /* target of the line being translated, mm */
	double excess[2];  /* extruder rounding carried to the next move, steps */
	double feedrate;   /* mm/min, the last F */
	unsigned speed_pc; /* M220 */
	unsigned extrude_pc[2]; /* M221 */
	int cur_tool, tgt_tool;
	double offset[7][3]; /* G10 P1-P6 work offsets; [0] is none */
	int cur_offset;
	unsigned nozzle[2], platform[2];     /* targets set so far, C */
	unsigned standby[2], active[2];	     /* G10 R/S tool temperatures, C */
	bool rel_xyz, rel_e;
	enum prog_state state;
	unsigned percent;
	bool stopped; /* M2 seen */
	int longest_dda;

	/* output of the current call */
	uint8_t out[OUT_CAP];
	size_t len;
	size_t cmd_start;
	int ncmds;
	bool overflow;
	uint64_t lineno;
	struct x3g_warning warn[X3G_WARNINGS_PER_LINE];
	size_t nwarn;
	uint64_t warn_total;
};

/* The words of one line, E already turned into A or B. */
struct words {
	unsigned flag;
	double v[5]; /* X Y Z A B */
	double f, p, r, s;
	int t;
	const char *text; /* message for M70/M71, NULL if none */
};

void x3g_machine_fcp(struct x3g_machine *m)
{
	static const struct x3g_machine fcp = {
	    .axis = {{94.117647, 18000, 2500, X3G_ENDSTOP_MAX},
		     {94.117647, 18000, 2500, X3G_ENDSTOP_MAX},
		     {400, 1170, 1100, X3G_ENDSTOP_MIN},
		     {96.275201870333662, 1600, 0, X3G_ENDSTOP_MIN},
		     {96.275201870333662, 1600, 0, X3G_ENDSTOP_MIN}},
	    .extruder_count = 2,
	    .heated_platform = true,
	    .home_timeout = 20,
	};
	*m = fcp;
}

/* ---- output ------------------------------------------------------------ */

static void warn(struct x3g_translator *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Record a warning for the current line. */
static void warn(struct x3g_translator *t, const char *fmt, ...)
{
	va_list ap;

	t->warn_total++;
	if (t->nwarn >= X3G_WARNINGS_PER_LINE)
		return;
	va_start(ap, fmt);
	t->warn[t->nwarn].line = t->lineno;
	vsnprintf(t->warn[t->nwarn].msg, sizeof(t->warn[t->nwarn].msg), fmt, ap);
	va_end(ap);
	t->nwarn++;
}

/* Start a command; the fixed buffer is far larger than one line needs, but
 * an overflow is still caught rather than trusted. */
static void put8(struct x3g_translator *t, unsigned v)
{
	if (t->len >= OUT_CAP) {
		t->overflow = true;
		return;
	}
	t->out[t->len++] = (uint8_t)v;
}

static void put16(struct x3g_translator *t, unsigned v)
{
	put8(t, v & 0xff);
	put8(t, (v >> 8) & 0xff);
}

static void put32(struct x3g_translator *t, uint32_t v)
{
	for (int i = 0; i < 4; i++)
		put8(t, (v >> (8 * i)) & 0xff);
}

static void put_i32(struct x3g_translator *t, double v)
{
	/* steps fit easily; clamp so a wild input cannot make the cast undefined */
	if (v > 2147483647.0)
		v = 2147483647.0;
	if (v < -2147483648.0)
		v = -2147483648.0;
	put32(t, (uint32_t)(int32_t)v);
}

static void put_float(struct x3g_translator *t, float f)
{
	uint32_t u;

	memcpy(&u, &f, sizeof(u));
	put32(t, u);
}

static void begin(struct x3g_translator *t, unsigned code)
{
	t->cmd_start = t->len;
	put8(t, code);
}

static void end(struct x3g_translator *t)
{
	t->ncmds++;
}

/* A double as an unsigned in [0, max]; NaN and negatives give 0. */
static unsigned clamp_u(double v, unsigned max)
{
	if (!(v > 0))
		return 0;
	if (v >= (double)max)
		return max;
	return (unsigned)v;
}

/* ---- commands ----------------------------------------------------------- */

static void cmd_build_start(struct x3g_translator *t)
{
	begin(t, 153);
	put32(t, 0);
	for (const char *s = t->build_name; *s; s++)
		put8(t, (uint8_t)*s);
	put8(t, 0);
	end(t);
}

static void cmd_percent(struct x3g_translator *t, unsigned pc)
{
	if (pc > 100)
		pc = 100;
	t->percent = pc;
	begin(t, 150);
	put8(t, pc);
	put8(t, 0);
	end(t);
}

static void cmd_build_end(struct x3g_translator *t)
{
	begin(t, 154);
	put8(t, 0);
	end(t);
}

static void cmd_change_tool(struct x3g_translator *t, int tool)
{
	begin(t, 134);
	put8(t, (unsigned)tool);
	end(t);
}

/* 136 tool action: a 16-bit argument for targets (3 nozzle, 31 platform),
 * one byte for toggles (12 fan, 13 blower "valve"). */
static void cmd_tool_action(struct x3g_translator *t, int tool, unsigned action, unsigned value)
{
	bool wide = action == 3 || action == 31;

	begin(t, 136);
	put8(t, (unsigned)tool);
	put8(t, action);
	put8(t, wide ? 2 : 1);
	if (wide)
		put16(t, value);
	else
		put8(t, value ? 1 : 0);
	end(t);
}

/* 135 wait for tool / 141 wait for platform: poll every 100 ms. */
static void cmd_wait(struct x3g_translator *t, unsigned code, int tool, unsigned timeout)
{
	begin(t, code);
	put8(t, (unsigned)tool);
	put16(t, 100);
	put16(t, timeout);
	end(t);
}

static void cmd_steppers(struct x3g_translator *t, unsigned axes, bool on)
{
	begin(t, 137);
	put8(t, (axes & BITS_AXES) | (on ? 0x80 : 0));
	end(t);
}

static void cmd_one_byte(struct x3g_translator *t, unsigned code, unsigned v)
{
	begin(t, code);
	put8(t, v);
	end(t);
}

/* 149: the text in rows of at most 20 characters (the LCD is 4 x 20);
 * bit 0 keeps the screen, bit 1 marks the last part, bit 2 waits for the
 * button. */
static void cmd_message(struct x3g_translator *t, const char *msg, unsigned row, unsigned col,
			unsigned timeout, bool wait_button)
{
	size_t len = strlen(msg), sent = 0;
	size_t room = col ? 20 - col : 20;
	unsigned bits = 0;

	if (row || col) {
		if (len > room)
			len = room;
		bits |= 0x01;
	} else if (len > 80) {
		len = 80;
	}
	while (sent < len) {
		unsigned secs = 0;
		size_t n = len - sent < room ? len - sent : room;

		if (sent + room >= len) {
			secs = timeout;
			bits |= 0x02;
			if (wait_button)
				bits |= 0x04;
		}
		if (sent > 0)
			bits |= 0x01;
		begin(t, 149);
		put8(t, bits);
		put8(t, col);
		put8(t, row);
		put8(t, secs & 0xff);
		for (size_t i = 0; i < n; i++)
			put8(t, (uint8_t)msg[sent + i]);
		put8(t, 0);
		end(t);
		sent += n;
	}
}

/* ---- motion ------------------------------------------------------------- */

static double axis_spm(const struct x3g_translator *t, int i)
{
	return t->m.axis[i].steps_per_mm;
}

/* Forget the position of the axes in flag (homing, M132); GPX sets them to
 * 0 so that what follows is at least deterministic. */
static void set_unknown(struct x3g_translator *t, unsigned flag)
{
	t->known &= ~(flag & t->mask);
	for (int i = 0; i < 5; i++)
		if (flag & (1u << i))
			t->cur[i] = 0;
}

/* The slowest DDA (us per step) the X, Y, Z maxima allow: the fallback
 * rate of 139 moves. */
static int longest_dda(struct x3g_translator *t)
{
	if (t->longest_dda == 0) {
		int best = 0;

		for (int i = 0; i < 3; i++) {
			int d = (int)(60e6 / (t->m.axis[i].max_feedrate * axis_spm(t, i)));

			if (i == 0 || d < best)
				best = d;
		}
		t->longest_dda = best;
	}
	return t->longest_dda;
}

/* Absolute steps of pos; the extruders carry their rounding remainder. */
static void to_steps(struct x3g_translator *t, const double pos[5], double steps[5])
{
	for (int i = 0; i < 3; i++)
		steps[i] = round(pos[i] * axis_spm(t, i));
	for (int i = AX_A; i <= AX_B; i++) {
		double v = pos[i] * axis_spm(t, i) + t->excess[i - AX_A];

		steps[i] = round(v);
		t->excess[i - AX_A] = v - steps[i];
	}
}

/* 139 queue extended point: absolute steps, fixed DDA; used when an axis
 * of the move has no known position, so no distance can be computed. */
static void queue_absolute(struct x3g_translator *t)
{
	double steps[5], fr = t->feedrate * t->speed_pc / 100.0;
	long dda = longest_dda(t);

	to_steps(t, t->tgt, steps);
	if (fr > 0) {
		for (int i = 0; i < 5; i++) {
			if (steps[i] != 0) {
				double d = 60e6 / (axis_spm(t, i) * fr);
				long l = d > 2e9 ? 2000000000L : (long)d;

				if (l > dda)
					dda = l;
			}
		}
	}
	if (dda <= 0)
		dda = 200; /* never "as fast as possible" */
	begin(t, 139);
	put_i32(t, steps[0]);
	put_i32(t, steps[1]);
	put_i32(t, steps[2]);
	put_i32(t, -steps[3]);
	put_i32(t, -steps[4]);
	put32(t, (uint32_t)dda);
	end(t);
	t->known = t->mask;
}

/* The feed rate (mm/min) after each axis's maximum is applied. */
static double safe_feedrate(const struct x3g_translator *t, unsigned flag, const double d[5])
{
	double fr = t->feedrate * t->speed_pc / 100.0, dist = 0;

	if (fr == 0)
		for (int i = 0; i < 5; i++)
			if (t->m.axis[i].max_feedrate > fr)
				fr = t->m.axis[i].max_feedrate;
	for (int i = 0; i < 3; i++)
		if (flag & (1u << i))
			dist += d[i] * d[i];
	dist = sqrt(dist);
	for (int i = 0; i < 5; i++) {
		double max = t->m.axis[i].max_feedrate;

		if (!(flag & (1u << i)))
			continue;
		if (dist > 0) {
			if (fr * d[i] / dist > max)
				fr = max * dist / d[i];
		} else if (i >= AX_A && fr > max) {
			fr = max;
		}
	}
	return fr;
}

/* 155 queue extended point x3g (GPX queue_ext_point): X, Y, Z absolute
 * unless their position is unknown or the move is relative, extruders
 * always relative. */
static void queue_point(struct x3g_translator *t, unsigned flag, const double delta[5],
			bool relative)
{
	unsigned mask = flag & t->mask;
	unsigned unknown = ~(t->known | mask) & t->mask;
	double dmm[5], dsteps[5], target[5], steps[5], any = 0, largest = 0, dist = 0;
	double fr, minutes, dda_rate;

	if ((t->known & mask) != mask && !relative && !unknown) {
		queue_absolute(t);
		return;
	}
	for (int i = 0; i < 5; i++) {
		if (unknown || relative)
			dmm[i] = delta[i];
		else if (flag & (1u << i))
			dmm[i] = t->tgt[i] - t->cur[i];
		else
			dmm[i] = 0;
		if (!(unknown || relative) && i >= AX_A)
			dmm[i] = dmm[i] * t->extrude_pc[i - AX_A] / 100;
		dsteps[i] = (flag & (1u << i)) ? round(fabs(dmm[i]) * axis_spm(t, i)) : 0;
		any += dsteps[i];
		if ((flag & (1u << i)) && dsteps[i] > largest)
			largest = dsteps[i];
	}
	if (any == 0)
		return; /* shorter than a step on every axis: GPX writes nothing */
	for (int i = 0; i < 3; i++)
		if (flag & (1u << i))
			dist += dmm[i] * dmm[i];
	dist = sqrt(dist);
	for (int i = 0; i < 3; i++) {
		target[i] = relative ? delta[i] : t->tgt[i];
		if (unknown & (1u << i))
			target[i] = 0;
	}
	target[AX_A] = -dmm[AX_A];
	target[AX_B] = -dmm[AX_B];
	for (int i = 0; i < 5; i++)
		dmm[i] = fabs(dmm[i]);
	fr = safe_feedrate(t, flag, dmm);
	minutes = dist / fr;
	if (minutes == 0) {
		dist = 0;
		if (flag & BIT_A)
			dist = dmm[AX_A];
		if ((flag & BIT_B) && dist < dmm[AX_B])
			dist = dmm[AX_B];
		minutes = dist / fr;
	}
	fr /= 60.0;
	to_steps(t, target, steps);
	dda_rate = 1e6 / (60e6 * minutes / largest);

	begin(t, 155);
	for (int i = 0; i < 5; i++)
		put_i32(t, steps[i]);
	put32(t, clamp_u(dda_rate, 0xffffffffu));
	put8(t, relative ? BITS_AXES : (unknown | BIT_A | BIT_B));
	put_float(t, (float)dist);
	put16(t, clamp_u(fr * 64.0, 0xffffffffu) & 0xffff);
	end(t);
}

/* Where the line's words take the head (GPX calculate_target_position);
 * delta gets the change per axis, relative whether X/Y/Z moved relatively
 * from a known position. */
static void calc_target(struct x3g_translator *t, const struct words *w, double delta[5],
			bool *relative)
{
	const double *off = t->offset[t->cur_offset];

	*relative = false;
	for (int i = 0; i < 5; i++) {
		unsigned bit = 1u << i;

		delta[i] = 0;
		t->tgt[i] = t->cur[i];
		if (!(w->flag & bit))
			continue;
		if (i < 3 && t->rel_xyz) {
			delta[i] = w->v[i];
			t->tgt[i] += delta[i];
			if (t->known & bit)
				*relative = true;
		} else if (i < 3) {
			t->tgt[i] = w->v[i] + off[i];
			delta[i] = t->tgt[i] - t->cur[i];
		} else if (t->rel_xyz || t->rel_e) {
			delta[i] = w->v[i];
			t->tgt[i] += w->v[i];
		} else {
			t->tgt[i] = w->v[i];
			delta[i] = t->tgt[i] - t->cur[i];
		}
	}
	if (w->flag & BIT_F)
		t->feedrate = w->f;
}

static void move(struct x3g_translator *t, const struct words *w)
{
	double delta[5];
	bool relative;

	calc_target(t, w, delta, &relative);
	queue_point(t, w->flag, delta, relative);
	memcpy(t->cur, t->tgt, sizeof(t->cur));
	if (!t->rel_xyz)
		t->known |= w->flag & t->mask;
}

/* 131/132 find axes minimum/maximum at the slowest homing rate of the axes. */
static void home_axes(struct x3g_translator *t, unsigned axes, enum x3g_endstop dir,
		      const struct words *w)
{
	double fr = 0, longest = 0, n = 0;

	if (w->flag & BIT_F) {
		fr = t->feedrate;
	} else {
		for (int i = 0; i < 3; i++)
			if ((w->flag & (1u << i)) && t->m.axis[i].home_feedrate > fr)
				fr = t->m.axis[i].home_feedrate;
	}
	for (int i = 0; i < 3; i++) {
		const struct x3g_axis *a = &t->m.axis[i];

		if (!(axes & (1u << i)))
			continue;
		if (!(fr > 0) || a->home_feedrate < fr)
			fr = a->home_feedrate;
		n++;
		if (a->steps_per_mm > longest)
			longest = a->steps_per_mm;
		if (a->endstop != dir)
			warn(t, "%c homes to its %s endstop but this printer's is at the %s", "XYZ"[i],
			     dir == X3G_ENDSTOP_MAX ? "maximum" : "minimum",
			     a->endstop == X3G_ENDSTOP_MAX ? "maximum" : "minimum");
	}
	begin(t, dir == X3G_ENDSTOP_MIN ? 131 : 132);
	put8(t, axes & BITS_XYZ);
	put32(t, clamp_u(round(sqrt(n) / fr * 60e6 / longest), 0xffffffffu));
	put16(t, t->m.home_timeout & 0xffff);
	end(t);
}

static void after_homing(struct x3g_translator *t, unsigned flag)
{
	set_unknown(t, flag);
	t->excess[0] = t->excess[1] = 0;
}

/* G28: each axis to its own endstop, the X end first as GPX does. */
static void g28(struct x3g_translator *t, struct words *w)
{
	unsigned to_max = 0, to_min = 0;

	if ((w->flag & t->mask) == 0)
		w->flag |= BITS_XYZ;
	if (w->flag & BIT_F)
		t->feedrate = w->f;
	for (int i = 0; i < 3; i++)
		if (w->flag & (1u << i)) {
			if (t->m.axis[i].endstop == X3G_ENDSTOP_MAX)
				to_max |= 1u << i;
			else
				to_min |= 1u << i;
		}
	if (t->m.axis[0].endstop == X3G_ENDSTOP_MAX) {
		if (to_max)
			home_axes(t, to_max, X3G_ENDSTOP_MAX, w);
		if (to_min)
			home_axes(t, to_min, X3G_ENDSTOP_MIN, w);
	} else {
		if (to_min)
			home_axes(t, to_min, X3G_ENDSTOP_MIN, w);
		if (to_max)
			home_axes(t, to_max, X3G_ENDSTOP_MAX, w);
	}
	after_homing(t, w->flag);
}

/* G161/G162: the named axes to one end. */
static void g161(struct x3g_translator *t, const struct words *w, enum x3g_endstop dir,
		 const char *name)
{
	if (w->flag & BIT_F)
		t->feedrate = w->f;
	if (!(w->flag & BITS_XYZ)) {
		warn(t, "%s names no axis (write e.g. %s X Y); nothing written", name, name);
		return;
	}
	home_axes(t, w->flag & BITS_XYZ, dir, w);
	after_homing(t, w->flag);
}

/* G92 -> 140 set extended position, which sets all five axes. */
static void g92(struct x3g_translator *t, const struct words *w)
{
	double steps[5];

	for (int i = 0; i < 5; i++)
		if (w->flag & (1u << i))
			t->cur[i] = w->v[i];
	if (((t->known | w->flag) & t->mask) != t->mask)
		warn(t, "G92 sets every axis in X3G; axes not given and not yet known are set "
			"to 0");
	for (int i = 0; i < 5; i++)
		steps[i] = round(t->cur[i] * axis_spm(t, i));
	begin(t, 140);
	for (int i = 0; i < 5; i++)
		put_i32(t, steps[i]);
	end(t);
	t->known |= w->flag & t->mask;
}

/* ---- tools and temperatures --------------------------------------------- */

static void set_nozzle(struct x3g_translator *t, int tool, unsigned temp)
{
	cmd_tool_action(t, tool, 3, temp);
	t->nozzle[tool] = temp;
}

/* GPX do_tool_change: G10 standby/active temperatures, 134, then a 139 to
 * where the head already is, so the firmware applies the toolhead offset
 * in a move of its own rather than bending the next one. */
static void tool_change(struct x3g_translator *t)
{
	int from = t->cur_tool, to = t->tgt_tool;

	if (t->standby[from] && t->standby[from] != t->nozzle[from])
		set_nozzle(t, from, t->standby[from]);
	if (t->active[to] && t->active[to] != t->nozzle[to])
		set_nozzle(t, to, t->active[to]);
	if (t->cur_offset == from + 1)
		t->cur_offset = to + 1;
	cmd_change_tool(t, to);
	if ((t->known & t->mask) == t->mask) {
		memcpy(t->tgt, t->cur, sizeof(t->tgt));
		queue_absolute(t);
	}
	t->cur_tool = to;
}

static unsigned timeout_of(const struct words *w)
{
	return (w->flag & BIT_P) ? clamp_u(w->p, 0xffff) : WAIT_FOREVER;
}

/* The tool whose controller drives the platform heater: tool 0, or the one
 * T names (GPX's r1d lets either extruder board carry it). */
static int platform_tool(const struct x3g_translator *t, const struct words *w)
{
	return (w->flag & BIT_T) ? t->tgt_tool : 0;
}

/* M140 (and Makerbot M109): the platform target. */
static void set_platform(struct x3g_translator *t, const struct words *w, int m)
{
	int tool = platform_tool(t, w);
	unsigned temp;

	if (!t->m.heated_platform) {
		warn(t, "M%d: this printer has no heated platform; nothing written", m);
		return;
	}
	if (!(w->flag & BIT_S)) {
		warn(t, "M%d without S (the temperature); nothing written", m);
		return;
	}
	temp = clamp_u(w->s, 0xffff);
	cmd_tool_action(t, tool, 31, temp);
	t->platform[tool] = temp;
}

/* M190/M134: set (when S is given) and wait for the platform. */
static void wait_platform(struct x3g_translator *t, const struct words *w, int m)
{
	int tool = platform_tool(t, w);

	if (!t->m.heated_platform) {
		warn(t, "M%d: this printer has no heated platform; nothing written", m);
		return;
	}
	if (w->flag & BIT_S)
		set_platform(t, w, m);
	if (tool != 0 || t->platform[0] > 0)
		cmd_wait(t, 141, tool, timeout_of(w));
	else
		warn(t, "M%d: no platform temperature set to wait for; no wait written", m);
}

static void m104(struct x3g_translator *t, const struct words *w)
{
	unsigned temp;

	if (!(w->flag & BIT_S)) {
		warn(t, "M104 without S (the temperature); nothing written");
		return;
	}
	temp = clamp_u(w->s, NOZZLE_MAX);
	if (temp && t->active[t->tgt_tool])
		temp = t->active[t->tgt_tool];
	set_nozzle(t, t->tgt_tool, temp);
}

static void m109_reprap(struct x3g_translator *t, const struct words *w)
{
	m104(t, w);
	if ((w->flag & BIT_S) && t->nozzle[t->tgt_tool] > 0)
		cmd_wait(t, 135, t->tgt_tool, timeout_of(w));
}

/* M6/M116: change tool (M6), then wait for the platform and the nozzles. */
static void m6_m116(struct x3g_translator *t, const struct words *w, int m)
{
	unsigned timeout = timeout_of(w);

	if (m == 6 && t->tgt_tool != t->cur_tool)
		tool_change(t);
	if (t->m.heated_platform && t->platform[0] > 0)
		cmd_wait(t, 141, 0, timeout);
	else if (t->m.heated_platform && t->platform[1] > 0)
		cmd_wait(t, 141, 1, timeout);
	if (m == 116 && !(w->flag & BIT_T)) {
		if (t->m.extruder_count > 1 && t->nozzle[1] > 0)
			cmd_wait(t, 135, 1, timeout);
		if (t->nozzle[0] > 0)
			cmd_wait(t, 135, 0, timeout);
	} else if (t->nozzle[t->tgt_tool] > 0) {
		cmd_wait(t, 135, t->tgt_tool, timeout);
	}
}

/* M106/M107: RepRap flavour drives the print-cooling blower (tool action
 * 13, "valve"), Makerbot flavour the heatsink fan (12), as GPX does. */
static void fan(struct x3g_translator *t, const struct words *w, unsigned dflt)
{
	unsigned on = (w->flag & BIT_S) ? (clamp_u(w->s, 255) != 0) : dflt;

	cmd_tool_action(t, t->tgt_tool, t->flavor == X3G_FLAVOR_REPRAP ? 13 : 12, on);
}

/* ---- build start and end ------------------------------------------------ */

static void start_program(struct x3g_translator *t, unsigned pc)
{
	t->state = PROG_RUNNING;
	cmd_build_start(t);
	cmd_percent(t, pc);
	cmd_change_tool(t, t->cur_tool); /* a known tool to start from */
}

static void end_program(struct x3g_translator *t)
{
	t->state = PROG_ENDED;
	cmd_percent(t, 100);
	cmd_build_end(t);
}

static void m73(struct x3g_translator *t, const struct words *w)
{
	unsigned pc;

	if (!(w->flag & BIT_P)) {
		warn(t, "M73 without P (the percentage); nothing written");
		return;
	}
	pc = clamp_u(w->p, 100);
	if (t->state == PROG_READY && pc < 100)
		start_program(t, pc);
	else if (t->state != PROG_ENDED && pc == 100)
		end_program(t);
	else if (t->state != PROG_ENDED && t->percent < pc)
		cmd_percent(t, pc);
}

/* ---- dispatch ------------------------------------------------------------ */

/* Collect the words GPX reads; E becomes A or B of the current tool. */
static void read_words(const struct x3g_translator *t, const struct gcode_line *l,
		       struct words *w)
{
	static const char axes[] = "XYZAB";
	double v;

	memset(w, 0, sizeof(*w));
	for (int i = 0; i < 5; i++)
		if (gcode_find_word(l, axes[i])) {
			w->flag |= 1u << i;
			w->v[i] = gcode_word_value(l, axes[i], &v) ? v : 0;
		}
	if (gcode_find_word(l, 'F')) {
		w->flag |= BIT_F;
		w->f = gcode_word_value(l, 'F', &v) ? v : 0;
	}
	if (gcode_find_word(l, 'P')) {
		w->flag |= BIT_P;
		w->p = gcode_word_value(l, 'P', &v) ? v : 0;
	}
	if (gcode_find_word(l, 'R')) {
		w->flag |= BIT_R;
		w->r = gcode_word_value(l, 'R', &v) ? v : 0;
	}
	if (gcode_find_word(l, 'S')) {
		w->flag |= BIT_S;
		w->s = gcode_word_value(l, 'S', &v) ? v : 0;
	}
	if (l->letter == 'T') {
		w->flag |= BIT_T;
		w->t = l->number;
	} else if (gcode_find_word(l, 'T')) {
		w->flag |= BIT_T;
		/* kept whole for the warning: GPX names T1250 as written */
		w->t = gcode_word_value(l, 'T', &v) ? (int)clamp_u(v, 65535) : 0;
	}
	if (gcode_find_word(l, 'E')) {
		int ax = t->cur_tool == 0 ? AX_A : AX_B;

		w->flag |= 1u << ax;
		w->v[ax] = gcode_word_value(l, 'E', &v) ? v : 0;
	}
	/* M70's text: a ';' comment (not a ";@macro"), else a "( )" one */
	if (l->has_comment && !(l->comment[0] == '@' && isalpha((unsigned char)l->comment[1])))
		w->text = l->comment;
	else if (l->has_paren)
		w->text = l->paren;
}

/* GPX ";@name args" macros: the flavour switch is honoured; the others that
 * only concern GPX's own options have no effect here; the rest are warned
 * about. */
static void macro(struct x3g_translator *t, const char *c)
{
	char name[32], arg[32] = "";
	size_t n = 0, k = 0;

	c++; /* '@' */
	while (*c && !isspace((unsigned char)*c) && n < sizeof(name) - 1)
		name[n++] = *c++;
	name[n] = 0;
	while (isspace((unsigned char)*c))
		c++;
	while (*c && !isspace((unsigned char)*c) && k < sizeof(arg) - 1)
		arg[k++] = *c++;
	arg[k] = 0;
	if (!strcmp(name, "flavor")) {
		if (!strcmp(arg, "reprap"))
			t->flavor = X3G_FLAVOR_REPRAP;
		else if (!strcmp(arg, "makerbot"))
			t->flavor = X3G_FLAVOR_MAKERBOT;
		else
			warn(t, "';@flavor %s': the flavour is reprap or makerbot; ignored", arg);
	} else if (strcmp(name, "body") && strcmp(name, "header") && strcmp(name, "footer") &&
		   strncmp(name, "open_", 5) && strncmp(name, "close_", 6)) {
		warn(t, "GPX macro ';@%s' is not supported; ignored", name);
	}
}

static void g_code(struct x3g_translator *t, const struct gcode_line *l, struct words *w)
{
	if (l->subcode >= 0) {
		warn(t, "G%d.%d is not supported in X3G; nothing written", l->number, l->subcode);
		return;
	}
	switch (l->number) {
	case 0:
	case 1:
		move(t, w);
		break;
	case 4:
		if (w->flag & BIT_P) {
			begin(t, 133);
			put32(t, clamp_u(w->p, 0xffffffffu));
			end(t);
		} else {
			warn(t, "G4 without P (milliseconds); nothing written");
		}
		break;
	case 10:
		if ((w->flag & BIT_P) && w->p >= 1 && w->p <= 6) {
			int i = (int)w->p;

			for (int k = 0; k < 3; k++)
				if (w->flag & (1u << k))
					t->offset[i][k] = w->v[k];
			if (i <= 2 && (w->flag & BIT_R))
				t->standby[i - 1] = clamp_u(w->r, NOZZLE_MAX);
			if (i <= 2 && (w->flag & BIT_S))
				t->active[i - 1] = clamp_u(w->s, NOZZLE_MAX);
		} else {
			warn(t, "G10 without a coordinate system P1-P6; ignored");
		}
		break;
	case 15:
	case 21:
	case 71:
		break; /* cartesian, millimetres: what X3G is anyway */
	case 28:
		g28(t, w);
		break;
	case 53:
	case 54:
	case 55:
	case 56:
	case 57:
	case 58:
	case 59:
		t->cur_offset = l->number - 53;
		break;
	case 90:
		t->rel_xyz = false;
		break;
	case 91:
		t->rel_xyz = true;
		break;
	case 92:
		g92(t, w);
		break;
	case 161:
		g161(t, w, X3G_ENDSTOP_MIN, "G161");
		break;
	case 162:
		g161(t, w, X3G_ENDSTOP_MAX, "G162");
		break;
	default:
		warn(t, "G%d is not supported in X3G; nothing written", l->number);
	}
}

static void steppers(struct x3g_translator *t, const struct words *w, bool on)
{
	unsigned all = t->m.extruder_count == 1 ? (BITS_XYZ | BIT_A) : BITS_AXES;

	cmd_steppers(t, (w && (w->flag & BITS_AXES)) ? w->flag & BITS_AXES : all, on);
}

static void m_code(struct x3g_translator *t, const struct gcode_line *l, struct words *w)
{
	int m = l->number;

	switch (m) {
	case 2:
		if (t->state != PROG_ENDED)
			end_program(t);
		t->stopped = true;
		break;
	case 6:
	case 116:
		m6_m116(t, w, m);
		break;
	case 17:
	case 18:
		steppers(t, w, m == 17);
		break;
	case 84:
		steppers(t, NULL, false);
		break;
	case 70:
	case 71:
		if (m == 70 && (!w->text || !*w->text)) {
			warn(t, "M70 without a message (write it as a comment: M70 P5 (text)); "
				"nothing written");
			break;
		}
		cmd_message(t, (w->text && *w->text) ? w->text : "Press M to continue",
			    (w->flag & BIT_Y) ? clamp_u(w->v[1], 3) : 0,
			    (w->flag & BIT_X) ? clamp_u(w->v[0], 19) : 0,
			    (w->flag & BIT_P) ? clamp_u(w->p, 0xffff) : 0, m == 71);
		break;
	case 72:
		if (w->flag & BIT_P)
			cmd_one_byte(t, 151, clamp_u(w->p, 2));
		else
			warn(t, "M72 without P (the song, 0-2); nothing written");
		break;
	case 73:
		m73(t, w);
		break;
	case 82:
		t->rel_e = false;
		break;
	case 83:
		t->rel_e = true;
		break;
	case 101:
	case 102:
	case 103:
		cmd_steppers(t, t->tgt_tool == 0 ? BIT_A : BIT_B, m != 103);
		break;
	case 104:
		m104(t, w);
		break;
	case 106:
		fan(t, w, 1);
		break;
	case 107:
		fan(t, w, 0);
		break;
	case 108:
		if (w->flag & BIT_T) {
			if (t->tgt_tool != t->cur_tool)
				tool_change(t);
		} else {
			warn(t, "M108 without T is not supported in X3G; nothing written");
		}
		break;
	case 109:
		if (t->flavor == X3G_FLAVOR_REPRAP)
			m109_reprap(t, w);
		else
			set_platform(t, w, m); /* Makerbot M109 sets the platform */
		break;
	case 140:
		set_platform(t, w, m);
		break;
	case 110:
	case 111:
	case 400:
		break; /* line numbers, debug level, finish moves: nothing to queue */
	case 126:
	case 127:
		cmd_tool_action(t, t->tgt_tool, 13,
				m == 127 ? 0 : ((w->flag & BIT_S) ? (clamp_u(w->s, 255) != 0) : 1));
		break;
	case 131:
	case 132:
		if (!(w->flag & BITS_AXES)) {
			warn(t, "M%d names no axis (write e.g. M%d X Y Z A B); nothing written", m, m);
			break;
		}
		cmd_one_byte(t, m == 131 ? 143 : 144, w->flag & BITS_AXES);
		if (m == 132) {
			after_homing(t, w->flag);
			/* extruder moves are relative: call their position 0 */
			for (int i = AX_A; i <= AX_B; i++)
				if (w->flag & (1u << i)) {
					t->known |= 1u << i;
					t->cur[i] = 0;
				}
		}
		break;
	case 133:
		if (t->nozzle[t->tgt_tool] > 0)
			cmd_wait(t, 135, t->tgt_tool, timeout_of(w));
		break;
	case 134:
	case 190:
		wait_platform(t, w, m);
		break;
	case 135:
		if (t->tgt_tool != t->cur_tool)
			tool_change(t);
		break;
	case 136:
		if (t->state == PROG_READY)
			start_program(t, 0);
		break;
	case 137:
		if (t->state != PROG_ENDED)
			end_program(t);
		break;
	case 220:
		if ((w->flag & BIT_S) && w->s > 0)
			t->speed_pc = clamp_u(w->s, 1000);
		break;
	case 221:
		if ((w->flag & BIT_S) && w->s > 0)
			t->extrude_pc[(w->flag & BIT_T) ? t->tgt_tool : t->cur_tool] =
			    clamp_u(w->s, 1000);
		break;
	case 300:
		begin(t, 147);
		put16(t, (w->flag & BIT_S) ? clamp_u(w->s, 0xffff) : 300);
		put16(t, (w->flag & BIT_P) ? clamp_u(w->p, 0xffff) : 1000);
		put8(t, 0);
		end(t);
		break;
	case 320:
	case 321:
		cmd_one_byte(t, 156, m == 320);
		break;
	default:
		if (l->subcode >= 0)
			warn(t, "M%d.%d is not supported in X3G; nothing written", m, l->subcode);
		else
			warn(t, "M%d is not supported in X3G; nothing written", m);
	}
}

int x3g_translate(struct x3g_translator *t, const struct gcode_line *l, uint64_t lineno,
		  struct st_error *err)
{
	struct words w;

	if (!t || !l)
		return st_error_set(err, ST_ERR_ARG, "x3g_translate: no translator or no line");
	t->len = 0;
	t->ncmds = 0;
	t->nwarn = 0;
	t->overflow = false;
	t->lineno = lineno;
	if (t->stopped) {
		if (l->letter)
			warn(t, "after M2 (end of program): ignored");
		return 0;
	}
	if (l->has_comment && l->comment[0] == '@' && isalpha((unsigned char)l->comment[1]))
		macro(t, l->comment);
	if (l->letter == 0 || l->letter == '@')
		return 0;
	if (l->letter == GCODE_LETTER_TEXT) {
		warn(t, "'%.60s' is not a G, M or T command (a Klipper macro or a text); X3G "
			"cannot express it; nothing written",
		     l->text);
		return 0;
	}
	if (l->letter == 'T' && l->number < 0) {
		warn(t, "%s (a Prusa MMU filament command) is not supported in X3G; nothing written",
		     l->text);
		return 0;
	}
	if (t->flavor == X3G_FLAVOR_MAKERBOT)
		t->tgt_tool = t->cur_tool; /* Makerbot's T on a command is for that line */
	read_words(t, l, &w);
	if (w.flag & BIT_T) {
		if (w.t >= 0 && w.t < t->m.extruder_count)
			t->tgt_tool = w.t;
		else
			warn(t, "T%d: this printer has %d extruder%s", w.t, t->m.extruder_count,
			     t->m.extruder_count == 1 ? "" : "s");
	}
	if (l->letter == 'G')
		g_code(t, l, &w);
	else if (l->letter == 'M')
		m_code(t, l, &w);
	else if (l->letter == 'T' && t->tgt_tool != t->cur_tool)
		tool_change(t);
	if (t->overflow)
		return st_error_set(err, ST_ERR_INTERNAL,
				    "line %llu: X3G output of one line exceeds %d bytes",
				    (unsigned long long)lineno, OUT_CAP);
	return t->ncmds;
}

int x3g_finish(struct x3g_translator *t, struct st_error *err)
{
	if (!t)
		return st_error_set(err, ST_ERR_ARG, "x3g_finish: no translator");
	t->len = 0;
	t->ncmds = 0;
	t->nwarn = 0;
	if (t->state != PROG_ENDED && !t->stopped)
		end_program(t);
	return t->ncmds;
}

const uint8_t *x3g_output(const struct x3g_translator *t, size_t *len)
{
	*len = t->len;
	return t->out;
}

size_t x3g_warnings(const struct x3g_translator *t, const struct x3g_warning **out)
{
	*out = t->warn;
	return t->nwarn;
}

uint64_t x3g_warning_total(const struct x3g_translator *t)
{
	return t->warn_total;
}

/* A machine we can compute with: every rate and scale positive and finite. */
static int check_machine(const struct x3g_machine *m, struct st_error *err)
{
	static const char names[] = "XYZAB";

	if (m->extruder_count < 1 || m->extruder_count > 2)
		return st_error_set(err, ST_ERR_ARG,
				    "X3G machine: %d extruders; Sailfish drives 1 or 2",
				    m->extruder_count);
	for (int i = 0; i < 3 + m->extruder_count; i++) {
		const struct x3g_axis *a = &m->axis[i];

		if (!(a->steps_per_mm > 0) || !isfinite(a->steps_per_mm))
			return st_error_set(err, ST_ERR_ARG,
					    "X3G machine: %c steps per mm must be more than 0",
					    names[i]);
		if (!(a->max_feedrate > 0) || !isfinite(a->max_feedrate))
			return st_error_set(err, ST_ERR_ARG,
					    "X3G machine: %c maximum feed rate must be more than 0",
					    names[i]);
		if (i < 3 && (!(a->home_feedrate > 0) || !isfinite(a->home_feedrate)))
			return st_error_set(err, ST_ERR_ARG,
					    "X3G machine: %c homing feed rate must be more than 0",
					    names[i]);
	}
	return 0;
}

int x3g_new(const struct x3g_machine *m, const struct x3g_options *opt,
	    struct x3g_translator **out, struct st_error *err)
{
	struct x3g_translator *t;
	const char *name;
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "x3g_new: no output pointer");
	*out = NULL;
	if (!m)
		return st_error_set(err, ST_ERR_ARG, "x3g_new: no machine");
	if ((rc = check_machine(m, err)))
		return rc;
	t = calloc(1, sizeof(*t));
	if (!t)
		return st_error_set(err, ST_ERR_NOMEM, "x3g_new: out of memory");
	t->m = *m;
	if (m->extruder_count == 1)
		t->m.axis[AX_B] = t->m.axis[AX_A]; /* B is never moved; keep its maths finite */
	t->flavor = opt ? opt->flavor : X3G_FLAVOR_REPRAP;
	name = opt && opt->build_name ? opt->build_name : "Stratum";
	snprintf(t->build_name, sizeof(t->build_name), "%s", name);
	t->mask = m->extruder_count == 1 ? (BITS_XYZ | BIT_A) : BITS_AXES;
	/* GPX: the extruders start at 0 (a build starts with them reset) */
	t->known = m->extruder_count == 1 ? BIT_A : (BIT_A | BIT_B);
	for (int i = 0; i < 3; i++)
		if (m->axis[i].home_feedrate > t->feedrate)
			t->feedrate = m->axis[i].home_feedrate;
	t->speed_pc = 100;
	t->extrude_pc[0] = t->extrude_pc[1] = 100;
	*out = t;
	return 0;
}

void x3g_free(struct x3g_translator *t)
{
	free(t);
}

/* ---- decoding ------------------------------------------------------------ */

/*
 * Layouts of the action commands an X3G file may hold (s3g protocol
 * document; 155's distance is a float32 as GPX writes it).  Field types:
 * '1' uint8, '2' uint16, '4' uint32, 'i' int32, 'f' float32, 'z' a
 * NUL-terminated string; 136 (tool action) is decoded apart.
 */
struct layout {
	uint8_t code;
	const char *name;
	const char *types;
	const char *fields[X3G_FIELDS_MAX];
};

static const struct layout layouts[] = {
    {129, "queue point absolute", "iii4", {"x", "y", "z", "dda_us"}},
    {130, "set position", "iii", {"x", "y", "z"}},
    {131, "find axes minimum", "142", {"axes", "dda_us", "timeout_s"}},
    {132, "find axes maximum", "142", {"axes", "dda_us", "timeout_s"}},
    {133, "delay", "4", {"ms"}},
    {134, "change tool", "1", {"tool"}},
    {135, "wait for tool ready", "122", {"tool", "poll_ms", "timeout_s"}},
    {136, "tool action", "", {NULL}},
    {137, "enable/disable axes", "1", {"axes"}},
    {139, "queue extended point", "iiiii4", {"x", "y", "z", "a", "b", "dda_us"}},
    {140, "set extended position", "iiiii", {"x", "y", "z", "a", "b"}},
    {141, "wait for platform ready", "122", {"tool", "poll_ms", "timeout_s"}},
    {142, "queue extended point new", "iiiii41",
     {"x", "y", "z", "a", "b", "duration_us", "relative"}},
    {143, "store home positions", "1", {"axes"}},
    {144, "recall home positions", "1", {"axes"}},
    {145, "set potentiometer", "11", {"axis", "value"}},
    {146, "set RGB LED", "11111", {"red", "green", "blue", "blink", "reserved"}},
    {147, "set beep", "221", {"frequency", "ms", "reserved"}},
    {148, "pause for button", "121", {"buttons", "timeout_s", "options"}},
    {149, "display message", "1111z", {"options", "x", "y", "timeout_s"}},
    {150, "set build percentage", "11", {"percent", "reserved"}},
    {151, "queue song", "1", {"song"}},
    {152, "reset to factory", "1", {"reserved"}},
    {153, "build start notification", "4z", {"reserved"}},
    {154, "build end notification", "1", {"reserved"}},
    {155, "queue extended point x3g", "iiiii41f2",
     {"x", "y", "z", "a", "b", "dda_rate", "relative", "distance", "feedrate_x64"}},
    {156, "set segment acceleration", "1", {"on"}},
    {157, "stream version", "11142244" "1",
     {"high", "low", "reserved", "reserved32", "bot_type", "reserved16", "reserved32b",
      "reserved32c", "reserved8"}},
    {158, "pause at z", "f", {"z"}},
};

static const struct layout *find_layout(uint8_t code)
{
	for (size_t i = 0; i < sizeof(layouts) / sizeof(layouts[0]); i++)
		if (layouts[i].code == code)
			return &layouts[i];
	return NULL;
}

static uint32_t get_le(const uint8_t *p, int n)
{
	uint32_t v = 0;

	for (int i = n - 1; i >= 0; i--)
		v = (v << 8) | p[i];
	return v;
}

/* Bytes of the fixed-size fields from ty to the end or the next string. */
static size_t fixed_span(const char *ty)
{
	size_t n = 0;

	for (; *ty && *ty != 'z'; ty++)
		n += *ty == '1' ? 1 : *ty == '2' ? 2 : 4;
	return n;
}

static int cut_short(struct st_error *err, uint64_t offset, const struct layout *lo, size_t need,
		     size_t have)
{
	return st_error_set(err, ST_ERR_PARSE,
			    "byte %llu: command %u (%s) needs %zu bytes but the data ends after %zu",
			    (unsigned long long)offset, lo->code, lo->name, need, have);
}

/* 136: tool, action, payload length, payload (1 byte on/off or int16). */
static int decode_tool_action(const uint8_t *buf, size_t len, uint64_t offset,
			      const struct layout *lo, struct x3g_command *c, struct st_error *err)
{
	size_t n;

	if (len < 4)
		return cut_short(err, offset, lo, 4, len);
	n = buf[3];
	if (4 + n > X3G_PAYLOAD_MAX)
		return st_error_set(err, ST_ERR_PARSE,
				    "byte %llu: tool action states a %zu-byte payload; a command holds "
				    "at most %d bytes",
				    (unsigned long long)offset, n, X3G_PAYLOAD_MAX);
	if (len < 4 + n)
		return cut_short(err, offset, lo, 4 + n, len);
	c->fields[0] = (struct x3g_field){"tool", buf[1]};
	c->fields[1] = (struct x3g_field){"action", buf[2]};
	c->fields[2] = (struct x3g_field){"length", (double)n};
	c->nfields = 3;
	if (n == 1)
		c->fields[c->nfields++] = (struct x3g_field){"value", buf[4]};
	else if (n == 2)
		c->fields[c->nfields++] =
		    (struct x3g_field){"value", (double)(int16_t)(uint16_t)get_le(buf + 4, 2)};
	return (int)(4 + n);
}

int x3g_decode(const uint8_t *buf, size_t len, uint64_t offset, struct x3g_command *cmd,
	       struct st_error *err)
{
	struct x3g_command c;
	const struct layout *lo;
	size_t pos = 1;
	int rc;

	if (len == 0)
		return 0;
	if (!buf || !cmd)
		return st_error_set(err, ST_ERR_ARG, "x3g_decode: no buffer or no command");
	lo = find_layout(buf[0]);
	if (!lo)
		return st_error_set(err, ST_ERR_PARSE,
				    "byte %llu: %u is not an X3G action command (expected 129-158)",
				    (unsigned long long)offset, buf[0]);
	memset(&c, 0, sizeof(c));
	c.code = lo->code;
	c.name = lo->name;
	c.offset = offset;
	if (lo->code == 136) {
		rc = decode_tool_action(buf, len, offset, lo, &c, err);
		if (rc < 0)
			return rc;
		pos = (size_t)rc;
	}
	for (const char *ty = lo->types; *ty; ty++) {
		size_t k = (size_t)(ty - lo->types);

		if (*ty == 'z') {
			const uint8_t *nul;
			size_t room = len - pos;

			if (room > X3G_PAYLOAD_MAX - pos)
				room = X3G_PAYLOAD_MAX - pos;
			nul = memchr(buf + pos, 0, room);
			if (!nul) {
				if (len - pos <= room)
					return cut_short(err, offset, lo, pos + 1, len);
				return st_error_set(err, ST_ERR_PARSE,
						    "byte %llu: command %u (%s) has text without its "
						    "NUL within %d bytes",
						    (unsigned long long)offset, lo->code, lo->name,
						    X3G_PAYLOAD_MAX);
			}
			memcpy(c.text, buf + pos, (size_t)(nul - (buf + pos)));
			c.text[nul - (buf + pos)] = 0;
			c.has_text = true;
			pos = (size_t)(nul - buf) + 1;
			continue;
		}
		{
			int n = *ty == '1' ? 1 : *ty == '2' ? 2 : 4;
			double v;

			/* name the whole command's length, not the field's */
			if (len - pos < (size_t)n)
				return cut_short(err, offset, lo, pos + fixed_span(ty), len);
			if (*ty == 'i') {
				v = (double)(int32_t)get_le(buf + pos, 4);
			} else if (*ty == 'f') {
				uint32_t u = get_le(buf + pos, 4);
				float f;

				memcpy(&f, &u, sizeof(f));
				v = f;
			} else {
				v = get_le(buf + pos, n);
			}
			c.fields[c.nfields++] = (struct x3g_field){lo->fields[k], v};
			pos += (size_t)n;
		}
	}
	c.length = pos;
	*cmd = c;
	return (int)pos;
}

bool x3g_field_value(const struct x3g_command *cmd, const char *name, double *value)
{
	for (size_t i = 0; i < cmd->nfields; i++)
		if (!strcmp(cmd->fields[i].name, name)) {
			*value = cmd->fields[i].value;
			return true;
		}
	return false;
}

int x3g_format(const struct x3g_command *cmd, char *out, size_t cap)
{
	int n = snprintf(out, cap, "%u %s:", cmd->code, cmd->name), total = n;

	for (size_t i = 0; i < cmd->nfields && n >= 0; i++) {
		size_t used = (size_t)total < cap ? (size_t)total : cap;

		n = snprintf(out + used, cap - used, " %s=%.9g", cmd->fields[i].name,
			     cmd->fields[i].value);
		total += n;
	}
	if (cmd->has_text && n >= 0) {
		size_t used = (size_t)total < cap ? (size_t)total : cap;

		n = snprintf(out + used, cap - used, " text=\"%s\"", cmd->text);
		total += n;
	}
	return total;
}

void x3g_build_name(const char *path, char *name, size_t cap)
{
	const char *base = strrchr(path, '/'), *dot;
	size_t n;

	base = base ? base + 1 : path;
	dot = strrchr(base, '.');
	n = dot && dot != base ? (size_t)(dot - base) : strlen(base);
	snprintf(name, cap, "%.*s", (int)n, base);
}

/*
 * x3g_emit.c - the X3G translator's output: little-endian fields into the
 * per-line buffer, warnings, and the commands of fixed layout (s3g
 * protocol document, docs/protocols.md section 2), numbered as GPX 2.6.8
 * writes them.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "x3g_int.h"

/* ---- output ------------------------------------------------------------ */

/* Record a warning for the current line. */
void x3g_warn(struct x3g_translator *t, const char *fmt, ...)
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
void x3g_put8(struct x3g_translator *t, unsigned v)
{
	if (t->len >= OUT_CAP) {
		t->overflow = true;
		return;
	}
	t->out[t->len++] = (uint8_t)v;
}

void x3g_put16(struct x3g_translator *t, unsigned v)
{
	x3g_put8(t, v & 0xff);
	x3g_put8(t, (v >> 8) & 0xff);
}

void x3g_put32(struct x3g_translator *t, uint32_t v)
{
	for (int i = 0; i < 4; i++)
		x3g_put8(t, (v >> (8 * i)) & 0xff);
}

void x3g_put_i32(struct x3g_translator *t, double v)
{
	/* steps fit easily; clamp so a wild input cannot make the cast undefined */
	if (v > 2147483647.0)
		v = 2147483647.0;
	if (v < -2147483648.0)
		v = -2147483648.0;
	x3g_put32(t, (uint32_t)(int32_t)v);
}

void x3g_put_float(struct x3g_translator *t, float f)
{
	uint32_t u;

	memcpy(&u, &f, sizeof(u));
	x3g_put32(t, u);
}

void x3g_begin(struct x3g_translator *t, unsigned code)
{
	t->cmd_start = t->len;
	x3g_put8(t, code);
}

void x3g_end(struct x3g_translator *t)
{
	t->ncmds++;
}

/* A double as an unsigned in [0, max]; NaN and negatives give 0. */
unsigned x3g_clamp_u(double v, unsigned max)
{
	if (!(v > 0))
		return 0;
	if (v >= (double)max)
		return max;
	return (unsigned)v;
}

/* ---- commands ----------------------------------------------------------- */

void x3g_cmd_build_start(struct x3g_translator *t)
{
	x3g_begin(t, 153);
	x3g_put32(t, 0);
	for (const char *s = t->build_name; *s; s++)
		x3g_put8(t, (uint8_t)*s);
	x3g_put8(t, 0);
	x3g_end(t);
}

void x3g_cmd_percent(struct x3g_translator *t, unsigned pc)
{
	if (pc > 100)
		pc = 100;
	t->percent = pc;
	x3g_begin(t, 150);
	x3g_put8(t, pc);
	x3g_put8(t, 0);
	x3g_end(t);
}

void x3g_cmd_build_end(struct x3g_translator *t)
{
	x3g_begin(t, 154);
	x3g_put8(t, 0);
	x3g_end(t);
}

void x3g_cmd_change_tool(struct x3g_translator *t, int tool)
{
	x3g_begin(t, 134);
	x3g_put8(t, (unsigned)tool);
	x3g_end(t);
}

/* 136 tool action: a 16-bit argument for targets (3 nozzle, 31 platform),
 * one byte for toggles (12 fan, 13 blower "valve"). */
void x3g_cmd_tool_action(struct x3g_translator *t, int tool, unsigned action, unsigned value)
{
	bool wide = action == 3 || action == 31;

	x3g_begin(t, 136);
	x3g_put8(t, (unsigned)tool);
	x3g_put8(t, action);
	x3g_put8(t, wide ? 2 : 1);
	if (wide)
		x3g_put16(t, value);
	else
		x3g_put8(t, value ? 1 : 0);
	x3g_end(t);
}

/* 135 wait for tool / 141 wait for platform: poll every 100 ms. */
void x3g_cmd_wait(struct x3g_translator *t, unsigned code, int tool, unsigned timeout)
{
	x3g_begin(t, code);
	x3g_put8(t, (unsigned)tool);
	x3g_put16(t, 100);
	x3g_put16(t, timeout);
	x3g_end(t);
}

void x3g_cmd_steppers(struct x3g_translator *t, unsigned axes, bool on)
{
	x3g_begin(t, 137);
	x3g_put8(t, (axes & BITS_AXES) | (on ? 0x80 : 0));
	x3g_end(t);
}

void x3g_cmd_one_byte(struct x3g_translator *t, unsigned code, unsigned v)
{
	x3g_begin(t, code);
	x3g_put8(t, v);
	x3g_end(t);
}

/* 149: the text in rows of at most 20 characters (the LCD is 4 x 20);
 * bit 0 keeps the screen, bit 1 marks the last part, bit 2 waits for the
 * button. */
void x3g_cmd_message(struct x3g_translator *t, const char *msg, unsigned row, unsigned col,
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
		x3g_begin(t, 149);
		x3g_put8(t, bits);
		x3g_put8(t, col);
		x3g_put8(t, row);
		x3g_put8(t, secs & 0xff);
		for (size_t i = 0; i < n; i++)
			x3g_put8(t, (uint8_t)msg[sent + i]);
		x3g_put8(t, 0);
		x3g_end(t);
		sent += n;
	}
}


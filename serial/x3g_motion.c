/*
 * x3g_motion.c - the X3G translator's moves (155, or 139 when a position
 * is unknown), homing and G92, with GPX 2.6.8's step rounding, DDA and
 * feed-rate limits so that the output matches `gpx -m fcp`.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "x3g_int.h"

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
void x3g_queue_absolute(struct x3g_translator *t)
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
	x3g_begin(t, 139);
	x3g_put_i32(t, steps[0]);
	x3g_put_i32(t, steps[1]);
	x3g_put_i32(t, steps[2]);
	x3g_put_i32(t, -steps[3]);
	x3g_put_i32(t, -steps[4]);
	x3g_put32(t, (uint32_t)dda);
	x3g_end(t);
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
		x3g_queue_absolute(t);
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

	x3g_begin(t, 155);
	for (int i = 0; i < 5; i++)
		x3g_put_i32(t, steps[i]);
	x3g_put32(t, x3g_clamp_u(dda_rate, 0xffffffffu));
	x3g_put8(t, relative ? BITS_AXES : (unknown | BIT_A | BIT_B));
	x3g_put_float(t, (float)dist);
	x3g_put16(t, x3g_clamp_u(fr * 64.0, 0xffffffffu) & 0xffff);
	x3g_end(t);
}

/* Where the line's words take the head (GPX calculate_target_position);
 * delta gets the change per axis, relative whether X/Y/Z moved relatively
 * from a known position. */
static void calc_target(struct x3g_translator *t, const struct x3g_words *w, double delta[5],
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

void x3g_move(struct x3g_translator *t, const struct x3g_words *w)
{
	double delta[5];
	bool relative;

	calc_target(t, w, delta, &relative);
	queue_point(t, w->flag, delta, relative);
	memcpy(t->cur, t->tgt, sizeof(t->cur));
	if (!t->rel_xyz)
		t->known |= w->flag & t->mask;
}

/*
 * The arc of a G2/G3 as the chords Marlin's ARC_SUPPORT cuts it into
 * (st_arc.h), each one point: the centre from I J (from the start) or R,
 * Z and E spread evenly, the last chord ending on the target; in the
 * line's own frame (work offset, relative or absolute axes).
 */
void x3g_arc(struct x3g_translator *t, const struct gcode_line *l, const struct x3g_words *w)
{
	const double *off = t->offset[t->cur_offset];
	int ax = t->cur_tool == 0 ? AX_A : AX_B;
	bool cw = l->number == 2, rel_e = t->rel_xyz || t->rel_e;
	double from[3], to[3], o[2] = {0, 0}, r, de = 0, prev[3];

	if ((t->known & BITS_XYZ) != BITS_XYZ) {
		x3g_warn(t, "G%d from a position not known (before homing or G92); nothing written",
			 l->number);
		return;
	}
	for (int i = 0; i < 3; i++) {
		from[i] = prev[i] = t->cur[i] - off[i];
		to[i] = !(w->flag & (1u << i)) ? from[i] : t->rel_xyz ? from[i] + w->v[i] : w->v[i];
	}
	if (gcode_word_value(l, 'R', &r)) {
		st_arc_r_offset(to[0] - from[0], to[1] - from[1], r, cw, o);
	} else {
		gcode_word_value(l, 'I', &o[0]);
		gcode_word_value(l, 'J', &o[1]);
	}
	if (o[0] == 0 && o[1] == 0) {
		x3g_warn(t, "G%d needs its centre: I and J, or R; nothing written", l->number);
		return;
	}
	if (w->flag & (1u << ax))
		de = rel_e ? w->v[ax] : w->v[ax] - t->cur[ax];
	double ang = st_arc_sweep(-o[0], -o[1], to[0] - from[0] - o[0], to[1] - from[1] - o[1], cw,
				  to[0] == from[0] && to[1] == from[1]);
	unsigned n = st_arc_segments(hypot(hypot(o[0], o[1]) * fabs(ang), to[2] - from[2]));
	double e0 = t->cur[ax];

	for (unsigned k = 1; k <= n; k++) {
		double f = (double)k / n, c = cos(ang * f), s = sin(ang * f), p[3];
		struct x3g_words cw_ = {.flag = BITS_XYZ | (w->flag & BIT_F), .f = w->f};

		p[0] = from[0] + o[0] - o[0] * c + o[1] * s;
		p[1] = from[1] + o[1] - o[0] * s - o[1] * c;
		p[2] = from[2] + (to[2] - from[2]) * f;
		if (k == n)
			memcpy(p, to, sizeof(p));
		for (int i = 0; i < 3; i++)
			cw_.v[i] = t->rel_xyz ? p[i] - prev[i] : p[i];
		if (de != 0) {
			cw_.flag |= 1u << ax;
			cw_.v[ax] = rel_e ? de * f - de * (k - 1) / n : e0 + de * f;
		}
		x3g_move(t, &cw_);
		memcpy(prev, p, sizeof(prev));
	}
}

/* 131/132 find axes minimum/maximum at the slowest homing rate of the axes. */
static void home_axes(struct x3g_translator *t, unsigned axes, enum x3g_endstop dir,
		      const struct x3g_words *w)
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
			x3g_warn(t, "%c homes to its %s endstop but this printer's is at the %s", "XYZ"[i],
			     dir == X3G_ENDSTOP_MAX ? "maximum" : "minimum",
			     a->endstop == X3G_ENDSTOP_MAX ? "maximum" : "minimum");
	}
	x3g_begin(t, dir == X3G_ENDSTOP_MIN ? 131 : 132);
	x3g_put8(t, axes & BITS_XYZ);
	x3g_put32(t, x3g_clamp_u(round(sqrt(n) / fr * 60e6 / longest), 0xffffffffu));
	x3g_put16(t, t->m.home_timeout & 0xffff);
	x3g_end(t);
}

void x3g_after_homing(struct x3g_translator *t, unsigned flag)
{
	set_unknown(t, flag);
	t->excess[0] = t->excess[1] = 0;
}

/* G28: each axis to its own endstop, the X end first as GPX does. */
void x3g_g28(struct x3g_translator *t, struct x3g_words *w)
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
	x3g_after_homing(t, w->flag);
}

/* G161/G162: the named axes to one end. */
void x3g_g161(struct x3g_translator *t, const struct x3g_words *w, enum x3g_endstop dir,
		 const char *name)
{
	if (w->flag & BIT_F)
		t->feedrate = w->f;
	if (!(w->flag & BITS_XYZ)) {
		x3g_warn(t, "%s names no axis (write e.g. %s X Y); nothing written", name, name);
		return;
	}
	home_axes(t, w->flag & BITS_XYZ, dir, w);
	x3g_after_homing(t, w->flag);
}

/* G92 -> 140 set extended position, which sets all five axes. */
void x3g_g92(struct x3g_translator *t, const struct x3g_words *w)
{
	double steps[5];

	for (int i = 0; i < 5; i++)
		if (w->flag & (1u << i))
			t->cur[i] = w->v[i];
	if (((t->known | w->flag) & t->mask) != t->mask)
		x3g_warn(t, "G92 sets every axis in X3G; axes not given and not yet known are set "
			"to 0");
	for (int i = 0; i < 5; i++)
		steps[i] = round(t->cur[i] * axis_spm(t, i));
	x3g_begin(t, 140);
	for (int i = 0; i < 5; i++)
		x3g_put_i32(t, steps[i]);
	x3g_end(t);
	t->known |= w->flag & t->mask;
}


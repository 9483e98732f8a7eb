/*
 * st_arc.h - how Marlin draws a G2/G3 arc (motion/G2_G3.cpp, ARC_SUPPORT):
 * as chords of MM_PER_ARC_SEGMENT, Z and E spread evenly over them, the
 * last one ending on the target (Marlin 1.1 and 2.0; 2.1 also cuts at
 * least MIN_CIRCLE_SEGMENTS, 72, to a circle, which is not modelled here).
 * Shared by whatever reads or times arcs: the G-code walker
 * (serial/gcwalk.h), the simulated Marlin, the X3G translator and the
 * G-code writer's time estimate (slicer/gcode_writer.h).
 */
#ifndef STRATUM_ST_ARC_H
#define STRATUM_ST_ARC_H

#include <math.h>
#include <stdbool.h>

/* Marlin's MM_PER_ARC_SEGMENT, mm, and a bound on the chords per arc (a
 * 1 m radius then strays under 0.001 mm from the circle). */
#define ST_ARC_SEGMENT_MM 1.0
#define ST_ARC_SEGMENTS_MAX 3600

/*
 * st_arc_sweep - the signed angle (rad) an arc turns from the radius
 * vector (rx, ry) (centre to start) to (tx, ty) (centre to target):
 * clockwise (cw, negative) or counter-clockwise, of magnitude in (0, 2 pi];
 * a whole circle when the target is the start (same, as Marlin reads it).
 */
static inline double st_arc_sweep(double rx, double ry, double tx, double ty, bool cw, bool same)
{
	double ang = atan2(rx * ty - ry * tx, rx * tx + ry * ty);

	if (ang < 0)
		ang += 2 * M_PI;
	if (cw)
		ang -= 2 * M_PI;
	if (fabs(ang) < 1e-9 && same)
		ang = cw ? -2 * M_PI : 2 * M_PI;
	return ang;
}

/*
 * st_arc_r_offset - the centre, from the start, of an arc given by its
 * radius r (R) to a target (dx, dy) from the start, as Marlin reads it:
 * on the side the sign of r and the direction give, at the chord's
 * midpoint when |r| is shorter than half the chord.  false (off left at
 * 0) when r is 0 or the target is the start.
 */
static inline bool st_arc_r_offset(double dx, double dy, double r, bool cw, double off[2])
{
	double hx = dx / 2, hy = dy / 2, len = hypot(hx, hy);

	off[0] = off[1] = 0;
	if (r == 0 || len == 0)
		return false;
	double side = (cw != (r < 0)) ? -1 : 1, h2 = (r - len) * (r + len);
	double h = h2 > 0 ? sqrt(h2) : 0;

	off[0] = hx - hy / len * side * h;
	off[1] = hy + hx / len * side * h;
	return true;
}

/* st_arc_segments - the chords Marlin cuts an arc mm long (with its Z
 * travel) into: whole MM_PER_ARC_SEGMENTs, at least 1. */
static inline unsigned st_arc_segments(double mm)
{
	double n = floor(mm / ST_ARC_SEGMENT_MM);

	return n < 1 ? 1 : n > ST_ARC_SEGMENTS_MAX ? ST_ARC_SEGMENTS_MAX : (unsigned)n;
}

#endif /* STRATUM_ST_ARC_H */

/*
 * gcode_writer_cool.c - cooling of a planned layer, PrusaSlicer's rule:
 * the fan from the layer's estimated time, and the slow-down of a layer
 * faster than slowdown_below_layer_time (see gcode_writer.h).
 */
#include "gcode_writer_int.h"

#include <math.h>

#define SLOWDOWN_STEPS 40 /* bisection steps for the slow-down factor */

/* Speed of an extrusion slowed by factor f, never below min_print_speed
 * unless it was slower already. */
static double slowed(double v, double f, double min_speed)
{
	return fmax(v * f, fmin(v, min_speed));
}

/* Planner time of the layer's ops with extrusions slowed by f. */
static int layer_time(struct gcodew *w, const double start[EST_AXES], double f, double *t)
{
	struct est_planner *p = est_planner_new(&w->s->limits, start, w->err);
	struct est_result r;
	double x = start[EST_X], y = start[EST_Y], z = start[EST_Z], e = 0;
	int rc = 0;

	if (!p)
		return w->err ? w->err->code : ST_ERR_NOMEM;
	if (w->accel > 0) /* what the machine was last told */
		est_planner_set_accel(p, &w->s->limits, w->accel, w->accel);
	for (size_t i = 0; i < w->nops && rc == 0; i++) {
		const struct op *o = &w->ops[i];
		double v = o->f;
		if (o->kind == OP_ACCEL) {
			int a = gcodew_accel_written(w->s, o->f);
			est_planner_set_accel(p, &w->s->limits, a, a);
		}
		if (o->kind != OP_MOVE)
			continue;
		double from[EST_AXES] = {x, y, z, e};
		if (o->xy) {
			x = o->x;
			y = o->y;
		}
		z = o->z;
		if (o->mv == MV_EXTRUDE) {
			e += o->e;
			v = slowed(v, f, w->s->min_print_speed);
		} else if (o->mv == MV_RETRACT) {
			e -= o->e;
		} else if (o->mv == MV_UNRETRACT) {
			e += o->e;
		}
		if (o->arc)
			rc = gcodew_arc_estimate(p, from, (double[EST_AXES]){x, y, z, e}, o->cx,
						 o->cy, o->ccw, v, w->err);
		else
			rc = est_planner_add(p, &(struct est_move){x, y, o->z, e, v}, w->err);
	}
	est_planner_result(p, &r);
	est_planner_free(p);
	*t = r.time_s;
	return rc;
}

/* The first layer (0-based) the fan may run on: a ramp starts on layer 2
 * at the earliest (PrusaSlicer). */
static size_t first_fan_layer(const struct gcodew_settings *s)
{
	return s->disable_fan_first_layers <= 0 && s->full_fan_speed_layer > 0
		   ? 1
		   : (size_t)s->disable_fan_first_layers;
}

/* fan percent on layer li, ramped up to full at full_fan_speed_layer (1-based). */
static int fan_ramp(const struct gcodew_settings *s, size_t li, int fan)
{
	double d = (double)first_fan_layer(s);

	if ((int)li + 1 >= s->full_fan_speed_layer)
		return fan;
	return (int)lround(fan * ((double)li + 1 - d) / (s->full_fan_speed_layer - d));
}

/* Fan percent of layer li taking t seconds (PrusaSlicer's rule). */
static int fan_for(const struct gcodew_settings *s, size_t li, double t)
{
	int fan;

	if (li < first_fan_layer(s))
		return 0;
	fan = s->fan_always_on ? s->min_fan_speed : 0;
	if (!s->cooling)
		return fan;
	if (t < s->slowdown_below_layer_time) {
		fan = s->max_fan_speed;
	} else if (t < s->fan_below_layer_time) {
		double k = (t - s->slowdown_below_layer_time) /
			   (s->fan_below_layer_time - s->slowdown_below_layer_time);
		fan = (int)lround(k * s->min_fan_speed + (1 - k) * s->max_fan_speed);
	}
	return fan_ramp(s, li, fan);
}

/* Decide the layer's fan and slow its extrusions down if it is too fast. */
int gcodew_cool_layer(struct gcodew *w, size_t li, const double start[EST_AXES])
{
	const struct gcodew_settings *s = w->s;
	double t, target = s->slowdown_below_layer_time, lo = 0, hi = 1;
	int rc = layer_time(w, start, 1, &t);

	if (rc)
		return rc;
	w->layer_fan = fan_for(s, li, t);
	w->bridge_fan = s->cooling && li >= first_fan_layer(s)
			    ? fan_ramp(s, li, s->bridge_fan_speed)
			    : -1;
	if (!s->cooling || t >= target || w->nops == 0)
		return 0;
	rc = layer_time(w, start, 0, &t);
	if (rc)
		return rc;
	if (t <= target) { /* even at min_print_speed it is too fast */
		hi = 0;
	} else {
		for (int i = 0; i < SLOWDOWN_STEPS && rc == 0; i++) {
			double mid = 0.5 * (lo + hi);
			rc = layer_time(w, start, mid, &t);
			if (t > target)
				lo = mid;
			else
				hi = mid;
		}
	}
	for (size_t i = 0; i < w->nops; i++)
		if (w->ops[i].kind == OP_MOVE && w->ops[i].mv == MV_EXTRUDE)
			w->ops[i].f = slowed(w->ops[i].f, hi, s->min_print_speed);
	return rc;
}

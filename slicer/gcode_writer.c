/*
 * gcode_writer.c - layer stack to Marlin G-code (see gcode_writer.h).
 *
 * Each layer is first planned into a list of operations (moves with their
 * kind, and role changes), so the layer's time can be estimated and its
 * speeds lowered before anything is written; then the operations are
 * emitted.  The print is generated once, into an anonymous temporary file
 * while the estimator runs beside it; the header with the estimates is
 * then written and the body copied after it.
 *
 * E is kept in integer units of 1e-5 mm (the written precision): the
 * position written is extruded - retracted, both rounded from exact
 * running sums, so per-layer amounts do not drift and every unretraction
 * restores exactly what its retraction took.
 *
 * The planning is gcode_writer_plan.c, the cooling gcode_writer_cool.c,
 * the settings table, placeholders and header gcode_writer_config.c; what
 * they share is gcode_writer_int.h.
 */
#include "gcode_writer_int.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "placeholder.h"
#include "st_file.h"
#include "travel.h"

#define E_UNITS 100000.0 /* E written in 1e-5 mm */
#define E_DIGITS 5
#define XYZ_DIGITS 3

/* ---------------------------------------------------------------------------
 * Emission
 */

/* printf to the current output. */
void gcodew_put(struct gcodew *w, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	vfprintf(w->fp, fmt, ap);
	va_end(ap);
}

/* Set the fan to percent when it differs from what was written. */
static void set_fan(struct gcodew *w, int percent)
{
	if (percent == w->fan)
		return;
	if (w->s->fan_on_off)
		gcodew_put(w, "%s", percent ? "M126\n" : "M127\n");
	else if (percent == 0)
		gcodew_put(w, "M107\n");
	else
		gcodew_put(w, "M106 S%ld\n", lround(percent * 255.0 / 100));
	w->fan = percent;
}

/* Write acceleration v (an OP_ACCEL) when it differs from the last, in
 * the flavour's words, and time what follows with it. */
static void set_accel(struct gcodew *w, double v)
{
	int a = gcodew_accel_written(w->s, v);

	if (a <= 0 || a == w->accel)
		return;
	if (w->s->accel_form == GCODEW_ACCEL_M201_M202)
		gcodew_put(w, "M201 X%d Y%d\nM202 X%d Y%d\n", a, a, a, a);
	else
		gcodew_put(w, "M204 %c%d\n", w->s->accel_form == GCODEW_ACCEL_M204_P ? 'P' : 'S', a);
	w->accel = a;
	est_planner_set_accel(w->est, &w->s->limits, a, a);
}

/*
 * Append " <letter><u / 10^digits>" to line at *len: a move's word, its
 * zero before the point dropped as PrusaSlicer writes it ("E.03113",
 * "Z.2"): a byte on almost every extrusion, and every G-code reader takes
 * it (Marlin's number parser, and stratum's own: send, x3g, preview).
 */
static void put_word(char *line, size_t *len, char letter, int64_t u, int digits)
{
	char *v = line + *len + 2;
	size_t n = gcodew_fmt_units(v, u, digits);
	size_t sign = v[0] == '-';

	line[*len] = ' ';
	line[*len + 1] = letter;
	if (n > sign + 1 && v[sign] == '0' && v[sign + 1] == '.') {
		memmove(v + sign, v + sign + 1, n - sign); /* the '\0' too */
		n--;
	}
	*len += 2 + n;
}

/* Write one move op (G1, or G2/G3 for an arc) and feed it to the
 * estimator. */
static int emit_move(struct gcodew *w, const struct op *o)
{
	int64_t x = o->xy ? llround(o->x * XYZ_UNITS) : w->wx;
	int64_t y = o->xy ? llround(o->y * XYZ_UNITS) : w->wy;
	int64_t z = llround(o->z * XYZ_UNITS), epos, de, ci = 0, cj = 0;
	long long f = llround(o->f * 60);
	bool mx, my, mz, arc;
	int arc_rc = 0;
	char line[6 * NUM_MAX];
	size_t len;

	switch (o->mv) {
	case MV_EXTRUDE:
		w->ext_exact += o->e;
		w->ext_units = llround(w->ext_exact * E_UNITS);
		w->filament_mm += o->e;
		break;
	case MV_RETRACT:
		w->r_exact += o->e;
		w->r_units = llround(w->r_exact * E_UNITS);
		break;
	case MV_UNRETRACT:
		w->r_exact = 0;
		w->r_units = 0;
		break;
	case MV_TRAVEL:
		break;
	}
	epos = w->ext_units - w->r_units;
	de = epos - w->epos_units;
	mx = o->xy && (!w->xy_known || x != w->wx);
	my = o->xy && (!w->xy_known || y != w->wy);
	mz = !w->z_known || z != w->wz;
	if (!mx && !my && !mz && de == 0)
		return 0;
	if (f < 1)
		f = 1;
	/* An arc's centre, from its start as written (I J); a line when its
	 * ends meet once written, which G2/G3 would read as a whole circle. */
	arc = o->arc && w->xy_known && (mx || my);
	if (arc) {
		ci = llround(o->cx * XYZ_UNITS) - w->wx;
		cj = llround(o->cy * XYZ_UNITS) - w->wy;
		arc = ci || cj;
	}
	/* The line is assembled here and written at once (see gcodew_fmt_units). */
	len = 2;
	memcpy(line, arc ? (o->ccw ? "G3" : "G2") : "G1", 2);
	if (mx)
		put_word(line, &len, 'X', x, XYZ_DIGITS);
	if (my)
		put_word(line, &len, 'Y', y, XYZ_DIGITS);
	if (arc) {
		put_word(line, &len, 'I', ci, XYZ_DIGITS);
		put_word(line, &len, 'J', cj, XYZ_DIGITS);
	}
	if (mz)
		put_word(line, &len, 'Z', z, XYZ_DIGITS);
	if (de)
		put_word(line, &len, 'E', w->s->use_relative_e_distances ? de : epos, E_DIGITS);
	if (f != w->wf)
		put_word(line, &len, 'F', f, 0);
	line[len++] = '\n';
	fwrite(line, 1, len, w->fp);
	w->moves++;
	if (arc) {
		double from[EST_AXES] = {w->wx / XYZ_UNITS, w->wy / XYZ_UNITS, w->wz / XYZ_UNITS,
					 w->e_machine};
		double to[EST_AXES] = {x / XYZ_UNITS, y / XYZ_UNITS, z / XYZ_UNITS,
				       w->e_machine + de / E_UNITS};
		arc_rc = gcodew_arc_estimate(w->est, from, to, (w->wx + ci) / XYZ_UNITS,
					     (w->wy + cj) / XYZ_UNITS, o->ccw, f / 60.0, w->err);
	}
	if (o->xy) {
		w->wx = x;
		w->wy = y;
		w->xy_known = true;
	}
	w->wz = z;
	w->z_known = true;
	w->wf = f;
	w->epos_units = epos;
	w->e_machine += de / E_UNITS;
	if (arc)
		return arc_rc;
	return est_planner_add(w->est,
			       &(struct est_move){x / XYZ_UNITS, y / XYZ_UNITS, z / XYZ_UNITS,
						  w->e_machine, f / 60.0},
			       w->err);
}

/* Write the planned ops of the current layer. */
static int emit_ops(struct gcodew *w)
{
	int rc = 0;

	for (size_t i = 0; i < w->nops && rc == 0; i++) {
		const struct op *o = &w->ops[i];
		if (o->kind == OP_ACCEL) {
			set_accel(w, o->f);
		} else if (o->kind == OP_ROLE) {
			gcodew_put(w, ";TYPE:%s\n", path_role_name(o->role));
			bool bridge = o->role == PATH_BRIDGE || o->role == PATH_OVERHANG_PERIMETER;
			set_fan(w, bridge && w->bridge_fan >= 0 ? w->bridge_fan : w->layer_fan);
		} else {
			rc = emit_move(w, o);
		}
	}
	return rc;
}

/* G92 E0: the written E position becomes 0, retraction state kept. */
static void reset_e(struct gcodew *w)
{
	gcodew_put(w, "G92 E0\n");
	w->ext_exact -= w->epos_units / E_UNITS;
	w->ext_units -= w->epos_units;
	w->epos_units = 0;
}

static int put_expanded(struct gcodew *w, const char *text, const char *what, size_t li,
			double z);

/* Plan, cool and write layer li. */
static int do_layer(struct gcodew *w, const struct layer_paths *l, size_t li)
{
	const struct gcodew_settings *s = w->s;
	double start[EST_AXES] = {w->wx / XYZ_UNITS, w->wy / XYZ_UNITS, w->wz / XYZ_UNITS, 0};
	char nz[NUM_MAX], nh[NUM_MAX];
	int rc;

	if (!isfinite(l->z) || !isfinite(l->height) || l->z <= 0 || l->height <= 0 ||
	    l->height > l->z + 1e-9)
		return st_error_set(w->err, ST_ERR_RANGE,
				    "G-code: layer %zu has Z %g mm and height %g mm; both must be "
				    "> 0 with the height at most Z",
				    li + 1, l->z, l->height);
	rc = gcodew_plan_layer(w, l, li);
	if (rc == 0)
		rc = gcodew_cool_layer(w, li, start);
	if (rc)
		return rc;
	gcodew_fmt_num(nz, l->z, XYZ_DIGITS);
	gcodew_fmt_num(nh, l->height, XYZ_DIGITS);
	/* PrusaSlicer 2.5's order: the layer change comments, before_layer_gcode
	 * (the new layer's number and Z, the old maximum), layer_gcode (the new
	 * maximum). */
	rc = gcodew_progress_mark(w, false);
	if (rc)
		return rc;
	gcodew_put(w, ";LAYER_CHANGE\n;Z:%s\n;HEIGHT:%s\n", nz, nh);
	rc = put_expanded(w, s->before_layer_gcode, "before_layer_gcode", li, l->z);
	if (rc)
		return rc;
	w->max_z = fmax(w->max_z, l->z);
	rc = put_expanded(w, s->layer_gcode, "layer_gcode", li, l->z);
	if (rc)
		return rc;
	if (!s->use_relative_e_distances && li > 0)
		reset_e(w);
	if (li == 1 && s->temperature > 0 && s->temperature != s->first_layer_temperature)
		gcodew_put(w, "M104 S%d ; set temperature\n", s->temperature);
	if (li == 1 && s->bed_temperature > 0 &&
	    s->bed_temperature != s->first_layer_bed_temperature)
		gcodew_put(w, "M140 S%d ; set bed temperature\n", s->bed_temperature);
	set_fan(w, w->layer_fan);
	return emit_ops(w);
}

/* Write custom G-code text, ending it with a newline. */
static void put_custom(struct gcodew *w, const char *text)
{
	size_t n = strlen(text);

	if (n)
		gcodew_put(w, "%s%s", text, text[n - 1] == '\n' ? "" : "\n");
}

/* Expand text for layer li at z and write it; nothing for an empty text. */
static int put_expanded(struct gcodew *w, const char *text, const char *what, size_t li, double z)
{
	char *out = NULL;
	int rc;

	if (!*text)
		return 0;
	rc = gcodew_set_layer_vars(w->vars, li, z, w->max_z, w->err);
	if (rc == 0)
		rc = ph_expand(text, what, w->vars, 0, &out, w->err);
	if (rc == 0)
		put_custom(w, out);
	free(out);
	return rc;
}

/* The machine limits in PrusaSlicer 2.5's words (GCode.cpp
 * print_machine_envelope), integers rounded, jerks with two decimals. */
static void put_limits(struct gcodew *w)
{
	const struct gcodew_settings *s = w->s;
	const struct est_limits *l = &s->limits;
	const double *a = l->max_acceleration, *f = l->max_feedrate, *j = l->max_jerk;
	double travel = s->limits_form == GCODEW_LIMITS_MARLIN2 ? l->accel_travel
								 : l->accel_extruding;

	if (s->limits_form == GCODEW_LIMITS_NONE)
		return;
	gcodew_put(w, "M201 X%d Y%d Z%d E%d ; sets maximum accelerations, mm/sec^2\n",
		   (int)(a[0] + 0.5), (int)(a[1] + 0.5), (int)(a[2] + 0.5), (int)(a[3] + 0.5));
	gcodew_put(w, "M203 X%d Y%d Z%d E%d ; sets maximum feedrates, mm / sec\n",
		   (int)(f[0] + 0.5), (int)(f[1] + 0.5), (int)(f[2] + 0.5), (int)(f[3] + 0.5));
	gcodew_put(w,
		   "M204 P%d R%d T%d ; sets acceleration (P, T) and retract acceleration (R), "
		   "mm/sec^2\n",
		   (int)(l->accel_extruding + 0.5), (int)(l->accel_retracting + 0.5),
		   (int)(travel + 0.5));
	gcodew_put(w, "M205 X%.2f Y%.2f Z%.2f E%.2f ; sets the jerk limits, mm/sec\n", j[0], j[1],
		   j[2], j[3]);
	gcodew_put(w, "M205 S%d T%d ; sets the minimum extruding and travel feed rate, mm/sec\n",
		   (int)(s->min_extruding_rate + 0.5), (int)(s->min_travel_rate + 0.5));
}

/* The part before the first layer: limits, temperatures, start G-code, modes. */
static void put_start(struct gcodew *w)
{
	const struct gcodew_settings *s = w->s;
	const char *start = w->start;
	bool bed_set = gcodew_text_sets(start, 140, 190),
	     nozzle_set = gcodew_text_sets(start, 104, 109);

	put_limits(w);
	if (!bed_set && s->first_layer_bed_temperature > 0)
		gcodew_put(w, "M190 S%d ; set bed temperature and wait for it to be reached\n",
			   s->first_layer_bed_temperature);
	if (!nozzle_set && s->first_layer_temperature > 0)
		gcodew_put(w, "M104 S%d ; set temperature\n", s->first_layer_temperature);
	put_custom(w, start);
	put_custom(w, w->start_filament); /* PrusaSlicer: the first tool's filament */
	if (!nozzle_set && s->first_layer_temperature > 0)
		gcodew_put(w, "M109 S%d ; set temperature and wait for it to be reached\n",
			   s->first_layer_temperature);
	gcodew_put(w, "G21 ; set units to millimeters\nG90 ; use absolute coordinates\n");
	gcodew_put(w, "%s\n",
		   s->use_relative_e_distances ? "M83 ; use relative distances for extrusion"
					       : "M82 ; use absolute distances for extrusion");
	gcodew_put(w, "G92 E0\n");
	w->fan = -1;
	set_fan(w, 0);
}

/* The part after the last layer: final retraction, fan off, end G-code. */
static int put_end(struct gcodew *w)
{
	int rc = 0;

	/* Final retraction, left for the end G-code to undo. */
	w->nops = 0;
	if (w->pos_known && w->s->retract_length > 0) {
		rc = gcodew_plan_retract(w);
		if (rc == 0)
			rc = emit_ops(w);
	}
	set_fan(w, 0);
	if (rc == 0)
		rc = put_expanded(w, w->s->end_filament_gcode, "end_filament_gcode",
				  w->nlayers ? w->nlayers - 1 : 0, w->layer_z);
	if (rc == 0)
		rc = put_expanded(w, w->s->end_gcode, "end_gcode", w->nlayers ? w->nlayers - 1 : 0,
				  w->layer_z);
	return rc;
}

/* Add the beads of layer l to the per-role sums of the header's widths
 * (in the order of the layers, so the sums do not depend on batching). */
static void add_widths(struct gcodew *w, const struct layer_paths *l)
{
	for (size_t pi = 0; pi < l->n; pi++) {
		const struct toolpath *p = &l->paths[pi];
		for (size_t k = 0; k + 1 < (p->closed ? p->n + 1 : p->n); k++) {
			const struct path_point *a = &p->pts[k], *b = &p->pts[trav(p, false, k + 1)];
			double d = hypot((double)(b->x - a->x), (double)(b->y - a->y));
			w->len[p->role] += d;
			w->area[p->role] += d * a->width;
		}
	}
}

/* The machine state before the first line: nothing known, fan unset. */
static void writer_start(struct gcodew *w)
{
	w->pos_known = false;
	w->spiral_below = false;
	w->px = w->py = w->pz = 0;
	w->nwipe = 0;
	w->ext_exact = w->r_exact = w->e_machine = 0;
	w->ext_units = w->r_units = w->epos_units = 0;
	w->xy_known = w->z_known = false;
	w->wx = w->wy = w->wz = 0;
	w->wf = 0;
	w->fan = -1;
	w->accel = 0;
	w->moves = 0;
	w->filament_mm = 0;
}

void gcodew_free(struct gcodew *w)
{
	if (!w)
		return;
	if (w->body)
		fclose(w->body);
	st_file_abort(&w->out); /* a file begun and never finished */
	est_planner_free(w->est);
	free(w->ops);
	free(w->wipe);
	free(w->done);
	travel_route_free(&w->route);
	gcodew_simplify_free(w);
	free(w->m73);
	free(w->start);
	free(w->start_filament);
	ph_vars_free(w->vars);
	free(w);
}

/*
 * The variables, the start texts expanded, and every other text expanded
 * once as it would be on its first use, so a mistake in any of them is
 * refused before the first layer rather than after the last.
 */
static int begin_texts(struct gcodew *w, struct st_error *err)
{
	const struct gcodew_settings *s = w->s;
	const char *const later[][2] = {{s->before_layer_gcode, "before_layer_gcode"},
					{s->layer_gcode, "layer_gcode"},
					{s->end_filament_gcode, "end_filament_gcode"},
					{s->end_gcode, "end_gcode"}};
	int rc;

	w->vars = gcodew_vars_new(s, w->nlayers, err);
	if (!w->vars)
		return err && err->code ? err->code : ST_ERR_NOMEM;
	rc = ph_expand(s->start_gcode, "start_gcode", w->vars, 0, &w->start, err);
	if (rc == 0)
		rc = ph_expand(s->start_filament_gcode, "start_filament_gcode", w->vars, 0,
			       &w->start_filament, err);
	for (size_t i = 0; rc == 0 && i < sizeof(later) / sizeof(later[0]); i++) {
		char *out = NULL;

		rc = gcodew_set_layer_vars(w->vars, 0, s->first_layer_height, s->first_layer_height,
					   err);
		if (rc == 0)
			rc = ph_expand(later[i][0], later[i][1], w->vars, 0, &out, err);
		free(out);
	}
	return rc;
}

int gcodew_begin(const struct gcodew_settings *s, size_t nlayers, struct gcodew **out,
		 struct st_error *err)
{
	struct gcodew *w;
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "G-code: gcodew_begin needs an out pointer");
	*out = NULL;
	if (!s)
		return st_error_set(err, ST_ERR_ARG, "G-code: no layers, settings or output given");
	rc = gcodew_settings_check(s, err);
	if (rc)
		return rc;
	w = calloc(1, sizeof(*w));
	if (!w)
		return st_error_set(err, ST_ERR_NOMEM, "G-code: out of memory");
	w->s = s;
	w->nlayers = nlayers;
	w->err = err;
	rc = begin_texts(w, err);
	if (rc)
		goto out_free;
	w->fil_area = M_PI * s->filament_diameter * s->filament_diameter / 4;

	/* One pass: the body into a temporary file, the estimator beside it. */
	w->body = tmpfile();
	if (!w->body) {
		rc = st_error_set(err, ST_ERR_IO, "G-code: cannot create a temporary file: %s",
				  strerror(errno));
		goto out_free;
	}
	w->est = est_planner_new(&s->limits, NULL, err);
	if (!w->est) {
		rc = err && err->code ? err->code : ST_ERR_NOMEM;
		goto out_free;
	}
	w->fp = w->body;
	writer_start(w);
	rc = gcodew_progress_mark(w, false);
	if (rc)
		goto out_free;
	put_start(w);
	*out = w;
	return 0;
out_free:
	gcodew_free(w);
	return rc;
}

int gcodew_layer(struct gcodew *w, const struct layer_paths *l, struct st_error *err)
{
	if (!w || !l)
		return st_error_set(err, ST_ERR_ARG, "G-code: no writer or layer given");
	if (w->next >= w->nlayers)
		return st_error_set(err, ST_ERR_ARG, "G-code: layer %zu is one more than the %zu "
				    "announced", w->next + 1, w->nlayers);
	w->err = err;
	add_widths(w, l);
	return do_layer(w, l, w->next++);
}

int gcodew_finish(struct gcodew *w, FILE *fp, struct gcodew_summary *sum, struct st_error *err)
{
	struct gcodew_summary res = {0};
	struct est_result er;
	int rc;

	if (!w || !fp)
		return st_error_set(err, ST_ERR_ARG, "G-code: no writer or output given");
	if (w->next != w->nlayers)
		return st_error_set(err, ST_ERR_ARG, "G-code: %zu of the %zu layers announced were "
				    "written", w->next, w->nlayers);
	w->err = err;
	rc = put_end(w);
	if (rc == 0)
		rc = gcodew_progress_mark(w, true);
	est_planner_result(w->est, &er);
	if (rc == 0 && (fflush(w->body) != 0 || ferror(w->body)))
		rc = st_error_set(err, ST_ERR_IO, "G-code: write failed: %s", strerror(errno));
	if (rc)
		return rc;
	res.time_s = er.time_s;
	res.filament_mm = w->filament_mm;
	res.filament_cm3 = w->filament_mm * w->fil_area / 1000;
	res.filament_g = res.filament_cm3 * w->s->filament_density;
	res.layers = w->nlayers;
	res.moves = w->moves;

	/* The header first, then the body as generated. */
	w->fp = fp;
	gcodew_put_header(w, &res);
	rc = gcodew_copy_body(w, fp, res.time_s, err);
	if (rc == 0 && (fflush(fp) != 0 || ferror(fp)))
		rc = st_error_set(err, ST_ERR_IO, "G-code: write failed: %s", strerror(errno));
	if (rc == 0 && sum)
		*sum = res;
	return rc;
}

int gcodew_write_stream(const struct layer_stack *stack, const struct gcodew_settings *s,
			FILE *fp, struct gcodew_summary *sum, struct st_error *err)
{
	struct st_error local;
	struct gcodew *w = NULL;
	int rc;

	if (!err)
		err = &local;
	if (!stack || !s || !fp || (stack->nlayers && !stack->layers))
		return st_error_set(err, ST_ERR_ARG, "G-code: no layers, settings or output given");
	rc = gcodew_begin(s, stack->nlayers, &w, err);
	for (size_t li = 0; rc == 0 && li < stack->nlayers; li++)
		rc = gcodew_layer(w, &stack->layers[li], err);
	if (rc == 0)
		rc = gcodew_finish(w, fp, sum, err);
	gcodew_free(w);
	return rc;
}

int gcodew_begin_file(const struct gcodew_settings *s, size_t nlayers, const char *path,
		      struct gcodew **out, struct st_error *err)
{
	struct st_file_out o;
	int rc;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "G-code: gcodew_begin_file needs an out pointer");
	*out = NULL;
	if (!path || !*path)
		return st_error_set(err, ST_ERR_ARG, "G-code: no output file name given");
	if ((rc = st_file_begin(&o, path, err)))
		return rc;
	if ((rc = gcodew_begin(s, nlayers, out, err))) {
		st_file_abort(&o);
		return rc;
	}
	(*out)->out = o;
	return 0;
}

int gcodew_finish_file(struct gcodew *w, struct gcodew_summary *sum, struct st_error *err)
{
	int rc;

	if (!w || !w->out.f)
		return st_error_set(err, ST_ERR_ARG, "G-code: no writer of a file given");
	if ((rc = gcodew_finish(w, w->out.f, sum, err))) {
		st_file_abort(&w->out);
		return rc;
	}
	return st_file_commit(&w->out, err);
}

int gcodew_write_file(const struct layer_stack *stack, const struct gcodew_settings *s,
		      const char *path, struct gcodew_summary *sum, struct st_error *err)
{
	struct st_error local;
	struct gcodew *w = NULL;
	int rc;

	if (!err)
		err = &local;
	if (!path || !*path)
		return st_error_set(err, ST_ERR_ARG, "G-code: no output file name given");
	if (!stack || !s || (stack->nlayers && !stack->layers))
		return st_error_set(err, ST_ERR_ARG, "G-code: no layers, settings or output given");
	rc = gcodew_begin_file(s, stack->nlayers, path, &w, err);
	for (size_t li = 0; rc == 0 && li < stack->nlayers; li++)
		rc = gcodew_layer(w, &stack->layers[li], err);
	if (rc == 0)
		rc = gcodew_finish_file(w, sum, err);
	gcodew_free(w);
	return rc;
}

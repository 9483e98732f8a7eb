/*
 * x3g.c - G-code to X3G translation (x3g.h): the translator's life, tools
 * and temperatures, build start and end, and the G- and M-code dispatch.
 * Bytes and fixed commands are in x3g_emit.c, moves in x3g_motion.c, the
 * decoder in x3g_decode.c.
 *
 * The numbers follow GPX 2.6.8 (markwal/GPX src/gpx/gpx.c), the translator
 * every Sailfish user has, so that our files match `gpx -m fcp` command for
 * command; where GPX does something only a serial link makes sense of
 * (writing query commands such as M105 into a file) we warn instead.
 */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "x3g_int.h"

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

/* ---- tools and temperatures --------------------------------------------- */

static void set_nozzle(struct x3g_translator *t, int tool, unsigned temp)
{
	x3g_cmd_tool_action(t, tool, 3, temp);
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
	x3g_cmd_change_tool(t, to);
	if ((t->known & t->mask) == t->mask) {
		memcpy(t->tgt, t->cur, sizeof(t->tgt));
		x3g_queue_absolute(t);
	}
	t->cur_tool = to;
}

static unsigned timeout_of(const struct x3g_words *w)
{
	return (w->flag & BIT_P) ? x3g_clamp_u(w->p, 0xffff) : WAIT_FOREVER;
}

/* The tool whose controller drives the platform heater: tool 0, or the one
 * T names (GPX's r1d lets either extruder board carry it). */
static int platform_tool(const struct x3g_translator *t, const struct x3g_words *w)
{
	return (w->flag & BIT_T) ? t->tgt_tool : 0;
}

/* M140 (and Makerbot M109): the platform target. */
static void set_platform(struct x3g_translator *t, const struct x3g_words *w, int m)
{
	int tool = platform_tool(t, w);
	unsigned temp;

	if (!t->m.heated_platform) {
		x3g_warn(t, "M%d: this printer has no heated platform; nothing written", m);
		return;
	}
	if (!(w->flag & BIT_S)) {
		x3g_warn(t, "M%d without S (the temperature); nothing written", m);
		return;
	}
	temp = x3g_clamp_u(w->s, 0xffff);
	x3g_cmd_tool_action(t, tool, 31, temp);
	t->platform[tool] = temp;
}

/* M190/M134: set (when S is given) and wait for the platform. */
static void wait_platform(struct x3g_translator *t, const struct x3g_words *w, int m)
{
	int tool = platform_tool(t, w);

	if (!t->m.heated_platform) {
		x3g_warn(t, "M%d: this printer has no heated platform; nothing written", m);
		return;
	}
	if (w->flag & BIT_S)
		set_platform(t, w, m);
	if (tool != 0 || t->platform[0] > 0)
		x3g_cmd_wait(t, 141, tool, timeout_of(w));
	else
		x3g_warn(t, "M%d: no platform temperature set to wait for; no wait written", m);
}

static void m104(struct x3g_translator *t, const struct x3g_words *w)
{
	unsigned temp;

	if (!(w->flag & BIT_S)) {
		x3g_warn(t, "M104 without S (the temperature); nothing written");
		return;
	}
	temp = x3g_clamp_u(w->s, NOZZLE_MAX);
	if (temp && t->active[t->tgt_tool])
		temp = t->active[t->tgt_tool];
	set_nozzle(t, t->tgt_tool, temp);
}

static void m109_reprap(struct x3g_translator *t, const struct x3g_words *w)
{
	m104(t, w);
	if ((w->flag & BIT_S) && t->nozzle[t->tgt_tool] > 0)
		x3g_cmd_wait(t, 135, t->tgt_tool, timeout_of(w));
}

/* M6/M116: change tool (M6), then wait for the platform and the nozzles. */
static void m6_m116(struct x3g_translator *t, const struct x3g_words *w, int m)
{
	unsigned timeout = timeout_of(w);

	if (m == 6 && t->tgt_tool != t->cur_tool)
		tool_change(t);
	if (t->m.heated_platform && t->platform[0] > 0)
		x3g_cmd_wait(t, 141, 0, timeout);
	else if (t->m.heated_platform && t->platform[1] > 0)
		x3g_cmd_wait(t, 141, 1, timeout);
	if (m == 116 && !(w->flag & BIT_T)) {
		if (t->m.extruder_count > 1 && t->nozzle[1] > 0)
			x3g_cmd_wait(t, 135, 1, timeout);
		if (t->nozzle[0] > 0)
			x3g_cmd_wait(t, 135, 0, timeout);
	} else if (t->nozzle[t->tgt_tool] > 0) {
		x3g_cmd_wait(t, 135, t->tgt_tool, timeout);
	}
}

/* M106/M107: RepRap flavour drives the print-cooling blower (tool action
 * 13, "valve"), Makerbot flavour the heatsink fan (12), as GPX does. */
static void fan(struct x3g_translator *t, const struct x3g_words *w, unsigned dflt)
{
	unsigned on = (w->flag & BIT_S) ? (x3g_clamp_u(w->s, 255) != 0) : dflt;

	x3g_cmd_tool_action(t, t->tgt_tool, t->flavor == X3G_FLAVOR_REPRAP ? 13 : 12, on);
}

/* ---- build start and end ------------------------------------------------ */

static void start_program(struct x3g_translator *t, unsigned pc)
{
	t->state = PROG_RUNNING;
	x3g_cmd_build_start(t);
	x3g_cmd_percent(t, pc);
	x3g_cmd_change_tool(t, t->cur_tool); /* a known tool to start from */
}

static void end_program(struct x3g_translator *t)
{
	t->state = PROG_ENDED;
	x3g_cmd_percent(t, 100);
	x3g_cmd_build_end(t);
}

static void m73(struct x3g_translator *t, const struct x3g_words *w)
{
	unsigned pc;

	if (!(w->flag & BIT_P)) {
		x3g_warn(t, "M73 without P (the percentage); nothing written");
		return;
	}
	pc = x3g_clamp_u(w->p, 100);
	if (t->state == PROG_READY && pc < 100)
		start_program(t, pc);
	else if (t->state != PROG_ENDED && pc == 100)
		end_program(t);
	else if (t->state != PROG_ENDED && t->percent < pc)
		x3g_cmd_percent(t, pc);
}

/* ---- dispatch ------------------------------------------------------------ */

/* Collect the words GPX reads; E becomes A or B of the current tool. */
static void read_words(const struct x3g_translator *t, const struct gcode_line *l,
		       struct x3g_words *w)
{
	static const char axes[] = "XYZAB";
	double v;

	memset(w, 0, sizeof(*w));
	for (int i = 0; i < 5; i++)
		if (gcode_find_word(l, axes[i])) {
			w->flag |= 1u << i;
			w->v[i] = gcode_word_value(l, axes[i], &v) ? v : 0;
		}
	if (gcode_word_value(l, 'F', &v)) { /* a bare F keeps the feed rate */
		w->flag |= BIT_F;
		w->f = v;
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
		w->t = gcode_word_value(l, 'T', &v) ? (int)x3g_clamp_u(v, 65535) : 0;
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
			x3g_warn(t, "';@flavor %s': the flavour is reprap or makerbot; ignored", arg);
	} else if (strcmp(name, "body") && strcmp(name, "header") && strcmp(name, "footer") &&
		   strncmp(name, "open_", 5) && strncmp(name, "close_", 6)) {
		x3g_warn(t, "GPX macro ';@%s' is not supported; ignored", name);
	}
}

static void g_code(struct x3g_translator *t, const struct gcode_line *l, struct x3g_words *w)
{
	if (l->subcode >= 0) {
		x3g_warn(t, "G%d.%d is not supported in X3G; nothing written", l->number, l->subcode);
		return;
	}
	switch (l->number) {
	case 0:
	case 1:
		x3g_move(t, w);
		break;
	case 2:
	case 3:
		x3g_arc(t, l, w);
		break;
	case 4:
		if (w->flag & BIT_P) {
			x3g_begin(t, 133);
			x3g_put32(t, x3g_clamp_u(w->p, 0xffffffffu));
			x3g_end(t);
		} else {
			x3g_warn(t, "G4 without P (milliseconds); nothing written");
		}
		break;
	case 10:
		if ((w->flag & BIT_P) && w->p >= 1 && w->p <= 6) {
			int i = (int)w->p;

			for (int k = 0; k < 3; k++)
				if (w->flag & (1u << k))
					t->offset[i][k] = w->v[k];
			if (i <= 2 && (w->flag & BIT_R))
				t->standby[i - 1] = x3g_clamp_u(w->r, NOZZLE_MAX);
			if (i <= 2 && (w->flag & BIT_S))
				t->active[i - 1] = x3g_clamp_u(w->s, NOZZLE_MAX);
		} else {
			x3g_warn(t, "G10 without a coordinate system P1-P6; ignored");
		}
		break;
	case 15:
	case 21:
	case 71:
		break; /* cartesian, millimetres: what X3G is anyway */
	case 28:
		x3g_g28(t, w);
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
		x3g_g92(t, w);
		break;
	case 161:
		x3g_g161(t, w, X3G_ENDSTOP_MIN, "G161");
		break;
	case 162:
		x3g_g161(t, w, X3G_ENDSTOP_MAX, "G162");
		break;
	default:
		x3g_warn(t, "G%d is not supported in X3G; nothing written", l->number);
	}
}

static void steppers(struct x3g_translator *t, const struct x3g_words *w, bool on)
{
	unsigned all = t->m.extruder_count == 1 ? (BITS_XYZ | BIT_A) : BITS_AXES;

	x3g_cmd_steppers(t, (w && (w->flag & BITS_AXES)) ? w->flag & BITS_AXES : all, on);
}

static void m_code(struct x3g_translator *t, const struct gcode_line *l, struct x3g_words *w)
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
			x3g_warn(t, "M70 without a message (write it as a comment: M70 P5 (text)); "
				"nothing written");
			break;
		}
		x3g_cmd_message(t, (w->text && *w->text) ? w->text : "Press M to continue",
			    (w->flag & BIT_Y) ? x3g_clamp_u(w->v[1], 3) : 0,
			    (w->flag & BIT_X) ? x3g_clamp_u(w->v[0], 19) : 0,
			    (w->flag & BIT_P) ? x3g_clamp_u(w->p, 0xffff) : 0, m == 71);
		break;
	case 72:
		if (w->flag & BIT_P)
			x3g_cmd_one_byte(t, 151, x3g_clamp_u(w->p, 2));
		else
			x3g_warn(t, "M72 without P (the song, 0-2); nothing written");
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
		x3g_cmd_steppers(t, t->tgt_tool == 0 ? BIT_A : BIT_B, m != 103);
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
			x3g_warn(t, "M108 without T is not supported in X3G; nothing written");
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
		x3g_cmd_tool_action(t, t->tgt_tool, 13,
				m == 127 ? 0 : ((w->flag & BIT_S) ? (x3g_clamp_u(w->s, 255) != 0) : 1));
		break;
	case 131:
	case 132:
		if (!(w->flag & BITS_AXES)) {
			x3g_warn(t, "M%d names no axis (write e.g. M%d X Y Z A B); nothing written", m, m);
			break;
		}
		x3g_cmd_one_byte(t, m == 131 ? 143 : 144, w->flag & BITS_AXES);
		if (m == 132) {
			x3g_after_homing(t, w->flag);
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
			x3g_cmd_wait(t, 135, t->tgt_tool, timeout_of(w));
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
			t->speed_pc = x3g_clamp_u(w->s, 1000);
		break;
	case 221:
		if ((w->flag & BIT_S) && w->s > 0)
			t->extrude_pc[(w->flag & BIT_T) ? t->tgt_tool : t->cur_tool] =
			    x3g_clamp_u(w->s, 1000);
		break;
	case 300:
		x3g_begin(t, 147);
		x3g_put16(t, (w->flag & BIT_S) ? x3g_clamp_u(w->s, 0xffff) : 300);
		x3g_put16(t, (w->flag & BIT_P) ? x3g_clamp_u(w->p, 0xffff) : 1000);
		x3g_put8(t, 0);
		x3g_end(t);
		break;
	case 320:
	case 321:
		x3g_cmd_one_byte(t, 156, m == 320);
		break;
	default:
		if (l->subcode >= 0)
			x3g_warn(t, "M%d.%d is not supported in X3G; nothing written", m, l->subcode);
		else
			x3g_warn(t, "M%d is not supported in X3G; nothing written", m);
	}
}

int x3g_translate(struct x3g_translator *t, const struct gcode_line *l, uint64_t lineno,
		  struct st_error *err)
{
	struct x3g_words w;

	if (!t || !l)
		return st_error_set(err, ST_ERR_ARG, "x3g_translate: no translator or no line");
	t->len = 0;
	t->ncmds = 0;
	t->nwarn = 0;
	t->overflow = false;
	t->lineno = lineno;
	if (t->stopped) {
		if (l->letter)
			x3g_warn(t, "after M2 (end of program): ignored");
		return 0;
	}
	if (l->has_comment && l->comment[0] == '@' && isalpha((unsigned char)l->comment[1]))
		macro(t, l->comment);
	if (l->letter == 0 || l->letter == '@')
		return 0;
	if (l->letter == GCODE_LETTER_TEXT) {
		x3g_warn(t, "'%.60s' is not a G, M or T command (a Klipper macro or a text); X3G "
			"cannot express it; nothing written",
		     l->text);
		return 0;
	}
	if (l->letter == 'T' && l->number < 0) {
		x3g_warn(t, "%s (a Prusa MMU filament command) is not supported in X3G; nothing written",
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
			x3g_warn(t, "T%d: this printer has %d extruder%s", w.t, t->m.extruder_count,
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

int x3g_translate_aside(struct x3g_translator *t, const struct gcode_line *l, uint64_t lineno,
			struct st_error *err)
{
	int tgt = t ? t->tgt_tool : 0;
	int rc = x3g_translate(t, l, lineno, err);

	if (rc >= 0 && l->letter != 'T')
		t->tgt_tool = tgt;
	return rc;
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


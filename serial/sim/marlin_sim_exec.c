/*
 * marlin_sim_exec.c - the simulated Marlin's executor: commands run from the
 * queue (moves timed through the planner, M109/M190 waits, M115, M112),
 * and the heaters' physics; replies go out through msim_send.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "marlin_sim_int.h"
#include "st_arc.h"

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

/* Plan a straight move from s->pos to target (X Y Z E) into the planner
 * (a free block is guaranteed), at the modal feed rate. */
static void sim_plan_block(struct sim_marlin *s, const double target[4], double now)
{
	double d2 = 0, de = fabs(target[3] - s->pos[3]);
	for (int a = 0; a < 3; a++)
		d2 += (target[a] - s->pos[a]) * (target[a] - s->pos[a]);
	memcpy(s->pos, target, sizeof(s->pos));
	double d = d2 > 0 ? sqrt(d2) : de;
	double dur = sim_move_time(d, s->feed) / s->o.speedup;
	if (dur <= 0)
		return;
	sim_machine_add(&s->machine_us, dur * s->o.speedup);
	double start = now;
	for (size_t i = 0; i < s->planner_n; i++)
		if (s->planner_end[i] > start)
			start = s->planner_end[i];
	s->planner_end[s->planner_n++] = start + dur;
}

/* The target of a G0-G3 (X Y Z E, absolute), its F taken. */
static void sim_target(struct sim_marlin *s, const struct gcode_line *g, double target[4])
{
	static const char axes[4] = {'X', 'Y', 'Z', 'E'};
	double v;
	if (gcode_word_value(g, 'F', &v) && v > 0)
		s->feed = v / 60.0;
	for (int a = 0; a < 4; a++) {
		bool rel = a == 3 ? s->rel_e : s->rel_xyz;
		target[a] = s->pos[a];
		if (gcode_word_value(g, axes[a], &v))
			target[a] = rel ? s->pos[a] + v : v;
	}
}

/* Set up s->arc for the G2/G3 g as Marlin's plan_arc reads it (I J from
 * the start, or R); false for an arc without its centre. */
static bool sim_arc_start(struct sim_marlin *s, const struct gcode_line *g)
{
	struct sim_arc *a = &s->arc;
	bool cw = g->number == 2;
	double to[4], off[2] = {0, 0}, r;

	sim_target(s, g, to);
	if (gcode_word_value(g, 'R', &r)) {
		st_arc_r_offset(to[0] - s->pos[0], to[1] - s->pos[1], r, cw, off);
	} else {
		gcode_word_value(g, 'I', &off[0]);
		gcode_word_value(g, 'J', &off[1]);
	}
	if (off[0] == 0 && off[1] == 0)
		return false;
	a->centre[0] = s->pos[0] + off[0];
	a->centre[1] = s->pos[1] + off[1];
	a->rvec[0] = -off[0];
	a->rvec[1] = -off[1];
	a->angle = st_arc_sweep(a->rvec[0], a->rvec[1], to[0] - a->centre[0], to[1] - a->centre[1],
				cw, to[0] == s->pos[0] && to[1] == s->pos[1]);
	a->nseg = st_arc_segments(hypot(hypot(off[0], off[1]) * fabs(a->angle), to[2] - s->pos[2]));
	a->seg = 0;
	memcpy(a->from, s->pos, sizeof(a->from));
	memcpy(a->to, to, sizeof(a->to));
	return true;
}

/* Plan the arc's chords while the planner has room; true when all are
 * planned (the last one ends on the target, as Marlin's). */
static bool sim_arc_plan(struct sim_marlin *s, double now)
{
	struct sim_arc *a = &s->arc;

	while (a->seg < a->nseg && msim_planner_free(s, now) > 0) {
		double p[4], f = (double)++a->seg / a->nseg, c = cos(a->angle * f),
			     sn = sin(a->angle * f);
		if (a->seg == a->nseg) {
			memcpy(p, a->to, sizeof(p));
		} else {
			p[0] = a->centre[0] + a->rvec[0] * c - a->rvec[1] * sn;
			p[1] = a->centre[1] + a->rvec[0] * sn + a->rvec[1] * c;
			p[2] = a->from[2] + (a->to[2] - a->from[2]) * f;
			p[3] = a->from[3] + (a->to[3] - a->from[3]) * f;
		}
		sim_plan_block(s, p, now);
	}
	return a->seg == a->nseg;
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
	msim_send(s, "FIRMWARE_NAME:Marlin 2.1.2 (Stratum simulator) "
		    "SOURCE_CODE_URL:github.com/MarlinFirmware/Marlin PROTOCOL_VERSION:1.0 "
		    "MACHINE_TYPE:Stratum Simulated Printer EXTRUDER_COUNT:1 "
		    "UUID:cede2a2f-41a2-4748-9b12-c55c62f367ff");
	for (size_t i = 0; i < sizeof(caps) / sizeof(caps[0]); i++)
		msim_sendf(s, "Cap:%s", caps[i]);
	msim_sendf(s, "Cap:ADVANCED_OK:%d", s->o.advanced_ok ? 1 : 0);
}

/* Start the queue-head command.  Returns true when it is finished. */
static bool sim_exec_start(struct sim_marlin *s, struct sim_cmd *c, double now)
{
	const struct gcode_line *g = &c->g;
	double v, target[4];
	char buf[160];

	if (!c->parsed || g->letter == 0) {
		if (c->raw[0])
			msim_sendf(s, "echo:Unknown command: \"%s\"", c->raw);
		return true;
	}
	if (g->letter == 'G') {
		switch (g->number) {
		case 0: case 1:
			if (msim_planner_free(s, now) == 0) {
				s->blk = SIM_BLK_PLANNER_SLOT;
				return false;
			}
			sim_target(s, g, target);
			sim_plan_block(s, target, now);
			return true;
		case 2: case 3: /* chords of MM_PER_ARC_SEGMENT, as Marlin's ARC_SUPPORT */
			if (!sim_arc_start(s, g)) {
				msim_send(s, "Error:G2/G3 bad parameters");
				return true;
			}
			if (sim_arc_plan(s, now))
				return true;
			s->blk = SIM_BLK_ARC;
			return false;
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
			msim_temp_string(s, buf, sizeof(buf));
			msim_sendf(s, "ok%s", buf);
			return true;
		case 110:
			if (!c->has_n && gcode_word_value(g, 'N', &v))
				s->last_n = (long)v;
			return true;
		case 114:
			msim_sendf(s, "X:%.2f Y:%.2f Z:%.2f E:%.2f Count X:0 Y:0 Z:0", s->pos[0],
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
	msim_sendf(s, "echo:Unknown command: \"%s\"", c->raw);
	return true;
}

/* Is the blocked head command done? */
static bool sim_exec_poll(struct sim_marlin *s, struct sim_cmd *c, double now)
{
	double target[4];

	switch (s->blk) {
	case SIM_BLK_PLANNER_SLOT:
		if (msim_planner_free(s, now) == 0)
			return false;
		sim_target(s, &c->g, target);
		sim_plan_block(s, target, now);
		return true;
	case SIM_BLK_ARC:
		return sim_arc_plan(s, now);
	case SIM_BLK_SYNC_TIMED:
		if (!s->blk_synced) {
			if (msim_planner_free(s, now) < SIM_PLANNER)
				return false;
			s->blk_synced = true;
			s->blk_until = now + s->blk_dur;
			sim_machine_add(&s->machine_us, s->blk_dur * s->o.speedup);
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
			msim_temp_string(s, buf, sizeof(buf));
			msim_sendf(s, "%s W:?", buf);
			s->next_temp_report = now + 1.0 / s->o.speedup;
		}
		return false;
	}
	default:
		return true;
	}
}

/* Run queued commands as far as they go at time now. */
void msim_execute(struct sim_marlin *s, double now)
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
				msim_reset_state(s);
				s->tx_len = s->tx_off = s->marks_n = 0;
				msim_boot(s, now);
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
				msim_send(s, "echo:busy: processing");
				s->next_busy = now + SIM_KEEPALIVE_S;
			}
			return;
		}
		s->blk = SIM_BLK_NONE;
		if (!(c->parsed && c->g.letter == 'M' && c->g.number == 105))
			msim_ok(s, c, now);
		if (c->has_n)
			atomic_store(&s->answered_n, c->n);
		s->q_head = (s->q_head + 1) % s->o.bufsize;
		s->q_count--;
		msim_serial_commands(s); /* the main loop reads input between commands */
	}
}

/* Heaters move toward their targets; M155 auto-reports. */
void msim_physics(struct sim_marlin *s, double now, double dt)
{
	for (int i = 0; i < 2; i++) {
		struct sim_heater *h = &s->heater[i];
		h->temp = sim_heater_step(h->temp, h->target, SIM_AMBIENT, h->heat_rate, h->cool_rate,
					  dt * s->o.speedup);
	}
	if (s->blk == SIM_BLK_HEAT && !s->halted) /* M109/M190: the machine waits */
		sim_machine_add(&s->machine_us, dt * s->o.speedup);
	if (s->autoreport_s > 0 && now >= s->next_autoreport && !s->halted) {
		char buf[160];
		msim_temp_string(s, buf, sizeof(buf));
		msim_send(s, buf);
		s->next_autoreport = now + s->autoreport_s;
	}
}

/* Write the reply lines whose last byte has crossed the link by now (each
 * starts when it is ready and the line before it is through); lower *wake
 * to when the next one will have. */

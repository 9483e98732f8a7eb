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
	sim_machine_add(&s->machine_us, dur * s->o.speedup);
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
	double v;
	char buf[160];

	if (!c->parsed || g->letter == 0) {
		if (c->raw[0])
			msim_sendf(s, "echo:Unknown command: \"%s\"", c->raw);
		return true;
	}
	if (g->letter == 'G') {
		switch (g->number) {
		case 0: case 1: case 2: case 3:
			if (msim_planner_free(s, now) == 0) {
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
	switch (s->blk) {
	case SIM_BLK_PLANNER_SLOT:
		if (msim_planner_free(s, now) == 0)
			return false;
		sim_plan_move(s, &c->g, now);
		return true;
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

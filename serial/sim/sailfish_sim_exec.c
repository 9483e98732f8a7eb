/*
 * sailfish_sim_exec.c - the simulated Sailfish's command processor: action
 * commands from the command buffer through the planner, homing, waits and
 * resets, and the heaters' physics.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sailfish_sim_int.h"

static void sf_plan(struct sim_sailfish *s, double dur, double now)
{
	if (dur <= 0)
		return;
	sim_machine_add(&s->machine_us, dur);
	double start = now;
	for (size_t i = 0; i < s->planner_n; i++)
		if (s->planner_end[i] > start)
			start = s->planner_end[i];
	s->planner_end[s->planner_n++] = start + dur / s->o.speedup;
}

/* Targets of a 5-axis move; returns the largest step count. */
static uint32_t sf_targets(struct sim_sailfish *s, const uint8_t *p, uint8_t rel)
{
	uint32_t most = 0;
	for (int i = 0; i < 5; i++) {
		int32_t v = (int32_t)sf_rd32(p + 4 * i);
		int64_t t = (rel >> i) & 1 ? (int64_t)s->pos[i] + v : v;
		uint64_t d = (uint64_t)llabs(t - s->pos[i]);
		if (d > most)
			most = d > UINT32_MAX ? UINT32_MAX : (uint32_t)d;
		s->pos[i] = (int32_t)t;
	}
	return most;
}

/* Commands the firmware runs without waiting for the planner to empty
 * (Command.cc's list of pipelined commands). */
static bool sf_pipelined(uint8_t code)
{
	switch (code) {
	case 139: case 142: case 155: case 137: case 134: case 140: case 156:
	case 144: case 131: case 132: case 136: case 148: case 150:
		return true;
	default:
		return false;
	}
}

/* One log line: sequence number, code, name, fields. */
static void sf_log(struct sim_sailfish *s, const uint8_t *c, size_t n)
{
	if (!s->log)
		return;
	FILE *f = s->log;
	fprintf(f, "%llu %u %s", (unsigned long long)s->seq, c[0], s3g_command_name(c[0]));
	switch (c[0]) {
	case 139: case 142: case 155: case 140:
		fprintf(f, " X=%d Y=%d Z=%d A=%d B=%d", (int32_t)sf_rd32(c + 1),
			(int32_t)sf_rd32(c + 5), (int32_t)sf_rd32(c + 9), (int32_t)sf_rd32(c + 13),
			(int32_t)sf_rd32(c + 17));
		if (c[0] == 139)
			fprintf(f, " us_per_step=%u", sf_rd32(c + 21));
		if (c[0] == 142)
			fprintf(f, " us=%u rel=0x%02X", sf_rd32(c + 21), c[25]);
		if (c[0] == 155) {
			uint32_t fb = sf_rd32(c + 26);
			float d;
			memcpy(&d, &fb, sizeof(d));
			fprintf(f, " rate=%u rel=0x%02X mm=%.4f feed=%.3f", sf_rd32(c + 21), c[25],
				(double)d, sf_rd16(c + 30) / 64.0);
		}
		break;
	case 131: case 132:
		fprintf(f, " axes=0x%02X us_per_step=%u timeout_s=%u", c[1], sf_rd32(c + 2),
			sf_rd16(c + 6));
		break;
	case 133:
		fprintf(f, " ms=%u", sf_rd32(c + 1));
		break;
	case 134: case 151: case 154: case 137: case 143: case 144: case 156: case 152:
		fprintf(f, " value=0x%02X", c[1]);
		break;
	case 135: case 141:
		fprintf(f, " tool=%u poll_ms=%u timeout_s=%u", c[1], sf_rd16(c + 2), sf_rd16(c + 4));
		break;
	case 136:
		fprintf(f, " tool=%u cmd=%u len=%u", c[1], c[2], c[3]);
		if (c[3] == 2 && n >= 6)
			fprintf(f, " value=%d", (int16_t)sf_rd16(c + 4));
		else if (c[3] == 1 && n >= 5)
			fprintf(f, " value=%u", c[4]);
		break;
	case 150:
		fprintf(f, " percent=%u", c[1]);
		break;
	case 149:
		fprintf(f, " options=0x%02X x=%u y=%u timeout_s=%u text=\"%.*s\"", c[1], c[2], c[3],
			c[4], (int)(n > 6 ? n - 6 : 0), (const char *)c + 5);
		break;
	case 153:
		fprintf(f, " name=\"%.*s\"", (int)(n > 6 ? n - 6 : 0), (const char *)c + 5);
		break;
	default:
		break;
	}
	fputc('\n', f);
	fflush(f);
}

/* Run the command taken out of the buffer. */
static void sf_execute(struct sim_sailfish *s, const uint8_t *c, size_t n, double now)
{
	switch (c[0]) {
	case 139: {
		uint32_t steps = sf_targets(s, c + 1, 0);
		sf_plan(s, (double)steps * sf_rd32(c + 21) * 1e-6, now);
		break;
	}
	case 142:
		sf_targets(s, c + 1, c[25]);
		sf_plan(s, sf_rd32(c + 21) * 1e-6, now);
		break;
	case 155: {
		uint32_t steps = sf_targets(s, c + 1, c[25]);
		uint32_t rate = sf_rd32(c + 21);
		if (rate)
			sf_plan(s, (double)steps / rate, now);
		break;
	}
	case 140:
		for (int i = 0; i < 5; i++)
			s->pos[i] = (int32_t)sf_rd32(c + 1 + 4 * i);
		break;
	case 131: case 132: {
		double t = sf_rd16(c + 6);
		s->mode = SF_HOMING;
		s->mode_until = now + (t > 0 && t < SF_HOME_S ? t : SF_HOME_S) / s->o.speedup;
		sim_machine_add(&s->machine_us, t > 0 && t < SF_HOME_S ? t : SF_HOME_S);
		break;
	}
	case 133:
		s->mode = SF_DELAY;
		s->mode_until = now + sf_rd32(c + 1) / 1000.0 / s->o.speedup;
		sim_machine_add(&s->machine_us, sf_rd32(c + 1) / 1000.0);
		break;
	case 134:
		s->tool = c[1] ? 1 : 0;
		break;
	case 135: case 141: {
		unsigned t = sf_rd16(c + 4);
		s->mode = c[0] == 135 ? SF_WAIT_TOOL : SF_WAIT_PLATFORM;
		s->wait_tool = c[1] == 1 ? 1 : 0;
		s->mode_until = t ? now + t / s->o.speedup : INFINITY;
		break;
	}
	case 136:
		if (n >= 6 && c[3] == 2) {
			int v = (int16_t)sf_rd16(c + 4);
			if (c[2] == S3G_TA_SET_TEMP)
				s->heater[c[1] == 1 ? 1 : 0].target = v;
			else if (c[2] == S3G_TA_SET_PLATFORM_TEMP)
				s->heater[2].target = v;
		}
		break;
	case 153: {
		size_t l = n > 6 ? n - 6 : 0;
		if (l >= sizeof(s->build_name))
			l = sizeof(s->build_name) - 1;
		memcpy(s->build_name, c + 5, l);
		s->build_name[l] = '\0';
		s->build_state = S3G_BUILD_RUNNING;
		s->build_t0 = now;
		s->line = 0;
		break;
	}
	case 154:
		s->last_line = s->line;
		s->build_state = S3G_BUILD_FINISHED;
		for (int i = 0; i < 3; i++)
			s->heater[i].target = 0;
		break;
	default:
		break;
	}
}

/* Is the command in progress done? */
static bool sf_mode_done(struct sim_sailfish *s, double now)
{
	switch (s->mode) {
	case SF_DELAY:
	case SF_HOMING:
		return now >= s->mode_until;
	case SF_WAIT_TOOL:
	case SF_WAIT_PLATFORM: {
		struct sf_heater *h = &s->heater[s->mode == SF_WAIT_TOOL ? s->wait_tool : 2];
		if (now >= s->mode_until || h->target <= 0)
			return true;
		return fabs(h->temp - h->target) <= SF_READY_BAND;
	}
	default:
		return true;
	}
}

/* The command processor (command::runCommandSlice). */
void sfsim_commands(struct sim_sailfish *s, double now)
{
	uint8_t c[4 + 255 + 61]; /* the longest command (136: 4 + 255) and then some */
	while (!s->unplugged && !s->paused && now >= s->boot_until) {
		if (s->mode != SF_READY) {
			if (!sf_mode_done(s, now))
				return;
			s->mode = SF_READY;
		}
		if (!s->cb_len)
			return;
		size_t have = sfsim_cb_peek(s, c, sizeof(c));
		int len = s3g_action_length(c, have);
		/* runCommandSlice waits until the whole command is in the
		 * buffer: the host may split one across packets, and a packet
		 * spoilt past CRC-8 may carry a code of another length (run
		 * early, it read stale bytes past the end of the buffer) */
		if (len == 0 || (len > 0 && (size_t)len > have))
			return;
		if (len < 0) { /* not a command the firmware knows: skip the byte */
			if (s->log)
				fprintf(s->log, "- %u unknown command byte skipped\n", c[0]);
			sfsim_cb_pop(s, 1);
			continue;
		}
		size_t used = sfsim_planner_used(s, now);
		if (!sf_pipelined(c[0]) && used > 0)
			return;
		bool move = c[0] == 139 || c[0] == 142 || c[0] == 155;
		if (move && used >= SF_PLANNER)
			return;
		if (s->o.reset_at > 0 && s->seq + 1 == (uint64_t)s->o.reset_at &&
		    s->resets == 0) {
			if (s->log) {
				fprintf(s->log, "# board reset before command %llu\n",
					(unsigned long long)(s->seq + 1));
				fflush(s->log);
			}
			sfsim_hard_reset(s, now);
			return;
		}
		sfsim_cb_pop(s, (size_t)len);
		s->seq++;
		if (c[0] != 153)
			s->line++;
		sf_log(s, c, (size_t)len);
		sf_execute(s, c, (size_t)len, now);
		if (s->o.unplug_at > 0 && s->seq == (uint64_t)s->o.unplug_at) {
			s->unplugged = true;
			return;
		}
	}
}

/* Heaters move toward their targets. */
void sfsim_physics(struct sim_sailfish *s, double dt)
{
	for (int i = 0; i < 3; i++) {
		struct sf_heater *h = &s->heater[i];
		h->temp = sim_heater_step(h->temp, h->target, SF_AMBIENT, h->heat_rate, h->cool_rate,
					  dt * s->o.speedup);
	}
	if (s->mode == SF_WAIT_TOOL || s->mode == SF_WAIT_PLATFORM) /* the machine waits */
		sim_machine_add(&s->machine_us, dt * s->o.speedup);
}

/* Write the reply bytes that have crossed the link by now; lower *wake to
 * when the next one will have. */

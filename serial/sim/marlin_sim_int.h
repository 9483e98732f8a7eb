/*
 * marlin_sim_int.h - what marlin_sim.c (the link, the RX ring, the line
 * reader and the loop) and marlin_sim_exec.c (the executor and heaters)
 * share; nothing else includes it.  The contract is marlin_sim.h.
 */
#ifndef STRATUM_SERIAL_SIM_MARLIN_SIM_INT_H
#define STRATUM_SERIAL_SIM_MARLIN_SIM_INT_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "gcode.h"
#include "marlin_sim.h"
#include "sim_util.h"
#include "st_grow.h"

#define SIM_MAX_CMD 96		/* Marlin MAX_CMD_SIZE (bytes, NUL included) */
#define SIM_PLANNER 16		/* Marlin BLOCK_BUFFER_SIZE */
#define SIM_TX_MAX (1u << 20)	/* TX backlog cap (bytes) */
#define SIM_AMBIENT 25.0	/* room temperature (degC) */
#define SIM_ACCEL 1000.0	/* default acceleration (mm/s^2) */
#define SIM_HOME_S 5.0		/* simulated G28 duration (s) */
#define SIM_KEEPALIVE_S 2.0	/* HOST_KEEPALIVE interval (wall s) */

/* A command waiting in (or running from) the queue. */
struct sim_cmd {
	bool has_n;
	long n;
	bool parsed;		/* gcode_parse accepted it */
	struct gcode_line g;
	char raw[SIM_MAX_CMD];	/* command text, for "Unknown command" */
};

/* What the command at the queue head is waiting for. */
enum sim_block {
	SIM_BLK_NONE = 0,
	SIM_BLK_PLANNER_SLOT, /* G0/G1 with the planner full */
	SIM_BLK_ARC,	      /* G2/G3 with chords left and the planner full */
	SIM_BLK_SYNC_TIMED,   /* planner empty, then wait dur (G4, G28, M400) */
	SIM_BLK_HEAT,	      /* M109 / M190 */
	SIM_BLK_BUSY,	      /* busy_at_line: held for busy_s wall seconds */
};

/* A reply line in the TX buffer: ends at byte end, may go out at ready. */
struct sim_txmark {
	size_t end;
	double ready;
};

/* A G2/G3 being planned in chords (st_arc.h): the centre, the radius
 * vector from it to the start, the signed angle, and X Y Z E before and
 * after (Z and E spread evenly). */
struct sim_arc {
	unsigned seg, nseg; /* chords planned, chords in all */
	double centre[2], rvec[2], angle;
	double from[4], to[4];
};

struct sim_heater {
	double temp, target;	 /* degC */
	double heat_rate, cool_rate; /* degC per simulated s */
};

struct sim_marlin {
	struct sim_marlin_options o;
	int master, slave;
	char slave_path[128];
	FILE *log;
	bool own_log;
	uint64_t rng;

	double t_prev;		/* last loop time (wall s) */
	uint8_t wire[4096];	/* bytes written by the host, still crossing the link */
	size_t wire_len;
	double in_t;		/* when the last byte delivered from wire arrived (wall s) */
	double out_t;		/* when the last reply byte written finished crossing (wall s) */
	double boot_until;	/* input ignored before this (wall s) */

	uint8_t *rx;		/* RX ring as a linear buffer */
	size_t rx_len;
	bool rx_flush;		/* a line error asks to empty the ring */
	uint64_t dropped;

	char line[SIM_MAX_CMD];	/* line being assembled from the RX ring */
	size_t line_len;
	bool line_comment;
	char ep[32];		/* emergency parser's view of the current line */
	size_t ep_len;
	bool ep_over;

	struct sim_cmd *q;	/* command queue ring */
	size_t q_head, q_count;
	long last_n;

	double planner_end[SIM_PLANNER]; /* end times of planned blocks (wall s) */
	size_t planner_n;
	double pos[4];		/* X Y Z E (mm) */
	bool rel_xyz, rel_e;
	double feed;		/* mm/s */
	struct sim_arc arc;	/* the G2/G3 being planned */

	enum sim_block blk;
	bool blk_synced;
	double blk_dur, blk_until;
	int blk_heater;		/* 0 hotend, 1 bed */
	bool blk_heat_both;	/* R: wait for cooling too */
	double next_temp_report, next_busy;
	bool wait_cancel;

	struct sim_heater heater[2];
	double autoreport_s, next_autoreport;

	char *tx;
	size_t tx_len, tx_off, tx_cap;
	struct sim_txmark *marks;
	size_t marks_n, marks_cap;

	bool halted, unplugged;
	bool frozen;		/* freeze_at_line ran: no byte in or out any more */
	bool number_spoilt;	/* spoil_number_at happened */
	bool star_cut;		/* star_to_newline_at happened */
	bool newline_lost[SIM_MARLIN_CUTS]; /* lose_newline_at[i] happened */
	double thaw_at;		/* when a freeze_s stall ends (sim_now) */
	_Atomic long answered_n; /* the last numbered line run and answered (read by tests) */
	_Atomic uint64_t machine_us; /* the machine's clock (sim_machine_add) */

	struct sim_thread th;
};

void msim_send(struct sim_marlin *s, const char *text);
void msim_sendf(struct sim_marlin *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void msim_boot(struct sim_marlin *s, double now);
void msim_reset_state(struct sim_marlin *s);
size_t msim_planner_free(struct sim_marlin *s, double now);
void msim_ok(struct sim_marlin *s, const struct sim_cmd *c, double now);
void msim_temp_string(const struct sim_marlin *s, char *buf, size_t cap);
void msim_serial_commands(struct sim_marlin *s);
void msim_execute(struct sim_marlin *s, double now);
void msim_physics(struct sim_marlin *s, double now, double dt);

#endif

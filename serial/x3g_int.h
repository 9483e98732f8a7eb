/*
 * x3g_int.h - what the X3G translator's parts share: x3g.c (the
 * translator's life and its G- and M-code dispatch), x3g_emit.c (bytes,
 * warnings and the fixed-layout commands) and x3g_motion.c (moves, homing,
 * G92); nothing else includes it.  x3g_decode.c (the decoder and formatter)
 * needs only x3g.h.  The contract is x3g.h.
 */
#ifndef STRATUM_SERIAL_X3G_INT_H
#define STRATUM_SERIAL_X3G_INT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_arc.h"
#include "x3g.h"

/* Axis bits, as S3G's axes bitfields and GPX's word flags use them. */
enum {
	BIT_X = 1u << 0,
	BIT_Y = 1u << 1,
	BIT_Z = 1u << 2,
	BIT_A = 1u << 3,
	BIT_B = 1u << 4,
	BITS_XYZ = 0x07,
	BITS_AXES = 0x1f,
	/* other words of a line */
	BIT_E = 1u << 5,
	BIT_F = 1u << 6,
	BIT_P = 1u << 8,
	BIT_R = 1u << 10,
	BIT_S = 1u << 11,
	BIT_T = 1u << 14,
};

#define AX_A 3
#define AX_B 4
#define NOZZLE_MAX 280u	   /* GPX clamps nozzle targets here (C) */
#define WAIT_FOREVER 0xffffu /* GPX MAX_TIMEOUT: wait timeouts when no P (s) */
/* Bytes one line can produce, with room to spare: an arc's chords
 * (x3g_arc) are the most, one 32-byte point each. */
#define OUT_CAP (40 * (ST_ARC_SEGMENTS_MAX + 25))

enum prog_state { PROG_READY, PROG_RUNNING, PROG_ENDED };

struct x3g_translator {
	struct x3g_machine m;
	enum x3g_flavor flavor;
	char build_name[X3G_BUILD_NAME_MAX + 1];
	unsigned mask;	   /* axes the machine has */
	unsigned known;	   /* axes whose position we know */
	double cur[5];	   /* position, mm */
	double tgt[5];	   /* target of the line being translated, mm */
	double excess[2];  /* extruder rounding carried to the next move, steps */
	double feedrate;   /* mm/min, the last F */
	unsigned speed_pc; /* M220 */
	unsigned extrude_pc[2]; /* M221 */
	int cur_tool, tgt_tool;
	double offset[7][3]; /* G10 P1-P6 work offsets; [0] is none */
	int cur_offset;
	unsigned nozzle[2], platform[2];     /* targets set so far, C */
	unsigned standby[2], active[2];	     /* G10 R/S tool temperatures, C */
	bool rel_xyz, rel_e;
	enum prog_state state;
	unsigned percent;
	bool stopped; /* M2 seen */
	int longest_dda;

	/* output of the current call */
	uint8_t out[OUT_CAP];
	size_t len;
	size_t cmd_start;
	int ncmds;
	bool overflow;
	uint64_t lineno;
	struct x3g_warning warn[X3G_WARNINGS_PER_LINE];
	size_t nwarn;
	uint64_t warn_total;
};

/* The words of one line, E already turned into A or B. */
struct x3g_words {
	unsigned flag;
	double v[5]; /* X Y Z A B */
	double f, p, r, s;
	int t;
	const char *text; /* message for M70/M71, NULL if none */
};

/* ---- x3g_emit.c: output --------------------------------------------------- */

/* Record a warning for the current line. */
void x3g_warn(struct x3g_translator *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
void x3g_put8(struct x3g_translator *t, unsigned v);
void x3g_put16(struct x3g_translator *t, unsigned v);
void x3g_put32(struct x3g_translator *t, uint32_t v);
void x3g_put_i32(struct x3g_translator *t, double v);
void x3g_put_float(struct x3g_translator *t, float f);
/* A command: x3g_begin(code), its fields, x3g_end. */
void x3g_begin(struct x3g_translator *t, unsigned code);
void x3g_end(struct x3g_translator *t);
unsigned x3g_clamp_u(double v, unsigned max);

/* ---- x3g_emit.c: commands ------------------------------------------------- */

void x3g_cmd_build_start(struct x3g_translator *t);
void x3g_cmd_percent(struct x3g_translator *t, unsigned pc);
void x3g_cmd_build_end(struct x3g_translator *t);
void x3g_cmd_change_tool(struct x3g_translator *t, int tool);
void x3g_cmd_tool_action(struct x3g_translator *t, int tool, unsigned action, unsigned value);
void x3g_cmd_wait(struct x3g_translator *t, unsigned code, int tool, unsigned timeout);
void x3g_cmd_steppers(struct x3g_translator *t, unsigned axes, bool on);
void x3g_cmd_one_byte(struct x3g_translator *t, unsigned code, unsigned v);
void x3g_cmd_message(struct x3g_translator *t, const char *msg, unsigned row, unsigned col,
		     unsigned timeout, bool wait_button);

/* ---- x3g_motion.c ----------------------------------------------------------- */

/* G0/G1 to the line's target. */
void x3g_move(struct x3g_translator *t, const struct x3g_words *w);
/* G2/G3 (l's I J or R): X3G has no arc, so its chords as Marlin cuts them. */
void x3g_arc(struct x3g_translator *t, const struct gcode_line *l, const struct x3g_words *w);
void x3g_queue_absolute(struct x3g_translator *t);
/* After homing or M132: the axes in flag have no known position. */
void x3g_after_homing(struct x3g_translator *t, unsigned flag);
void x3g_g28(struct x3g_translator *t, struct x3g_words *w);
void x3g_g161(struct x3g_translator *t, const struct x3g_words *w, enum x3g_endstop dir,
	      const char *name);
void x3g_g92(struct x3g_translator *t, const struct x3g_words *w);

#endif

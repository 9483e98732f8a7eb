/*
 * estimate.h - print-time estimate of a sequence of moves, planned the way
 * Marlin's planner plans them: each move is a block with a trapezoidal speed
 * profile (accelerate, cruise, decelerate), its nominal speed and
 * acceleration limited per axis, the speed at each junction limited by the
 * classic per-axis jerk (machine_max_jerk), and entry speeds settled by a
 * backward pass (every block must be able to stop in time) and a forward
 * pass (every block can only reach what acceleration allows).
 *
 * A sequence starts and ends at rest: the first block starts at, and the
 * last stops from, its safe speed (the largest speed from which no axis
 * changes speed by more than its jerk), as PrusaSlicer's estimator assumes;
 * a dwell (G4, heat waits) also brings the machine to rest.  Not modelled:
 * Marlin's minimum segment time and minimum planner speed, junction
 * deviation, S-curve acceleration and the 16-block look-ahead limit of the
 * firmware (the estimate plans over a much longer window).
 *
 * The estimator takes absolute target positions and feedrates, so it runs on
 * the G-code writer's own moves as well as on any G-code file a host has
 * parsed.  Memory is bounded: blocks are planned in a window of
 * EST_WINDOW blocks and the older half committed once the window is full;
 * adding blocks can only raise the entry speeds of a window's blocks, never
 * lower them, so what is committed is final.
 *
 * Thread safety: a planner is used by one thread; distinct planners are
 * independent.  No global state.
 */
#ifndef STRATUM_SLICER_ESTIMATE_H
#define STRATUM_SLICER_ESTIMATE_H

#include <stdbool.h>
#include <stddef.h>

#include "st_error.h"

/* Axis indices of the per-axis arrays. */
enum est_axis { EST_X = 0, EST_Y, EST_Z, EST_E, EST_AXES };

/* Blocks held for look-ahead before the older half is committed. */
#define EST_WINDOW 1024

/* Machine limits, as PrusaSlicer's machine_max_* keys and Marlin's M201,
 * M203, M204 and M205. */
struct est_limits {
	double max_feedrate[EST_AXES];	   /* mm/s (M203) */
	double max_acceleration[EST_AXES]; /* mm/s^2 (M201) */
	double accel_extruding;		   /* mm/s^2, moves with XYZ and E (M204 P) */
	double accel_retracting;	   /* mm/s^2, E-only moves (M204 R) */
	double accel_travel;		   /* mm/s^2, moves without E (M204 T); 0 = accel_extruding */
	double max_jerk[EST_AXES];	   /* mm/s, classic jerk (M205 X Y Z E) */
};

/* One move: where it ends (absolute) and how fast it is asked to go. */
struct est_move {
	double x, y, z, e; /* mm, absolute target; e is the filament position */
	double feedrate;   /* mm/s, the F of the move */
};

/* What a run of the planner found. */
struct est_result {
	double time_s;	    /* seconds, moves and dwells */
	size_t moves;	    /* moves given, zero-length ones included */
	size_t blocks;	    /* moves that moved an axis */
	double extruded_mm; /* filament pushed (positive E steps), mm */
	double retracted_mm; /* filament pulled back (negative E steps), mm */
};

struct est_planner;

/* est_limits_init - the declared defaults of the machine_max_* settings
 * (settings.h; PrusaSlicer's, MK3 normal mode). */
void est_limits_init(struct est_limits *lim);

/*
 * est_planner_new - a planner starting at rest at @start (x, y, z, e in mm;
 * NULL = all zero).  @lim is copied; every limit must be finite and > 0
 * except jerk (>= 0) and accel_travel (0 = accel_extruding).
 * Returns NULL with err filled (ST_ERR_ARG for a bad limit, ST_ERR_NOMEM).
 */
struct est_planner *est_planner_new(const struct est_limits *lim, const double start[EST_AXES],
				    struct st_error *err);

/*
 * est_planner_set_accel - moves added from now on accelerate at @print
 * (with E) and @travel (without) mm/s^2, each at most the limit it
 * replaces (M204 S within the machine's limits); values <= 0 are ignored.
 */
void est_planner_set_accel(struct est_planner *p, const struct est_limits *lim, double print,
			   double travel);

/* est_planner_free - free a planner; NULL is fine. */
void est_planner_free(struct est_planner *p);

/*
 * est_planner_add - queue one move to the absolute target @m.
 * A move that changes no axis only counts; a move with feedrate <= 0 or a
 * non-finite value is refused with ST_ERR_ARG and changes nothing.
 * Returns 0, ST_ERR_ARG or ST_ERR_NOMEM.
 */
int est_planner_add(struct est_planner *p, const struct est_move *m, struct st_error *err);

/*
 * est_planner_dwell - the machine comes to rest (G4, M400, a heat wait)
 * and then waits @seconds (>= 0).  Returns 0 or ST_ERR_ARG.
 */
int est_planner_dwell(struct est_planner *p, double seconds, struct st_error *err);

/*
 * est_planner_result - plan what is queued as if the machine stops after
 * the last move, and fill @out with the totals so far.  The planner stays
 * usable: moves added later are planned with the queued ones.
 */
void est_planner_result(struct est_planner *p, struct est_result *out);

/*
 * est_moves - convenience: plan n moves from rest at @start (NULL = zero)
 * and fill @out.  Returns 0 or a negative class as est_planner_add.
 */
int est_moves(const struct est_limits *lim, const double start[EST_AXES],
	      const struct est_move *moves, size_t n, struct est_result *out,
	      struct st_error *err);

#endif /* STRATUM_SLICER_ESTIMATE_H */

/*
 * estimate.c - Marlin-style look-ahead planner used as a print-time
 * estimator (see estimate.h).
 *
 * Per block: the move's length (XYZ, or E alone for an E-only move), its
 * nominal speed (the F of the move, lowered until no axis exceeds its
 * max_feedrate), its acceleration (extruding / retracting / travel, lowered
 * until no axis exceeds its max_acceleration), its safe speed (the speed it
 * may start from or stop to with no axis changing speed by more than its
 * jerk) and the largest speed allowed at its junction with the previous
 * block (classic jerk: both sides scaled to the smaller nominal speed, then
 * scaled down until every axis's speed change is within its jerk).
 */
#include "estimate.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "settings.h"

/* A length below this (mm) does not move an axis. */
#define EST_EPS 1e-9

/* One planned move. */
struct est_block {
	double dist;	  /* mm */
	double nominal;	  /* mm/s, cruise speed */
	double accel;	  /* mm/s^2 */
	double safe;	  /* mm/s, speed it may start from or stop to */
	double max_entry; /* mm/s, junction limit with the previous block */
	double entry;	  /* mm/s, planned entry speed */
};

struct est_planner {
	struct est_limits lim;
	double pos[EST_AXES];	   /* mm, where the last move ended */
	bool have_prev;		   /* the last block is still moving into the next */
	double prev_vel[EST_AXES]; /* mm/s, per-axis cruise velocity of the last block */
	double prev_nominal;	   /* mm/s */
	struct est_block blocks[EST_WINDOW];
	size_t nblocks;	      /* blocks in the window, not committed */
	double committed_s;   /* time of committed blocks and dwells */
	struct est_result tally; /* counts and filament, time filled on demand */
};

/* The declared default of a machine limit (settings.h); NaN, which every
 * planner refuses, if the declaration lost it. */
static double limit_default(const char *name)
{
	double v;

	return setting_default_number(name, false, &v) ? v : NAN;
}

void est_limits_init(struct est_limits *lim)
{
	static const char axis[EST_AXES] = {'x', 'y', 'z', 'e'};
	char name[64];

	for (int a = 0; a < EST_AXES; a++) {
		snprintf(name, sizeof(name), "machine_max_feedrate_%c", axis[a]);
		lim->max_feedrate[a] = limit_default(name);
		snprintf(name, sizeof(name), "machine_max_acceleration_%c", axis[a]);
		lim->max_acceleration[a] = limit_default(name);
		snprintf(name, sizeof(name), "machine_max_jerk_%c", axis[a]);
		lim->max_jerk[a] = limit_default(name);
	}
	lim->accel_extruding = limit_default("machine_max_acceleration_extruding");
	lim->accel_retracting = limit_default("machine_max_acceleration_retracting");
	lim->accel_travel = limit_default("machine_max_acceleration_travel");
}

/* True when v is finite and > 0 (or >= 0 with zero_ok). */
static bool positive(double v, bool zero_ok)
{
	return isfinite(v) && (v > 0 || (zero_ok && v == 0));
}

/* Check every limit; fills err naming the first bad one. */
static int check_limits(const struct est_limits *lim, struct st_error *err)
{
	static const char axis[EST_AXES] = {'x', 'y', 'z', 'e'};

	for (int a = 0; a < EST_AXES; a++) {
		if (!positive(lim->max_feedrate[a], false))
			return st_error_set(err, ST_ERR_ARG,
					    "estimate: machine_max_feedrate_%c must be > 0 mm/s",
					    axis[a]);
		if (!positive(lim->max_acceleration[a], false))
			return st_error_set(err, ST_ERR_ARG,
					    "estimate: machine_max_acceleration_%c must be > 0 mm/s^2",
					    axis[a]);
		if (!positive(lim->max_jerk[a], true))
			return st_error_set(err, ST_ERR_ARG,
					    "estimate: machine_max_jerk_%c must be >= 0 mm/s", axis[a]);
	}
	if (!positive(lim->accel_extruding, false) || !positive(lim->accel_retracting, false) ||
	    !positive(lim->accel_travel, true))
		return st_error_set(err, ST_ERR_ARG,
				    "estimate: machine_max_acceleration_extruding and _retracting "
				    "must be > 0 mm/s^2, _travel >= 0");
	return 0;
}

struct est_planner *est_planner_new(const struct est_limits *lim, const double start[EST_AXES],
				    struct st_error *err)
{
	struct est_planner *p;

	if (!lim) {
		st_error_set(err, ST_ERR_ARG, "estimate: no machine limits given");
		return NULL;
	}
	if (check_limits(lim, err))
		return NULL;
	for (int a = 0; start && a < EST_AXES; a++)
		if (!isfinite(start[a])) {
			st_error_set(err, ST_ERR_ARG, "estimate: start position is not finite");
			return NULL;
		}
	p = calloc(1, sizeof(*p));
	if (!p) {
		st_error_set(err, ST_ERR_NOMEM, "estimate: out of memory for the planner");
		return NULL;
	}
	p->lim = *lim;
	if (p->lim.accel_travel == 0)
		p->lim.accel_travel = p->lim.accel_extruding;
	if (start)
		memcpy(p->pos, start, sizeof(p->pos));
	return p;
}

void est_planner_set_accel(struct est_planner *p, const struct est_limits *lim, double print,
			   double travel)
{
	double tl = lim->accel_travel > 0 ? lim->accel_travel : lim->accel_extruding;

	if (print > 0)
		p->lim.accel_extruding = fmin(print, lim->accel_extruding);
	if (travel > 0)
		p->lim.accel_travel = fmin(travel, tl);
}

void est_planner_free(struct est_planner *p)
{
	free(p);
}

/* Time (s) of one block: trapezoid, or triangle when it cannot cruise. */
static double block_time(double dist, double vi, double vc, double vo, double a)
{
	double d_acc, d_dec, vp;

	if (dist <= 0)
		return 0;
	d_acc = (vc * vc - vi * vi) / (2 * a);
	d_dec = (vc * vc - vo * vo) / (2 * a);
	if (d_acc + d_dec <= dist)
		return (vc - vi) / a + (vc - vo) / a + (dist - d_acc - d_dec) / vc;
	vp = sqrt(a * dist + 0.5 * (vi * vi + vo * vo));
	vp = fmax(vp, fmax(vi, vo));
	return (vp - vi) / a + (vp - vo) / a;
}

/* Highest speed at the far end of dist reachable from v with accel a. */
static double reach(double v, double a, double dist)
{
	return sqrt(v * v + 2 * a * dist);
}

/*
 * Set entry speeds of the window as if the machine stops after its last
 * block (exiting at that block's safe speed): backward pass, then forward.
 */
static void plan_window(struct est_planner *p)
{
	struct est_block *b = p->blocks;
	size_t n = p->nblocks;

	if (n == 0)
		return;
	double exit = b[n - 1].safe;
	for (size_t i = n; i-- > 0;) {
		b[i].entry = fmin(b[i].max_entry, reach(exit, b[i].accel, b[i].dist));
		exit = b[i].entry;
	}
	for (size_t i = 0; i + 1 < n; i++)
		b[i + 1].entry = fmin(b[i + 1].entry, reach(b[i].entry, b[i].accel, b[i].dist));
}

/* Exit speed of block i of a planned window. */
static double block_exit(const struct est_planner *p, size_t i)
{
	const struct est_block *b = &p->blocks[i];

	if (i + 1 < p->nblocks)
		return p->blocks[i + 1].entry;
	return fmin(b->safe, reach(b->entry, b->accel, b->dist));
}

/* Sum of the times of blocks [0, n) of a planned window. */
static double window_time(const struct est_planner *p, size_t n)
{
	double t = 0;

	for (size_t i = 0; i < n; i++) {
		const struct est_block *b = &p->blocks[i];
		t += block_time(b->dist, b->entry, b->nominal, block_exit(p, i), b->accel);
	}
	return t;
}

/* Plan the window and commit its first n blocks; the next block keeps
 * its planned entry speed as a fixed limit. */
static void commit(struct est_planner *p, size_t n)
{
	plan_window(p);
	p->committed_s += window_time(p, n);
	memmove(p->blocks, p->blocks + n, (p->nblocks - n) * sizeof(p->blocks[0]));
	p->nblocks -= n;
	if (p->nblocks)
		p->blocks[0].max_entry = p->blocks[0].entry;
}

/* Speed change an axis sees at a junction, as Marlin's classic jerk counts
 * it: the difference when the axis keeps its direction (or starts/stops),
 * the larger magnitude when it reverses. */
static double axis_jerk(double v_exit, double v_entry)
{
	if ((v_exit > 0 && v_entry < 0) || (v_exit < 0 && v_entry > 0))
		return fmax(fabs(v_exit), fabs(v_entry));
	return fabs(v_entry - v_exit);
}

int est_planner_add(struct est_planner *p, const struct est_move *m, struct st_error *err)
{
	const struct est_limits *lim;
	double target[EST_AXES], delta[EST_AXES], vel[EST_AXES];
	double dist_xyz, dist, v, accel, safe_f, junction;
	struct est_block *b;

	if (!p || !m)
		return st_error_set(err, ST_ERR_ARG, "estimate: no planner or move given");
	lim = &p->lim;
	target[EST_X] = m->x;
	target[EST_Y] = m->y;
	target[EST_Z] = m->z;
	target[EST_E] = m->e;
	for (int a = 0; a < EST_AXES; a++)
		if (!isfinite(target[a]))
			return st_error_set(err, ST_ERR_ARG, "estimate: move %zu has a non-finite target",
					    p->tally.moves + 1);
	if (!positive(m->feedrate, false))
		return st_error_set(err, ST_ERR_ARG, "estimate: move %zu has feedrate %g (must be > 0)",
				    p->tally.moves + 1, m->feedrate);
	p->tally.moves++;
	for (int a = 0; a < EST_AXES; a++)
		delta[a] = target[a] - p->pos[a];
	dist_xyz = sqrt(delta[EST_X] * delta[EST_X] + delta[EST_Y] * delta[EST_Y] +
			delta[EST_Z] * delta[EST_Z]);
	dist = dist_xyz > EST_EPS ? dist_xyz : fabs(delta[EST_E]);
	if (dist <= EST_EPS)
		return 0;
	if (delta[EST_E] > 0)
		p->tally.extruded_mm += delta[EST_E];
	else
		p->tally.retracted_mm -= delta[EST_E];
	memcpy(p->pos, target, sizeof(p->pos));

	/* Nominal speed and acceleration, limited per axis. */
	v = m->feedrate;
	if (fabs(delta[EST_E]) <= EST_EPS)
		accel = lim->accel_travel;
	else if (dist_xyz <= EST_EPS)
		accel = lim->accel_retracting;
	else
		accel = lim->accel_extruding;
	for (int a = 0; a < EST_AXES; a++) {
		double share = fabs(delta[a]) / dist;
		if (share * v > lim->max_feedrate[a])
			v = lim->max_feedrate[a] / share;
		if (share * accel > lim->max_acceleration[a])
			accel = lim->max_acceleration[a] / share;
	}
	safe_f = 1;
	for (int a = 0; a < EST_AXES; a++) {
		vel[a] = delta[a] / dist * v;
		if (fabs(vel[a]) > lim->max_jerk[a])
			safe_f = fmin(safe_f, lim->max_jerk[a] / fabs(vel[a]));
	}

	/* Junction with the previous block: both sides at the smaller nominal
	 * speed, then scaled until each axis's speed change is within jerk. */
	if (p->have_prev) {
		double vj = fmin(v, p->prev_nominal), f = 1;
		for (int a = 0; a < EST_AXES; a++) {
			double j = axis_jerk(p->prev_vel[a] * vj / p->prev_nominal, vel[a] * vj / v);
			if (j > lim->max_jerk[a])
				f = fmin(f, lim->max_jerk[a] / j);
		}
		junction = vj * f;
	} else {
		junction = v * safe_f;
	}

	if (p->nblocks == EST_WINDOW)
		commit(p, EST_WINDOW / 2);
	b = &p->blocks[p->nblocks++];
	*b = (struct est_block){.dist = dist, .nominal = v, .accel = accel, .safe = v * safe_f,
				.max_entry = junction, .entry = junction};
	memcpy(p->prev_vel, vel, sizeof(vel));
	p->prev_nominal = v;
	p->have_prev = true;
	p->tally.blocks++;
	return 0;
}

int est_planner_dwell(struct est_planner *p, double seconds, struct st_error *err)
{
	if (!p || !isfinite(seconds) || seconds < 0)
		return st_error_set(err, ST_ERR_ARG, "estimate: a dwell needs a time >= 0 s");
	commit(p, p->nblocks);
	p->committed_s += seconds;
	p->have_prev = false;
	return 0;
}

void est_planner_result(struct est_planner *p, struct est_result *out)
{
	plan_window(p);
	*out = p->tally;
	out->time_s = p->committed_s + window_time(p, p->nblocks);
}

int est_moves(const struct est_limits *lim, const double start[EST_AXES],
	      const struct est_move *moves, size_t n, struct est_result *out,
	      struct st_error *err)
{
	struct st_error local;
	struct est_planner *p;
	int rc = 0;

	if (!err)
		err = &local;
	if ((!moves && n) || !out)
		return st_error_set(err, ST_ERR_ARG, "estimate: no moves or no result given");
	p = est_planner_new(lim, start, err);
	if (!p)
		return err->code;
	for (size_t i = 0; i < n && rc == 0; i++)
		rc = est_planner_add(p, &moves[i], err);
	if (rc == 0)
		est_planner_result(p, out);
	est_planner_free(p);
	return rc;
}

/*
 * gcode_writer_int.h - what the G-code writer's parts share:
 * gcode_writer.c (emission and the writer's life), gcode_writer_config.c
 * (the settings table: defaults, checks, placeholders, the header),
 * gcode_writer_plan.c (a layer's paths into moves),
 * gcode_writer_cool.c (fan and slow-down per layer), gcode_writer_simplify.c
 * and gcode_writer_arc.c (gcode_resolution, arc_fitting) and
 * gcode_writer_progress.c (M73); nothing else includes it.  The contract
 * is gcode_writer.h.
 */
#ifndef STRATUM_SLICER_GCODE_WRITER_INT_H
#define STRATUM_SLICER_GCODE_WRITER_INT_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <sys/types.h>

#include "arcfit.h"
#include "estimate.h"
#include "gcode_writer.h"
#include "placeholder.h"
#include "simplify.h"
#include "st_error.h"
#include "st_file.h"
#include "toolpath.h"
#include "travel.h"

#define NUM_MAX 48 /* longest formatted number */
#define XYZ_UNITS 1000.0 /* X, Y, Z written in um */

/* A layer is planned into operations (moves and role changes), cooled,
 * then emitted. */
enum op_kind { OP_MOVE, OP_ROLE, OP_ACCEL /* f: mm/s^2 */ };

enum move_kind {
	MV_TRAVEL,    /* no extrusion */
	MV_EXTRUDE,   /* e mm of filament extruded; slowed down for cooling */
	MV_RETRACT,   /* e mm pulled back (standing, or wiping when xy) */
	MV_UNRETRACT, /* everything retracted pushed back */
};

struct op {
	enum op_kind kind;
	enum move_kind mv;
	enum path_role role; /* OP_ROLE */
	bool xy;	     /* the move has an XY target */
	bool arc, ccw;	     /* arc_fitting: an arc (G3 when ccw, else G2) around (cx, cy) */
	double cx, cy;	     /* mm */
	double x, y, z;	     /* mm, target */
	double e;	     /* mm of filament, see enum move_kind */
	double f;	     /* mm/s */
};

/* arc_fitting: the segment from a point of a simplified path to the
 * next, when it is an arc (arcfit.h), printed forwards. */
struct gcodew_arcseg {
	bool arc, ccw;
	double cx, cy; /* centre, nm */
	double len;    /* arc length, nm */
};

/* remaining_times: where an M73 line goes in the body, and the time planned
 * before it (gcode_writer_progress.c). */
struct gcodew_m73 {
	off_t off;   /* bytes into the body */
	double t;    /* s */
	bool last;   /* the end of the print: P100 R0 */
};

struct gcodew {
	const struct gcodew_settings *s;
	size_t nlayers;		 /* layers announced to gcodew_begin */
	size_t next;		 /* index of the next layer to write */
	char *start, *start_filament; /* custom G-code, placeholders expanded */
	struct ph_vars *vars;	 /* placeholders: the print's variables */
	double max_z;		 /* mm, highest layer written so far */
	FILE *body;		 /* the body, generated before the header */
	struct st_file_out out;	 /* gcodew_begin_file: the file being written */
	double len[PATH_ROLES], area[PATH_ROLES]; /* per role: nm and nm^2 of
						     * beads, for the mean widths */
	struct st_error *err;
	FILE *fp;		 /* where gcodew_put() writes: the body, then the output */
	struct est_planner *est; /* times the body's moves as they are written */

	/* Planning state, in mm */
	bool pos_known;
	double px, py, pz;
	double layer_z;
	int plan_role; /* role of the last path planned in this layer, -1 none */
	bool plan_retracted; /* retracted at the layer change, not yet unretracted */
	double fil_area;
	struct op *ops;
	size_t nops, opcap;
	double *wipe; /* x, y pairs: the last path backwards from the nozzle */
	size_t nwipe, wipecap;
	bool *done; /* per path of the layer: already planned */
	size_t donecap;
	struct travel_map *map;	  /* this layer's, NULL: straight travels */
	bool spiral_below;	  /* the layer below was a spiral (layer_paths.spiral) */
	struct travel_route route; /* the travel being planned */

	/* gcode_resolution: the path being planned as printed (simplify.h),
	 * gcodew_simplify_path; per original point while marking, then per
	 * kept point of view */
	struct simplify_work simp;
	int64_t *sxy;		 /* the path's points, the seam again at the end; nm */
	int64_t *smv;		 /* ... where each kept one is printed (simplify_balance) */
	int64_t *sbal;		 /* one run's kept points, moved */
	bool *skeep;		 /* kept */
	size_t *sidx;		 /* index in the original path */
	double *sstretch;	 /* filament factor of the segment from the point */
	struct path_point *spts; /* the kept points */
	struct gcodew_arcseg *sarc; /* arc_fitting: the segment from the point */
	struct arcfit_work afit;
	bool no_arcs;		 /* the path being planned gets lines only */
	size_t sloop;		 /* its segments when a closed path of one width, else 0 */
	size_t sxycap, smvcap, sbalcap, skeepcap, sidxcap, sstretchcap, sptscap, sarccap;
	struct toolpath view;	 /* spts as a path of the original's role */

	/* Emission state */
	double ext_exact, r_exact; /* mm extruded since the last reset / retracted now */
	int64_t ext_units, r_units, epos_units; /* the same in E units; position written */
	double e_machine;			/* mm, absolute E for the estimator */
	bool xy_known, z_known;
	int64_t wx, wy, wz; /* um, last written */
	long long wf;	    /* mm/min, last written, 0 none */
	int fan;	    /* percent written, -1 unknown */
	int accel;	    /* mm/s^2 last written (M204), 0 none */
	int layer_fan;	    /* percent for this layer's non-bridge paths */
	int bridge_fan;	    /* percent for bridges on this layer; -1: layer_fan */
	size_t moves;
	double filament_mm;
	struct gcodew_m73 *m73; /* remaining_times, in the order of the body */
	size_t nm73, m73cap;
};

/* gcode_writer.c: printf to the writer's current output (w->fp). */
void gcodew_put(struct gcodew *w, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* gcode_writer_config.c */
/* u / 10^digits into buf (NUM_MAX bytes, digits < NUM_MAX - 3), trailing
 * zeros dropped; returns its length. */
size_t gcodew_fmt_units(char *buf, int64_t u, int digits);
/* v rounded to digits decimals into buf (NUM_MAX bytes). */
void gcodew_fmt_num(char *buf, double v, int digits);
/* The placeholder variables of a print of nlayers layers, before its
 * first layer; NULL on error (err set). */
struct ph_vars *gcodew_vars_new(const struct gcodew_settings *s, size_t nlayers,
				struct st_error *err);
/* layer_num (from 0), layer_z and max_layer_z for the next text. */
int gcodew_set_layer_vars(struct ph_vars *v, size_t li, double z, double max_z,
			  struct st_error *err);
/* Whether a line of text is the command M<m1> or M<m2>. */
bool gcodew_text_sets(const char *text, int m1, int m2);
/* The header: printer, estimates, settings, machine limits, bead widths. */
void gcodew_put_header(struct gcodew *w, const struct gcodew_summary *sum);

/* gcode_writer_plan.c */
/* Plan every path of layer li into w->ops. */
int gcodew_plan_layer(struct gcodew *w, const struct layer_paths *l, size_t li);
/* Plan a retraction, wiping back over the last path when asked. */
int gcodew_plan_retract(struct gcodew *w);

/* gcode_writer_simplify.c */
/* Path p within gcode_resolution into w->view (w->sidx, w->sstretch
 * and, with arc_fitting, w->sarc beside it); p itself when the key is 0.
 * Sets *out to the path to print. */
int gcodew_simplify_path(struct gcodew *w, const struct toolpath *p, const struct toolpath **out);
/* The turns of w->route (after the start (ax, ay), nm) within
 * gcode_resolution: dropped ones removed from it. */
int gcodew_simplify_route(struct gcodew *w, int64_t ax, int64_t ay);
/* Release the scratch arrays above. */
void gcodew_simplify_free(struct gcodew *w);

/* gcode_writer_arc.c: arc_fitting */
/* Fit arcs to the run of points i .. j of w->sxy within tol nm: their
 * ends kept and w->sarc set, the points between dropped; the stretches
 * between arcs (lines) are marked with mark_lines(w, a, b, tol). */
int gcodew_arcs_run(struct gcodew *w, size_t i, size_t j, double tol,
		    int (*mark_lines)(struct gcodew *w, size_t a, size_t b, double tol));
/* Add the arc from `from` to `to` (X Y Z E, mm) around (cx, cy) (mm),
 * counter-clockwise when ccw, to the estimator p in the chords Marlin
 * cuts it into (st_arc.h), Z and E spread evenly, at v mm/s. */
int gcodew_arc_estimate(struct est_planner *p, const double from[EST_AXES],
			const double to[EST_AXES], double cx, double cy, bool ccw, double v,
			struct st_error *err);

/* gcode_writer_progress.c */
/* remaining_times: an M73 line here in the body (last: the end's P100 R0);
 * nothing when the key is off. */
int gcodew_progress_mark(struct gcodew *w, bool last);
/* The body to fp, the M73 lines for a print of total s written in it. */
int gcodew_copy_body(struct gcodew *w, FILE *fp, double total, struct st_error *err);

/* gcode_writer_progress.c, beside the M73 lines: an acceleration op's
 * value as written (rounded, capped), 0 = nothing to write. */
int gcodew_accel_written(const struct gcodew_settings *s, double v);

/* gcode_writer_cool.c */
/* Decide layer li's fan and slow its extrusions down if it is too fast;
 * start is the nozzle's position before the layer. */
int gcodew_cool_layer(struct gcodew *w, size_t li, const double start[EST_AXES]);

/* Whether the path being simplified is fitted with arcs (arc_fitting). */
static inline bool gcodew_arcs(const struct gcodew *w)
{
	return w->s->arc_fitting && !w->no_arcs;
}

/* Point index of step k (0 .. n or n-1) of a path printed forwards or
 * reversed; a closed loop ends back at its seam. */
static inline size_t trav(const struct toolpath *p, bool rev, size_t k)
{
	if (rev)
		return p->n - 1 - k;
	return k == p->n ? 0 : k;
}

#endif /* STRATUM_SLICER_GCODE_WRITER_INT_H */

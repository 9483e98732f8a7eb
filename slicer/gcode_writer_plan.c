/*
 * gcode_writer_plan.c - a layer's paths into the writer's moves: path
 * order, travels (routed, retracted, lifted), wipes, speeds per role and
 * the flow of each segment, spiral vase layers (see gcode_writer.h).
 */
#include "gcode_writer_int.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "st_grow.h"

#define MOVE_EPS 1e-7	     /* mm: shorter travels are no travel */
#define WIPE_SPEED_SHARE 0.8 /* wipe at 80% of the travel speed, as PrusaSlicer */

/* Append an operation. */
static int push(struct gcodew *w, struct op o)
{
	struct op *grown = st_grow(w->ops, &w->opcap, w->nops + 1, sizeof(*grown));

	if (!grown)
		return st_error_set(w->err, ST_ERR_NOMEM, "G-code: out of memory planning a layer");
	w->ops = grown;
	w->ops[w->nops++] = o;
	return 0;
}

/* A move op to (x, y, z); xy false leaves X and Y alone. */
static int push_move(struct gcodew *w, enum move_kind mv, bool xy, double x, double y, double z,
		     double e, double f)
{
	int rc = push(w, (struct op){.kind = OP_MOVE, .mv = mv, .xy = xy, .x = x, .y = y, .z = z,
				     .e = e, .f = f});
	if (rc == 0) {
		if (xy) {
			w->px = x;
			w->py = y;
		}
		w->pz = z;
	}
	return rc;
}

/* Z speed: travel_speed_z, else the machine's Z limit. */
static double z_speed(const struct gcodew_settings *s)
{
	return s->travel_speed_z > 0 ? s->travel_speed_z : s->limits.max_feedrate[EST_Z];
}

/* Retract, wiping back over the last path when asked. */
int gcodew_plan_retract(struct gcodew *w)
{
	const struct gcodew_settings *s = w->s;
	double len = s->retract_length, taken = 0;
	int rc = 0;

	if (s->wipe && w->nwipe >= 2) {
		double speed = WIPE_SPEED_SHARE * s->travel_speed, walked = 0, dist;
		double before = len * s->retract_before_wipe / 100, wlen = len - before;

		if (before > 1e-9) { /* standing first; the wipe takes the rest */
			rc = push_move(w, MV_RETRACT, false, w->px, w->py, w->pz, before,
				       s->retract_speed);
			taken = before;
		}
		dist = wlen / s->retract_speed * speed;
		for (size_t k = 0; k + 1 < w->nwipe && walked < dist && rc == 0; k++) {
			double x0 = w->wipe[2 * k], y0 = w->wipe[2 * k + 1];
			double x1 = w->wipe[2 * k + 2], y1 = w->wipe[2 * k + 3];
			double seg = hypot(x1 - x0, y1 - y0), step = fmin(seg, dist - walked);
			if (seg <= 0)
				continue;
			double t = step / seg, r = wlen * step / dist;
			rc = push_move(w, MV_RETRACT, true, x0 + t * (x1 - x0), y0 + t * (y1 - y0),
				       w->pz, r, speed);
			walked += step;
			taken += r;
		}
	}
	w->nwipe = 0;
	if (rc == 0 && len - taken > 1e-9)
		rc = push_move(w, MV_RETRACT, false, w->px, w->py, w->pz, len - taken,
			       s->retract_speed);
	return rc;
}

/* Whether a retraction at Z z lifts: retract_lift within PrusaSlicer's
 * retract_lift_above / retract_lift_below range. */
static bool lifts_at(const struct gcodew_settings *s, double z)
{
	return s->retract_lift > 0 && z >= s->retract_lift_above &&
	       (s->retract_lift_below == 0 || z <= s->retract_lift_below);
}

/* Push back what was retracted, at Z z. */
static int plan_unretract(struct gcodew *w, double z)
{
	const struct gcodew_settings *s = w->s;

	w->plan_retracted = false;
	return push_move(w, MV_UNRETRACT, false, 0, 0, z, s->retract_length,
			 s->deretract_speed > 0 ? s->deretract_speed : s->retract_speed);
}

/*
 * Travel to (x, y) on the current layer, routed inside the part when the
 * layer has a travel map: retract (and lift) when longer than
 * retract_before_travel unless the route stays inside one island and is
 * short enough to skip it, reach the layer's Z before moving in XY when not
 * lifted, unretract on arrival.
 */
static int plan_travel(struct gcodew *w, double x, double y)
{
	const struct gcodew_settings *s = w->s;
	struct travel_route *r = &w->route;
	double lz = w->layer_z, tz = lz, d, len;
	int64_t ax, ay; /* nm, where the route starts */
	bool retract;
	int rc = 0;

	if (!w->pos_known) {
		w->pos_known = true;
		rc = push_move(w, MV_TRAVEL, false, 0, 0, lz, 0, z_speed(s));
		if (rc == 0)
			rc = push_move(w, MV_TRAVEL, true, x, y, lz, 0, s->travel_speed);
		return rc || !w->plan_retracted ? rc : plan_unretract(w, lz);
	}
	d = hypot(x - w->px, y - w->py);
	if (d < MOVE_EPS && fabs(w->pz - lz) < 1e-9)
		return w->plan_retracted ? plan_unretract(w, lz) : 0;
	ax = llround(w->px * SLICE_UNITS_PER_MM);
	ay = llround(w->py * SLICE_UNITS_PER_MM);
	rc = travel_plan(w->map, ax, ay, llround(x * SLICE_UNITS_PER_MM),
			 llround(y * SLICE_UNITS_PER_MM), r, w->err);
	if (rc)
		return rc;
	len = r->length / SLICE_UNITS_PER_MM;
	retract = s->retract_length > 0 && len > s->retract_before_travel;
	if (retract && r->inside && s->only_retract_when_crossing_perimeters &&
	    (s->max_unretracted_travel == 0 || len <= s->max_unretracted_travel))
		retract = false; /* any ooze falls inside the part */
	if (retract) {
		/* Already retracted at the layer change: PrusaSlicer only lifts. */
		if (!w->plan_retracted)
			rc = gcodew_plan_retract(w);
		if (lifts_at(s, lz))
			tz = lz + s->retract_lift;
	}
	/* Still lifted above the new layer by the layer change's lift: as
	 * PrusaSlicer, the travel stays there instead of going down, or up. */
	if (w->plan_retracted && w->pz > lz + 1e-9)
		tz = w->pz;
	if (rc == 0 && fabs(w->pz - tz) > 1e-9)
		rc = push_move(w, MV_TRAVEL, false, 0, 0, tz, 0, z_speed(s));
	if (rc == 0)
		rc = gcodew_simplify_route(w, ax, ay);
	for (size_t k = 0; k + 1 < r->n && rc == 0; k++) /* the route's turns */
		rc = push_move(w, MV_TRAVEL, true, r->xy[2 * k] / SLICE_UNITS_PER_MM,
			       r->xy[2 * k + 1] / SLICE_UNITS_PER_MM, tz, 0, s->travel_speed);
	if (rc == 0)
		rc = push_move(w, MV_TRAVEL, true, x, y, tz, 0, s->travel_speed);
	if (rc == 0 && tz != lz)
		rc = push_move(w, MV_TRAVEL, false, 0, 0, lz, 0, z_speed(s));
	if (rc == 0 && (retract || w->plan_retracted))
		rc = plan_unretract(w, lz);
	return rc;
}

/* Print speed of a role, PrusaSlicer's choice of key. */
static double role_base_speed(const struct gcodew_settings *s, enum path_role role)
{
	switch (role) {
	case PATH_OUTER_PERIMETER:
	case PATH_THIN_WALL:
		return s->external_perimeter_speed;
	case PATH_GAP_FILL:
		return s->gap_fill_speed;
	case PATH_SOLID_INFILL:
	case PATH_BOTTOM_SKIN:
		return s->solid_infill_speed;
	case PATH_TOP_SKIN:
		return s->top_solid_infill_speed;
	case PATH_SPARSE_INFILL:
		return s->infill_speed;
	case PATH_BRIDGE:
	case PATH_OVERHANG_PERIMETER:
		return s->bridge_speed;
	case PATH_SUPPORT:
	case PATH_SKIRT:
	case PATH_BRIM:
		return s->support_material_speed;
	case PATH_SUPPORT_INTERFACE:
		return s->support_material_interface_speed;
	case PATH_IRONING:
		return s->ironing_speed;
	default: /* inner perimeters */
		return s->perimeter_speed;
	}
}

/* A closed wall this long or shorter prints at small_perimeter_speed
 * (PrusaSlicer's SMALL_PERIMETER_LENGTH: a circle of radius 6.5 mm), mm. */
#define SMALL_PERIMETER_MM (2 * M_PI * 6.5)

/* Whether p is a small perimeter: a closed wall loop at most SMALL_PERIMETER_MM long. */
static bool small_perimeter(const struct toolpath *p)
{
	double len = 0;

	if (!p->closed || (p->role != PATH_OUTER_PERIMETER && p->role != PATH_INNER_PERIMETER))
		return false;
	for (size_t k = 0; k < p->n && len <= SMALL_PERIMETER_MM; k++) {
		const struct path_point *a = &p->pts[k], *b = &p->pts[(k + 1) % p->n];
		len += hypot((double)(b->x - a->x), (double)(b->y - a->y)) / SLICE_UNITS_PER_MM;
	}
	return len <= SMALL_PERIMETER_MM;
}

/* Print speed of path p on layer li (0-based): its role's, or
 * small_perimeter_speed for a small wall loop; the first layer's replaces
 * it, or scales it when a percentage, and so does the part's first layer
 * on a raft (PrusaSlicer's first_layer_speed_over_raft). */
static double path_speed(const struct gcodew_settings *s, const struct toolpath *p, size_t li)
{
	double v = small_perimeter(p) ? s->small_perimeter_speed : role_base_speed(s, p->role);
	double f = s->first_layer_speed;
	bool pct = s->first_layer_speed_is_percent;

	if (li > 0 && s->raft_layers > 0 && li == (size_t)s->raft_layers) {
		f = s->first_layer_speed_over_raft;
		pct = s->first_layer_speed_over_raft_is_percent;
	} else if (li > 0) {
		return v;
	}
	if (f <= 0)
		return v;
	return pct ? v * f / 100 : f;
}

/* Remember the printed path backwards from its end, for a wipe; a closed
 * path printed from point first (a spiral loop) is rotated by first. */
static int record_wipe(struct gcodew *w, const struct toolpath *p, bool rev, size_t steps,
		       size_t first)
{
	const struct gcodew_settings *s = w->s;
	double dist = s->retract_length / s->retract_speed * WIPE_SPEED_SHARE * s->travel_speed;
	double walked = 0;

	w->nwipe = 0;
	for (size_t k = steps; k-- > 0;) {
		const struct path_point *q = &p->pts[(trav(p, rev, k) + first) % p->n];
		double x = q->x / SLICE_UNITS_PER_MM, y = q->y / SLICE_UNITS_PER_MM;
		double *grown = st_grow(w->wipe, &w->wipecap, w->nwipe + 1, 2 * sizeof(*grown));
		if (!grown)
			return st_error_set(w->err, ST_ERR_NOMEM, "G-code: out of memory for a wipe");
		w->wipe = grown;
		if (w->nwipe)
			walked += hypot(x - w->wipe[2 * w->nwipe - 2], y - w->wipe[2 * w->nwipe - 1]);
		w->wipe[2 * w->nwipe] = x;
		w->wipe[2 * w->nwipe + 1] = y;
		w->nwipe++;
		if (walked >= dist)
			break;
	}
	return 0;
}

/*
 * Extrude from pa to pb (path pi of layer li; pb is its point at, for
 * messages), ending at height z: a bead width nm wide, its filament from
 * the flow model at the top of gcode_writer.h times share, at speed or
 * slower where the volumetric limits ask it; along the arc when arc is
 * not NULL (printed backwards when rev).  A bead narrower than the layer
 * is refused; a segment of no length adds nothing.
 */
static int plan_segment(struct gcodew *w, const struct layer_paths *l, size_t li, size_t pi,
			size_t at, const struct path_point *pa, const struct path_point *pb,
			int64_t width, double z, double speed, double share,
			const struct gcodew_arcseg *arc, bool rev)
{
	double h = l->height, bead = width / SLICE_UNITS_PER_MM;
	double len = (arc ? arc->len : hypot((double)(pb->x - pa->x), (double)(pb->y - pa->y))) /
		     SLICE_UNITS_PER_MM;
	int rc;
	bool iron = l->paths[pi].role == PATH_IRONING;
	double area = iron ? bead * w->s->layer_height * w->s->ironing_flowrate / 100
			   : (bead - h) * h + M_PI * h * h / 4;

	if (bead < h && !iron)
		return st_error_set(w->err, ST_ERR_RANGE,
				    "G-code: layer %zu, path %zu (%s), point %zu: bead width %.4f mm "
				    "is below the layer height %.4f mm",
				    li + 1, pi, path_role_name(l->paths[pi].role), at, bead, h);
	if (len <= 0)
		return 0;
	/* PrusaSlicer caps with the path's cross-section, not the E written */
	if (w->s->max_volumetric_speed > 0)
		speed = fmin(speed, w->s->max_volumetric_speed / area);
	if (w->s->filament_max_volumetric_speed > 0)
		speed = fmin(speed, w->s->filament_max_volumetric_speed / area);
	rc = push_move(w, MV_EXTRUDE, true, pb->x / SLICE_UNITS_PER_MM, pb->y / SLICE_UNITS_PER_MM,
		       z, share * area * len / w->fil_area * w->s->extrusion_multiplier, speed);
	if (rc == 0 && arc) {
		struct op *o = &w->ops[w->nops - 1];
		o->arc = true;
		o->ccw = arc->ccw != rev;
		o->cx = arc->cx / SLICE_UNITS_PER_MM;
		o->cy = arc->cy / SLICE_UNITS_PER_MM;
	}
	return rc;
}

/* The arc from kept point f of the path being planned, or NULL for a line. */
static const struct gcodew_arcseg *arc_at(const struct gcodew *w, bool simplified, size_t f)
{
	return simplified && gcodew_arcs(w) && w->sarc[f].arc ? &w->sarc[f] : NULL;
}

/* PrusaSlicer 2.5's acceleration for a path of role on layer li (0-based):
 * the first layer's, else by role, each when above 0, else the default. */
static double path_accel(const struct gcodew_settings *s, enum path_role role, size_t li)
{
	double v = 0;

	if (li == 0 && s->first_layer_acceleration > 0)
		return s->first_layer_acceleration;
	if (role == PATH_OVERHANG_PERIMETER) /* a wall, then a bridge, as PrusaSlicer */
		v = s->perimeter_acceleration > 0 ? s->perimeter_acceleration
						  : s->bridge_acceleration;
	else if (role == PATH_OUTER_PERIMETER || role == PATH_INNER_PERIMETER ||
		 role == PATH_THIN_WALL)
		v = s->perimeter_acceleration;
	else if (role == PATH_BRIDGE && s->bridge_acceleration > 0)
		v = s->bridge_acceleration;
	else if (role == PATH_BRIDGE || role == PATH_SOLID_INFILL || role == PATH_BOTTOM_SKIN ||
		 role == PATH_TOP_SKIN || role == PATH_SPARSE_INFILL || role == PATH_IRONING)
		v = s->infill_acceleration; /* a bridge is infill too */
	return v > 0 ? v : s->default_acceleration;
}

/* Plan path pi of layer li: travel to its start, then its segments, as
 * simplified to gcode_resolution (the speed is the original path's). */
static int plan_path(struct gcodew *w, const struct layer_paths *l, size_t li, size_t pi, bool rev)
{
	const struct gcodew_settings *s = w->s;
	const struct toolpath *p = &l->paths[pi], *q;
	double speed = path_speed(s, p, li);
	int rc = gcodew_simplify_path(w, p, &q);
	size_t steps = q->closed ? q->n + 1 : q->n;
	bool simplified = q != p;

	if (rc)
		return rc;
	const struct path_point *q0 = &q->pts[trav(q, rev, 0)];
	rc = plan_travel(w, q0->x / SLICE_UNITS_PER_MM, q0->y / SLICE_UNITS_PER_MM);
	if (rc == 0 && s->default_acceleration > 0)
		rc = push(w, (struct op){.kind = OP_ACCEL, .f = path_accel(s, p->role, li)});
	if (rc == 0 && w->plan_role != (int)p->role) {
		rc = push(w, (struct op){.kind = OP_ROLE, .role = p->role});
		w->plan_role = (int)p->role;
	}
	for (size_t k = 0; k + 1 < steps && rc == 0; k++) {
		size_t a = trav(q, rev, k), b = trav(q, rev, k + 1), f = rev ? b : a;
		const struct path_point *pa = &q->pts[a], *pb = &q->pts[b];
		rc = plan_segment(w, l, li, pi, simplified ? w->sidx[f] : f, pa, pb, q->pts[f].width,
				  w->layer_z, speed, simplified ? w->sstretch[f] : 1,
				  arc_at(w, simplified, f), rev);
	}
	if (rc == 0 && s->default_acceleration > 0) /* reset after the path, as PrusaSlicer */
		rc = push(w, (struct op){.kind = OP_ACCEL, .f = s->default_acceleration});
	/* With arcs the wipe follows the path as sliced, not the arcs' chords. */
	if (rc == 0 && s->wipe && s->arc_fitting)
		rc = record_wipe(w, p, rev, p->closed ? p->n + 1 : p->n, 0);
	else if (rc == 0 && s->wipe)
		rc = record_wipe(w, q, rev, steps, 0);
	return rc;
}

/* Squared distance (mm^2) from the nozzle to (x, y) in nm. */
static double dist2(const struct gcodew *w, int64_t x, int64_t y)
{
	double dx = x / SLICE_UNITS_PER_MM - w->px, dy = y / SLICE_UNITS_PER_MM - w->py;
	return dx * dx + dy * dy;
}

/* Perimeters, closed sparse infill (concentric loops, outermost first)
 * and ordered paths (monotonic skins) keep their order; other paths go
 * nearest first. */
static bool keep_order(const struct toolpath *p)
{
	return p->role == PATH_OUTER_PERIMETER || p->role == PATH_INNER_PERIMETER ||
	       (p->role == PATH_SPARSE_INFILL && p->closed) || p->ordered;
}

/* Plan the paths [i, j) of one role run, nearest neighbour first. */
static int plan_run(struct gcodew *w, const struct layer_paths *l, size_t li, size_t i, size_t j)
{
	for (size_t left = j - i; left > 0; left--) {
		size_t best = j;
		bool best_rev = false;
		double best_d = INFINITY;
		for (size_t k = i; k < j; k++) {
			const struct toolpath *p = &l->paths[k];
			if (w->done[k])
				continue;
			if (!w->pos_known || keep_order(p)) {
				best = k;
				break;
			}
			double d0 = dist2(w, p->pts[0].x, p->pts[0].y);
			double d1 = p->closed ? INFINITY : dist2(w, p->pts[p->n - 1].x, p->pts[p->n - 1].y);
			if (d0 < best_d || d1 < best_d) {
				best = k;
				best_rev = d1 < d0;
				best_d = fmin(d0, d1);
			}
		}
		w->done[best] = true;
		int rc = plan_path(w, l, li, best, best_rev);
		if (rc)
			return rc;
	}
	return 0;
}

/*
 * Plan spiral layer li (layer_paths.spiral): its one loop from the vertex
 * nearest the nozzle, Z rising with the length printed from the top of the
 * layer below to l->z.  Reached from a spiral below by a plain move (no
 * retraction: it is the loop's own continuation), else by a travel; then,
 * as PrusaSlicer's transition layer, the flow rises with Z from nothing,
 * since the gap under the nozzle starts at nothing.  Simplified to
 * gcode_resolution, the loop starts at its kept vertex nearest the nozzle
 * and Z and the flow ramp are taken at the kept vertices.
 */
static int plan_spiral(struct gcodew *w, const struct layer_paths *l, size_t li)
{
	const struct toolpath *p = &l->paths[0], *q;
	double h = l->height, z0 = l->z - h, speed = path_speed(w->s, p, li);
	double total = 0, done = 0, best = INFINITY;
	size_t first = 0;
	int rc;
	bool simplified;

	/* The transition layer's flow rises along the loop, point by point:
	 * lines only, so the ramp is not one arc long. */
	w->no_arcs = !w->spiral_below;
	rc = gcodew_simplify_path(w, p, &q);
	simplified = q != p;
	if (rc)
		return rc;
	for (size_t k = 0; k < p->n; k++) {
		const struct path_point *a = &p->pts[k], *b = &p->pts[(k + 1) % p->n];
		total += hypot((double)(b->x - a->x), (double)(b->y - a->y)) / SLICE_UNITS_PER_MM;
	}
	for (size_t k = 0; k < q->n; k++) {
		double d = w->pos_known ? dist2(w, q->pts[k].x, q->pts[k].y) : 0;
		if (d < best) {
			best = d;
			first = k;
		}
	}
	w->layer_z = z0;
	if (w->spiral_below && w->pos_known)
		rc = push_move(w, MV_TRAVEL, true, q->pts[first].x / SLICE_UNITS_PER_MM,
			       q->pts[first].y / SLICE_UNITS_PER_MM, z0, 0, w->s->travel_speed);
	else
		rc = plan_travel(w, q->pts[first].x / SLICE_UNITS_PER_MM,
				 q->pts[first].y / SLICE_UNITS_PER_MM);
	if (rc == 0)
		rc = push(w, (struct op){.kind = OP_ROLE, .role = p->role});
	for (size_t k = 0; k < q->n && rc == 0; k++) {
		size_t a = (first + k) % q->n, b = (first + k + 1) % q->n;
		size_t i = simplified ? w->sidx[a] : a, ib = simplified ? w->sidx[b] : b;
		const struct path_point *pa = &q->pts[a], *pb = &q->pts[b];
		double t;
		do { /* Z rises with the original length, dropped points' included */
			const struct path_point *u = &p->pts[i], *v = &p->pts[(i + 1) % p->n];
			done += hypot((double)(v->x - u->x), (double)(v->y - u->y)) / SLICE_UNITS_PER_MM;
			i = (i + 1) % p->n;
		} while (i != ib);
		t = fmin(1, done / total);
		rc = plan_segment(w, l, li, 0, simplified ? w->sidx[a] : a, pa, pb, pa->width,
				  z0 + h * t, speed,
				  (w->spiral_below ? 1 : t) * (simplified ? w->sstretch[a] : 1),
				  arc_at(w, simplified, a), false);
	}
	w->layer_z = l->z;
	w->no_arcs = false;
	if (rc == 0 && w->s->wipe && w->s->arc_fitting)
		rc = record_wipe(w, p, false, p->n + 1, simplified ? w->sidx[first] : first);
	else if (rc == 0 && w->s->wipe)
		rc = record_wipe(w, q, false, q->n + 1, first);
	return rc;
}

/*
 * retract_layer_change: retract (wiping) and lift before the move to layer
 * l, as PrusaSlicer does whenever Z is to change; the first travel on l
 * unretracts.  Not between spiral layers (the loop goes on), for a layer
 * with nothing to print, nor before the first layer (nothing printed yet;
 * where the start G-code left the nozzle is not known).
 */
static int plan_layer_retract(struct gcodew *w, const struct layer_paths *l)
{
	const struct gcodew_settings *s = w->s;
	int rc;

	if (!s->retract_layer_change || s->retract_length <= 0 || l->n == 0 || !w->pos_known ||
	    (l->spiral && w->spiral_below) || fabs(w->pz - l->z) < 1e-9)
		return 0;
	rc = gcodew_plan_retract(w);
	w->plan_retracted = rc == 0;
	if (rc == 0 && lifts_at(s, w->pz))
		rc = push_move(w, MV_TRAVEL, false, 0, 0, w->pz + s->retract_lift, 0, z_speed(s));
	return rc;
}

/* Plan every path of layer li into w->ops. */
int gcodew_plan_layer(struct gcodew *w, const struct layer_paths *l, size_t li)
{
	int rc;

	w->nops = 0;
	rc = plan_layer_retract(w, l);
	if (rc)
		return rc;
	w->layer_z = l->z;
	w->plan_role = -1;
	w->map = w->s->avoid_crossing_perimeters ? l->travel : NULL;
	if (l->n > w->donecap) {
		bool *grown = st_grow(w->done, &w->donecap, l->n, sizeof(*grown));
		if (!grown)
			return st_error_set(w->err, ST_ERR_NOMEM, "G-code: out of memory planning a layer");
		w->done = grown;
	}
	if (l->n)
		memset(w->done, 0, l->n * sizeof(*w->done));
	if (l->spiral && l->n == 1 && l->paths[0].closed) {
		rc = plan_spiral(w, l, li);
		w->spiral_below = true;
		return rc;
	}
	w->spiral_below = false;
	for (size_t i = 0, j; i < l->n && rc == 0; i = j) {
		for (j = i + 1; j < l->n && l->paths[j].role == l->paths[i].role; j++)
			;
		rc = plan_run(w, l, li, i, j);
	}
	return rc;
}

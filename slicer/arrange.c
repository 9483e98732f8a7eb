/*
 * arrange.c - footprints of several models packed on one bed (arrange.h).
 */
#include "arrange.h"

#include <math.h>
#include <stdlib.h>

#include "toolpath.h"

/* Scores closer than this are equal (the earlier candidate wins). */
#define ARRANGE_TIE 1e-9

/* A footprint as placed: lower-left corner and size, mm. */
struct rect {
	double x, y, w, h;
};

/* How good a candidate is: lower is better, compared in order. */
struct score {
	double fill, area, dist;
};

static bool better(const struct score *a, const struct score *b)
{
	if (fabs(a->fill - b->fill) > ARRANGE_TIE)
		return a->fill < b->fill;
	if (fabs(a->area - b->area) > ARRANGE_TIE * fmax(1.0, b->area))
		return a->area < b->area;
	return a->dist < b->dist - ARRANGE_TIE;
}

/* Whether r keeps gap (less the tie slack) from every one of placed[0..n). */
static bool clear_of(const struct rect *r, const struct rect *placed, size_t n, double gap)
{
	double g = gap - ARRANGE_TIE;

	for (size_t i = 0; i < n; i++) {
		const struct rect *q = &placed[i];
		if (!(r->x >= q->x + q->w + g || r->x + r->w <= q->x - g ||
		      r->y >= q->y + q->h + g || r->y + r->h <= q->y - g))
			return false;
	}
	return true;
}

/* The pile's box (lo, hi) grown by r. */
static void pile_add(double lo[2], double hi[2], const struct rect *r)
{
	lo[0] = fmin(lo[0], r->x);
	lo[1] = fmin(lo[1], r->y);
	hi[0] = fmax(hi[0], r->x + r->w);
	hi[1] = fmax(hi[1], r->y + r->h);
}

/* The twelve places beside q for a w x h footprint, gap apart: right,
 * left, back, front, each aligned with q's low edge, high edge, centre. */
static void beside(const struct rect *q, double w, double h, double gap, struct rect out[12])
{
	double ys[3] = {q->y, q->y + q->h - h, q->y + (q->h - h) / 2.0};
	double xs[3] = {q->x, q->x + q->w - w, q->x + (q->w - w) / 2.0};

	for (int k = 0; k < 3; k++) {
		out[k] = (struct rect){q->x + q->w + gap, ys[k], w, h};
		out[3 + k] = (struct rect){q->x - gap - w, ys[k], w, h};
		out[6 + k] = (struct rect){xs[k], q->y + q->h + gap, w, h};
		out[9 + k] = (struct rect){xs[k], q->y - gap - h, w, h};
	}
}

/* Room the bed leaves around the point the pile is centred on, mm. */
static void room_of(const struct slicer_bed *bed, double room[2])
{
	double c[2] = {bed->has_center ? bed->center_x : (bed->min_x + bed->max_x) / 2.0,
		       bed->has_center ? bed->center_y : (bed->min_y + bed->max_y) / 2.0};

	room[0] = 2.0 * fmin(c[0] - bed->min_x, bed->max_x - c[0]);
	room[1] = 2.0 * fmin(c[1] - bed->min_y, bed->max_y - c[1]);
}

/* Footprint area, mm^2. */
static double area_of(const struct arrange_item *a)
{
	return (a->max[0] - a->min[0]) * (a->max[1] - a->min[1]);
}

/* order[] = the indices of it[] by footprint area, largest first, ties in
 * input order (an insertion sort: stable, no shared state, n is small). */
static void sort_by_area(const struct arrange_item *it, size_t n, size_t *order)
{
	for (size_t i = 0; i < n; i++) {
		size_t k = i;
		while (k > 0 && area_of(&it[order[k - 1]]) < area_of(&it[i])) {
			order[k] = order[k - 1];
			k--;
		}
		order[k] = i;
	}
}

/* Place footprint r (size set) into placed[n]; false when nothing fits. */
static bool place_one(struct rect *placed, size_t n, struct rect *r, double lo[2], double hi[2],
		      const double room[2], double gap)
{
	struct score best = {INFINITY, INFINITY, INFINITY};
	struct rect cand[12], pick = *r;
	double cx = (lo[0] + hi[0]) / 2.0, cy = (lo[1] + hi[1]) / 2.0;
	bool found = false;

	for (size_t q = 0; q < n; q++) {
		beside(&placed[q], r->w, r->h, gap, cand);
		for (int k = 0; k < 12; k++) {
			double nlo[2] = {lo[0], lo[1]}, nhi[2] = {hi[0], hi[1]};
			struct score s;

			if (!clear_of(&cand[k], placed, n, gap))
				continue;
			pile_add(nlo, nhi, &cand[k]);
			if (nhi[0] - nlo[0] > room[0] + SLICER_FIT_SLACK ||
			    nhi[1] - nlo[1] > room[1] + SLICER_FIT_SLACK)
				continue;
			s.fill = fmax((nhi[0] - nlo[0]) / room[0], (nhi[1] - nlo[1]) / room[1]);
			s.area = (nhi[0] - nlo[0]) * (nhi[1] - nlo[1]);
			s.dist = hypot(cand[k].x + r->w / 2.0 - cx, cand[k].y + r->h / 2.0 - cy);
			if (!found || better(&s, &best)) {
				best = s;
				pick = cand[k];
				found = true;
			}
		}
	}
	if (found) {
		*r = pick;
		pile_add(lo, hi, r);
	}
	return found;
}

int arrange_footprints(struct arrange_item *it, size_t n, const struct slicer_bed *bed,
		       size_t *failed, struct st_error *err)
{
	double room[2], gap = bed->object_distance, lo[2], hi[2];
	struct rect *placed;
	size_t *order;
	int rc = 0;

	if (n == 0 || n > ARRANGE_MAX_ITEMS)
		return st_error_set(err, ST_ERR_ARG, "arrange: %zu models; 1 to %d fit one bed", n,
				    ARRANGE_MAX_ITEMS);
	for (size_t i = 0; i < n; i++)
		if (!(it[i].max[0] >= it[i].min[0] && it[i].max[1] >= it[i].min[1]))
			return st_error_set(err, ST_ERR_ARG, "arrange: model %zu has no footprint",
					    i + 1);
	placed = calloc(n, sizeof(*placed));
	order = calloc(n, sizeof(*order));
	if (!placed || !order) {
		rc = st_error_set(err, ST_ERR_NOMEM, "arrange: out of memory");
		goto out;
	}
	room_of(bed, room);
	sort_by_area(it, n, order);
	for (size_t k = 0; k < n; k++) {
		const struct arrange_item *a = &it[order[k]];
		struct rect r = {0, 0, a->max[0] - a->min[0], a->max[1] - a->min[1]};

		if (k == 0) {
			r.x = -r.w / 2.0;
			r.y = -r.h / 2.0;
			lo[0] = r.x, lo[1] = r.y, hi[0] = r.x + r.w, hi[1] = r.y + r.h;
		}
		if ((k == 0 && (r.w > room[0] + SLICER_FIT_SLACK || r.h > room[1] + SLICER_FIT_SLACK)) ||
		    (k > 0 && !place_one(placed, k, &r, lo, hi, room, gap))) {
			if (failed)
				*failed = order[k];
			rc = st_error_set(err, ST_ERR_RANGE,
					  "the %.2f x %.2f mm model finds no room beside the others: "
					  "together, %.0f mm apart (duplicate_distance), they do not "
					  "fit the %.2f x %.2f mm the bed leaves around the centre; "
					  "slice fewer models at once",
					  r.w, r.h, gap, room[0], room[1]);
			goto out;
		}
		placed[k] = r;
	}
	for (size_t k = 0; k < n; k++) {
		struct arrange_item *a = &it[order[k]];
		/* Whole nanometres, as slicer_place moves a model. */
		a->shift[0] = round((placed[k].x - a->min[0]) * SLICE_UNITS_PER_MM) /
			      SLICE_UNITS_PER_MM;
		a->shift[1] = round((placed[k].y - a->min[1]) * SLICE_UNITS_PER_MM) /
			      SLICE_UNITS_PER_MM;
	}
out:
	free(placed);
	free(order);
	return rc;
}

bool arrange_overlap(const struct arrange_item *it, size_t n)
{
	for (size_t i = 0; i < n; i++)
		for (size_t j = i + 1; j < n; j++)
			if (it[i].min[0] < it[j].max[0] && it[j].min[0] < it[i].max[0] &&
			    it[i].min[1] < it[j].max[1] && it[j].min[1] < it[i].max[1])
				return true;
	return false;
}

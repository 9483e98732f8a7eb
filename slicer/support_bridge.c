/*
 * support_bridge.c - bridges left unsupported (dont_support_bridges,
 * support.h).  A bridge prints as threads that rest on the layer below at
 * both ends, so only threads with an end in the air need support
 * (PrusaSlicer keeps support under a bridge's unanchored edges only).
 *
 * For the contact area C of layer i: P = C grown by SUPPORT_BRIDGE_REACH
 * bead widths (as far as bridge infill reaches into its anchors), within
 * M_i.  In each of SUPPORT_BRIDGE_DIRS directions lines
 * SUPPORT_BRIDGE_SCORE_STRIDE flow spacings apart are cut to P; a piece
 * spans the air when its midpoint is off M_{i-1}, and is anchored when
 * both its ends (a micrometre inward) lie on M_{i-1}.  The direction
 * anchoring the largest share of the spanning length is the bridge's; its
 * anchored spanning pieces, lines one flow spacing apart, each swept a
 * spacing to either side (so neighbours overlap and reach the edges), are
 * taken out of C.  A cantilever keeps its support: its lines have a free
 * end in every direction.
 */
#include "support_int.h"

#include <math.h>

#include "perimeters.h"

/* Directions tried: every 180 / this many degrees (the infill's bridge
 * detector tries the same 5 degree steps). */
#define SUPPORT_BRIDGE_DIRS 36
/* How far lines reach into their anchors, bead widths (the infill's bridge
 * anchor margin). */
#define SUPPORT_BRIDGE_REACH 3.0
/* The directions are scored with lines this many flow spacings apart (the
 * score is a share of length, which sparser lines estimate well); the
 * bridge's own lines, taken out of the contact, are one spacing apart. */
#define SUPPORT_BRIDGE_SCORE_STRIDE 4.0
/* A line end is nudged this far inward before the anchor test, nm. */
#define SUPPORT_BRIDGE_NUDGE_NM 1000.0

/* Anchored spanning length (*held) and all spanning length (*span) of the
 * pieces in cut, the anchored ones appended to held_pieces when not NULL. */
static int score_pieces(struct support_ctx *c, const struct clip_paths *cut,
			const struct clip_locator *below, double *held, double *span,
			struct clip_paths *held_pieces)
{
	int rc = 0;

	*held = *span = 0.0;
	for (size_t k = 0; k < cut->n && !rc; k++) {
		const int64_t *xy = clip_path_xy(cut, k);
		size_t m = clip_path_len(cut, k);
		double dx = (double)(xy[2 * m - 2] - xy[0]), dy = (double)(xy[2 * m - 1] - xy[1]);
		double len = hypot(dx, dy);
		if (len <= 2.0 * SUPPORT_BRIDGE_NUDGE_NM ||
		    clip_locator_inside(below, (xy[0] + xy[2 * m - 2]) / 2,
					(xy[1] + xy[2 * m - 1]) / 2))
			continue; /* not over the air */
		int64_t ux = llround(dx / len * SUPPORT_BRIDGE_NUDGE_NM),
			uy = llround(dy / len * SUPPORT_BRIDGE_NUDGE_NM);
		*span += len;
		if (!clip_locator_inside(below, xy[0] + ux, xy[1] + uy) ||
		    !clip_locator_inside(below, xy[2 * m - 2] - ux, xy[2 * m - 1] - uy))
			continue;
		*held += len;
		if (held_pieces) {
			int64_t seg[4] = {xy[0], xy[1], xy[2 * m - 2], xy[2 * m - 1]};
			rc = clip_paths_add(held_pieces, seg, 2, c->err);
		}
	}
	return rc;
}

int support_drop_bridges(struct support_ctx *c, size_t i, struct clip_paths *contact)
{
	struct clip_paths P = {0}, cut = {0}, held = {0};
	struct clip_locator *below = NULL;
	double sp = perim_spacing(c->w, c->st->layers[i].height * SLICE_UNITS_PER_MM);
	double best = 0.0, best_a = 0.0;
	int rc;

	if (!support_model(c, i - 1)->n)
		return 0; /* nothing below to rest on */
	rc = clip_offset(contact, SUPPORT_BRIDGE_REACH * c->w, CLIP_JOIN_ROUND, 2.0, c->arc, &P,
			 c->err);

	if (!rc)
		rc = clip_boolean(CLIP_INTERSECTION, &P, support_model(c, i), CLIP_NONZERO, &P,
				  c->err);
	if (!rc && !(below = clip_locator_new(support_model(c, i - 1), c->err)))
		rc = c->err ? c->err->code : ST_ERR_NOMEM;
	for (int k = 0; k < SUPPORT_BRIDGE_DIRS && !rc; k++) {
		double a = k * M_PI / SUPPORT_BRIDGE_DIRS, h, span;
		rc = support_line_pieces(c, &P, SUPPORT_BRIDGE_SCORE_STRIDE * sp, a, 0, &cut);
		if (!rc)
			rc = score_pieces(c, &cut, below, &h, &span, NULL);
		if (!rc && span > 0 && h / span > best) {
			best = h / span;
			best_a = a;
		}
	}
	if (!rc && best > 0)
		rc = support_line_pieces(c, &P, sp, best_a, 0, &cut);
	double h, span;
	if (!rc && best > 0)
		rc = score_pieces(c, &cut, below, &h, &span, &held);
	if (!rc && held.n)
		rc = clip_offset_open(&held, sp, CLIP_JOIN_SQUARE, CLIP_END_BUTT, 2.0, c->arc, &held,
				      c->err);
	if (!rc && held.n)
		rc = clip_boolean(CLIP_DIFFERENCE, contact, &held, CLIP_NONZERO, contact, c->err);
	clip_locator_free(below);
	clip_paths_free(&P);
	clip_paths_free(&cut);
	clip_paths_free(&held);
	return rc;
}

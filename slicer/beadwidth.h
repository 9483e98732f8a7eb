/*
 * beadwidth.h - variable-width wall loops (private to the perimeter
 * generator): where a wall is between one and two bead widths thick, the
 * strip its loops leave between their beads can be narrower than any bead
 * that gap fill can print (at least the layer height and gap_fill_min).
 * Such a strip is shared out to the beads on its two sides, as Arachne's
 * wall_distribution_count = 1 does: each side's bead grows by half the
 * strip's width and its centre line moves half of that towards the strip,
 * so its other face stays where it was (on the model's surface for the
 * outer wall).  A 1.0 mm wall with 0.45 mm beads becomes one loop of
 * 0.521 mm beads, (T + h (1 - pi/4)) / 2, with no strip left between them.
 *
 * How: the loop is resampled every step along the segments that come near
 * a strip; from each sample a ray along the segment's normal (left into
 * the strip inside the loop, right into the strip outside it) must enter
 * the strip within tol of half the loop's spacing (the strip's edge next
 * to this bead), and the distance it then runs inside the strip is the
 * strip's width there, if it leaves through a side facing this one (at
 * least 45 degrees across the ray, not a strip's end or corner).  Widths below gmax are absorbed; each sample moves
 * by (g_in - g_out) / 4 along its normal and its bead widens by
 * (g_in + g_out) / 2; the loop's corners move to where their two shifted
 * segments meet.  Every point's width is the width from it to the next
 * (toolpath.h), so the writer computes E per segment of constant width.
 */
#ifndef STRATUM_SLICER_BEADWIDTH_H
#define STRATUM_SLICER_BEADWIDTH_H

#include <stdbool.h>
#include <stddef.h>

#include "clip.h"
#include "st_error.h"
#include "toolpath.h"

/* How one loop's beads take up the strips beside them, nm. */
struct bead_fit {
	double width;	/* the loop's bead width */
	double spacing; /* its spacing: the strips begin spacing / 2 from its centre line */
	double gmax;	/* strips narrower than this are absorbed (and at most spacing) */
	double gmax_in; /* the same for the strips inside; 0: gmax */
	double step;	/* resampling distance along segments near a strip */
	double tol;	/* how far from spacing / 2 a strip's edge may start */
};

/*
 * bead_strips - the pieces of strip (nm) that are strips: those of at
 * least gmax x min_len area, and the smaller ones with a centre line
 * (medial.h) at least min_len long that narrows below gmax somewhere,
 * appended to out.  A convex corner's speck between a sharp
 * loop and the round one inside it (its centre lines are its two cusps,
 * shorter than the nozzle) is left out: it is no wall, and its beads stay
 * as they are.  arc: the chord tolerance (nm).  Returns 0 or ST_ERR_NOMEM.
 */
int bead_strips(const struct clip_expolys *strip, double gmax, double min_len, double arc,
		struct clip_paths *out, struct st_error *err);

/*
 * bead_fit_loop - the points of the closed loop xy[0 .. 2n) (nm, its solid
 * on the left), widened into the strips inside (on its left; may be NULL)
 * and outside it (on its right; may be NULL) as above.  *out is a new
 * array of *nout points (free it), every point width wide where nothing
 * is absorbed; *changed says whether anything was (when not, *out is the
 * loop as given).  Returns 0 or ST_ERR_NOMEM.
 */
int bead_fit_loop(const int64_t *xy, size_t n, const struct clip_paths *inside,
		  const struct clip_paths *outside, const struct bead_fit *f,
		  struct path_point **out, size_t *nout, bool *changed, struct st_error *err);

/*
 * bead_split_line - one centre-line bead of an open line l (nm, medial.h)
 * as two beads side by side that fill the same width W, as one closed
 * loop: each (W + k) / 2 wide, their centres (W - k) / 4 either side of
 * the line (k = h (1 - pi/4), the flow model's overlap of two beads), the
 * loop's ends moved out by (W - (W + k) / 2) / 2 so its round ends reach
 * as far as the single bead's did.  Only when every segment is at least
 * min_width wide: else *n = 0.  *out is a new array (free it).  Returns 0
 * or ST_ERR_NOMEM.
 */
struct medial_line;
int bead_split_line(const struct medial_line *l, double k, double min_width,
		    struct path_point **out, size_t *n, struct st_error *err);

#endif /* STRATUM_SLICER_BEADWIDTH_H */

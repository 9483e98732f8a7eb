/*
 * patterns.h - infill line patterns (private to slicer/infill_fill.c,
 * ironing.c and support_lines.c): open polylines covering a bounding box, in nm, to be clipped
 * to the region they fill.  Every pattern is anchored to the bed origin,
 * so the same parameters give the same lines on every layer and sparse
 * infill stacks.
 */
#ifndef STRATUM_SLICER_PATTERNS_H
#define STRATUM_SLICER_PATTERNS_H

#include <stdbool.h>
#include <stdint.h>

#include "clip.h"
#include "st_error.h"

/* Axis-aligned box of a point set, nm: x0, y0, x1, y1. */
struct pat_box {
	int64_t x0, y0, x1, y1;
};

/* pat_box_of - the box of every point of ps; false when ps has no point. */
bool pat_box_of(const struct clip_paths *ps, struct pat_box *box);

/*
 * pat_extent - the range [*vmin, *vmax] (nm) of v = -x sin a + y cos a over
 * every point of ps: how far the set reaches across lines of direction a
 * (radians).  ps must have at least one point.
 */
void pat_extent(const struct clip_paths *ps, double a, double *vmin, double *vmax);

/*
 * pat_lines - append to out straight lines of direction a (radians) at
 * v = phase + k spacing (v as in pat_extent, every integer k) that cross
 * box, each reaching beyond the box on both sides.  spacing > 0 nm.
 * Returns 0, ST_ERR_RANGE (more than PAT_MAX_LINES lines), ST_ERR_NOMEM.
 */
int pat_lines(double a, double spacing, double phase, const struct pat_box *box,
	      struct clip_paths *out, struct st_error *err);

/*
 * pat_line_set - append to out PrusaSlicer's "line" pattern over the point
 * set ps: straight lines of direction a at v = k spacing (v as in
 * pat_extent), the odd-k ones tilted so that across ps (along the lines)
 * they run from v + osc to v - osc (their ends come within spacing - osc of
 * the neighbouring lines).  Each line reaches beyond ps on both sides.
 * Returns 0, ST_ERR_ARG (spacing not > 0), ST_ERR_RANGE (more than
 * PAT_MAX_LINES lines), ST_ERR_NOMEM.
 */
int pat_line_set(const struct clip_paths *ps, double a, double spacing, double osc,
		 struct clip_paths *out, struct st_error *err);

/*
 * pat_honeycomb - append to out PrusaSlicer's 2D honeycomb covering box:
 * hexagons of width d across the flats (side 2 d / sqrt 3), traced as
 * pairs of mirrored zig-zag columns joined at one end, lines inset by inset
 * nm from the cell walls so the walls two columns share are two beads side
 * by side.  The columns run at direction theta (radians) turned about the
 * centre of the hexagon at (d, 2 d / sqrt 3), which maps the lattice onto
 * itself for multiples of 60 degrees.  d > 2 inset > 0.  Returns 0,
 * ST_ERR_ARG, ST_ERR_RANGE (too many cells), ST_ERR_NOMEM.
 */
int pat_honeycomb(double d, double inset, double theta, const struct pat_box *box,
		  struct clip_paths *out, struct st_error *err);

/*
 * pat_honeycomb_cell - the cell width d (nm) of the honeycomb whose lines,
 * sp apart where two columns share a wall, have the length per area of
 * lines S apart: a period of the pattern (2 d wide, 2 sqrt 3 d tall) holds
 * (16 d - 4 sp) / sqrt 3 of line, so 3 d^2 - 4 S d + S sp = 0.
 * (PrusaSlicer takes d = S: 28 % more than rectilinear on the infill test's
 * two 20 mm boxes at 15 %.)
 */
double pat_honeycomb_cell(double sp, double S);

/*
 * pat_gyroid - append to out the cross-section of the gyroid surface
 * sin x cos y + sin y cos z + sin z cos x = 0, with (x, y, z) = k (X, Y, Z)
 * for bed coordinates X, Y, Z in nm, at height z_nm, as polylines covering
 * box, their chords within PAT_GYROID_TOLERANCE_NM of the curve and across
 * it, as long as it to a few tenths of a per cent.  k > 0
 * (radians per nm) sets the period 2 pi / k.  Returns 0, ST_ERR_RANGE (too
 * many polylines), ST_ERR_NOMEM.
 */
int pat_gyroid(double k, double z_nm, const struct pat_box *box, struct clip_paths *out,
	       struct st_error *err);

/*
 * Mean length of the gyroid's horizontal cross-section per unit area, over
 * a period in z, for period 2 pi (k = 1): measured by sampling the level
 * set on a 200 x 200 x 24 grid (0.35 to 0.40 depending on z).  Lines of
 * spacing s at density d need k = d / (s PAT_GYROID_LENGTH).
 */
#define PAT_GYROID_LENGTH 0.392

/*
 * How far the gyroid's chords may leave the curve, nm.  Sparse infill is
 * inside the part, so its curve needs no more.  At 10 um a 20 mm cube's
 * sparse gyroid took 1.7 times PrusaSlicer's infill moves, 30,447 against
 * 17,837; at 50 um 15,644; at 75 um the 20 mm cylinder's whole G-code
 * went from 1.03 to 0.96 times PrusaSlicer's lines, the outer wall, held
 * to half of gcode_resolution, being the rest (docs/benchmarks.md,
 * "G-code size").
 */
#define PAT_GYROID_TOLERANCE_NM 75000.0

/* Most lines one call may produce (a guard against absurd spacings). */
#define PAT_MAX_LINES 1000000

#endif /* STRATUM_SLICER_PATTERNS_H */

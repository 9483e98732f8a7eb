/*
 * perimeters_settings.c - the wall settings: defaults, checks, the flow
 * model's widths and the seam names (see perimeters.h).
 */
#include "perimeters.h"

#include <math.h>
#include <string.h>

#include "settings.h"

void perim_settings_init(struct perim_settings *s, double nozzle_diameter)
{
	s->nozzle_diameter = nozzle_diameter;
	s->extrusion_width = 1.125 * nozzle_diameter;
	s->external_extrusion_width = 0.0;
	s->perimeters = 2;
	s->outer_first = false;
	s->seam = PERIM_SEAM_ALIGNED;
	s->thin_walls = true;
	s->gap_fill = true;
	s->gap_fill_min = 0.1;
	s->min_feature_size = 0.25 * nozzle_diameter;
	s->min_bead_width = 0.85 * nozzle_diameter;
	s->transition_length = nozzle_diameter;
	s->transition_angle = 10.0;
	s->arc_tolerance = 0.002;
}

double perim_spacing(double width, double height)
{
	return width - height * (1.0 - M_PI / 4.0);
}

double perim_bead_area(double width, double height)
{
	return (width - height) * height + M_PI * (height / 2.0) * (height / 2.0);
}

double perim_outer_width(const struct perim_settings *s)
{
	return s->external_extrusion_width > 0.0 ? s->external_extrusion_width
						 : s->extrusion_width;
}

double perim_round_bead(double d, double height)
{
	return fmax(height, height + M_PI * (d * d - height * height) / (4.0 * height));
}

int perim_settings_check(const struct perim_settings *s, double layer_height,
			 struct st_error *err)
{
	if (!s)
		return st_error_set(err, ST_ERR_ARG, "perimeters: no settings given");
	if (!(s->nozzle_diameter > 0.0 && s->nozzle_diameter <= 5.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: nozzle diameter %g mm is out of range; use (0, 5] mm",
				    s->nozzle_diameter);
	if (!(layer_height > 0.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: layer height %g mm must be greater than 0",
				    layer_height);
	if (layer_height > s->nozzle_diameter)
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: layer height %g mm is larger than the nozzle "
				    "diameter %g mm; use layers of at most the nozzle diameter",
				    layer_height, s->nozzle_diameter);
	if (!(s->extrusion_width > 0.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: extrusion width %g mm must be greater than 0 "
				    "(default 1.125 x nozzle diameter)",
				    s->extrusion_width);
	if (s->extrusion_width < layer_height || s->extrusion_width > 4.0 * s->nozzle_diameter)
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: extrusion width %g mm is out of range; use between "
				    "the layer height %g mm and 4 x the nozzle diameter (%g mm)",
				    s->extrusion_width, layer_height, 4.0 * s->nozzle_diameter);
	if (!(s->external_extrusion_width >= 0.0) ||
	    (s->external_extrusion_width > 0.0 &&
	     (s->external_extrusion_width < layer_height ||
	      s->external_extrusion_width > 4.0 * s->nozzle_diameter)))
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: external_perimeter_extrusion_width %g mm is out of "
				    "range; use 0 (the walls' width) or between the layer height %g "
				    "mm and 4 x the nozzle diameter (%g mm)",
				    s->external_extrusion_width, layer_height,
				    4.0 * s->nozzle_diameter);
	if (s->perimeters < 0)
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: perimeter count %d is negative; use 0 or more",
				    s->perimeters);
	if (s->perimeters > 1000)
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: perimeter count %d is too large; use at most 1000",
				    s->perimeters);
	if ((unsigned)s->seam >= PERIM_SEAMS)
		return st_error_set(err, ST_ERR_ARG,
				    "perimeters: seam mode %d is unknown; use aligned, nearest, "
				    "random or rear",
				    (int)s->seam);
	if (!(s->gap_fill_min >= 0.0 && s->gap_fill_min <= 10.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: gap fill minimum width %g mm is out of range; use "
				    "[0, 10] mm",
				    s->gap_fill_min);
	if (!(s->min_feature_size >= 0.0 && s->min_feature_size <= s->nozzle_diameter))
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: min_feature_size %g mm is out of range; use 0 to "
				    "the nozzle diameter %g mm",
				    s->min_feature_size, s->nozzle_diameter);
	if (!(s->min_bead_width > 0.0 && s->min_bead_width <= 4.0 * s->nozzle_diameter))
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: min_bead_width %g mm is out of range; use (0, %g] "
				    "mm (4 x the nozzle diameter)",
				    s->min_bead_width, 4.0 * s->nozzle_diameter);
	int rc = setting_check("perimeters", "wall_transition_length", s->transition_length, err);
	if (!rc)
		rc = setting_check("perimeters", "wall_transition_angle", s->transition_angle, err);
	if (rc)
		return rc;
	double narrowest = fmin(s->extrusion_width, perim_outer_width(s));
	if (!(s->arc_tolerance > 0.0 && s->arc_tolerance <= narrowest / 4.0))
		return st_error_set(err, ST_ERR_RANGE,
				    "perimeters: arc tolerance %g mm is out of range; use (0, %g] mm "
				    "(a quarter of the extrusion width)",
				    s->arc_tolerance, narrowest / 4.0);
	return 0;
}

/* The names are seam_position's declaration (settings.c), in enum order. */
int perim_seam_parse(const char *name, enum perim_seam *out, struct st_error *err)
{
	const struct setting *d = settings_find("seam_position");

	for (size_t i = 0; name && d && i < d->nnames && i < PERIM_SEAMS; i++)
		if (!strcmp(name, d->names[i])) {
			*out = (enum perim_seam)i;
			return 0;
		}
	return st_error_set(err, ST_ERR_ARG,
			    "perimeters: seam_position \"%.64s\" is unknown; use aligned, nearest, "
			    "random or rear",
			    name ? name : "(none)");
}

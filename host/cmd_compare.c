/*
 * cmd_compare.c - `stratum compare A [B] [--reference FINE] [--tolerance
 * MM] [--samples N] [--json] [--png PICTURE.png]`: the symmetric surface
 * distance between A and B, and seed 003's chordal error of each facet of
 * A against a finer surface with the facets over a tolerance isolated
 * (repair/deviation.h).  Exit 0, 2 usage, 65 unreadable model, 1 the
 * picture could not be written, 70 out of memory.  docs/accuracy.md.
 */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accplot.h"
#include "commands.h"
#include "deviation.h"
#include "mesh.h"
#include "meshio.h"
#include "st_error.h"
#include "surfsample.h"

#define FACETS_SHOWN 20 /* over-tolerance facets the text report names */

static const char compare_head[] =
    "usage: stratum compare A [B] [--reference FINE] [--tolerance MM] [--samples N]\n"
    "                       [--json] [--png PICTURE.png]\n"
    "\n"
    "With B: how far the surfaces of meshes A and B (STL, OBJ, OFF or 3MF) lie\n"
    "from each other - the largest distance both ways (Hausdorff), the mean and\n"
    "the 95th percentile weighted by area, and a histogram - from even samples\n"
    "on each surface and the nearest point of the other (CGAL's AABB tree).\n"
    "With --reference FINE: seed 003's chordal error of every facet of A, the\n"
    "distance along the facet's normal from points on it to the finer surface\n"
    "(or FINE's points nearest to the facet, if farther) - the measure `stratum\n"
    "refine` stops by - and the facets over the tolerance, in edge-connected\n"
    "regions.  --png draws\n"
    "A coloured by its distance to B (else by its chordal error).  See\n"
    "docs/accuracy.md.\n"
    "\n";

struct compare_args {
	const char *pos[2], *reference, *png;
	double tolerance;
	long samples;
	bool json;
	size_t npos;
};

static int read_model(const char *path, struct mesh **m)
{
	int rc = cmd_read_mesh("stratum compare", path, m, NULL);

	if (rc || surfsample_area(*m) > 0)
		return rc;
	return cmd_fail("stratum compare", ST_EXIT_DATAERR,
			"%s: no triangle has an area; there is no surface to measure", path);
}

static json_t *side_json(const struct deviation_side *s)
{
	json_t *o = json_object();

	cmd_json_set(o, "z:samples", s->samples, "f:area", s->area, "f:max", s->max, "f:mean",
		     s->mean, NULL);
	return o;
}

static int print_json(const struct compare_args *a, const struct mesh *ma, const struct mesh *mb,
		      const struct deviation_report *d, const struct chordal_report *c)
{
	json_t *o = json_object();

	cmd_json_set(o, "s:a", a->pos[0], "z:a_triangles", ma->ntris, NULL);
	if (mb) {
		json_t *dist = json_object(), *hist = json_array();
		for (int i = 0; i < DEVIATION_BINS; i++)
			json_array_append_new(hist, json_real(d->hist[i]));
		cmd_json_set(dist, "f:max", d->max, "f:mean", d->mean, "f:p95", d->p95,
			     "o:a_to_b", side_json(&d->a_to_b), "o:b_to_a", side_json(&d->b_to_a),
			     "f:bin_width", d->bin_width, "o:histogram", hist, NULL);
		cmd_json_set(o, "s:b", a->pos[1], "z:b_triangles", mb->ntris, "o:distance", dist,
			     NULL);
	}
	if (c) {
		json_t *ch = json_object(), *over = json_array();
		for (size_t i = 0; i < c->nover; i++)
			json_array_append_new(over, json_integer(c->over[i]));
		cmd_json_set(ch, "s:reference", a->reference, "z:points", c->points, "f:max", c->max,
			     "f:mean", c->mean, "f:tolerance", c->tolerance, "z:facets_over",
			     c->nover, "z:regions", c->regions, "f:area_over", c->over_area,
			     "o:over", over, NULL);
		cmd_json_set(o, "o:chordal", ch, NULL);
	}
	return cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(8));
}

static void print_text(const struct compare_args *a, const struct mesh *ma, const struct mesh *mb,
		       const struct deviation_report *d, const struct chordal_report *c)
{
	printf("%s: %zu triangles\n", a->pos[0], ma->ntris);
	if (mb) {
		printf("%s: %zu triangles\n", a->pos[1], mb->ntris);
		printf("surface distance (%zu samples on A, %zu on B):\n", d->a_to_b.samples,
		       d->b_to_a.samples);
		printf("  max %.6f mm, mean %.6f mm, 95th percentile %.6f mm\n", d->max, d->mean,
		       d->p95);
		printf("  A to B: max %.6f mm, mean %.6f mm; B to A: max %.6f mm, mean %.6f mm\n",
		       d->a_to_b.max, d->a_to_b.mean, d->b_to_a.max, d->b_to_a.mean);
		printf("  share of the area by distance:\n");
		for (int i = 0; i < DEVIATION_BINS; i++)
			printf("    %9.6f - %-9.6f mm %6.2f%%\n", d->bin_width * i,
			       d->bin_width * (i + 1), 100 * d->hist[i]);
	}
	if (c) {
		printf("chordal error of A against %s (%zu points): max %.6f mm, mean %.6f mm\n",
		       a->reference, c->points, c->max, c->mean);
		printf("  facets over %g mm: %zu of %zu (%.6g mm^2, %zu regions)", c->tolerance,
		       c->nover, ma->ntris, c->over_area, c->regions);
		for (size_t i = 0; i < c->nover && i < FACETS_SHOWN; i++)
			printf("%s%u", i ? " " : ": ", (unsigned)c->over[i]);
		printf("%s\n", c->nover > FACETS_SHOWN ? " ..." : "");
	}
}

static int draw(const struct compare_args *a, const struct mesh *ma,
		const struct deviation_report *d, const struct chordal_report *c)
{
	struct st_error err = {0};
	char title[600];
	int rc;

	if (d) {
		struct accplot_hist h = {d->hist, DEVIATION_BINS, d->bin_width};
		snprintf(title, sizeof(title), "%s against %s: max %.4g mm, mean %.4g mm, 95%% %.4g mm",
			 a->pos[0], a->pos[1], d->max, d->mean, d->p95);
		struct accplot_values v = {d->facet_a, d->max, -1, "distance to B", false};
		rc = accplot_mesh(ma, &v, &h, title, a->png, &err);
	} else {
		snprintf(title, sizeof(title),
			 "chordal error of %s against %s: max %.4g mm, %zu facets over %g mm",
			 a->pos[0], a->reference, c->max, c->nover, c->tolerance);
		/* seed 003's isolation: the facets within the tolerance grey */
		struct accplot_values v = {c->facet, c->max, c->tolerance, "chordal error", false};
		rc = accplot_mesh(ma, &v, NULL, title, a->png, &err);
	}
	if (rc)
		fprintf(stderr, "stratum compare: %s\n", err.msg);
	return !rc ? 0 : rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_FAILURE;
}

/* The measurements asked for, the report and the picture. */
static int compare_models(const struct compare_args *a, struct mesh *ma, struct mesh *mb,
			  struct mesh *mref)
{
	struct deviation_report d = {0};
	struct chordal_report c = {0};
	struct st_error err = {0};
	int rc = 0;

	if (mb && (rc = deviation_measure(ma, mb, (size_t)a->samples, &d, &err)))
		goto failed;
	if (mref && (rc = chordal_measure(ma, mref, (size_t)a->samples, a->tolerance, &c, &err)))
		goto failed;
	if (a->png && (rc = draw(a, ma, mb ? &d : NULL, mref ? &c : NULL)))
		goto done;
	rc = cmd_report_end("stratum compare", "report",
			    a->json ? print_json(a, ma, mb, &d, mref ? &c : NULL) != 0
				    : (print_text(a, ma, mb, &d, mref ? &c : NULL), 0));
	goto done;
failed:
	fprintf(stderr, "stratum compare: %s\n", err.msg);
	rc = rc == ST_ERR_ARG ? ST_EXIT_DATAERR : ST_EXIT_SOFTWARE;
done:
	deviation_report_free(&d);
	chordal_report_free(&c);
	return rc;
}

int cmd_compare(int argc, char **argv)
{
	struct compare_args a = {.tolerance = 0.01, .samples = DEVIATION_SAMPLES_DEFAULT};
	struct mesh *ma = NULL, *mb = NULL, *mref = NULL;
	char msg[512];
	int rc;

	const struct cmd_opt opts[] = {
	    CMD_OPT_STRING("--reference", 0, &a.reference, CMD_NONEMPTY, "a mesh file", "FINE",
			   "a finer mesh of the same part: chordal error of A's facets"),
	    {"--tolerance", 0, CMD_DOUBLE, &a.tolerance, CMD_RANGE, 0, 1000,
	     "a distance from %g to %g mm", "MM",
	     "facets whose chordal error is above MM are isolated,\n%g to %g mm (default %g)", NULL,
	     NULL},
	    {"--samples", 0, CMD_LONG, &a.samples, CMD_RANGE, 1000, 1e8, "a number from %g to %g",
	     "N", "about N samples on each surface, at least one a facet,\n%g to %g (default %g)",
	     NULL, NULL},
	    CMD_OPT_FLAG("--json", &a.json, "one JSON object on stdout instead of the text report"),
	    CMD_OPT_STRING("--png", 0, &a.png, CMD_NONEMPTY, "a file name", "PICTURE.png",
			   "A coloured by its distance to B, or by its chordal error"),
	};
	const struct cmd_spec spec = {
	    .cmd = "stratum compare", .head = compare_head, CMD_TABLE(opts), .col = 24,
	    .tail = "\nExit status: 0 measured, 1 the picture could not be written, 2 usage,\n"
		    "65 unreadable model.\n",
	    .pos = a.pos, .npos = 2, .ngot = &a.npos,
	    .extra = "two models at most (%d given before '%s')"};

	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (!a.npos || (a.npos < 2 && !a.reference))
		return cmd_refuse(&spec, "%s",
				  !a.npos ? "no model given"
					  : "give a second model B or --reference FINE");
	if (a.png && (rc = cmd_output_check(a.pos[0], a.png, msg, sizeof(msg))))
		return cmd_fail("stratum compare", rc, "%s", msg);
	if (!(rc = read_model(a.pos[0], &ma)) && !(a.npos == 2 && (rc = read_model(a.pos[1], &mb))) &&
	    !(a.reference && (rc = read_model(a.reference, &mref))))
		rc = compare_models(&a, ma, mb, mref);
	mesh_free(ma);
	mesh_free(mb);
	mesh_free(mref);
	return rc;
}

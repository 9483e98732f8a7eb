/*
 * cmd_analyze.c - `stratum analyze MODEL --layer-height H [--spacing MM]
 * [--json] [--png PLOT.png]`: the staircase error of printing MODEL in
 * layers H mm thick, by seed 004's bounding-box method on a point cloud
 * (repair/cusp_measure.h), per layer and overall, and its plot against Z.
 * Exit 0, 2 usage, 65 unreadable model, 1 the plot could not be written,
 * 70 out of memory.  docs/accuracy.md.
 */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accplot.h"
#include "clio.h"
#include "commands.h"
#include "cusp_measure.h"
#include "mesh.h"
#include "meshio.h"
#include "st_error.h"

static const char analyze_head[] =
    "usage: stratum analyze MODEL --layer-height H [--spacing MM] [--json]\n"
    "                       [--png PLOT.png]\n"
    "\n"
    "Measures the staircase error (cusp height) of printing MODEL (STL, OBJ, OFF\n"
    "or 3MF; '-' reads stdin) in layers H mm thick, cut at mid-height as\n"
    "'stratum slice' cuts them, by seed 004's bounding-box method: a point cloud\n"
    "on the surface with its normals, two boxes on every segment a layer's plane\n"
    "cuts from a facet, and in each box the longest ray from a point along its\n"
    "normal to the box's wall, top or bottom.  Reports each layer's maximum and\n"
    "mean and the part's.  See docs/accuracy.md.\n"
    "\n";

struct analyze_args {
	const char *in, *png;
	double layer_height, spacing;
	bool json;
	const char *has_layer_height;
};

static int print_json(const char *shown, const struct mesh *m, const struct cusp_report *r)
{
	json_t *o = json_object(), *slices = json_array();

	for (size_t i = 0; i < r->nslices; i++) {
		json_t *s = json_object();
		cmd_json_set(s, "f:z", r->slices[i].z, "f:max", r->slices[i].max, "f:mean",
			     r->slices[i].mean, "z:boxes", r->slices[i].boxes, NULL);
		json_array_append_new(slices, s);
	}
	cmd_json_set(o, "s:file", shown, "z:triangles", m->ntris, "f:layer_height",
		     r->layer_height, "f:spacing", r->spacing, "z:points", r->points, "z:layers",
		     r->nslices, "z:boxes", r->nboxes, "f:max", r->max, "f:max_z", r->max_z,
		     "f:mean", r->mean, "o:slices", slices, NULL);
	return cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(8));
}

static void print_text(const char *shown, const struct mesh *m, const struct cusp_report *r)
{
	printf("%s: %zu triangles, %zu layers of %g mm (cut at mid-height), %zu cloud points "
	       "%g mm apart\n",
	       shown, m->ntris, r->nslices, r->layer_height, r->points, r->spacing);
	printf("cusp height: max %.4f mm (layer at z %.4g mm), mean %.4f mm over %zu boxes\n",
	       r->max, r->max_z, r->mean, r->nboxes);
	printf("  %10s %10s %10s %7s\n", "z mm", "max mm", "mean mm", "boxes");
	for (size_t i = 0; i < r->nslices; i++)
		printf("  %10.4f %10.4f %10.4f %7zu\n", r->slices[i].z, r->slices[i].max,
		       r->slices[i].mean, r->slices[i].boxes);
}

static int analyze_run(int argc, char **argv, struct clio *io)
{
	struct analyze_args a = {0};
	struct st_error err = {0};
	struct cusp_report r;
	struct mesh *m = NULL;
	const char *shown;
	char msg[512];
	int rc;

	const struct cmd_opt opts[] = {
	    {"--layer-height", 0, CMD_DOUBLE, &a.layer_height, CMD_RANGE | CMD_ABOVE_LO, 0, 10,
	     "a height above %g and up to %g mm", "H", "layer height, mm (needed)", NULL,
	     &a.has_layer_height},
	    {"--spacing", 0, CMD_DOUBLE, &a.spacing, CMD_RANGE | CMD_ABOVE_LO, 0, 100,
	     "a distance above %g and up to %g mm", "MM",
	     "cloud points MM apart (default: the layer height / " CMD_TEXT_OF(
		 CUSP_MEASURE_POINTS_PER_LAYER) ")",
	     NULL, NULL},
	    CMD_OPT_FLAG("--json", &a.json, "one JSON object on stdout instead of the text report"),
	    CMD_OPT_STRING("--png", 0, &a.png, CMD_NONEMPTY, "a file name", "PLOT.png",
			   "the cusp height against Z as a PNG plot"),
	};
	const struct cmd_spec spec = {
	    .cmd = "stratum analyze", .head = analyze_head, CMD_TABLE(opts), .col = 22,
	    .tail = "\nExit status: 0 measured, 1 the plot could not be written, 2 usage,\n"
		    "65 unreadable model.\n",
	    .pos = &a.in, .npos = 1, .extra = "one model at a time ('%s' and '%s')"};

	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (!a.in || !a.has_layer_height)
		return cmd_refuse(&spec, "%s",
				  !a.in ? "no model given" : "--layer-height H is needed");
	if (!a.spacing)
		a.spacing = a.layer_height / CUSP_MEASURE_POINTS_PER_LAYER;
	if (a.png && (rc = cmd_output_check(a.in, a.png, msg, sizeof(msg))))
		return cmd_fail("stratum analyze", rc, "%s", msg);
	shown = a.in;
	if ((rc = clio_input(io, &a.in, "")))
		return rc;
	if ((rc = cmd_read_mesh("stratum analyze", a.in, &m, NULL)))
		return rc;
	if ((rc = cusp_measure(m, a.layer_height, a.spacing, &r, &err))) {
		fprintf(stderr, "stratum analyze: %s: %s\n", shown, err.msg);
		mesh_free(m);
		return rc == ST_ERR_RANGE || rc == ST_ERR_ARG ? ST_EXIT_DATAERR : ST_EXIT_SOFTWARE;
	}
	if (a.png) {
		snprintf(msg, sizeof(msg), "cusp height of %s in %g mm layers (seed 004's boxes)",
			 shown, a.layer_height);
		if (accplot_cusp(&r, msg, a.png, &err)) {
			fprintf(stderr, "stratum analyze: %s\n", err.msg);
			cusp_report_free(&r);
			mesh_free(m);
			return err.code == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_FAILURE;
		}
	}
	rc = cmd_report_end("stratum analyze", "report",
			    a.json ? print_json(shown, m, &r) != 0 : (print_text(shown, m, &r), 0));
	cusp_report_free(&r);
	mesh_free(m);
	return rc;
}

int cmd_analyze(int argc, char **argv)
{
	return clio_run("stratum analyze", analyze_run, argc, argv);
}

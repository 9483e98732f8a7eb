/*
 * cmd_refine.c - `stratum refine COARSE --reference FINE --tolerance MM -o
 * OUT.stl [--uniform] [--json] [--png PICTURE.png]`: seed 003's vertex
 * translation against a finer mesh of the same part (repair/refine.h), and
 * with --uniform the uniform subdivision that reaches the same tolerance,
 * for its size.  Exit 0 written, 1 the tolerance was not reached (nothing
 * written) or the picture could not be written, 2 usage, 65 an unreadable
 * or unprintable model, 70 internal.  docs/accuracy.md.
 */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>

#include "accplot.h"
#include "commands.h"
#include "meshio.h"
#include "refine.h"
#include "st_error.h"
#include "surfsample.h"

static const char refine_head[] =
    "usage: stratum refine COARSE --reference FINE -o OUT.stl [--tolerance MM]\n"
    "                      [--move-vertices] [--uniform] [--json] [--png PICTURE.png]\n"
    "\n"
    "Seed 003's vertex translation: the facets of COARSE whose chordal error\n"
    "against FINE, a finer mesh of the same part (STL, OBJ, OFF or 3MF), is over\n"
    "the tolerance are split, each new vertex moved onto FINE's surface - onto\n"
    "the crease where FINE's faces meet at a sharp edge, else along the facets'\n"
    "normal - until every facet is within the tolerance, measured both ways.\n"
    "Moves that would make triangles cross (exact test) are refused.  COARSE\n"
    "must be printable; OUT is too.  --uniform also splits every edge of COARSE\n"
    "round after round until the same tolerance, to compare the sizes.  See\n"
    "docs/accuracy.md.\n"
    "\n";

struct refine_args {
	const char *in, *reference, *out, *png;
	bool json, uniform;
	struct refine_options opt;
};

/* The model at path, or an exit status after the message. */
static int read_model(const char *path, struct mesh **m)
{
	int rc = cmd_read_mesh("stratum refine", path, m, NULL);

	if (rc || surfsample_area(*m) > 0)
		return rc;
	return cmd_fail("stratum refine", ST_EXIT_DATAERR, "%s: no triangle has an area", path);
}

static json_t *run_json(const struct refine_report *r)
{
	json_t *o = json_object();

	cmd_json_set(o, "b:reached", r->reached, "z:rounds", r->rounds, "z:triangles",
		     r->triangles_after, "z:stl_bytes", refine_stl_bytes(r->triangles_after),
		     "f:error_before", r->error_before, "f:error_after", r->error_after,
		     "z:facets_over", r->facets_over, "z:vertices_added", r->vertices_added,
		     "z:on_creases", r->on_creases, "z:vertices_moved", r->vertices_moved,
		     "z:moves_refused", r->refused, NULL);
	return o;
}

static int print_json(const struct refine_args *a, const struct refine_report *r,
		      const struct refine_report *u)
{
	json_t *o = json_object();

	cmd_json_set(o, "s:coarse", a->in, "s:reference", a->reference, "s:output", a->out,
		     "f:tolerance", a->opt.tolerance, "z:triangles_before", r->triangles_before,
		     "f:vertex_error", r->vertex_error, "o:refined", run_json(r), NULL);
	if (u)
		cmd_json_set(o, "o:uniform", run_json(u), NULL);
	return cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(8));
}

static void print_run(const char *what, const struct refine_report *r)
{
	printf("%s: %zu triangles (%zu bytes of binary STL) after %zu rounds, largest chordal "
	       "error %.6f mm\n",
	       what, r->triangles_after, refine_stl_bytes(r->triangles_after), r->rounds,
	       r->error_after);
}

static void print_text(const struct refine_args *a, const struct refine_report *r,
		       const struct refine_report *u)
{
	printf("%s: %zu triangles, largest chordal error %.6f mm against %s\n", a->in,
	       r->triangles_before, r->error_before, a->reference);
	print_run("refined", r);
	printf("  %zu vertices added (%zu on creases), %zu of COARSE's moved onto %s, %zu moves "
	       "refused as they would make triangles cross, flip or collapse\n",
	       r->vertices_added, r->on_creases, r->vertices_moved, a->reference, r->refused);
	if (u) {
		print_run("uniform subdivision", u);
		if (u->reached)
			printf("  refined is %.1f%% of its triangles\n",
			       100.0 * (double)r->triangles_after / (double)u->triangles_after);
		else
			printf("  it does not reach %g mm under %zu triangles\n", a->opt.tolerance,
			       a->opt.max_triangles);
	}
	printf("wrote %s\n", a->out);
}

/* Why the tolerance was not reached, on stderr. */
static void explain(const struct refine_args *a, const struct refine_report *r)
{
	if (r->vertex_error > a->opt.tolerance)
		fprintf(stderr,
			"stratum refine: a vertex of %s lies %.6f mm from %s, farther than the "
			"tolerance; without --move-vertices refine moves only the vertices it adds\n",
			a->in, r->vertex_error, a->reference);
	else
		fprintf(stderr,
			"stratum refine: %zu facets still over %g mm (largest %.6f mm) after %zu "
			"rounds and %zu triangles, %zu moves refused; %s not written\n",
			r->facets_over, a->opt.tolerance, r->error_after, r->rounds,
			r->triangles_after, r->refused, a->out);
}

static int draw(const struct refine_args *a, const struct mesh *m, const struct refine_report *r)
{
	struct st_error err = {0};
	char title[600];
	struct accplot_values v = {r->facet_error, a->opt.tolerance, -1, "chordal error", true};
	int rc;

	snprintf(title, sizeof(title),
		 "%s refined against %s: %zu -> %zu triangles, largest chordal error %.4g mm",
		 a->in, a->reference, r->triangles_before, r->triangles_after, r->error_after);
	rc = accplot_mesh(m, &v, NULL, title, a->png, &err);
	if (rc)
		fprintf(stderr, "stratum refine: %s\n", err.msg);
	return !rc ? 0 : rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_FAILURE;
}

/* The status of a failed refine_mesh after its message. */
static int failed(const char *path, int rc, const struct st_error *err)
{
	if (rc == ST_ERR_UNSUPPORTED || rc == ST_ERR_RANGE) {
		fprintf(stderr, "stratum refine: %s: %s\n", path, err->msg);
		return ST_EXIT_DATAERR;
	}
	fprintf(stderr, "stratum refine: %s\n", err->msg);
	return ST_EXIT_SOFTWARE;
}

static int refine_models(struct refine_args *a, const struct mesh *coarse, const struct mesh *ref)
{
	struct refine_report r = {0}, u = {0};
	struct st_error err = {0};
	struct mesh *out = NULL, *uout = NULL;
	int rc = refine_mesh(coarse, ref, &a->opt, &out, &r, &err);

	if (rc)
		return failed(a->in, rc, &err);
	if (!r.reached) {
		explain(a, &r);
		rc = ST_EXIT_FAILURE;
		goto done;
	}
	if (a->uniform) {
		struct refine_options uo = a->opt;
		uo.uniform = true;
		if ((rc = refine_mesh(coarse, ref, &uo, &uout, &u, &err))) {
			rc = failed(a->in, rc, &err);
			goto done;
		}
	}
	if ((rc = meshio_write_stl(a->out, out, MESHIO_STL_BINARY, &err))) {
		fprintf(stderr, "stratum refine: %s\n", err.msg);
		rc = rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_FAILURE;
		goto done;
	}
	if (a->png && (rc = draw(a, out, &r)))
		goto done;
	rc = cmd_report_end("stratum refine", "report",
			    a->json ? print_json(a, &r, a->uniform ? &u : NULL) != 0
				    : (print_text(a, &r, a->uniform ? &u : NULL), 0));
done:
	refine_report_free(&r);
	refine_report_free(&u);
	mesh_free(out);
	mesh_free(uout);
	return rc;
}

int cmd_refine(int argc, char **argv)
{
	struct refine_args a = {0};
	struct mesh *coarse = NULL, *ref = NULL;
	long samples, max_tris;
	char msg[512];
	int rc;

	refine_options_init(&a.opt);
	samples = (long)a.opt.samples;
	max_tris = (long)a.opt.max_triangles;
	const struct cmd_opt opts[] = {
	    CMD_OPT_STRING("--reference", 0, &a.reference, CMD_NONEMPTY, "a mesh file", "FINE",
			   "a finer mesh of the same part, the surface to reach"),
	    CMD_OPT_STRING("--output", 'o', &a.out, CMD_NONEMPTY, "the output file name", "OUT",
			   "the refined mesh, binary STL (written only when the\n"
			   "tolerance is reached)"),
	    {"--tolerance", 0, CMD_DOUBLE, &a.opt.tolerance, CMD_RANGE | CMD_ABOVE_LO, 0, 1000,
	     "a distance in mm above %g and at most %g", "MM",
	     "the largest chordal error of a facet, %g < MM <= %g\n(default %g)", NULL, NULL},
	    {"--feature-angle", 0, CMD_DOUBLE, &a.opt.feature_angle, CMD_RANGE, 0, 180,
	     "an angle in degrees from %g to %g", "DEG",
	     "facets meeting at more than DEG make a crease whose new\n"
	     "vertices stay on FINE's crease, %g..%g (default %g)", NULL, NULL},
	    {"--samples", 0, CMD_LONG, &samples, CMD_RANGE, 1000, 1e8,
	     "a number from %g to %g", "N",
	     "about N measuring points on each surface per round,\n%g to %g (default %g)", NULL,
	     NULL},
	    {"--max-triangles", 0, CMD_LONG, &max_tris, CMD_RANGE, 100, 1e8,
	     "a number from %g to %g", "N",
	     "give up rather than grow past N triangles, %g to %g\n(default %g)", NULL, NULL},
	    CMD_OPT_FLAG("--move-vertices", &a.opt.move_vertices,
			 "first move COARSE's own vertices onto FINE too (a scan\n"
			 "and its decimation: COARSE's corners off FINE's surface)"),
	    CMD_OPT_FLAG("--uniform", &a.uniform,
			 "also subdivide every facet round after round to the same\n"
			 "tolerance and report its size (not written)"),
	    CMD_OPT_FLAG("--json", &a.json, "one JSON object on stdout instead of the text report"),
	    CMD_OPT_STRING("--png", 0, &a.png, CMD_NONEMPTY, "a file name", "PICTURE.png",
			   "the refined mesh, each facet coloured by its chordal error"),
	    CMD_OPT_THREADS(&a.opt.threads, "cores for the exact checks (default: all)"),
	};
	const struct cmd_spec spec = {
	    .cmd = "stratum refine", .head = refine_head, CMD_TABLE(opts), .col = 24,
	    .tail = "\nExit status: 0 written, 1 the tolerance was not reached (nothing written)\n"
		    "or the picture could not be written, 2 usage, 65 unreadable or unprintable\n"
		    "model, 70 internal error.\n",
	    .pos = &a.in, .npos = 1,
	    .extra = "one coarse model at a time ('%s' and '%s'); name the finer one with "
		     "--reference"};

	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (!a.in || !a.reference || !a.out) {
		fprintf(stderr, "stratum refine: %s\n",
			!a.in	       ? "no model given"
			: !a.reference ? "no reference given; add --reference FINE"
				       : "no output file given; add -o OUT.stl");
		cmd_usage(&spec, stderr);
		return ST_EXIT_USAGE;
	}
	a.opt.samples = (size_t)samples;
	a.opt.max_triangles = (size_t)max_tris;
	if ((rc = cmd_output_check(a.in, a.out, msg, sizeof(msg))) ||
	    (a.png && (rc = cmd_output_check(a.in, a.png, msg, sizeof(msg)))))
		return cmd_fail("stratum refine", rc, "%s", msg);
	if (!(rc = read_model(a.in, &coarse)) && !(rc = read_model(a.reference, &ref)))
		rc = refine_models(&a, coarse, ref);
	mesh_free(coarse);
	mesh_free(ref);
	return rc;
}

/*
 * cmd_repair.c - `stratum repair IN -o OUT [--printer NAME|FILE.ini |
 * --epsilon MM] [--split] [--json] [--threads N] [--ascii] [--weld MM]
 * [--stitch MM] [--keep-holes] [--simplify-planar [--angle DEG]
 * [--flatness MM]]`: read a mesh, repair it with seed 000's pipeline
 * (repair/repair.h), optionally merge its flat faces (seed 001 §4,
 * repair/simplify_planar.h), and write the printable result as STL, one
 * file or one per manifold-connected part (host/stl_parts.h).
 * Exit 0 repaired and written, 1 no printable result (nothing written) or
 * the output could not be written, 2 usage, 65 unreadable input or bad
 * printer profile, 70 internal error.
 */
#include <jansson.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "clio.h"
#include "commands.h"
#include "mesh.h"
#include "meshio.h"
#include "profile.h"
#include "progress.h"
#include "repair.h"
#include "simplify_planar.h"
#include "st_error.h"
#include "st_number.h"
#include "stl_parts.h"

#define REPAIR_EPSILON_DEFAULT 0.4   /* mm, when no printer is named */
#define REPAIR_EPSILON_MAX 10.0	     /* mm; more is a typo, not a wall */
#define REPAIR_HEAL_MAX 10.0	     /* mm, for --weld and --stitch: more is a typo */
#define REPAIR_PROGRESS_MIN 100000   /* triangles before progress goes to a log */

/* The help text around the option lines. */
static const char repair_head[] =
    "usage: stratum repair IN -o OUT [--printer NAME|FILE.ini | --epsilon MM]\n"
    "                      [--split] [--json] [--threads N] [--ascii]\n"
    "                      [--weld MM] [--stitch MM] [--keep-holes]\n"
    "                      [--simplify-planar [--angle DEG] [--flatness MM]]\n"
    "\n"
    "Repairs a mesh (STL, OBJ or OFF) into printable solids with Attene's\n"
    "as-exact-as-possible pipeline: welds vertices a few float ulps apart,\n"
    "stitches boundary gaps narrower than the stitch distance and fills holes\n"
    "small against their shell, removes degenerate and duplicate triangles,\n"
    "resolves every self-intersection exactly, keeps the outer hull, thickens\n"
    "sheets and wires to EPSILON, and writes the result as STL.  Nothing that was\n"
    "already solid is moved (except by rounding to the output precision).\n"
    "With --simplify-planar, nearly flat faces are then re-triangulated with the\n"
    "fewest triangles, never changing the topology or moving a surface by more\n"
    "than the flatness.\n"
    "\n";
static const char repair_tail[] =
    "\n"
    "Exit status: 0 repaired, 1 no printable result or OUT not written, 2 usage,\n"
    "65 unreadable input or printer profile, 70 internal error.  See docs/repair.md.\n";

/* Everything the report shows besides struct repair_report. */
struct repair_run {
	const char *input;
	enum meshio_format format;
	const char *printer;	/* profile id, or NULL */
	double epsilon;		/* mm */
	const char *eps_source;	/* "--epsilon", "printer" or "default" */
	bool ascii;
	/* How far the run got, for the report printed on every exit. */
	const char *stage;	/* "arguments", "reading", "repairing", "simplifying", "writing", "done" */
	bool read, repaired;	/* the input was read / repair_mesh returned */
	bool simplify;		/* --simplify-planar */
	struct planar_options planar;
	bool simplified;	/* planar_simplify returned, simp holds its report */
	struct planar_report simp;
	size_t input_triangles;
	int exit;		/* the exit status */
	char error[512];	/* the last error message, "" when none */
};

/* Print "stratum repair: MESSAGE" on stderr and keep it for the report. */
static void say(struct repair_run *run, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));

static void say(struct repair_run *run, const char *fmt, ...)
{
	va_list ap;

	va_start(ap, fmt);
	vsnprintf(run->error, sizeof(run->error), fmt, ap);
	va_end(ap);
	fprintf(stderr, "stratum repair: %s\n", run->error);
}


/* The healing figures (docs/repair.md "Healing") into obj. */
static void json_heal(json_t *obj, const struct repair_report *r)
{
	json_t *areas = json_array();
	const size_t listed = r->holes_filled < REPAIR_HOLES_LISTED ? r->holes_filled
								    : REPAIR_HOLES_LISTED;

	for (size_t i = 0; areas && i < listed; i++)
		json_array_append_new(areas, json_real(r->hole_area[i]));
	cmd_json_set(obj, "f:weld_tolerance", r->weld_tolerance,
		     "z:welded_vertices", r->welded_vertices, "z:weld_collapsed", r->weld_collapsed,
		     "f:stitch_tolerance", r->stitch_tolerance,
		     "z:stitched_vertices", r->stitched_vertices, "z:stitched_gaps", r->stitched_gaps,
		     "f:stitch_max_gap", r->stitch_max_gap, "z:stitch_collapsed", r->stitch_collapsed,
		     "z:holes_filled", r->holes_filled, "z:fill_triangles", r->fill_triangles,
		     "f:fill_area", r->fill_area, "o:hole_areas", areas ? areas : json_null(),
		     "z:holes_kept", r->holes_kept, "f:kept_patch_fraction", r->kept_patch_fraction,
		     "z:holes_crossing", r->holes_crossing, NULL);
}

/* One line of what the healing did, e.g. "welded 24 vertices, stitched ...". */
static void print_heal(const struct repair_report *r)
{
	printf("  healing: welded %zu vertices (within %.3g mm)", r->welded_vertices,
	       r->weld_tolerance);
	if (r->weld_collapsed)
		printf(", %zu triangles collapsed", r->weld_collapsed);
	if (r->stitch_tolerance == 0) {
		printf("; stitching and hole filling off\n");
		return;
	}
	printf(", stitched %zu gap%s", r->stitched_gaps, r->stitched_gaps == 1 ? "" : "s");
	if (r->stitched_vertices)
		printf(" <= %.3g mm (%zu vertices)", r->stitch_max_gap, r->stitched_vertices);
	else
		printf(" (gamma %g mm)", r->stitch_tolerance);
	if (r->stitch_collapsed)
		printf(", %zu triangles collapsed", r->stitch_collapsed);
	printf(", filled %zu hole%s", r->holes_filled, r->holes_filled == 1 ? "" : "s");
	for (size_t i = 0; i < r->holes_filled && i < REPAIR_HOLES_LISTED; i++)
		printf("%s%.3g", i == 0 ? " of " : i + 1 == r->holes_filled ? " and " : ", ",
		       r->hole_area[i]);
	if (r->holes_filled > REPAIR_HOLES_LISTED)
		printf(" ... (%.6g in all)", r->fill_area);
	if (r->holes_filled)
		printf(" mm^2");
	if (r->holes_kept)
		printf("; %zu hole%s left open (patch >= %.3g of its shell: a sheet)", r->holes_kept,
		       r->holes_kept == 1 ? "" : "s", r->kept_patch_fraction);
	if (r->holes_crossing)
		printf(", %zu of them because the patch would cross the model", r->holes_crossing);
	printf("\n");
}

/* The planar simplification's figures, or null when it did not run. */
static json_t *json_simplify(const struct repair_run *run)
{
	const struct planar_report *s = &run->simp;
	json_t *obj;

	if (!run->simplified)
		return json_null();
	obj = json_object();
	if (obj)
		cmd_json_set(obj, "f:angle", run->planar.angle, "f:flatness", run->planar.flatness,
			     "z:triangles_before", s->triangles_before,
			     "z:triangles_after", s->triangles_after,
			     "z:vertices_before", s->vertices_before,
			     "z:vertices_after", s->vertices_after, "z:clusters", s->clusters,
			     "z:retriangulated", s->retriangulated,
			     "z:refused_shape", s->refused_shape,
			     "z:refused_deviation", s->refused_deviation,
			     "z:refused_topology", s->refused_topology,
			     "z:refused_crossing", s->refused_crossing,
			     "f:max_deviation", s->max_deviation, "f:volume_before", s->volume_before,
			     "f:volume_after", s->volume_after, "f:area", s->area, NULL);
	return obj ? obj : json_null();
}

/* One line of what --simplify-planar did. */
static void print_simplify(const struct repair_run *run)
{
	const struct planar_report *s = &run->simp;
	const size_t refused = s->refused_shape + s->refused_deviation + s->refused_topology +
			       s->refused_crossing;

	printf("  planar simplification (angle %g deg, flatness %g mm): %zu -> %zu triangles, "
	       "%zu -> %zu vertices; %zu of %zu flat faces re-triangulated, %zu left as they "
	       "were; largest deviation %.3g mm; volume %.9g -> %.9g mm^3\n",
	       run->planar.angle, run->planar.flatness, s->triangles_before, s->triangles_after,
	       s->vertices_before, s->vertices_after, s->retriangulated, s->clusters, refused,
	       s->max_deviation, s->volume_before, s->volume_after);
}

static int print_json(const struct repair_run *run, const struct repair_report *r,
		      const struct stl_outputs *o)
{
	json_t *obj = json_object();
	json_t *outs = json_array();

	if (!obj || !outs) {
		json_decref(obj);
		json_decref(outs);
		return -1;
	}
	for (size_t i = 0; i < o->count; i++)
		json_array_append_new(outs, json_string(o->path[i]));
	cmd_json_set(obj, "b:ok", run->exit == ST_EXIT_OK, "i:exit", run->exit,
		     "o:error", run->error[0] ? json_string(run->error) : json_null(),
		     "s:stage", run->stage,
		     "o:input", run->input ? json_string(run->input) : json_null(),
		     "s:format", meshio_format_name(run->format),
		     "o:printer", run->printer ? json_string(run->printer) : json_null(),
		     "f:epsilon", run->epsilon, "s:epsilon_source", run->eps_source,
		     "s:precision", run->ascii ? "float64" : "float32",
		     "o:input_triangles",
		     run->read ? json_integer((json_int_t)run->input_triangles) : json_null(), NULL);
	if (!run->repaired)
		goto out_dump; /* nothing measured beyond the input */
	json_heal(obj, r);
	cmd_json_set(obj, "z:irregular_removed", r->irregular_removed,
		     "z:degenerate_removed", r->degenerate_removed,
		     "z:duplicates_removed", r->duplicates_removed,
		     "I:intersecting_pairs", (json_int_t)r->intersecting_pairs,
		     "z:triangles_split", r->triangles_split, "z:interior_deleted", r->interior_deleted,
		     "z:enclosed_deleted", r->enclosed_deleted,
		     "z:enclosed_components", r->enclosed_components, "z:cavities", r->cavities,
		     "z:parts_dropped", r->parts_dropped, "z:dropped_triangles", r->dropped_triangles,
		     "z:sheet_triangles", r->sheet_triangles, "f:sheet_area", r->sheet_area,
		     "z:sheet_components", r->sheet_components, "z:wires", r->wires,
		     "f:wire_length", r->wire_length, "z:wires_discarded", r->wires_discarded,
		     "b:second_pass", r->second_pass,
		     "z:thickened_triangles", r->thickened_triangles,
		     "z:second_sheet_triangles", r->second_sheet_triangles, "z:batches", r->batches,
		     "b:batch_fallback", r->batch_fallback, "i:rounding_rounds", r->rounding_rounds,
		     "z:rounding_merged", r->rounding_merged, "f:solid_deviation", r->solid_deviation,
		     "f:rounding_deviation", r->rounding_deviation,
		     "f:sheet_deviation", r->sheet_deviation,
		     "z:output_triangles", r->output_triangles,
		     "z:output_vertices", r->output_vertices, "z:components", r->components,
		     "b:printable", r->printable,
		     "o:why", r->printable ? json_null() : json_string(r->why),
		     "o:simplify", json_simplify(run), NULL);
out_dump:
	json_object_set_new(obj, "outputs", outs);
	return cmd_json_out(obj, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(10));
}

/* What a run that stopped early got to, and why it stopped. */
static void print_failure(const struct repair_run *run, const struct stl_outputs *o)
{
	if (run->read)
		printf("%s: %s, %zu triangles\n", run->input, meshio_format_name(run->format),
		       run->input_triangles);
	else
		printf("%s: not read\n", run->input ? run->input : "(no input)");
	printf("failed while %s: %s (exit %d)\n", run->stage,
	       run->error[0] ? run->error : "see the message above", run->exit);
	printf("written: %s\n", o->count ? "see below" : "nothing");
	for (size_t i = 0; i < o->count; i++)
		printf("  %s\n", o->path[i]);
}

static void print_text(const struct repair_run *run, const struct repair_report *r,
		       const struct stl_outputs *o)
{
	if (!run->repaired) {
		print_failure(run, o);
		return;
	}
	printf("%s: %s, %zu triangles\n", run->input, meshio_format_name(run->format),
	       r->input_triangles);
	if (!strcmp(run->eps_source, "printer"))
		printf("  epsilon %g mm (nozzle of printer %s)", run->epsilon, run->printer);
	else
		printf("  epsilon %g mm (%s)", run->epsilon, run->eps_source);
	printf(", output %s\n", run->ascii ? "ASCII STL (float64)" : "binary STL (float32)");
	print_heal(r);
	printf("  removed %zu irregular, %zu degenerate (kept as wires), %zu duplicate triangles\n",
	       r->irregular_removed, r->degenerate_removed, r->duplicates_removed);
	printf("  self-intersections: %llu intersecting pairs resolved, %zu triangles split\n",
	       (unsigned long long)r->intersecting_pairs, r->triangles_split);
	printf("  outer hull: %zu interior triangles deleted, %zu enclosed components (%zu "
	       "triangles) deleted, %zu cavit%s kept\n",
	       r->interior_deleted, r->enclosed_components, r->enclosed_deleted, r->cavities,
	       r->cavities == 1 ? "y" : "ies");
	if (r->sheet_triangles)
		printf("  sheets: %zu triangles in %zu component%s, %.6g mm^2, thickened to %g mm\n",
		       r->sheet_triangles, r->sheet_components, r->sheet_components == 1 ? "" : "s",
		       r->sheet_area, run->epsilon);
	else
		printf("  sheets: none\n");
	if (r->wires || r->wires_discarded)
		printf("  wires: %zu thickened to %g mm, %.6g mm long; %zu discarded (on the "
		       "surface or inside a solid)\n",
		       r->wires, run->epsilon, r->wire_length, r->wires_discarded);
	else
		printf("  wires: none\n");
	if (r->second_pass)
		printf("  second pass: yes (%zu triangles from thickening, %zu sheet triangles "
		       "left)\n", r->thickened_triangles, r->second_sheet_triangles);
	else
		printf("  second pass: no\n");
	if (r->batches > 1)
		printf("  repaired apart: %zu batches of parts that cannot meet\n", r->batches);
	else if (r->batch_fallback)
		printf("  repaired apart: no (one batch's result lay inside another's, so the "
		       "whole was repaired at once)\n");
	printf("  rounding to %s: %d re-check round%s\n", run->ascii ? "float64" : "float32",
	       r->rounding_rounds, r->rounding_rounds == 1 ? "" : "s");
	printf("  deviation: solid parts %.3g mm, rounding %.3g mm", r->solid_deviation,
	       r->rounding_deviation);
	if (r->second_pass)
		printf(", sheets and wires %.6g mm (at most epsilon/2 + rounding = %.6g mm)",
		       r->sheet_deviation, run->epsilon / 2 + r->rounding_deviation);
	printf("\n  output: %zu triangles, %zu vertices, %zu part%s", r->output_triangles,
	       r->output_vertices, r->components, r->components == 1 ? "" : "s");
	if (r->parts_dropped)
		printf(" (%zu smaller than epsilon in every direction dropped, %zu triangles)",
		       r->parts_dropped, r->dropped_triangles);
	printf("\n");
	if (run->simplified)
		print_simplify(run);
	printf("printable: %s\n", r->printable ? "yes" : "no");
	if (!r->printable)
		printf("  why: %s\n", r->why);
	if (run->exit && run->error[0])
		printf("failed while %s: %s (exit %d)\n", run->stage, run->error, run->exit);
	if (o->count == 0)
		printf("written: nothing\n");
	for (size_t i = 0; i < o->count; i++)
		printf("%s %s\n", i ? "        " : "written:", o->path[i]);
	if (o->count == 1 && r->components > 1)
		printf("note: the %zu parts are in one file (printable as it is); --split writes "
		       "one file per part\n", r->components);
}

/*
 * Planar simplification of the repaired mesh *m, in place; component
 * (the part of each triangle, or NULL) follows the triangles.  Returns 0
 * or the exit status, with the message said.
 */
static int simplify_result(struct repair_run *run, const char *in, struct mesh **m,
			   uint32_t *component)
{
	struct st_error err = {0};
	struct mesh *simple = NULL;
	uint32_t *origin = NULL;
	int rc;

	rc = planar_simplify(*m, &run->planar, &simple, &origin, &run->simp, &err);
	if (rc) {
		say(run, "%s: %s", in, err.msg);
		return ST_EXIT_SOFTWARE; /* NOMEM, INTERNAL; ARG only from a bug here */
	}
	run->simplified = true;
	if (component) { /* the part of each output triangle's origin, in origin's place */
		for (size_t i = 0; i < simple->ntris; i++)
			origin[i] = component[origin[i]];
		memcpy(component, origin, simple->ntris * sizeof(*component));
	}
	free(origin);
	mesh_free(*m);
	*m = simple;
	return 0;
}

static int repair_command(int argc, char **argv, struct repair_run *run, struct clio *io)
{
	const char *in = NULL, *out = NULL, *printer = NULL, *eps_arg = NULL;
	const char *angle_arg = NULL, *flat_arg = NULL;
	bool json = false, split = false, ascii = false, keep_holes = false, out_std = false;
	double weld = -1, stitch = -1; /* < 0: the defaults of repair_options_init */
	int threads = 0, status = ST_EXIT_OK, rc;
	char msg[sizeof(run->error)];
	struct st_error err = {0};
	struct profile *prof = NULL;
	struct repair_options opt;
	struct repair_report rep;
	struct progress prog;
	struct stl_outputs outs = {0};
	struct mesh *m = NULL, *fixed = NULL;

	memset(&rep, 0, sizeof(rep));
	uint32_t *component = NULL;
	planar_options_init(&run->planar); /* before the table: --help shows the defaults */

	const struct cmd_opt opts[] = {
	    CMD_OPT_STRING("--output", 'o', &out, CMD_NONEMPTY, "the output file name", "OUT",
	     "the STL to write (written only when the result is printable);\n"
	     "'-': stdout, and IN '-' reads stdin"),
	    CMD_OPT_STRING("--printer", 0, &printer, CMD_NONEMPTY,
	     "a printer name or file (see 'stratum printers')", "P",
	     "take EPSILON from this printer's nozzle diameter"),
	    {"--epsilon", 0, CMD_DOUBLE, &run->epsilon, CMD_RANGE | CMD_ABOVE_LO, 0,
	     REPAIR_EPSILON_MAX, "a thickness in mm greater than %g and at most %g", "MM",
	     "thickness for sheets and wires, %g < MM <= %g\n"
	     "(default: the printer's nozzle, else 0.4; wins over --printer)", NULL, &eps_arg},
	    CMD_OPT_FLAG("--split", &split,
	     "one file per part: OUT part.stl gives part-1.stl, part-2.stl..."),
	    CMD_OPT_FLAG("--json", &json, "one JSON object on stdout instead of the text report"),
	    CMD_OPT_THREADS(&threads, "cores for the exact passes (default: all)"),
	    CMD_OPT_FLAG("--ascii", &ascii,
	     "write ASCII STL (double precision) instead of binary (float)"),
	    {"--weld", 0, CMD_DOUBLE, &weld, CMD_RANGE, 0, REPAIR_HEAL_MAX,
	     "a distance in mm from %g (off) to %g", "MM",
	     "weld vertices closer than MM (default: 8 float32 ulps of\n"
	     "the largest coordinate; 0 = off)", NULL, NULL},
	    {"--stitch", 0, CMD_DOUBLE, &stitch, CMD_RANGE, 0, REPAIR_HEAL_MAX,
	     "a distance in mm from %g (off) to %g", "MM",
	     "stitch boundary gaps up to MM (default 1.5 * EPSILON; 0 = off)", NULL, NULL},
	    CMD_OPT_FLAG("--keep-holes", &keep_holes,
	     "no stitching, no hole filling: every open part is a sheet"),
	    CMD_OPT_FLAG("--simplify-planar", &run->simplify,
	     "then re-triangulate nearly flat faces with the fewest\n"
	     "triangles (topology, solidity and volume kept)"),
	    {"--angle", 0, CMD_DOUBLE, &run->planar.angle, CMD_RANGE, 0, PLANAR_ANGLE_MAX,
	     "an angle in degrees from %g to %g", "DEG",
	     "with --simplify-planar: largest angle between a facet and\n"
	     "its face's plane, %g..%g (default %g)", NULL, &angle_arg},
	    {"--flatness", 0, CMD_DOUBLE, &run->planar.flatness, CMD_RANGE, 0, PLANAR_FLATNESS_MAX,
	     "a distance in mm from %g to %g", "MM",
	     "with --simplify-planar: largest distance of a vertex from\n"
	     "its face's plane, and of a removed vertex from the new\n"
	     "triangles, %g..%g (default %g)", NULL, &flat_arg},
	};
	const struct cmd_spec spec = {
	    .cmd = "stratum repair", .head = repair_head, CMD_TABLE(opts), .col = 20, .tail = repair_tail, .pos = &in,
	    .npos = 1,
	    .extra = "one input file at a time ('%s' and '%s'); name the output with -o"};

	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (!in || !out)
		return cmd_refuse(&spec, "%s",
				  !in ? "no input file given"
				      : "no output file given; add -o OUT.stl");

	if ((angle_arg || flat_arg) && !run->simplify)
		return cmd_fail("stratum repair", ST_EXIT_USAGE,
				"%s applies to --simplify-planar; add it or leave %s out",
				angle_arg ? angle_arg : flat_arg, angle_arg ? angle_arg : flat_arg);
	if (split && clio_is_std(out))
		return cmd_fail(
		    "stratum repair", ST_EXIT_USAGE,
		    "--split writes one file per part; -o - takes one stream (leave out --split)");
	run->input = in;
	out_std = clio_is_std(out);
	/* "-": stdin spooled, the STL held back until it is whole (clio.h) */
	if ((status = clio_input(io, &in, "")) ||
	    (status = clio_output(io, &out, !ascii, ".stl")))
		return status;
	run->ascii = ascii;
	run->eps_source = eps_arg ? "--epsilon" : "default";
	run->epsilon = eps_arg ? run->epsilon : REPAIR_EPSILON_DEFAULT;
	run->stage = "checking the output";
	/* Before any work: never the input, and a directory we can write in.
	 * With --split the parts are OUT-1, OUT-2, ...; each is checked
	 * against the input again just before it is written. */
	status = cmd_output_check(in, out, run->error, sizeof(run->error));
	if (!status && split && stl_input_is_a_part(in, out)) {
		snprintf(run->error, sizeof(run->error),
			 "%s is named like a part of %s (--split writes PART-1, PART-2, ...); name "
			 "another output so the input is kept", in, out);
		status = ST_EXIT_USAGE;
	}
	if (status) {
		fprintf(stderr, "stratum repair: %s\n", run->error);
		goto out_report;
	}

	/* The printer is checked even when --epsilon overrides its nozzle. */
	run->stage = "reading the printer profile";
	if (printer) {
		rc = profile_find(printer, &prof, &err);
		if (rc) {
			say(run, "%s", err.msg);
			status = profile_exit_status(rc);
			goto out_report;
		}
		run->printer = prof->id;
		if (!eps_arg) {
			run->eps_source = "printer";
			run->epsilon = prof->nozzle_diameter[0];
		}
	}

	run->stage = "reading";
	rc = meshio_read(in, MESHIO_AUTO, &m, &run->format, &err);
	if (rc) {
		say(run, "%s", err.msg);
		status = rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR;
		goto out_report;
	}
	run->read = true;
	run->input_triangles = m->ntris;

	repair_options_init(&opt);
	opt.epsilon = run->epsilon;
	opt.precision = ascii ? REPAIR_FLOAT64 : REPAIR_FLOAT32;
	opt.threads = threads;
	opt.weld = weld;
	opt.stitch = stitch;
	opt.keep_holes = keep_holes;
	/* a terminal always gets the line: a small soup can take a minute */
	if ((m->ntris >= REPAIR_PROGRESS_MIN || isatty(STDERR_FILENO)) &&
	    progress_start(&prog, "stratum repair")) {
		opt.progress = progress_update;
		opt.progress_ctx = &prog;
	}
	run->stage = "repairing";
	rc = repair_mesh(m, &opt, &fixed, &component, &rep, &err);
	if (opt.progress)
		progress_end(&prog);
	mesh_free(m);
	if (rc < 0) {
		/* What the repair measured before it failed is still reported. */
		run->repaired = true;
		say(run, "%s: %s", in, err.msg);
		status = rc == ST_ERR_ARG ? ST_EXIT_SOFTWARE : st_exit_for(rc);
		goto out_report;
	}
	run->repaired = true;
	if (!rep.printable) {
		say(run, "%s: could not reach a printable result: %s", in, rep.why);
		status = ST_EXIT_FAILURE;
		goto out_report;
	}
	if (run->simplify) {
		run->stage = "simplifying";
		run->planar.threads = threads;
		status = simplify_result(run, in, &fixed, component);
		if (status)
			goto out_report;
	}
	run->stage = "writing";
	status = stl_write_outputs(run->input, out, fixed, component, rep.components, split,
				   ascii ? MESHIO_STL_ASCII : MESHIO_STL_BINARY, &outs, msg,
				   sizeof(msg));
	if (status)
		say(run, "%s", msg);
	if (status && outs.count)
		say(run, "only %zu of %zu parts were written", outs.count, rep.components);
	if (!status)
		run->stage = "done";
	if (outs.count == 1 && out_std) {
		free(outs.path[0]);
		outs.path[0] = strdup("-"); /* the report names stdout, not the spool */
	}

out_report:
	run->exit = status;
	rc = cmd_report_end("stratum repair", "report", json ? print_json(run, &rep, &outs) != 0
							   : (print_text(run, &rep, &outs), 0));
	if (!status && rc)
		status = rc;
	stl_outputs_free(&outs);
	free(component); /* NULL unless repair_mesh set them */
	mesh_free(fixed);
	profile_free(prof);
	return status;
}

/*
 * Argument errors end before there is a report; with --json the caller
 * still gets a JSON object saying so.
 */
int cmd_repair(int argc, char **argv)
{
	struct repair_run run;
	struct clio io;
	int status;

	memset(&run, 0, sizeof(run));
	run.stage = "arguments";
	clio_init(&io, "stratum repair");
	status = repair_command(argc, argv, &run, &io);
	if (status && !strcmp(run.stage, "arguments")) {
		bool json = false;

		for (int i = 1; i < argc; i++)
			json = json || !strcmp(argv[i], "--json");
		if (json) {
			json_t *o = json_pack("{s:b, s:i, s:s, s:s}", "ok", 0, "exit", status,
					      "error", "the command line was refused (the reason "
					      "is on stderr)", "stage", "arguments");
			cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
		}
	}
	return clio_finish(&io, status);
}

/*
 * cmd_slice.c - `stratum slice MODEL... -o OUT.gcode --printer NAME
 * [--layer-height H] [--first-layer-height H] [--perimeters N]
 * [--infill D] [--center X,Y] [--adaptive [--max-cusp MM]] [--png PLOT.png]
 * [--no-repair] [--json] [--threads N]`:
 * read each mesh, repair it (seed 000, epsilon = the nozzle diameter),
 * place it, or arrange several, on the bed (host/slicejob.h), slice them
 * together (slicer/slicer.h) and write one G-code file.
 * Exit 0 written, 1 the job cannot be done (no printable repair, does not
 * fit, nothing to print, OUT not written), 2 usage or bad settings, 65
 * unreadable model or bad printer profile, 70 internal error.
 *
 * The printer profile is mapped to struct slicer_config here, so slicer/
 * never includes host/.
 */
#include <jansson.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfgopt.h"
#include "clio.h"
#include "adaptive.h"
#include "commands.h"
#include "layerplot.h"
#include "meshio.h"
#include "placeholder.h"
#include "profile.h"
#include "profile_slicer.h"
#include "repair.h"
#include "slicejob.h"
#include "slicer.h"
#include "st_error.h"
#include "st_number.h"

#define SLICE_CMD "stratum slice"

/* The command line, checked for form; values are checked with the profile. */
struct slice_args {
	const char *in[SLICEJOB_MODELS_MAX]; /* the model files, in order */
	size_t nin;
	const char *out, *printer;
	struct cfgopt cfg; /* --load, --set, --KEY-NAME ... */
	bool json, no_repair, adaptive;
	const char *png; /* the layer-height plot, or NULL */
	int threads; /* 0 = all */
	/* the option's name when it was given */
	const char *has_layer, *has_first, *has_perimeters, *has_infill, *has_center, *has_cusp;
	double layer_height, first_layer_height, infill, center[2], max_cusp;
	int perimeters;
};

/* --infill D or D%: a number of percent. */
static bool read_percent(const char *v, void *dest)
{
	size_t n = strlen(v);

	if (n && v[n - 1] == '%')
		n--;
	return n && st_parse_double(v, n, 0, dest) == ST_NUMBER_OK;
}

/* --center X,Y. */
static bool read_center(const char *v, void *dest)
{
	const char *comma = strchr(v, ',');
	double *c = dest;

	return comma && st_parse_double(v, (size_t)(comma - v), 0, &c[0]) == ST_NUMBER_OK &&
	       st_parse_double(comma + 1, strlen(comma + 1), 0, &c[1]) == ST_NUMBER_OK;
}

/* Parse argv; 0 to go on, -1 after --help, else the exit status. */
static int parse_args(int argc, char **argv, struct slice_args *a)
{
	const struct cmd_opt opts[] = {
	    CMD_OPT_STRING("--output", 'o', &a->out, CMD_NONEMPTY, "the output file name", "OUT",
			   "the G-code file (written only when everything succeeded);\n"
			   "'-': stdout, and a MODEL '-' reads stdin"),
	    CMD_OPT_STRING("--printer", 0, &a->printer, CMD_NONEMPTY,
			   "a printer name or file (see 'stratum printers')", "P",
			   "printer profile name ('stratum printers') or .ini file"),
	    {"--layer-height", 0, CMD_DOUBLE, &a->layer_height, 0, 0, 0, "a height in mm", "H",
	     "mm, > 0 and at most the nozzle (default: the profile's)", NULL, &a->has_layer},
	    {"--first-layer-height", 0, CMD_DOUBLE, &a->first_layer_height, 0, 0, 0,
	     "a height in mm", "H", "mm, likewise (default: the profile's)", NULL, &a->has_first},
	    /* the range of --perimeters is checked with the settings */
	    {"--perimeters", 0, CMD_INT, &a->perimeters, CMD_RANGE, -1e6, 1e6,
	     "a whole number of walls", "N", "walls per island, 0 or more (default: the profile's)",
	     NULL, &a->has_perimeters},
	    {"--infill", 0, CMD_CUSTOM, &a->infill, 0, 0, 0, "a density in percent from 0 to 100",
	     "D", "infill density in percent, 0 to 100 (fill_density)", read_percent,
	     &a->has_infill},
	    {"--center", 0, CMD_CUSTOM, a->center, 0, 0, 0, "X,Y in mm (such as 125,105)", "X,Y",
	     "put the model's (or the models') centre there, mm\n(default: the bed centre)",
	     read_center, &a->has_center},
	    CMD_OPT_FLAG("--adaptive", &a->adaptive,
			 "adaptive layer heights: each layer as thick as the\n"
			 "cusp bound allows, from min_layer_height to\n"
			 "max_layer_height (adaptive_layer_height = 1)"),
	    {"--max-cusp", 0, CMD_DOUBLE, &a->max_cusp, 0, 0, 0, "a height in mm", "MM",
	     "the adaptive layers' largest staircase step, mm;\n"
	     "implies --adaptive (adaptive_max_cusp; default: the\n"
	     "profile's)",
	     NULL, &a->has_cusp},
	    CMD_OPT_STRING("--png", 0, &a->png, CMD_NONEMPTY, "a file name", "PLOT.png",
			   "also plot the layer heights against Z into PLOT.png"),
	    CMD_OPT_FLAG("--no-repair", &a->no_repair, "slice the meshes as they are read"),
	    CMD_OPT_FLAG("--json", &a->json,
			 "one JSON object on stdout instead of the text summary"),
	    CMD_OPT_THREADS(&a->threads, "cores for the repair, walls and infill (default: all)"),
	};
	const struct cmd_spec spec = {
	    .cmd = SLICE_CMD, CMD_TABLE(opts), .col = 26,
	    .head =
		"usage: stratum slice MODEL... -o OUT.gcode --printer NAME|FILE.ini\n"
		"                     [--load FILE.ini]... [--set KEY=VALUE]... [--KEY-NAME V]...\n"
		"                     [--layer-height H] [--first-layer-height H] [--perimeters N]\n"
		"                     [--infill D] [--center X,Y] [--adaptive [--max-cusp MM]]\n"
		"                     [--png PLOT.png] [--no-repair] [--json] [--threads N]\n"
		"\n"
		"Slices a mesh (STL, OBJ, OFF or 3MF) into G-code for the printer.  The model\n"
		"is first repaired exactly (as 'stratum repair', epsilon = the nozzle diameter),\n"
		"then placed with its bounding box centred on the bed and its lowest point on\n"
		"the bed, and refused when it does not fit the bed or the build height.\n"
		"Several models are repaired one by one and printed together: arranged around\n"
		"the bed centre with duplicate_distance (6 mm) between their footprints, or,\n"
		"when all are 3MF files whose parts do not overlap, kept where the files put\n"
		"them; a model that finds no room is named and nothing is written.\n"
		"It prints walls (perimeters, gap fill, thin walls), skins and sparse infill,\n"
		"bridges, supports, skirt/brim, a raft, spiral vases and ironing as the\n"
		"settings ask.  A 3MF project's layer height profile (PrusaSlicer's variable\n"
		"layer height) gives the layers, as in PrusaSlicer.  See docs/slicing.md.\n"
		"\n",
	    .mid = "\nSettings (--printer may be left out when --load gives a whole config):\n",
	    .cfg = &a->cfg,
	    .tail =
		"\n"
		"Exit status: 0 written, 1 the job cannot be done (no printable repair, the model\n"
		"does not fit, OUT not written), 2 usage or bad settings, 65 unreadable model or\n"
		"printer profile, 70 internal error.\n",
	    .pos = a->in, .npos = SLICEJOB_MODELS_MAX, .ngot = &a->nin,
	    .extra = "more than %d models at once ('%s')"};
	int rc = cmd_parse(&spec, argc, argv);

	if (rc)
		return rc;
	if (!a->nin || !a->out || (!a->printer && !a->cfg.has_files))
		return cmd_refuse(&spec, "%s",
				  !a->nin ? "no model file given"
				  : !a->out
				      ? "no output file given; add -o OUT.gcode"
				      : "no printer given; add --printer NAME ('stratum printers' "
					"lists them) or --load a PrusaSlicer config");
	return 0;
}

/*
 * The job's settings from the printer profile (host/profile_slicer.h), then
 * the command line's overrides.  Returns 0 or the exit status with the
 * message printed.
 */
static int config_from_profile(const struct profile *p, const struct slice_args *a,
			       struct slicer_config *c)
{
	struct st_error err = {0};
	int rc = profile_slicer_config(p, c, &err);

	if (rc)
		return cmd_fail(SLICE_CMD, profile_exit_status(rc), "%s", err.msg);
	if (a->has_layer)
		c->layer_height = a->layer_height;
	if (a->has_first)
		c->first_layer_height = a->first_layer_height;
	if (a->has_perimeters)
		c->perim.perimeters = a->perimeters;
	if (a->has_infill)
		c->infill.density = a->infill;
	if (a->adaptive || a->has_cusp)
		c->adaptive.enabled = true;
	if (a->has_cusp)
		c->adaptive.max_cusp = a->max_cusp;
	slicer_config_modes(c); /* the summary shows what is printed */
	c->bed.has_center = a->has_center != NULL;
	c->bed.center_x = a->center[0];
	c->bed.center_y = a->center[1];
	c->threads = a->threads;
	return 0;
}

/* The layers as printed (slicer_config.planned): the raft's, then the part's. */
struct plan_copy {
	struct layer_span *v;
	size_t n;
};

static void keep_plan(void *ctx, const struct layer_span *layers, size_t n)
{
	struct plan_copy *p = ctx;

	p->v = malloc((n ? n : 1) * sizeof(*p->v));
	p->n = p->v ? n : 0; /* out of memory: no profile shown, the G-code still written */
	if (p->v)
		memcpy(p->v, layers, n * sizeof(*layers));
}

/* What the summary shows besides struct slicer_summary. */
struct slice_run {
	const struct slice_args *a;
	const struct slicer_config *c;
	const struct profile *prof;
	const struct slicejob_result *res;
	const struct repair_report *rep; /* NULL with --no-repair */
	const struct plan_copy *plan;
};

/* Bands of Z the text summary's layer-height profile shows. */
#define PROFILE_BANDS 8

/* The part's layers, one JSON [z, height] pair each. */
static json_t *json_profile(const struct slice_run *r, size_t raft)
{
	json_t *arr = json_array();

	for (size_t i = raft; arr && i < r->plan->n; i++) {
		json_t *pair = json_array();

		json_array_append_new(pair, json_real(r->plan->v[i].z));
		json_array_append_new(pair, json_real(r->plan->v[i].height));
		json_array_append_new(arr, pair);
	}
	return arr;
}

/* The part's layers in PROFILE_BANDS equal spans of Z: count and heights of each. */
static void print_profile(const struct slice_run *r, size_t raft)
{
	const struct layer_span *l = r->plan->v + raft;
	size_t n = r->plan->n > raft ? r->plan->n - raft : 0, i = 0;
	double z0 = n ? l[0].z - l[0].height : 0.0, span = n ? (l[n - 1].z - z0) / PROFILE_BANDS : 0;

	for (int b = 0; b < PROFILE_BANDS && i < n; b++) {
		double top = b == PROFILE_BANDS - 1 ? INFINITY : z0 + (b + 1) * span;
		double lo = INFINITY, hi = 0.0, from = l[i].z - l[i].height, to = from;
		size_t count = 0;

		for (; i < n && (l[i].z - l[i].height / 2 < top); i++, count++) {
			lo = fmin(lo, l[i].height);
			hi = fmax(hi, l[i].height);
			to = l[i].z;
		}
		if (count)
			printf("  Z %7.2f to %7.2f mm: %4zu layers of %.3f to %.3f mm\n", from, to,
			       count, lo, hi);
	}
}

/* JSON keys of the path roles, in enum path_role order (the G-code names
 * of path_role_name are not unique: skirt and brim share one). */
static const char *const role_keys[] = {
    "outer_perimeter", "inner_perimeter", "thin_wall", "gap_fill", "solid_infill",
    "top_skin", "bottom_skin", "sparse_infill", "bridge", "skirt", "brim", "support",
    "support_interface", "ironing", "overhang_perimeter"};
_Static_assert(sizeof(role_keys) / sizeof(role_keys[0]) == PATH_ROLES,
	       "one JSON key per path role");

static json_t *json_xyz(const double v[3])
{
	json_t *arr = json_array();

	for (int k = 0; k < 3; k++)
		json_array_append_new(arr, json_real(v[k]));
	return arr;
}

/* The repair's counts as JSON; null without a repair. */
static json_t *json_repair(const struct repair_report *r)
{
	json_t *rep = r ? json_object() : json_null();

	if (!r || !rep)
		return rep;
	cmd_json_set(rep, "z:input_triangles", r->input_triangles,
		     "I:intersecting_pairs", (json_int_t)r->intersecting_pairs,
		     "z:output_triangles", r->output_triangles, "z:components", r->components, NULL);
	return rep;
}

/* Every model of the job: file, format, its repair, where it was moved. */
static json_t *json_models(const struct slice_run *r)
{
	json_t *arr = json_array();

	for (size_t i = 0; arr && i < r->res->nmodels; i++) {
		const struct slicejob_model *m = &r->res->models[i];
		json_t *o = json_object();

		cmd_json_set(o, "s:input", m->path, "s:format", meshio_format_name(m->format),
			     "z:input_triangles", m->input_triangles,
			     "o:repair", json_repair(r->rep ? &m->rep : NULL),
			     "o:offset", json_xyz(m->offset), NULL);
		json_array_append_new(arr, o);
	}
	return arr;
}

static int print_json(const struct slice_run *r, const struct slicer_summary *s)
{
	json_t *o = json_object(), *paths = json_object(), *stages = json_object(),
	       *place = json_object(), *rep = json_repair(r->rep);

	if (!o || !paths || !stages || !place || !rep)
		goto out_nomem;
	for (int k = 0; k < PATH_ROLES; k++)
		json_object_set_new(paths, role_keys[k],
				    json_integer((json_int_t)s->paths[k]));
	cmd_json_set(stages, "b:walls", s->walls, "b:infill", s->infill, "b:support", s->support,
		     "b:skirt", s->skirt, NULL);
	cmd_json_set(place, "o:offset", json_xyz(s->offset), "o:min", json_xyz(s->min),
		     "o:max", json_xyz(s->max), NULL);
	cmd_json_set(o, "s:input", r->a->in[0], "s:format", meshio_format_name(r->res->format),
		     "z:input_triangles", r->res->input_triangles, "s:printer", r->prof->id,
		     "f:nozzle_diameter", r->c->perim.nozzle_diameter, "o:repair", rep,
		     "s:output", r->a->out, "z:layers", s->layers,
		     "f:layer_height", r->c->layer_height,
		     "f:first_layer_height", r->c->first_layer_height,
		     "z:raft_layers", s->raft_layers, "i:perimeters", r->c->perim.perimeters,
		     "f:fill_density", r->c->infill.density, "f:time_s", s->time_s,
		     "f:filament_mm", s->filament_mm, "f:filament_cm3", s->filament_cm3,
		     "f:filament_g", s->filament_g, "z:moves", s->moves, "o:placement", place,
		     "o:models", json_models(r), "b:arranged", r->res->arranged, "o:paths", paths,
		     "o:stages", stages, "z:open_contours_dropped", s->open_dropped,
		     "z:thin_dropped", s->thin.dropped, "z:thin_widened_layers",
		     s->thin.widened_layers, NULL);
	if (s->thin.widened_layers)
		cmd_json_set(o, "f:thin_designed_mm", s->thin.designed, "f:thin_printed_mm",
			     s->thin.printed, NULL);
	if (s->profiled)
		cmd_json_set(o, "s:layer_heights", "3mf_profile", "z:profile_clamped_layers",
			     s->profile_clamped, "f:layer_height_min", s->height_min,
			     "f:layer_height_max", s->height_max, "f:cusp_max", s->cusp_max,
			     "f:cusp_mean", s->cusp_mean, "o:layer_profile",
			     json_profile(r, s->raft_layers), NULL);
	if (s->adaptive)
		cmd_json_set(o, "b:adaptive", true, "f:max_cusp", r->c->adaptive.max_cusp,
			     "f:layer_height_min", s->height_min, "f:layer_height_max", s->height_max,
			     "f:cusp_max", s->cusp_max, "f:cusp_mean", s->cusp_mean,
			     "o:layer_profile", json_profile(r, s->raft_layers), NULL);
	return cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(10));

out_nomem:
	json_decref(o);
	json_decref(paths);
	json_decref(stages);
	json_decref(place);
	json_decref(rep);
	return -1;
}

static void print_text(const struct slice_run *r, const struct slicer_summary *s)
{
	long secs = lround(s->time_s);

	for (size_t i = 0; i < r->res->nmodels; i++) {
		const struct slicejob_model *m = &r->res->models[i];

		printf("%s: %s, %zu triangles\n", m->path, meshio_format_name(m->format),
		       m->input_triangles);
		if (r->rep)
			printf("  repaired (epsilon %g mm): %zu triangles, %zu part%s, %llu "
			       "intersecting pairs resolved\n",
			       r->c->perim.nozzle_diameter, m->rep.output_triangles,
			       m->rep.components, m->rep.components == 1 ? "" : "s",
			       (unsigned long long)m->rep.intersecting_pairs);
		else
			printf("  not repaired (--no-repair)\n");
		if (r->res->nmodels > 1)
			printf("  %s by X %+.2f, Y %+.2f, Z %+.2f mm\n",
			       r->res->arranged ? "arranged: moved" : "kept as its 3MF places it: moved",
			       m->offset[0], m->offset[1], m->offset[2]);
	}
	printf("printer: %s (%s), nozzle %g mm\n", r->prof->id, r->prof->name,
	       r->c->perim.nozzle_diameter);
	if (s->raft_layers) {
		printf("placed: X %.2f to %.2f, Y %.2f to %.2f, Z %.2f to %.2f mm (on the raft)\n",
		       s->min[0], s->max[0], s->min[1], s->max[1], s->min[2], s->max[2]);
		if (s->adaptive || s->profiled)
			printf("layers: %zu (%zu of raft, the first %g mm; the part's from %g mm, "
			       "then %s)\n",
			       s->layers, s->raft_layers, r->c->first_layer_height,
			       r->c->layer_height, s->adaptive ? "adaptive" : "as the 3MF's profile");
		else
			printf("layers: %zu (%zu of raft, the first %g mm; the part's %g mm)\n",
			       s->layers, s->raft_layers, r->c->first_layer_height,
			       r->c->layer_height);
	} else {
		printf("placed: X %.2f to %.2f, Y %.2f to %.2f, Z 0 to %.2f mm\n", s->min[0],
		       s->max[0], s->min[1], s->max[1], s->max[2]);
		if (s->adaptive || s->profiled)
			printf("layers: %zu (first %g mm, then %s)\n", s->layers,
			       r->c->first_layer_height,
			       s->adaptive ? "adaptive" : "as the 3MF's profile");
		else
			printf("layers: %zu (first %g mm, then %g mm)\n", s->layers,
			       r->c->first_layer_height, r->c->layer_height);
	}
	if (s->adaptive) {
		printf("adaptive layers: %zu of the part, above the first %.3f to %.3f mm thick, their "
		       "cusp at most %.3f mm (bound %g mm), mean %.3f mm\n",
		       s->layers - s->raft_layers, s->height_min, s->height_max, s->cusp_max,
		       r->c->adaptive.max_cusp, s->cusp_mean);
		print_profile(r, s->raft_layers);
	}
	if (s->profiled) {
		printf("layer height profile (" MESHIO_3MF_LAYER_PROFILE_ENTRY "): %zu layers of "
		       "the part, above the first %.3f to %.3f mm thick, their cusp at most %.3f mm, "
		       "mean %.3f mm\n",
		       s->layers - s->raft_layers, s->height_min, s->height_max, s->cusp_max,
		       s->cusp_mean);
		print_profile(r, s->raft_layers);
	}
	printf("paths: %zu external perimeters, %zu perimeters, %zu thin walls, %zu gap fills",
	       s->paths[PATH_OUTER_PERIMETER], s->paths[PATH_INNER_PERIMETER],
	       s->paths[PATH_THIN_WALL], s->paths[PATH_GAP_FILL]);
	if (s->paths[PATH_OVERHANG_PERIMETER]) /* overhangs = 1 only */
		printf(", %zu overhang perimeters", s->paths[PATH_OVERHANG_PERIMETER]);
	printf("\n");
	printf("       %zu top, %zu bottom, %zu solid, %zu sparse (%g%% %s), %zu bridge infill\n",
	       s->paths[PATH_TOP_SKIN], s->paths[PATH_BOTTOM_SKIN], s->paths[PATH_SOLID_INFILL],
	       s->paths[PATH_SPARSE_INFILL], r->c->infill.density, r->c->infill.pattern,
	       s->paths[PATH_BRIDGE]);
	printf("       %zu support, %zu support interface, %zu skirt, %zu brim, %zu ironing\n",
	       s->paths[PATH_SUPPORT], s->paths[PATH_SUPPORT_INTERFACE], s->paths[PATH_SKIRT],
	       s->paths[PATH_BRIM], s->paths[PATH_IRONING]);
	printf("time: %ldh %02ldm %02lds (estimate, heating excluded)\n", secs / 3600,
	       secs / 60 % 60, secs % 60);
	printf("filament: %.1f mm, %.2f cm^3, %.2f g\n", s->filament_mm, s->filament_cm3,
	       s->filament_g);
	printf("written: %s\n", r->a->out);
}

/*
 * One warning on stderr for thin walls printed wider than the model
 * (min_bead_width) or dropped (narrower than min_feature_size).
 */
static void warn_thin(const struct slicer_config *c, const struct slicer_thin *t)
{
	if (t->widened_layers)
		fprintf(stderr,
			SLICE_CMD ": warning: thin walls on %zu layer%s (%zu to %zu) are narrower "
			"than min_bead_width and print wider than designed: down to %.3f mm wide, "
			"printed %.3f mm (%.3f mm wider)\n",
			t->widened_layers, t->widened_layers == 1 ? "" : "s", t->first, t->last,
			t->designed, t->printed, t->printed - t->designed);
	if (t->dropped)
		fprintf(stderr,
			SLICE_CMD ": warning: %zu island%s narrower than min_feature_size (%g mm) "
			"not printed\n",
			t->dropped, t->dropped == 1 ? "" : "s", c->perim.min_feature_size);
}

/* What became of a 3MF's layer height profile, when it is not used or not
 * all of it: a note or a warning on stderr. */
static void note_profile(const struct slice_args *a, const struct slicejob_result *res,
			 const struct slicer_config *c)
{
	static const char *const why[] = {
	    [SLICEJOB_PROFILE_ADAPTIVE] = "adaptive layers were asked for",
	    [SLICEJOB_PROFILE_NOT_ALLOWED] = "the printer allows no variable layer heights "
					     "(variable_layer_height = 0)",
	    [SLICEJOB_PROFILE_SEVERAL] = "it is one object's, and the plate holds several, "
					 "sliced in one set of layers",
	};

	if (res->profile == SLICEJOB_PROFILE_STALE)
		fprintf(stderr,
			SLICE_CMD ": note: %s carries a layer height profile ("
			MESHIO_3MF_LAYER_PROFILE_ENTRY "), not used: it ends at Z %g mm, not at "
			"the object's top, %g mm (the object changed since; PrusaSlicer drops "
			"it too)\n",
			a->in[0], res->profile_top, res->model_top);
	else if (res->profile != SLICEJOB_PROFILE_NONE && res->profile != SLICEJOB_PROFILE_USED)
		fprintf(stderr,
			SLICE_CMD ": note: %s carries a layer height profile ("
			MESHIO_3MF_LAYER_PROFILE_ENTRY "), not used: %s\n",
			a->in[0], why[res->profile]);
	struct adaptive_settings as;

	slicer_adaptive_settings(c, &as);
	if (res->sum.profiled && res->sum.profile_clamped)
		fprintf(stderr,
			SLICE_CMD ": warning: %zu layer%s of the 3MF's layer height profile lay "
			"outside min_layer_height..max_layer_height (%g to %g mm) and were kept "
			"within them\n",
			res->sum.profile_clamped, res->sum.profile_clamped == 1 ? "" : "s",
			as.min_height, as.max_height);
}

/* --png: the layer heights as printed; 0 or the exit status with the message printed. */
static int write_plot(const struct slice_args *a, const struct slicer_config *c,
		      const struct slicer_summary *s, const struct plan_copy *plan)
{
	struct st_error err = {0};
	struct adaptive_settings as;
	char title[256];
	struct layerplot_opts o = {.title = title, .raft_layers = s->raft_layers};
	int rc;

	slicer_adaptive_settings(c, &as);
	if (s->adaptive || s->profiled) {
		o.min_height = as.min_height;
		o.max_height = as.max_height;
	}
	snprintf(title, sizeof(title), "%s: %zu layers, %s", a->in[0], s->layers,
		 s->adaptive ? "adaptive" : s->profiled ? "the 3MF's layer height profile" : "uniform");
	rc = layerplot_write(a->png, plan->v, plan->n, &o, &err);
	if (rc)
		fprintf(stderr, SLICE_CMD ": %s: %s; the G-code %s was written\n", a->png, err.msg,
			a->out);
	return rc ? ST_EXIT_FAILURE : 0;
}

/* PrusaSlicer's input_filename and input_filename_base for the custom G-code. */
static int input_vars(struct profile *p, const char *in)
{
	const char *base = strrchr(in, '/') ? strrchr(in, '/') + 1 : in;
	const char *dot = strrchr(base, '.');
	char stem[PROFILE_PATH_MAX];
	const char *stem_p = stem;
	struct st_error err = {0};
	int rc;

	snprintf(stem, sizeof(stem), "%.*s", (int)(dot && dot != base ? dot - base : (long)strlen(base)),
		 base);
	rc = ph_vars_set_strings(p->vars, "input_filename", &base, 1, false, &err);
	if (rc == 0)
		rc = ph_vars_set_strings(p->vars, "input_filename_base", &stem_p, 1, false, &err);
	if (rc)
		fprintf(stderr, SLICE_CMD ": %s\n", err.msg);
	return rc ? ST_EXIT_SOFTWARE : 0;
}

static int slice_run(int argc, char **argv, struct clio *io)
{
	struct slice_args a = {0};
	struct slice_run run = {0};
	struct slicer_config cfg;
	struct slicejob_result res;
	struct plan_copy plan = {0};
	struct st_error err = {0};
	struct profile *prof = NULL;
	const char *in[SLICEJOB_MODELS_MAX], *out;
	int status, rc;

	status = parse_args(argc, argv, &a);
	if (status)
		return status < 0 ? ST_EXIT_OK : status;
	out = a.out;
	/* "-": the files read and written; a.in and a.out keep the names shown */
	memcpy(in, a.in, sizeof(in));
	for (size_t i = 0; i < a.nin; i++)
		if ((status = clio_input(io, &in[i], "")))
			return status;
	if ((status = clio_output(io, &out, false, ".gcode")))
		return status;
	{
		/* Before any work: never over the model, and a writable directory. */
		char why[512];

		for (size_t i = 0; i < a.nin; i++) {
			status = cmd_output_check(in[i], out, why, sizeof(why));
			if (!status && a.png)
				status = cmd_output_check(in[i], a.png, why, sizeof(why));
			if (status)
				return cmd_fail(SLICE_CMD, status, "%s; nothing was written", why);
		}
	}

	/* Settings that cannot slice are refused like a bad --layer-height. */
	if ((status = cfgopt_load(&a.cfg, SLICE_CMD, a.printer, &prof)))
		return status;
	cfgopt_warn_unsupported(prof, SLICE_CMD);
	cfgopt_note_project_settings(&a.cfg, SLICE_CMD, a.in, a.nin);
	status = input_vars(prof, a.in[0]); /* the first model's, as PrusaSlicer */
	if (status)
		goto out_profile;
	status = config_from_profile(prof, &a, &cfg);
	if (status)
		goto out_profile;
	rc = slicer_config_check(&cfg, &err);
	if (rc) {
		status = cmd_fail(SLICE_CMD, ST_EXIT_USAGE, "%s", err.msg);
		goto out_profile;
	}
	cfg.planned = keep_plan;
	cfg.planned_ctx = &plan;
	status = slicejob_run(SLICE_CMD, in, a.nin, &cfg, a.no_repair, out, true, &res);
	if (!status && a.png)
		status = write_plot(&a, &cfg, &res.sum, &plan);
	if (!status) {
		warn_thin(&cfg, &res.sum.thin);
		note_profile(&a, &res, &cfg);
	}
	if (!status) {
		run.plan = &plan;
		run.a = &a;
		run.c = &cfg;
		run.prof = prof;
		run.res = &res;
		run.rep = res.repaired ? &res.rep : NULL;
		status = cmd_report_end(SLICE_CMD, "summary", a.json ? print_json(&run, &res.sum) != 0
								 : (print_text(&run, &res.sum), 0));
	}
	slicejob_result_free(&res);
out_profile:
	free(plan.v);
	profile_free(prof);
	return status;
}

/* "stratum slice - -o -" reads stdin and writes stdout (clio.h). */
int cmd_slice(int argc, char **argv)
{
	return clio_run(SLICE_CMD, slice_run, argc, argv);
}

/*
 * cmd_preview.c - `stratum preview FILE.gcode (--layer N | --z Z)
 * -o OUT.(svg|png) [--model MODEL] [--center X,Y] [--width PX]
 * [--filament-diameter D] [--json]`: draw one layer of a G-code file
 * (preview.h, pvdraw.h).  Exit 0 written, 1 OUT not written, 2 usage (bad
 * option, no such layer), 65 unreadable G-code or model, 70 internal.
 */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clio.h"
#include "commands.h"
#include "mesh.h"
#include "meshio.h"
#include "preview.h"
#include "pvdraw.h"
#include "st_error.h"
#include "st_number.h"

#define PREVIEW_CMD "stratum preview"

struct preview_args {
	const char *in, *out, *model;
	const char *has_layer, *has_z; /* the option's name when given */
	bool json;
	struct preview_opts o;
	int width;
};

/* --center X,Y into struct preview_opts. */
static bool read_center(const char *v, void *dest)
{
	struct preview_opts *o = dest;
	const char *comma = strchr(v, ',');

	o->has_center =
	    comma && st_parse_double(v, (size_t)(comma - v), 0, &o->center_x) == ST_NUMBER_OK &&
	    st_parse_double(comma + 1, strlen(comma + 1), 0, &o->center_y) == ST_NUMBER_OK;
	return o->has_center;
}

/* Parse argv; 0 to go on, -1 after --help, else the exit status. */
static int parse_args(int argc, char **argv, struct preview_args *a)
{
	enum pvdraw_format fmt;

	const struct cmd_opt opts[] = {
	    {"--layer", 0, CMD_LONG, &a->o.layer, CMD_RANGE, 1, 1e9, "a layer number from %g", "N",
	     "the N-th layer, from 1 (the slicer's layer comments, or\n"
	     "the distinct heights of the extrusion when there are none)", NULL, &a->has_layer},
	    {"--z", 0, CMD_DOUBLE, &a->o.z, 0, 0, 0, "a height in mm", "Z",
	     "the layer printed at height Z mm", NULL, &a->has_z},
	    CMD_OPT_STRING("--output", 'o', &a->out, CMD_NONEMPTY, "the picture's file name", "OUT",
			   "the picture, .svg or .png (written only when complete)"),
	    CMD_OPT_STRING("--model", 0, &a->model, CMD_NONEMPTY, "a mesh file", "MODEL",
			   "also draw the model's section (STL, OBJ or OFF) at the\n"
			   "layer's mid-height, placed as the slicer placed it"),
	    {"--center", 0, CMD_CUSTOM, &a->o, 0, 0, 0, "X,Y in mm", "X,Y",
	     "the model's centre on the bed, mm (default: the centre of\n"
	     "the printed part, right for 'stratum slice' and PrusaSlicer\n"
	     "unless the part is lopsided under --center)", read_center, NULL},
	    {"--width", 0, CMD_INT, &a->width, CMD_RANGE, PVDRAW_WIDTH_MIN, PVDRAW_WIDTH_MAX,
	     "a whole number of pixels from %g to %g", "PX",
	     "picture width, %g to %g px (default %g)", NULL, NULL},
	    {"--filament-diameter", 0, CMD_DOUBLE, &a->o.filament_diameter,
	     CMD_RANGE | CMD_ABOVE_LO, 0, 10, "a diameter in mm in (%g, %g]", "D",
	     "mm, when the file has no '; filament_diameter =' line", NULL, NULL},
	    CMD_OPT_FLAG("--json", &a->json,
	     "one JSON object on stdout instead of the text summary"),
	};
	const struct cmd_spec spec = {
	    .cmd = PREVIEW_CMD, CMD_TABLE(opts), .col = 20,
	    .head = "usage: stratum preview FILE.gcode (--layer N | --z Z) -o OUT.svg|OUT.png\n"
		    "                       [--model MODEL] [--center X,Y] [--width PX]\n"
		    "                       [--filament-diameter D] [--json]\n"
		    "\n"
		    "Draws one layer of a G-code file seen from above: outer and inner perimeters,\n"
		    "gap fill, solid and sparse infill, bridges, support, skirt/brim and other\n"
		    "extrusion in their own colours, each bead at the width its filament makes;\n"
		    "travels thin and dashed; a legend and a scale bar in mm.  FILE '-' reads the\n"
		    "G-code on stdin.  See docs/preview.md.\n"
		    "\n",
	    .tail = "\n"
		    "Exit status: 0 written, 1 OUT not written, 2 usage or no such layer,\n"
		    "65 unreadable G-code or model, 70 internal error.\n",
	    .pos = &a->in, .npos = 1, .extra = "one G-code file at a time ('%s' and '%s')"};
	int rc;

	preview_opts_init(&a->o);
	a->width = PVDRAW_WIDTH_DEFAULT;
	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc;
	const char *missing = !a->in	  ? "no G-code file given"
			      : !a->out	  ? "no picture given; add -o OUT.svg or -o OUT.png"
			      : !a->has_layer == !a->has_z ? "give either --layer N or --z Z"
							 : NULL;
	if (missing)
		return cmd_refuse(&spec, "%s", missing);
	if (!pvdraw_format_of(a->out, &fmt))
		return cmd_fail(PREVIEW_CMD, ST_EXIT_USAGE,
				"%s: the picture must end in .svg or .png", a->out);
	if (a->has_z)
		a->o.layer = 0;
	return 0;
}

/* The file name without its directories, for the picture's title. */
static const char *base_name(const char *path)
{
	const char *slash = strrchr(path, '/');
	return slash ? slash + 1 : path;
}

static void print_text(const struct preview_args *a, const struct preview *pv, int w, int h)
{
	bool any = false;

	printf("layer %zu of %zu: Z %g mm, %g mm high\npaths:", pv->layer, pv->layers, pv->z,
	       pv->height);
	for (int f = 0; f < PREVIEW_FEATURES; f++) {
		if (!pv->count[f])
			continue;
		printf("%s %zu %s", any ? "," : "", pv->count[f], preview_feature_name(f));
		any = true;
	}
	printf("%s\n", any ? "" : " none");
	if (pv->has_model)
		printf("model section: %zu loop%s (model moved by %.3f, %.3f, %.3f mm)\n",
		       pv->noutline, pv->noutline == 1 ? "" : "s", pv->model_offset[0] + 0.0,
		       pv->model_offset[1] + 0.0, pv->model_offset[2] + 0.0); /* no "-0.000" */
	printf("written: %s (%d x %d px)\n", a->out, w, h);
}

static int print_json(const struct preview_args *a, const struct preview *pv, int w, int h)
{
	json_t *o = json_object(), *paths = json_object();

	for (int f = 0; f < PREVIEW_FEATURES; f++)
		json_object_set_new(paths, preview_feature_id(f), json_integer((json_int_t)pv->count[f]));
	cmd_json_set(o, "s:file", a->in, "I:layer", (json_int_t)pv->layer,
		     "I:layers", (json_int_t)pv->layers,
		     "s:layers_from", pv->by_comments ? "comments" : "z", "f:z", pv->z,
		     "f:height", pv->height, "o:paths", paths,
		     "o:model_loops",
		     pv->has_model ? json_integer((json_int_t)pv->noutline) : json_null(),
		     "s:output", a->out, "i:width_px", w, "i:height_px", h, NULL);
	return cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
}

/* Exit status for a library error class. */
static int exit_for(const struct st_error *err)
{
	fprintf(stderr, PREVIEW_CMD ": %s\n", err->msg);
	return err->code == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : st_exit_for(err->code);
}

static int preview_run(int argc, char **argv, struct clio *io)
{
	struct preview_args a = {0};
	struct preview *pv = NULL;
	struct mesh *m = NULL;
	struct st_error err = {0};
	struct pvdraw_opts d;
	int w, h, status = parse_args(argc, argv, &a);

	if (status)
		return status < 0 ? ST_EXIT_OK : status;
	if ((status = clio_input(io, &a.in, ".gcode")))
		return status;
	if (preview_load(a.in, &a.o, &pv, &err))
		return exit_for(&err);
	if (a.model) {
		if (meshio_read(a.model, MESHIO_AUTO, &m, NULL, &err) ||
		    preview_add_model(pv, m, &a.o, &err)) {
			status = exit_for(&err);
			goto out;
		}
		if (!pv->noutline)
			fprintf(stderr,
				PREVIEW_CMD ": note: %s has no cross-section at this layer's "
					    "mid-height (%g mm above its lowest point)\n",
				a.model, pv->z - pv->height / 2);
	}
	d = (struct pvdraw_opts){.width_px = a.width, .title = base_name(a.in)};
	if (pvdraw_size(pv, &d, &w, &h, &err)) {
		status = exit_for(&err);
		goto out;
	}
	if (pvdraw_write(pv, &d, a.out, &err)) {
		status = exit_for(&err);
		if (err.code == ST_ERR_IO)
			status = ST_EXIT_FAILURE; /* the job, not the input, failed */
		goto out;
	}
	if (a.json ? print_json(&a, pv, w, h) : (print_text(&a, pv, w, h), 0))
		status = ST_EXIT_SOFTWARE;
	if (fflush(stdout) == EOF)
		status = ST_EXIT_SOFTWARE;
out:
	mesh_free(m);
	preview_free(pv);
	return status;
}

/* "stratum preview -" draws the G-code on stdin (clio.h). */
int cmd_preview(int argc, char **argv)
{
	return clio_run(PREVIEW_CMD, preview_run, argc, argv);
}

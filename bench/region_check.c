/*
 * region_check.c - the slicer's "Done when" measurement (issue 5) for the
 * benchmark: how well does the region a G-code file prints match the
 * model's cross-sections?  See host/region.h for what is measured.
 *
 *   region_check MODEL GCODE [--center X,Y] [--filament-diameter D]
 *                [--step MM] [--json] [--layers] [--support DEG,GAP,REACH]
 *
 * --support also checks the support the file prints (region.h,
 * region_support_check): overhang threshold DEG degrees, top contact
 * distance GAP mm, REACH mm around support counted as holding the part.
 *
 * Exit status: 0 measured, 2 usage, 65 unreadable model or G-code,
 * 70 internal error.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meshio.h"
#include "region.h"

static void usage(void)
{
	fprintf(stderr, "usage: region_check MODEL GCODE [--center X,Y] [--filament-diameter D]\n"
			"                    [--step MM] [--json] [--layers] [--support DEG,GAP,REACH]\n");
	exit(ST_EXIT_USAGE);
}

/* A positive number argument, or exit 2. */
static double num_arg(const char *opt, const char *s)
{
	char *end;
	double v = strtod(s, &end);

	if (end == s || *end || !(v > 0.0)) {
		fprintf(stderr, "region_check: %s needs a number > 0, got '%s'\n", opt, s);
		exit(ST_EXIT_USAGE);
	}
	return v;
}

/* s: the support check, NULL when not asked for. */
static void print_json(const struct region_print *p, const struct region_report *r, bool layers,
		       const struct region_support_report *s)
{
	printf("{\n  \"layers\": %zu,\n  \"beads\": %zu,\n  \"skipped_moves\": %zu,\n", r->layers,
	       p->beads, p->skipped);
	printf("  \"filament_diameter\": %g,\n  \"width_min\": %.4f,\n  \"width_max\": %.4f,\n",
	       p->filament_diameter, p->width_min, p->width_max);
	printf("  \"offset\": [%.6f, %.6f, %.6f],\n", r->offset[0], r->offset[1], r->offset[2]);
	printf("  \"samples\": %zu,\n  \"dev_p95\": %.6f,\n  \"dev_max\": %.6f,\n", r->samples,
	       r->dev_p95, r->dev_max);
	printf("  \"dev_p95_printed\": %.6f,\n  \"dev_p95_model\": %.6f,\n", r->dev_p95_printed,
	       r->dev_p95_model);
	printf("  \"outside_max\": %.6f,\n  \"inside_max\": %.6f,\n", r->outside_max, r->inside_max);
	printf("  \"area_error\": %.6f,\n  \"area_error_raw\": %.6f,\n", r->area_error,
	       r->area_error_raw);
	printf("  \"gap\": %.6f,\n  \"overlap\": %.6f,\n", r->gap, r->overlap);
	printf("  \"layer_area_error_max\": %.6f,\n  \"empty_sections\": %zu", r->layer_area_error_max,
	       r->empty_sections);
	if (layers) {
		printf(",\n  \"per_layer\": [");
		for (size_t i = 0; i < r->layers; i++) {
			const struct region_layer_result *l = &r->per_layer[i];
			printf("%s\n    {\"z\": %.4f, \"height\": %.4f, \"section_mm2\": %.4f, "
			       "\"envelope_mm2\": %.4f, \"xor_mm2\": %.5f, \"xor_raw_mm2\": %.4f, "
			       "\"dev_max\": %.5f}",
			       i ? "," : "", l->z, l->height, l->section_mm2, l->envelope_mm2,
			       l->xor_mm2, l->xor_raw_mm2, l->dev_max);
		}
		printf("\n  ]");
	}
	if (s)
		printf(",\n  \"support\": {\"moves\": %zu, \"stray_moves\": %zu, \"inside_mm2\": "
		       "%.5f, \"overhang_mm2\": %.4f, \"unsupported_mm2\": %.5f, \"worst_z\": %.4f}",
		       s->beads, s->stray, s->inside_mm2, s->overhang_mm2, s->unsupported_mm2,
		       s->worst_z);
	printf("\n}\n");
}

static void print_support(const struct region_support_report *s)
{
	printf("support: %zu moves (%zu on no layer of the part), %.5f mm2 inside the part; "
	       "overhang %.4f mm2, %.5f mm2 of it unsupported (worst at z %.2f)\n",
	       s->beads, s->stray, s->inside_mm2, s->overhang_mm2, s->unsupported_mm2, s->worst_z);
}

static void print_text(const struct region_print *p, const struct region_report *r, bool layers)
{
	printf("layers: %zu compared (%zu with no cross-section), %zu beads, %zu skipped moves\n",
	       r->layers, r->empty_sections, p->beads, p->skipped);
	printf("beads: filament %g mm, widths %.3f to %.3f mm\n", p->filament_diameter,
	       p->width_min, p->width_max);
	printf("model placed by: %+.4f %+.4f %+.4f mm\n", r->offset[0], r->offset[1], r->offset[2]);
	printf("outer deviation: p95 %.4f mm, max %.4f mm (printed->model p95 %.4f, "
	       "model->printed p95 %.4f; %zu samples)\n",
	       r->dev_p95, r->dev_max, r->dev_p95_printed, r->dev_p95_model, r->samples);
	printf("printed boundary: up to %.4f mm outside the model, up to %.4f mm inside\n",
	       r->outside_max, r->inside_max);
	printf("area error: %.5f (voids filled), %.5f (voids counted), worst layer %.5f\n",
	       r->area_error, r->area_error_raw, r->layer_area_error_max);
	printf("gap: %.5f of the section no bead covers; overlap: %.5f under two or more runs\n",
	       r->gap, r->overlap);
	for (size_t i = 0; layers && i < r->layers; i++) {
		const struct region_layer_result *l = &r->per_layer[i];
		printf("  z %.3f h %.3f: section %.3f mm2, envelope %.3f, xor %.4f, raw xor %.3f, "
		       "dev max %.4f\n",
		       l->z, l->height, l->section_mm2, l->envelope_mm2, l->xor_mm2, l->xor_raw_mm2,
		       l->dev_max);
	}
}

int main(int argc, char **argv)
{
	struct region_opts o;
	struct st_error err = {0};
	struct mesh *m = NULL;
	struct region_print *p = NULL;
	struct region_report *r = NULL;
	const char *files[2] = {NULL, NULL};
	bool json = false, layers = false;
	double sup[3] = {0, 0, 0}; /* --support: degrees, gap, reach */
	struct region_support_report sr;
	int nfiles = 0, rc;

	region_opts_init(&o);
	for (int i = 1; i < argc; i++) {
		if (!strcmp(argv[i], "--json")) {
			json = true;
		} else if (!strcmp(argv[i], "--layers")) {
			layers = true;
		} else if (!strcmp(argv[i], "--center") && i + 1 < argc) {
			char *end;
			o.center_x = strtod(argv[++i], &end);
			if (*end != ',')
				usage();
			o.center_y = strtod(end + 1, &end);
			if (*end)
				usage();
			o.has_center = true;
		} else if (!strcmp(argv[i], "--filament-diameter") && i + 1 < argc) {
			o.filament_diameter = num_arg(argv[i], argv[i + 1]);
			i++;
		} else if (!strcmp(argv[i], "--step") && i + 1 < argc) {
			o.sample_step = num_arg(argv[i], argv[i + 1]);
			i++;
		} else if (!strcmp(argv[i], "--support") && i + 1 < argc) {
			if (sscanf(argv[++i], "%lf,%lf,%lf", &sup[0], &sup[1], &sup[2]) != 3 ||
			    !(sup[0] > 0 && sup[0] < 90 && sup[1] >= 0 && sup[2] >= 0)) {
				fprintf(stderr, "region_check: --support needs DEG (0 to 90, "
						"exclusive),GAP,REACH (mm, >= 0), got '%s'\n",
					argv[i]);
				exit(ST_EXIT_USAGE);
			}
		} else if (argv[i][0] == '-' || nfiles == 2) {
			usage();
		} else {
			files[nfiles++] = argv[i];
		}
	}
	if (nfiles != 2)
		usage();
	if ((rc = meshio_read(files[0], MESHIO_AUTO, &m, NULL, &err)) ||
	    (rc = region_read(files[1], &o, &p, &err)) || (rc = region_compare(m, p, &o, &r, &err)) ||
	    (sup[0] != 0 &&
	     (rc = region_support_check(files[1], m, p, &o, sup[0], sup[1], sup[2], &sr, &err)))) {
		fprintf(stderr, "region_check: %s\n", err.msg);
		mesh_free(m);
		region_print_free(p);
		return st_exit_for(rc);
	}
	if (json)
		print_json(p, r, layers, sup[0] != 0 ? &sr : NULL);
	else
		print_text(p, r, layers);
	if (!json && sup[0] != 0)
		print_support(&sr);
	region_report_free(r);
	region_print_free(p);
	mesh_free(m);
	return 0;
}

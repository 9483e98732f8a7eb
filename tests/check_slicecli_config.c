/*
 * check_slicecli_config.c - `stratum slice` with PrusaSlicer's configs, part
 * of the slicecli suite (check_slicecli.c, the same "slice" case): every
 * preset of the bundles installed, a preset as a flat config, a saved
 * default config, a project 3MF's config, the order of --load and --set,
 * and the options' doc.
 */
#include <check.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fixtures.h"
#include "meshio.h"
#include "sliceclitest.h"
#include "suites.h"
#include "testutil.h"

static char out[1 << 16];

/* ---------------------------------------------------------------------------
 * PrusaSlicer configs (--load, bundles, --set; issue 18 items 3 and 5)
 */

#define BUNDLES "/usr/share/PrusaSlicer/profiles"

/* A copy of a tu_path (its buffer is reused by the next call). */
static void scratch(char *buf, size_t cap, const char *name)
{
	snprintf(buf, cap, "%s", tu_path(name));
}

/* Slurp path into buf; the length. */
static size_t slurp(const char *path, char *buf, size_t cap)
{
	FILE *f = fopen(path, "rb");
	size_t n = f ? fread(buf, 1, cap - 1, f) : 0;

	if (f)
		fclose(f);
	buf[n] = '\0';
	return n;
}

START_TEST(bundle_presets_slice)
{
	static char gcode[1 << 20];
	char model[4096], gc[4096];
	int status;

	if (access(BUNDLES "/PrusaResearch.ini", R_OK) || access(BUNDLES "/Creality.ini", R_OK)) {
		fprintf(stderr, "bundle_presets_slice: skipped, no PrusaSlicer bundles in "
				BUNDLES "\n");
		return;
	}
	snprintf(model, sizeof(model), "%s", stl_file(fx_box(0, 0, 0, 10, 10, 2), "bcube.stl"));
	scratch(gc, sizeof(gc), "mk3s.gcode");
	status = tu_run(out, sizeof(out),
			"slice '%s' -o '%s' --load " BUNDLES "/PrusaResearch.ini --printer-preset "
			"'Original Prusa i3 MK3S & MK3S+' --print-preset '0.20mm QUALITY @MK3' "
			"--filament-preset 'Prusament PLA'",
			model, gc);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	/* Every key of the presets is honoured: no warning line. */
	ck_assert_msg(!strstr(out, "not supported"), "%s", out);
	slurp(gc, gcode, sizeof(gcode));
	/* remaining_times = 1 and silent_mode = 1 of the MK3 presets, marlin. */
	ck_assert_msg(strstr(gcode, "\nM73 P0 R") && strstr(gcode, "\nM73 Q0 S") &&
			      strstr(gcode, "\nM73 P100 R0\nM73 Q100 S0\n"),
		      "M73");
	/* PrusaSlicer's own expansions of the MK3S start, filament and end G-code. */
	ck_assert_msg(strstr(gcode, "M862.3 P \"MK3S\" ; printer model check\n"), "start");
	ck_assert_msg(strstr(gcode, "M862.1 P0.4 ; nozzle diameter check\n"), "nozzle");
	ck_assert_msg(strstr(gcode, "M104 S215 ; set extruder temp\n"), "temperature");
	ck_assert_msg(strstr(gcode, "M900 K0.05 ; Filament gcode LA 1.5\n"), "filament gcode");
	ck_assert_msg(strstr(gcode, ";BEFORE_LAYER_CHANGE\nG92 E0.0\n;0.2\n"), "before layer");
	ck_assert_msg(strstr(gcode, ";AFTER_LAYER_CHANGE\n;0.2\n"), "after layer");
	ck_assert_msg(strstr(gcode, "G1 Z3 F720 ; Move print head up\n"), "end: max_layer_z + 1");
	ck_assert_msg(strstr(gcode, "; layer_height = 0.2\n"), "0.20mm QUALITY's layers");

	scratch(gc, sizeof(gc), "ender3.gcode");
	status = tu_run(out, sizeof(out),
			"slice '%s' -o '%s' --load " BUNDLES "/Creality.ini --printer-preset "
			"'Creality Ender-3 (0.4 mm nozzle)'",
			model, gc);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	slurp(gc, gcode, sizeof(gcode));
	ck_assert_msg(strstr(gcode, "G1 X5 Y182.4 F9000 ; present print\n"), "print_bed_max");

	/* A bundle needs its printer named; a preset it lacks is exit 2. */
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --load " BUNDLES "/Creality.ini",
			model, gc);
	ck_assert_msg(status == 2 && strstr(out, "choose its printer with --printer-preset"),
		      "exit %d: %s", status, out);
	status = tu_run(out, sizeof(out),
			"slice '%s' -o '%s' --load " BUNDLES "/Creality.ini --printer-preset nope",
			model, gc);
	ck_assert_msg(status == 2 && strstr(out, "no [printer:nope] preset"), "exit %d: %s",
		      status, out);
}
END_TEST

/* `stratum printers --show` with the settings options writes a bundle preset
 * as one flat config that PrusaSlicer and Stratum both load as it was: the
 * per-filament texts quoted (unquoted, PrusaSlicer splits them at ';'), a
 * multi-extruder printer's default filaments "A; B" taken as A, and a key
 * neither tool knows, with a blank in it (Prusa's 2.5.5 bundle has
 * "top solid_infill_speed"), skipped as PrusaSlicer skips it: the bundle
 * was refused at that line. */
START_TEST(bundle_preset_as_flat_config)
{
	static char text[1 << 16], again[1 << 16];
	char bundle[4096], flat[4096];
	int status;

	scratch(bundle, sizeof(bundle), "tiny-bundle.ini");
	scratch(flat, sizeof(flat), "tiny-flat.ini");
	tu_write_str(bundle, "[vendor]\nname = Tiny\n\n[printer:*common*]\nbed_shape = "
			     "0x0,200x0,200x200,0x200\n\n[printer:Tiny Two]\ninherits = *common*\n"
			     "printer_model = TINY2\ndefault_print_profile = 0.2mm\n"
			     "default_filament_profile = PLA; PETG\n\n[print:0.2mm]\n"
			     "layer_height = 0.2\ntop solid_infill_speed = 40\n\n[filament:PLA]\nend_filament_gcode = "
			     "\"; Filament-specific end gcode\"\n\n[filament:PETG]\n"
			     "temperature = 240\n");
	status = tu_run(text, sizeof(text), "printers --show --load '%s' --printer-preset "
			"'Tiny Two' > '%s'", bundle, flat);
	ck_assert_msg(status == 0, "exit %d: %s", status, text);
	slurp(flat, text, sizeof(text));
	ck_assert_msg(strstr(text, "\nend_filament_gcode = \"; Filament-specific end gcode\"\n") &&
			      strstr(text, "\nprinter_settings_id = Tiny Two\n") &&
			      strstr(text, "\nfilament_settings_id = \"PLA\"\n") &&
			      strstr(text, "\nbed_shape = 0x0,200x0,200x200,0x200\n") &&
			      !strstr(text, "top solid"),
		      "%s", text);
	/* Loaded again, the same config. */
	status = tu_run(again, sizeof(again), "printers --show '%s' | grep -v '^#'", flat);
	ck_assert_int_eq(status, 0);
	status = tu_run(text, sizeof(text), "printers --show --load '%s' --printer-preset "
			"'Tiny Two' | grep -v '^#'", bundle);
	ck_assert_int_eq(status, 0);
	ck_assert_str_eq(again, text);
	status = tu_run(text, sizeof(text), "printers --set layer_height=0.3");
	ck_assert_msg(status == 2 && strstr(text, "the settings options go with --show"), "%s",
		      text);
}
END_TEST

/* A 10 mm cube as a 3MF model part, and the lines of a PrusaSlicer project's
 * Metadata/Slic3r_PE.config: "; key = value" under its "; generated by"
 * line (PrusaSlicer 2.5's 3mf.cpp), a G-code value with \n escapes. */
#define CUBE_3MF_MODEL                                                                     \
	"<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<model unit=\"millimeter\" "            \
	"xmlns=\"http://schemas.microsoft.com/3dmanufacturing/core/2015/02\"><resources>"      \
	"<object id=\"1\" type=\"model\"><mesh><vertices>"                                    \
	"<vertex x=\"0\" y=\"0\" z=\"0\"/><vertex x=\"10\" y=\"0\" z=\"0\"/>"                \
	"<vertex x=\"10\" y=\"10\" z=\"0\"/><vertex x=\"0\" y=\"10\" z=\"0\"/>"              \
	"<vertex x=\"0\" y=\"0\" z=\"10\"/><vertex x=\"10\" y=\"0\" z=\"10\"/>"              \
	"<vertex x=\"10\" y=\"10\" z=\"10\"/><vertex x=\"0\" y=\"10\" z=\"10\"/>"            \
	"</vertices><triangles>"                                                           \
	"<triangle v1=\"0\" v2=\"2\" v3=\"1\"/><triangle v1=\"0\" v2=\"3\" v3=\"2\"/>"       \
	"<triangle v1=\"4\" v2=\"5\" v3=\"6\"/><triangle v1=\"4\" v2=\"6\" v3=\"7\"/>"       \
	"<triangle v1=\"0\" v2=\"1\" v3=\"5\"/><triangle v1=\"0\" v2=\"5\" v3=\"4\"/>"       \
	"<triangle v1=\"3\" v2=\"7\" v3=\"6\"/><triangle v1=\"3\" v2=\"6\" v3=\"2\"/>"       \
	"<triangle v1=\"0\" v2=\"4\" v3=\"7\"/><triangle v1=\"0\" v2=\"7\" v3=\"3\"/>"       \
	"<triangle v1=\"1\" v2=\"2\" v3=\"6\"/><triangle v1=\"1\" v2=\"6\" v3=\"5\"/>"       \
	"</triangles></mesh></object></resources><build><item objectid=\"1\"/></build></model>\n"
#define PROJECT_CONFIG_HEAD                                                                \
	"; generated by PrusaSlicer 2.5.0+linux-x64-GTK3 on 2026-12-07 at 12:00:00 UTC\n\n"

/* A project 3MF at path: the cube and config (no config entry: NULL). */
static void write_project(const char *path, const char *config)
{
	const char *names[] = {"_rels/.rels", "3D/3dmodel.model", "Metadata/Slic3r_PE.config"};
	const char *texts[] = {tu_3mf_rels, CUBE_3MF_MODEL, config};

	tu_write_zip(path, names, texts, config ? 3 : 2);
}

/* `prusa-slicer --save` (every key, PrusaSlicer's defaults) loads with one
 * warning naming just the two defaults Stratum does not print
 * (docs/slicing.md), and the same keys as a PrusaSlicer project carries them
 * (Metadata/Slic3r_PE.config, without compatible_printers as 2.5 writes it)
 * slice to the same G-code. */
START_TEST(saved_default_config_loads)
{
	static char text[1 << 16], config[1 << 17];
	char model[4096], ini[4096], proj[4096], gc[4096], gc3[4096], cmd[9000];
	const char *warning;
	size_t n = 0;
	int status;

	if (access("/usr/bin/prusa-slicer", X_OK)) {
		fprintf(stderr, "saved_default_config_loads: skipped, no prusa-slicer\n");
		return;
	}
	snprintf(model, sizeof(model), "%s", stl_file(fx_box(0, 0, 0, 10, 10, 2), "dcube.stl"));
	scratch(ini, sizeof(ini), "default.ini");
	scratch(proj, sizeof(proj), "default.3mf");
	scratch(gc, sizeof(gc), "default.gcode");
	scratch(gc3, sizeof(gc3), "default-3mf.gcode");
	snprintf(cmd, sizeof(cmd), "prusa-slicer --save '%s' >/dev/null 2>&1", ini);
	ck_assert_int_eq(system(cmd), 0);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --load '%s'", model, gc, ini);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	/* PrusaSlicer's default pattern, stars, is printed. */
	ck_assert_msg(!strstr(out, "fill_pattern=stars") && strstr(out, "% stars)"), "%s", out);
	warning = strstr(out, "warning");
	ck_assert_msg(warning && !strstr(warning + 1, "warning") &&
			      strstr(out, "stratum slice: warning: not supported, ignored: "
					  "ensure_vertical_shell_thickness=0, extra_perimeters=1\n"),
		      "%s", out);

	slurp(ini, text, sizeof(text));
	n += (size_t)snprintf(config, sizeof(config), PROJECT_CONFIG_HEAD);
	for (char *l = strtok(text, "\n"); l; l = strtok(NULL, "\n"))
		if (*l != '#' && strncmp(l, "compatible_printers =", 21))
			n += (size_t)snprintf(config + n, sizeof(config) - n, "; %s\n", l);
	ck_assert_uint_lt(n, sizeof(config));
	write_project(proj, config);
	status = tu_run(text, sizeof(text), "slice '%s' -o '%s' --load '%s'", model, gc3, proj);
	ck_assert_msg(status == 0, "exit %d: %s", status, text);
	*strstr(text, "written: ") = *strstr(out, "written: ") = '\0'; /* the G-code files' names */
	ck_assert_str_eq(text, out);
	snprintf(cmd, sizeof(cmd), "cmp -s '%s' '%s'", gc, gc3);
	ck_assert_msg(system(cmd) == 0, "the project's settings slice otherwise than the .ini's");
}
END_TEST

/* --load PROJECT.3mf takes the settings a PrusaSlicer project carries, as a
 * flat config in its place among the --load files; the project's model
 * slices as given, with or without them. */
START_TEST(load_project_3mf_config)
{
	static char gcode[1 << 20];
	char proj[4096], bare[4096], later[4096], gc[4096];
	int status;

	scratch(proj, sizeof(proj), "project.3mf");
	scratch(bare, sizeof(bare), "bare.3mf");
	scratch(later, sizeof(later), "later.ini");
	scratch(gc, sizeof(gc), "project.gcode");
	write_project(proj, PROJECT_CONFIG_HEAD "; layer_height = 0.25\n; temperature = 222\n"
					       "; start_gcode = ; project [temperature]\\nG28\n"
					       "; fuzzy_skin = random\n");
	tu_write_str(later, "temperature = 230\n");
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S " --load '%s'", proj, gc,
			proj);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	ck_assert_msg(strstr(out, "warning: not supported, ignored: fuzzy_skin=random\n") &&
			      !strstr(out, "note:"),
		      "%s", out);
	slurp(gc, gcode, sizeof(gcode));
	ck_assert_msg(strstr(gcode, "\n; project 222\nG28\n") &&
			      strstr(gcode, "\n; layer_height = 0.25\n"),
		      "the project's settings");
	/* A later --load wins over the project's, as between two files. */
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S " --load '%s' --load '%s'",
			proj, gc, proj, later);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	slurp(gc, gcode, sizeof(gcode));
	ck_assert_msg(strstr(gcode, "\n; project 230\nG28\n"), "later.ini wins");
	/* Given as a model only, its settings are not applied, and that is said. */
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S, proj, gc);
	ck_assert_msg(status == 0 && strstr(out, "stratum slice: note: ") &&
			      strstr(out, "project.3mf carries PrusaSlicer settings "
					  "(Metadata/Slic3r_PE.config), not applied; add --load "),
		      "exit %d: %s", status, out);
	slurp(gc, gcode, sizeof(gcode));
	ck_assert_msg(!strstr(gcode, "; project"), "the profile's start G-code");
	/* print takes --load PROJECT.3mf, and says the same without it. */
	status = tu_run(out, sizeof(out), "print '%s' " MK3S " --dry-run -o '%s' --load '%s' && "
			"grep -q '^; project 222$' '%s'", proj, gc, proj, gc);
	ck_assert_msg(status == 0 && !strstr(out, "note:"), "exit %d: %s", status, out);
	status = tu_run(out, sizeof(out), "print '%s' " MK3S " --dry-run -o '%s'", proj, gc);
	ck_assert_msg(status == 0 && strstr(out, "stratum print: note: "), "exit %d: %s", status,
		      out);
	/* Errors name the entry and its line; a 3MF without settings says so. */
	write_project(proj, PROJECT_CONFIG_HEAD "; layer_height = thick\n");
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S " --load '%s'", proj, gc,
			proj);
	ck_assert_msg(status == 65 && strstr(out, "project.3mf: Metadata/Slic3r_PE.config: line 3: "
						  "layer_height: 'thick' is not a number"),
		      "exit %d: %s", status, out);
	write_project(bare, NULL);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S " --load '%s'", bare, gc,
			bare);
	ck_assert_msg(status == 65 && strstr(out, "bare.3mf: a 3MF without PrusaSlicer settings"),
		      "exit %d: %s", status, out);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' " MK3S, bare, gc);
	ck_assert_msg(status == 0 && !strstr(out, "note:"), "exit %d: %s", status, out);
}
END_TEST

START_TEST(settings_options_doc)
{
	static char doc[1 << 17], help[1 << 16];
	const char *a = tu_read_between("docs/slicing.md", doc, sizeof(doc),
					"<!-- cfgopt:begin -->\n```\n", "```\n<!-- cfgopt:end -->");

	ck_assert_int_eq(tu_run(help, sizeof(help), "slice --help"), 0);
	ck_assert_msg(strstr(help, a), "docs/slicing.md's settings options differ from "
				       "'stratum slice --help' (host/cfgopt.c)");
}
END_TEST

START_TEST(load_order_and_set)
{
	static char gcode[1 << 20];
	char model[4096], a[4096], b[4096], gc[4096];
	int status;

	snprintf(model, sizeof(model), "%s", stl_file(fx_box(0, 0, 0, 10, 10, 2), "ocube.stl"));
	scratch(a, sizeof(a), "a.ini");
	scratch(b, sizeof(b), "b.ini");
	scratch(gc, sizeof(gc), "order.gcode");
	tu_write_str(a, "temperature = 200\nbed_temperature = 50\nstart_gcode = ; A [temperature]\n");
	tu_write_str(b, "temperature = 230\n");
	/* Later files replace earlier ones; --set and --KEY-NAME come last. */
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --load '%s' --load '%s'", model, gc,
			a, b);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	slurp(gc, gcode, sizeof(gcode));
	ck_assert_msg(strstr(gcode, "; A 230\n") && strstr(gcode, "; bed_temperature = 50\n"), "b wins");
	status = tu_run(out, sizeof(out),
			"slice '%s' -o '%s' --load '%s' --load '%s' --set temperature=240 "
			"--bed-temperature 65 --brim-width 3 --fill-density 30%% --support-material",
			model, gc, b, a);
	ck_assert_msg(status == 0, "exit %d: %s", status, out);
	slurp(gc, gcode, sizeof(gcode));
	ck_assert_msg(strstr(gcode, "; A 240\n") && strstr(gcode, "; bed_temperature = 65\n"),
		      "--set wins");
	ck_assert_msg(strstr(out, "(30% "), "--fill-density: %s", out);

	/* Bad values: exit 2 before any repair, naming the option. */
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --load '%s' --set temperature=900",
			model, gc, a);
	ck_assert_msg(status == 2 && strstr(out, "--set: temperature: 900 is out of range") &&
			      !strstr(out, "repaired"),
		      "exit %d: %s", status, out);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --load '%s' --brim-width wide", model,
			gc, a);
	ck_assert_msg(status == 2 && strstr(out, "--brim-width: brim_width: 'wide' is not a number"),
		      "exit %d: %s", status, out);
	status = tu_run(out, sizeof(out), "slice '%s' -o '%s' --load '%s' --set nokey", model, gc, a);
	ck_assert_msg(status == 2 && strstr(out, "--set wants KEY=VALUE"), "exit %d: %s", status,
		      out);
	/* An unsupported key is named once, with its value. */
	status = tu_run(out, sizeof(out),
			"slice '%s' -o '%s' --load '%s' --set fuzzy_skin=random --set complete_objects=1 "
			"--set infill_first=1 --set external_fill_pattern=concentric",
			model, gc, a);
	ck_assert_msg(status == 0 && strstr(out, "warning: not supported, ignored: fuzzy_skin=random, "
						 "complete_objects=1, infill_first=1, "
						 "external_fill_pattern=concentric\n"),
		      "exit %d: %s", status, out);
	/* The raft is printed: its keys are not named, a raft key Stratum
	 * does not print is, and the header lists the values used. */
	status = tu_run(out, sizeof(out),
			"slice '%s' -o '%s' --load '%s' --set raft_layers=3 --set raft_expansion=2 "
			"--set first_layer_acceleration_over_raft=500",
			model, gc, a);
	ck_assert_msg(status == 0 && strstr(out, "warning: not supported, ignored: "
						 "first_layer_acceleration_over_raft=500\n"),
		      "exit %d: %s", status, out);
	slurp(gc, gcode, sizeof(gcode));
	ck_assert_msg(strstr(gcode, "; raft_layers = 3\n") && strstr(gcode, "; raft_expansion = 2\n"),
		      "raft header");
	ck_assert_msg(strstr(gcode, ";TYPE:Support material interface\n"), "raft paths");
	/* Spiral vase and ironing are printed, so not named; nor are thick
	 * bridges, the only ones Stratum prints. */
	status = tu_run(out, sizeof(out),
			"slice '%s' -o '%s' --load '%s' --set spiral_vase=1 --set ironing=1 "
			"--set thick_bridges=1 "
			"--set ironing_type=solid --set ironing_flowrate=10%% --set ironing_speed=20",
			model, gc, a);
	ck_assert_msg(status == 0 && !strstr(out, "not supported"), "exit %d: %s", status, out);
	/* the summary shows what is printed: no infill (the vase's), and the ironing */
	ck_assert_msg(strstr(out, " sparse (0% ") && strstr(out, " ironing\n") &&
			      !strstr(out, " 0 ironing\n"),
		      "%s", out);
	slurp(gc, gcode, sizeof(gcode));
	ck_assert_msg(strstr(gcode, "; spiral_vase = 1\n; ironing = 1\n; ironing_type = solid\n"
				    "; ironing_flowrate = 10%\n; ironing_spacing = 0.1\n"
				    "; ironing_speed = 20\n"),
		      "header");
}
END_TEST

/* The tests of the "slice" case on PrusaSlicer's configs, in their place. */
void slicecli_config_tests(TCase *tc)
{
	tcase_add_test(tc, bundle_presets_slice);
	tcase_add_test(tc, bundle_preset_as_flat_config);
	tcase_add_test(tc, saved_default_config_loads);
	tcase_add_test(tc, load_order_and_set);
	tcase_add_test(tc, load_project_3mf_config);
	tcase_add_test(tc, settings_options_doc);
}

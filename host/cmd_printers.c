/*
 * cmd_printers.c - `stratum printers [--json]` lists the printer profiles;
 * `stratum printers --show NAME|FILE.ini [--json]` prints one profile's
 * resolved settings.  A broken profile in the list is reported on stderr
 * and left out; the listing still succeeds.  Exit 0 ok, 2 usage or unknown
 * printer name, 65 the profile asked for with --show is invalid.
 */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfgopt.h"
#include "commands.h"
#include "profile.h"
#include "settings.h"
#include "st_append.h"
#include "st_error.h"

/* The help text around the option lines. */
static const char printers_head[] =
    "usage: stratum printers [--json]\n"
    "       stratum printers --show NAME|FILE.ini [--json] [SETTINGS OPTIONS]\n"
    "       stratum printers --show --load BUNDLE.ini --printer-preset NAME ...\n"
    "       stratum printers --keys\n"
    "\n"
    "Lists the printer profiles (NAME.ini files) found in, in this order:\n"
    "$STRATUM_PRINTERS_DIR, $XDG_CONFIG_HOME/stratum/printers (default\n"
    "~/.config/stratum/printers), PREFIX/share/stratum/printers beside the\n"
    "installed binary (or the printers/ folder of the build tree), and\n"
    STRATUM_DATADIR ".  NAME is what --printer takes.\n"
    "\n";
static const char printers_tail[] =
    "\n"
    "A profile that fails to load is reported on stderr and left out of the\n"
    "list.  Exit status: 0 ok, 2 usage error or unknown printer, 65 the profile\n"
    "given to --show is invalid.  See docs/printers.md.\n";

/* "0.4" when every nozzle is the same, else "0.4,0.6". */
static void nozzle_text(const struct profile *p, char *buf, size_t cap)
{
	bool same = true;

	for (int i = 1; i < p->extruder_count; i++)
		same = same && p->nozzle_diameter[i] == p->nozzle_diameter[0];
	buf[0] = '\0';
	for (int i = 0; i < (same ? 1 : p->extruder_count); i++)
		st_appendf(buf, cap, "%s%g", i ? "," : "", p->nozzle_diameter[i]);
}

/* One row of the listing as JSON (new reference, NULL when out of memory). */
static json_t *summary_json(const struct profile *p)
{
	json_t *o, *nozzles, *usb;

	nozzles = json_array();
	usb = json_array();
	if (!nozzles || !usb)
		goto out_free;
	for (int i = 0; i < p->extruder_count; i++)
		if (json_array_append_new(nozzles, json_real(p->nozzle_diameter[i])))
			goto out_free;
	for (size_t i = 0; i < p->usb_id_count; i++) {
		char id[16];

		snprintf(id, sizeof(id), "%04x:%04x", p->usb_ids[i].vid, p->usb_ids[i].pid);
		if (json_array_append_new(usb, json_string(id)))
			goto out_free;
	}
	o = json_pack(
	    "{s:s, s:s?, s:s?, s:s?, s:s, s:s, s:{s:f, s:f, s:f, s:f, s:f, s:f}, "
	    "s:f, s:i, s:o, s:f, s:i, s:o, s:s}",
	    "id", p->id, "name", p->name, "printer_model", p->printer_model, "description",
	    p->description, "protocol", profile_protocol_name(p->protocol), "gcode_flavor",
	    profile_flavor_name(p->gcode_flavor), "bed", "width", p->bed_max_x - p->bed_min_x,
	    "depth", p->bed_max_y - p->bed_min_y, "min_x", p->bed_min_x, "min_y", p->bed_min_y,
	    "max_x", p->bed_max_x, "max_y", p->bed_max_y, "max_print_height", p->max_print_height,
	    "extruders", p->extruder_count, "nozzle_diameter", nozzles, "filament_diameter",
	    p->filament_diameter[0], "baudrate", (int)p->baudrate, "usb_ids", usb, "path", p->path);
	/* "o" steals both arrays, also on failure. */
	return o;

out_free:
	json_decref(nozzles);
	json_decref(usb);
	return NULL;
}

/* Print the table of loaded profiles. */
static void print_table(struct profile **ps, size_t n)
{
	const char *head[7] = {"NAME",	 "MODEL",  "PROTOCOL", "BED (mm)",
			       "HEIGHT", "NOZZLE", "EXTRUDERS"};
	int w[7];
	char cell[7][128];

	for (int c = 0; c < 7; c++)
		w[c] = (int)strlen(head[c]);
	for (int pass = 0; pass < 2; pass++) {
		if (pass == 1) {
			for (int c = 0; c < 7; c++)
				printf("%-*s%s", c < 6 ? w[c] : 0, head[c], c < 6 ? "  " : "\n");
		}
		for (size_t i = 0; i < n; i++) {
			const struct profile *p = ps[i];

			snprintf(cell[0], sizeof(cell[0]), "%s", p->id);
			snprintf(cell[1], sizeof(cell[1]), "%s", p->name);
			snprintf(cell[2], sizeof(cell[2]), "%s",
				 profile_protocol_name(p->protocol));
			snprintf(cell[3], sizeof(cell[3]), "%g x %g", p->bed_max_x - p->bed_min_x,
				 p->bed_max_y - p->bed_min_y);
			snprintf(cell[4], sizeof(cell[4]), "%g", p->max_print_height);
			nozzle_text(p, cell[5], sizeof(cell[5]));
			snprintf(cell[6], sizeof(cell[6]), "%d", p->extruder_count);
			for (int c = 0; c < 7; c++) {
				/* One-line cells: a name may hold a decoded "\n". */
				for (char *s = cell[c]; *s; s++)
					if (*s == '\n' || *s == '\r' || *s == '\t')
						*s = ' ';
				if (pass == 0 && (int)strlen(cell[c]) > w[c])
					w[c] = (int)strlen(cell[c]);
				if (pass == 1)
					printf("%-*s%s", c < 6 ? w[c] : 0, cell[c],
					       c < 6 ? "  " : "\n");
			}
		}
	}
}

/* Make sure stdout reached its destination (a full disk, a closed pipe). */
static int finish_output(void)
{
	if (fflush(stdout) != 0 || ferror(stdout))
		return cmd_fail("stratum printers", ST_EXIT_FAILURE, "could not write the output");
	return ST_EXIT_OK;
}

/* Write o (stolen) as --json does; 0 or the exit status (message printed). */
static int json_out(json_t *o)
{
	if (!cmd_json_out(o, JSON_INDENT(2) | JSON_PRESERVE_ORDER | JSON_REAL_PRECISION(15)))
		return 0;
	fprintf(stderr, "stratum printers: out of memory building the JSON\n");
	return ST_EXIT_SOFTWARE;
}

/* `--show`: one profile's resolved settings (which NULL: the options' alone). */
static int show_one(const char *which, const struct cfgopt *cfg, bool json)
{
	struct profile *p;
	int rc = cfgopt_load(cfg, "stratum printers", which, &p);

	if (rc)
		return rc;
	rc = json ? json_out(profile_to_json(p)) : 0;
	if (!json)
		profile_write(p, stdout); /* a write error shows in finish_output() */
	profile_free(p);
	return rc ? rc : finish_output();
}

/* The listing: load every profile, report the broken ones, print the rest. */
static int list_all(bool json)
{
	struct st_error err = {0};
	struct profile_entry *list = NULL;
	struct profile **ps = NULL;
	size_t n = 0, good = 0;
	int status = ST_EXIT_OK;

	if (profile_list(&list, &n, &err))
		return cmd_fail("stratum printers", ST_EXIT_SOFTWARE, "%s", err.msg);
	if (n) {
		ps = calloc(n, sizeof(*ps));
		if (!ps) {
			status = cmd_fail("stratum printers", ST_EXIT_SOFTWARE, "out of memory");
			goto out_free_list;
		}
	}
	for (size_t i = 0; i < n; i++) {
		struct st_error lerr = {0};

		if (profile_load_file(list[i].path, &ps[good], &lerr))
			fprintf(stderr, "stratum printers: skipping %s: %s\n", list[i].id,
				lerr.msg);
		else
			good++;
	}
	if (n == 0) {
		struct profile_dirs dirs;

		profile_search_dirs(&dirs);
		fprintf(stderr, "stratum printers: no printer profiles found; looked in:\n");
		for (size_t i = 0; i < dirs.count; i++)
			fprintf(stderr, "  %s\n", dirs.path[i]);
	}
	if (json) {
		json_t *arr = json_array();

		for (size_t i = 0; arr && i < good; i++)
			if (json_array_append_new(arr, summary_json(ps[i]))) {
				json_decref(arr);
				arr = NULL;
			}
		status = json_out(arr);
	} else if (good) {
		print_table(ps, good);
	}
	if (!status)
		status = finish_output();
	for (size_t i = 0; i < good; i++)
		profile_free(ps[i]);
	free(ps);
out_free_list:
	profile_list_free(list, n);
	return status;
}

/* Parse the options and run the listing or --show. */
int cmd_printers(int argc, char **argv)
{
	static struct cfgopt cfg; /* large; one per process */
	const char *show = NULL, *showing = NULL;
	bool json = false, keys = false;
	const struct cmd_opt opts[] = {
	    CMD_OPT_FLAG("--keys", &keys,
			 "every key a profile takes: the tables of docs/printers.md"),
	    CMD_OPT_FLAG("--json", &json, "a JSON array (or, with --show, one object) on stdout"),
	    {"--printer", 0, CMD_STRING, &show, CMD_OPTIONAL, 0, 0, NULL, "PRINTER",
	     "the same as --show", NULL, &showing},
	    {"--show", 0, CMD_STRING, &show, CMD_OPTIONAL, 0, 0, NULL, "PRINTER",
	     "print every resolved setting of one profile, defaults\n"
	     "included, as a profile file; with the settings options\n"
	     "of 'stratum slice', as they resolve it:", NULL, &showing},
	};
	const struct cmd_spec spec = {.cmd = "stratum printers", .head = printers_head,
				      CMD_TABLE(opts),
				      .col = 21, .cfg = &cfg, .tail = printers_tail};
	int rc;

	memset(&cfg, 0, sizeof(cfg));
	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (keys) /* docs/printers.md's key tables, from the one declaration */
		return settings_write_doc(stdout) || fflush(stdout) == EOF ? ST_EXIT_SOFTWARE
									  : ST_EXIT_OK;
	if ((cfg.n || cfg.presets.printer) && !showing)
		return cmd_fail("stratum printers", ST_EXIT_USAGE,
				"the settings options go with --show");
	if (showing && !show && !cfg.has_files)
		return cmd_fail("stratum printers", ST_EXIT_USAGE,
				"--show needs a printer name or file, or --load FILE");
	return showing ? show_one(show, &cfg, json) : list_all(json);
}

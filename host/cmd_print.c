/*
 * cmd_print.c - `stratum print MODEL... [--printer NAME] [--port ...]`: one
 * command from models to printed parts (docs/printing.md).  Stages:
 * repair and slice (host/slicejob.c, the same path as `stratum slice`),
 * optional layer previews, then streaming through serial/printer.h, one
 * path whatever the printer's dialect.
 * G-code and X3G input skip the first stages.
 *
 * With no --port (or --port sim) the printer is the built-in simulated one
 * of the profile's dialect, run in this process and sped up.  G-code jobs
 * keep a journal (host/journal.h) synced per layer and every few seconds,
 * so `--resume JOB` can continue after a crash, a power cut or a lost
 * printer.  Ctrl-C/SIGTERM stop safely and exit 130; a lost printer exits
 * 69 with the last confirmed line and layer; a firmware error exits 1.
 */
#include <errno.h>
#include <fcntl.h>
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "clio.h"
#include "commands.h"
#include "gcode.h"
#include "guard.h"
#include "jobs.h"
#include "print_job.h"
#include "preview.h"
#include "profile.h"
#include "profile_slicer.h"
#include "resume.h"
#include "pvdraw.h"
#include "send.h"
#include "slicejob.h"
#include "st_error.h"

#define PRINT_PREVIEW_LAYERS 3	 /* --preview: the first layers drawn */

/* Parse argv; 0 to go on, -1 after --help, else the exit status. */
static int print_parse(int argc, char **argv, struct print_args *a)
{
	const struct cmd_opt opts[] = {
	    CMD_OPT_PRINTER_NAME(&a->printer),
	    CMD_OPT_PORT_OR_SIM(&a->port),
	    CMD_OPT_SPEEDUP(&a->speedup),
	    {"--dry-run", 0, CMD_FLAG, &a->dry_run, 0, 0, 0, NULL, "-o OUT",
	     "write the G-code (X3G for Sailfish printers unless OUT\n"
	     "ends in .gcode) instead of printing", NULL, NULL},
	    CMD_OPT_STRING("--output", 'o', &a->out, 0, NULL, "OUT",
			   "where --dry-run writes"),
	    CMD_OPT_FLAG("--preview", &a->preview,
			 "write PNGs of the first layers (MODEL-layerN.png) first;\n"
			 "without --port only them (the print needs --yes);\n"
			 "with --dry-run of the G-code written"),
	    CMD_OPT_FLAG("--json", &a->json, "the summary as one JSON object on stdout"),
	    CMD_OPT_STRING("--resume", 0, &a->resume, 0, NULL, "JOB",
			   "continue an interrupted print (G-code, Marlin or Sailfish)\n"
			   "from the start of the last layer the printer confirmed:\n"
			   "reheat, home X and Y only,\n"
			   "restore Z and E.  Asks first; --yes answers for scripts"),
	    {"--yes", 'y', CMD_FLAG, &a->yes, 0, 0, 0, NULL, NULL,
	     "answer yes to --resume's question; with --preview and no\n"
	     "--port: print on the simulator after the preview", NULL, NULL},
	    CMD_OPT_FLAG("--force", &a->force, GUARD_FORCE_HELP),
	    CMD_OPT_SIM_LOG(&a->sim_log),
	};
	const struct cmd_spec spec = {
	    .cmd = PRINT_CMD, CMD_TABLE(opts), .col = 21,
	    .head =
		"usage: stratum print MODEL... --printer NAME [--port PATH|auto|tcp://HOST:PORT|sim]\n"
		"                     [--dry-run -o OUT] [--preview] [--json] [--speedup K]\n"
		"                     [--force] [--load FILE.ini ...] [--set KEY=VALUE ...]\n"
		"       stratum print --resume JOB [--yes] [--port ...] [--json]\n"
		"\n"
		"Repairs and slices MODEL (STL, OBJ, OFF or 3MF) as 'stratum slice' does, then\n"
		"prints it; several models are arranged on the bed and printed together, as\n"
		"'stratum slice' arranges them.  A .gcode file (or .x3g for Sailfish printers)\n"
		"is printed as it is, alone.  MODEL '-' reads a model from stdin.\n",
	    .mid = "Settings for slicing MODEL (on top of --printer, or instead of it), as\n"
		   "'stratum slice' takes them:\n",
	    .cfg = &a->cfg,
	    .tail = "Ctrl-C stops safely (heaters and motors off).  Exit status: 0 printed, 1 the\n"
		    "job failed (firmware error, not repaired, resume declined), 2 usage or G-code\n"
		    "sliced for another printer, 65 bad input, 69 printer unavailable or lost,\n"
		    "70 internal error, 130 interrupted.\n",
	    .pos = a->models, .npos = SLICEJOB_MODELS_MAX, .ngot = &a->nmodels,
	    .extra = "more than %d models at once ('%s')"};
	int rc;

	memset(a, 0, sizeof(*a));
	a->speedup = CMD_SIM_SPEEDUP;
	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc;
	a->in = a->models[0];
	if (a->resume && (a->in || a->dry_run || a->cfg.n || a->cfg.presets.printer))
		return cmd_fail(PRINT_CMD, ST_EXIT_USAGE,
				"--resume JOB takes no model, no --dry-run and no settings "
				"options: the job journal names the file");
	if (!a->resume && (!a->in || (!a->printer && !a->cfg.has_files)))
		return cmd_refuse(
		    &spec, "%s",
		    !a->in ? "no model file given"
			   : "no printer given; add --printer NAME ('stratum printers' lists "
			     "them)");
	if (a->dry_run != (a->out != NULL))
		return cmd_fail(PRINT_CMD, ST_EXIT_USAGE, "%s",
				a->dry_run ? "--dry-run needs -o OUT"
					   : "-o OUT goes with --dry-run");
	return 0;
}

static enum print_input print_input_of(const char *path)
{
	if (cmd_has_ext(path, ".x3g"))
		return PRINT_X3G;
	if (cmd_has_ext(path, ".gcode") || cmd_has_ext(path, ".gco") || cmd_has_ext(path, ".g"))
		return PRINT_GCODE;
	return PRINT_MODEL;
}

/* -------- stages -------- */

/* Slice the model into job->gcode (or OUT); 0 or the exit status. */
static int print_slice(struct print_job *job, const char *out)
{
	struct slicer_config cfg;
	struct st_error err = {0};
	int rc = profile_slicer_config(job->prof, &cfg, &err);

	if (rc)
		return cmd_fail(PRINT_CMD, profile_exit_status(rc), "%s", err.msg);
	if ((rc = slicer_config_check(&cfg, &err)))
		return cmd_fail(PRINT_CMD, ST_EXIT_DATAERR, "%s", err.msg);
	rc = slicejob_run(PRINT_CMD, job->a->models, job->a->nmodels, &cfg, false, out, true,
			  &job->slice);
	job->sliced = rc == 0;
	return rc;
}

/* --preview: the first layers as MODEL-layerN.png; 0 or the exit status. */
static int print_preview(struct print_job *job)
{
	const char *in = clio_is_std(job->a->in) ? "stdin" : job->a->in;
	const char *base = strrchr(in, '/');
	const char *dot;
	char name[PATH_MAX];
	int n;

	base = base ? base + 1 : in;
	dot = strrchr(base, '.');
	n = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
	for (int l = 1; l <= PRINT_PREVIEW_LAYERS && (size_t)l <= job->layers.n; l++) {
		struct preview_opts o;
		struct pvdraw_opts d = {.width_px = PVDRAW_WIDTH_DEFAULT, .title = base};
		struct preview *pv = NULL;
		struct st_error err = {0};

		preview_opts_init(&o);
		o.layer = l;
		snprintf(name, sizeof(name), "%.*s-layer%d.png", n, base, l);
		if (preview_load(job->gcode, &o, &pv, &err) || pvdraw_write(pv, &d, name, &err)) {
			preview_free(pv);
			return cmd_fail(PRINT_CMD, ST_EXIT_FAILURE, "preview of layer %d: %s", l,
					err.msg);
		}
		preview_free(pv);
		if (!job->a->json)
			fprintf(stderr, PRINT_CMD ": preview: %s\n", name);
	}
	return 0;
}

/* --preview without --port or --yes: say what was drawn, that nothing was
 * printed, and how to print. */
static void print_preview_stop(const struct print_job *job)
{
	size_t n = job->layers.n < PRINT_PREVIEW_LAYERS ? job->layers.n : PRINT_PREVIEW_LAYERS;

	if (job->a->json) {
		json_t *o = json_object();
		cmd_json_set(o, "b:ok", true, "i:exit", 0, "s:input", job->a->in, "s:printer",
			     job->prof->id, "b:printed", false, "z:previews", n, NULL);
		send_report_emit(o);
		return;
	}
	printf("preview: %zu layer%s of %s drawn; nothing was printed (add --yes to print on the "
	       "simulated printer, or --port to print on a real one)\n", n, n == 1 ? "" : "s",
	       job->a->in);
}

/* Ask before a resume (or take --yes); true to go on.  It shows what the
 * preamble will set (resume_locate), not the temperatures last reported. */
static bool print_confirm(const struct print_job *job)
{
	char line[16] = "";
	const struct print_layer *L = &job->layers.v[job->start_layer];
	struct resume_state rs;
	struct st_error err = {0};

	if (resume_locate(job->gcode, L->offset, job->saved, &rs, &err)) {
		fprintf(stderr, PRINT_CMD ": job %s: %s\n", job->j.id, err.msg);
		return false;
	}
	fprintf(stderr, PRINT_CMD ": resume job %s: %s on %s, from layer %ld of %zu (Z %.2f mm, "
			"line %llu); the printer heats the bed to %.0f and the nozzle to %.0f degC, "
			"takes the nozzle's Z as %.3f mm (its last move), homes X and Y only, and "
			"goes on with the remaining layers.\n",
		job->j.id, job->gcode, job->prof->id, job->start_layer + 1, job->layers.n, L->z,
		(unsigned long long)L->line, rs.bed, rs.tool, rs.z_nozzle);
	if (job->a->yes)
		return true;
	fprintf(stderr, "Is the part still on the bed, untouched?  Continue? [y/N] ");
	fflush(stderr);
	if (!fgets(line, sizeof(line), stdin)) {
		fprintf(stderr, "\n" PRINT_CMD ": no answer on stdin; add --yes to resume without "
				"asking\n");
		return false;
	}
	return line[0] == 'y' || line[0] == 'Y';
}

/* Set up a resume from the journal; 0 or the exit status. */
static int print_setup_resume(struct print_job *job)
{
	struct st_error err = {0};
	char hex[65];
	int rc;

	if ((rc = journal_load(job->a->resume, &job->j, &err)))
		return cmd_fail(PRINT_CMD, rc == ST_ERR_PARSE ? ST_EXIT_DATAERR : ST_EXIT_USAGE,
				"%s", err.msg);
	if (!strcmp(job->j.state, "done"))
		return cmd_fail(PRINT_CMD, ST_EXIT_USAGE,
				"job %s finished printing; there is nothing to resume", job->j.id);
	if ((rc = journal_sha256(job->j.gcode, hex, &err)))
		return cmd_fail(PRINT_CMD, ST_EXIT_DATAERR, "job %s: %s", job->j.id, err.msg);
	if (strcmp(hex, job->j.sha256))
		return cmd_fail(PRINT_CMD, ST_EXIT_DATAERR,
				"job %s: %s changed since the print started (SHA-256 %.12s..., the "
				"journal has %.12s...); refusing to resume with another file",
				job->j.id, job->j.gcode, hex, job->j.sha256);
	snprintf(job->gcode_buf, sizeof(job->gcode_buf), "%s", job->j.gcode);
	job->gcode = job->gcode_buf;
	if (!job->a->printer)
		job->a->printer = job->j.printer;
	if (!job->a->port)
		job->a->port = job->j.port;
	job->input = PRINT_GCODE;
	return 0;
}

/* A figure of seconds as "1h 02m 03s" or "4.2 s". */
static void print_duration(char *out, size_t cap, double s)
{
	long t = lround(s);

	if (s < 60)
		snprintf(out, cap, "%.1f s", s);
	else
		snprintf(out, cap, "%ldh %02ldm %02lds", t / 3600, t / 60 % 60, t % 60);
}

static void print_summary_text(const struct print_job *job)
{
	char est[32], took[32], sim[32];
	const struct slicer_summary *s = &job->slice.sum;

	printf("%s %s on %s: %s\n", job->status == 0 ? "printed" : "stopped",
	       job->a->in ? job->a->in : job->gcode, job->prof->id,
	       job->printer_desc[0] ? job->printer_desc : job->port ? job->port : "");
	if (job->sliced && job->slice.repaired)
		printf("  repair: %zu triangles in, %zu out, %zu part%s, %llu intersecting pairs "
		       "resolved\n", job->slice.input_triangles, job->slice.rep.output_triangles,
		       job->slice.rep.components, job->slice.rep.components == 1 ? "" : "s",
		       (unsigned long long)job->slice.rep.intersecting_pairs);
	if (job->sliced && job->slice.nmodels > 1) {
		printf("  models:");
		for (size_t i = 0; i < job->slice.nmodels; i++)
			printf(" %s", job->slice.models[i].path);
		printf(" (%s)\n", job->slice.arranged ? "arranged" : "kept as their 3MF files place them");
	}
	if (job->sliced)
		printf("  slice: %zu layers, filament %.1f mm (%.2f g)\n", s->layers, s->filament_mm,
		       s->filament_g);
	if (job->start_layer >= 0)
		printf("  resumed job %s from layer %ld of %zu\n", job->j.id, job->start_layer + 1,
		       job->layers.n);
	if (job->input == PRINT_X3G)
		printf("  streamed: %llu of %llu commands (%llu resends)\n",
		       (unsigned long long)job->done, (unsigned long long)job->total,
		       (unsigned long long)job->resends);
	else
		printf("  streamed: line %llu of %llu confirmed, layer %ld of %zu (%llu resends)\n",
		       (unsigned long long)job->last_line, (unsigned long long)job->layers.lines,
		       job->layer + 1, job->layers.n, (unsigned long long)job->resends);
	print_duration(took, sizeof(took), job->stream_s);
	if (job->sliced) {
		print_duration(est, sizeof(est), s->time_s);
		printf("  time: estimated %s (heating excluded), took %s", est, took);
	} else {
		printf("  time: took %s", took);
	}
	if (job->simulated && isfinite(job->machine_s)) {
		print_duration(sim, sizeof(sim), job->machine_s);
		printf("; the simulated printer's clock ran %s", sim);
	}
	printf("\n");
	if (job->journal_saved)
		printf("  journal: %s\n", job->j.file);
	if (job->fail)
		printf("  stopped: %s\n", job->fail);
}

static void print_summary_json(const struct print_job *job)
{
	json_t *o = json_object();
	const struct slicer_summary *s = &job->slice.sum;

	if (!o)
		return;
	cmd_json_set(o, "b:ok", job->status == 0, "i:exit", job->status,
		     "s:input", job->a->in ? job->a->in : job->gcode, "s:gcode", job->gcode,
		     "s:printer", job->prof->id, "s:port", job->port ? job->port : "",
		     "s:firmware", job->printer_desc, "b:simulated", job->simulated, NULL);
	if (job->simulated)
		cmd_json_set(o, "f:speedup", job->a->speedup, NULL);
	if (job->simulated && isfinite(job->machine_s))
		cmd_json_set(o, "f:printer_s", job->machine_s, NULL);
	if (job->sliced && job->slice.repaired) {
		json_t *r = json_object();
		cmd_json_set(r, "z:input_triangles", job->slice.input_triangles,
			     "z:output_triangles", job->slice.rep.output_triangles,
			     "z:components", job->slice.rep.components,
			     "I:intersecting_pairs", (json_int_t)job->slice.rep.intersecting_pairs, NULL);
		json_object_set_new(o, "repair", r);
	}
	if (job->sliced) {
		json_t *models = json_array();
		for (size_t i = 0; i < job->slice.nmodels; i++)
			json_array_append_new(models, json_string(job->slice.models[i].path));
		json_object_set_new(o, "models", models);
	}
	cmd_json_set(o, "z:layers", job->sliced ? s->layers : job->layers.n, NULL);
	if (job->sliced)
		cmd_json_set(o, "f:filament_mm", s->filament_mm, "f:filament_g", s->filament_g,
			     "f:estimated_s", s->time_s, NULL);
	cmd_json_set(o, "s:unit", job->input == PRINT_X3G ? "commands" : "lines",
		     "I:done", (json_int_t)job->done, "I:total", (json_int_t)job->total,
		     "I:last_line", (json_int_t)job->last_line, "I:layer", (json_int_t)(job->layer + 1),
		     "I:resends", (json_int_t)job->resends, "f:seconds", job->stream_s, NULL);
	if (job->start_layer >= 0)
		cmd_json_set(o, "I:resumed_from_layer", (json_int_t)(job->start_layer + 1), NULL);
	if (job->journal_saved)
		cmd_json_set(o, "s:job", job->j.id, "s:journal", job->j.file, NULL);
	if (job->fail)
		cmd_json_set(o, "s:error", job->fail, NULL);
	send_report_emit(o);
}

/* --dry-run: G-code (or X3G) into OUT; 0 or the exit status. */
static int print_dry_run(struct print_job *job)
{
	const char *out = job->a->out;
	bool sailfish = job->prof->protocol == PROFILE_PROTOCOL_SAILFISH;
	bool x3g = sailfish && !cmd_has_ext(out, ".gcode");
	int status;

	if (job->input != PRINT_MODEL && !(x3g && job->input == PRINT_GCODE))
		return cmd_fail(PRINT_CMD, ST_EXIT_USAGE,
				"--dry-run: %s is already what would be printed", job->a->in);
	if (job->input == PRINT_MODEL) {
		if (x3g) {
			struct st_error err = {0};
			char dir[JOURNAL_PATH_MAX - 64];
			if (journal_dir(dir, sizeof(dir), &err))
				return cmd_fail(PRINT_CMD, ST_EXIT_FAILURE, "%s", err.msg);
			snprintf(job->gcode_buf, sizeof(job->gcode_buf), "%s/dry-run-%ld.gcode", dir,
				 (long)getpid());
		} else {
			snprintf(job->gcode_buf, sizeof(job->gcode_buf), "%s", out);
		}
		job->gcode = job->gcode_buf;
		if ((status = print_slice(job, job->gcode)))
			return status;
	}
	/* --preview draws what was written (the G-code the X3G comes from) */
	if (job->a->preview && ((status = print_scan(job->gcode, &job->layers)) ||
				(status = print_preview(job)))) {
		if (x3g && job->input == PRINT_MODEL)
			unlink(job->gcode);
		return status;
	}
	if (x3g) {
		/* the guard has judged the file already (cmd_print) */
		char *argv[] = {"x3g", (char *)job->gcode, "-o", (char *)out, "--printer",
				(char *)job->prof->path, job->a->force ? "--force" : NULL, NULL};
		int saved = -1;
		fflush(stdout);
		if (job->a->json) /* one JSON object on stdout: ours */
			saved = dup(STDOUT_FILENO), freopen("/dev/null", "w", stdout);
		status = cmd_x3g(job->a->force ? 7 : 6, argv);
		if (saved >= 0) {
			fflush(stdout);
			dup2(saved, STDOUT_FILENO);
			close(saved);
		}
		if (job->input == PRINT_MODEL)
			unlink(job->gcode);
		if (status)
			return status;
	}
	if (job->a->json) {
		json_t *o = json_object();
		cmd_json_set(o, "o:ok", json_true(), "s:input", job->a->in, "s:printer", job->prof->id,
			     "s:output", out, "s:format", x3g ? "x3g" : "gcode", NULL);
		if (job->sliced)
			cmd_json_set(o, "z:layers", job->slice.sum.layers,
				     "f:filament_mm", job->slice.sum.filament_mm,
				     "f:estimated_s", job->slice.sum.time_s, NULL);
		send_report_emit(o);
	} else {
		printf("dry run: %s for %s written to %s", x3g ? "X3G" : "G-code", job->prof->id,
		       out);
		if (job->sliced)
			printf(" (%zu layers, filament %.1f mm)", job->slice.sum.layers,
			       job->slice.sum.filament_mm);
		printf("; nothing was printed\n");
	}
	return 0;
}

/*
 * A model "-" is read from stdin (clio.h); a.in keeps "-" for the reports.
 * G-code on stdin is refused: a print journals its file so that it can be
 * resumed, and a spool removed at the end could not be.  0 or the exit status.
 */
static int print_stdin(struct print_args *a, struct clio *io)
{
	for (size_t i = 0; i < a->nmodels; i++) {
		char head[64] = "";
		size_t k = 0;
		FILE *f;
		int status;

		if (!clio_is_std(a->models[i]))
			continue;
		if ((status = clio_input(io, &a->models[i], "")))
			return status;
		if ((f = fopen(a->models[i], "rb")) != NULL) {
			head[fread(head, 1, sizeof(head) - 1, f)] = '\0';
			fclose(f);
		}
		while (head[k] == ' ' || head[k] == '\t' || head[k] == '\r' || head[k] == '\n')
			k++;
		/* a comment or a command word ("G1", "M104"); a binary STL's header
		 * may start with any text ("MeshLab"), not with these */
		if (head[k] == ';' || (head[k] && strchr("GMTN", head[k]) && head[k + 1] >= '0' &&
				       head[k + 1] <= '9'))
			return cmd_fail(PRINT_CMD, ST_EXIT_USAGE,
					"stdin holds G-code; print it from a file, so that the job "
					"can be resumed ('-' takes a model)");
	}
	return 0;
}

/* The print; *answered is set when the JSON summary went out. */
static int print_run(int argc, char **argv, bool *answered, struct clio *io)
{
	struct print_args a;
	struct print_job *job;
	struct st_error err = {0};
	bool preview_only;
	int status, rc;

	status = print_parse(argc, argv, &a);
	if (status)
		return status < 0 ? ST_EXIT_OK : status;
	if ((status = print_stdin(&a, io)))
		return status;
	job = calloc(1, sizeof(*job));
	if (!job)
		return cmd_fail(PRINT_CMD, ST_EXIT_SOFTWARE, "out of memory");
	job->a = &a;
	job->start_layer = -1;
	job->layer = -1;
	job->machine_s = NAN;
	if (a.resume && (status = print_setup_resume(job)))
		goto out;
	if ((status = cfgopt_load(&a.cfg, PRINT_CMD, a.printer, &job->prof)))
		goto out;
	if (a.cfg.n || a.cfg.presets.printer)
		cfgopt_warn_unsupported(job->prof, PRINT_CMD);
	if (!a.resume) {
		job->input = print_input_of(a.in);
		job->gcode = a.in;
		for (size_t i = 0; i < a.nmodels && a.nmodels > 1; i++)
			if (print_input_of(a.models[i]) != PRINT_MODEL) {
				status = cmd_fail(PRINT_CMD, ST_EXIT_USAGE,
						  "%s is already G-code or X3G: only models are "
						  "printed together; print it alone",
						  a.models[i]);
				goto out;
			}
		if (job->input == PRINT_MODEL)
			cfgopt_note_project_settings(&a.cfg, PRINT_CMD, a.models, a.nmodels);
	}
	if (job->input == PRINT_X3G && job->prof->protocol != PROFILE_PROTOCOL_SAILFISH) {
		status = cmd_fail(PRINT_CMD, ST_EXIT_USAGE,
				  "%s is X3G, which only Sailfish printers take; printer '%s' "
				  "speaks %s: print the model or its G-code",
				  a.in, job->prof->id, profile_protocol_name(job->prof->protocol));
		goto out;
	}
	if (job->input == PRINT_GCODE &&
	    (status = guard_cli(PRINT_CMD, job->gcode, job->prof, a.force)))
		goto out;
	if (a.dry_run) {
		status = print_dry_run(job);
		*answered = a.json && status == 0;
		goto out;
	}
	/* --preview alone on the simulator is a look, not a print: the PNGs,
	 * then stop; --yes or a --port goes on to print */
	preview_only = a.preview && !a.port && !a.yes && !a.resume && job->input != PRINT_X3G;
	/* an X3G file has no G-code lines to resume from; a look keeps no job */
	job->journal_on = job->input != PRINT_X3G && !preview_only;
	if (!a.resume && job->journal_on) { /* the jobs kept stay under their cap (jobs.h) */
		uint64_t freed;
		long n = jobs_trim(&freed, &err);
		if (n > 0)
			fprintf(stderr, PRINT_CMD ": removed %ld old job%s (%.1f MB) to keep the jobs "
					"directory under its cap ('stratum jobs list')\n", n,
				n == 1 ? "" : "s", (double)freed / 1e6);
	}
	if (!a.resume && job->journal_on && (rc = journal_init(&job->j, &err))) {
		status = cmd_fail(PRINT_CMD, ST_EXIT_FAILURE, "%s", err.msg);
		goto out;
	}
	if (job->input == PRINT_MODEL) {
		char dir[JOURNAL_PATH_MAX - 64];
		if (!job->journal_on && (rc = journal_dir(dir, sizeof(dir), &err))) {
			status = cmd_fail(PRINT_CMD, ST_EXIT_FAILURE, "%s", err.msg);
			goto out;
		}
		/* the sliced G-code is kept beside the journal so the job can resume */
		if (job->journal_on)
			snprintf(job->gcode_buf, sizeof(job->gcode_buf), "%.*s.gcode",
				 (int)(strlen(job->j.file) - 5), job->j.file);
		else
			snprintf(job->gcode_buf, sizeof(job->gcode_buf), "%s/print-%ld.gcode", dir,
				 (long)getpid());
		job->gcode = job->gcode_buf;
		if ((status = print_slice(job, job->gcode)))
			goto out;
	}
	if (job->input != PRINT_X3G &&
	    (status = print_scan(job->gcode, &job->layers)))
		goto out;
	if (a.resume) {
		job->start_layer = job->j.layer >= 0 && (size_t)job->j.layer < job->layers.n
					   ? job->j.layer : 0;
		if (!job->layers.n) {
			status = cmd_fail(PRINT_CMD, ST_EXIT_DATAERR,
					  "%s has no layer comments; cannot tell where to resume",
					  job->gcode);
			goto out;
		}
		if ((status = print_byte_after(job->gcode, job->j.last_line, &job->saved)))
			goto out;
		if (!print_confirm(job)) {
			status = cmd_fail(PRINT_CMD, ST_EXIT_FAILURE, "not resumed");
			goto out;
		}
		snprintf(job->j.state, sizeof(job->j.state), "printing");
	} else if (job->journal_on) {
		char path[PATH_MAX];
		if (!realpath(job->gcode, path) || journal_sha256(path, job->j.sha256, &err)) {
			status = cmd_fail(PRINT_CMD, ST_EXIT_DATAERR, "%s: %s", job->gcode,
					  err.msg[0] ? err.msg : strerror(errno));
			goto out;
		}
		snprintf(job->j.gcode, sizeof(job->j.gcode), "%s", path);
		snprintf(job->j.printer, sizeof(job->j.printer), "%s", job->prof->path);
		job->j.lines = job->layers.lines;
	}
	if (a.preview && job->input != PRINT_X3G && (status = print_preview(job)))
		goto out_gcode;
	if (preview_only) {
		print_preview_stop(job);
		*answered = a.json;
		goto out_gcode;
	}
	status = print_stream(job);
	job->status = status;
	if (a.json)
		print_summary_json(job), *answered = true;
	else
		print_summary_text(job);
out_gcode:
	if (job->sliced && !job->journal_on)
		unlink(job->gcode);
out:
	slicejob_result_free(&job->slice);
	free(job->port_auto);
	free(job->layers.v);
	profile_free(job->prof);
	free(job);
	return status;
}

/*
 * --json answers with one object whatever happens: a command line refused,
 * a bad profile or an unreadable model end before the summary, so their
 * message on stderr is kept (clio_capture_begin) and becomes "error".
 */
int cmd_print(int argc, char **argv)
{
	bool json = false, answered = false;
	struct clio io;
	char msg[512];
	int status;

	clio_init(&io, PRINT_CMD);
	for (int i = 1; i < argc; i++)
		json = json || !strcmp(argv[i], "--json");
	if (!json)
		return clio_finish(&io, print_run(argc, argv, &answered, &io));
	clio_capture_begin();
	status = clio_finish(&io, print_run(argc, argv, &answered, &io));
	clio_capture_end(msg, sizeof(msg));
	if (status && !answered) {
		json_t *o = json_object();
		cmd_json_set(o, "b:ok", false, "i:exit", status, "s:error",
			     msg[0] ? msg : "the print did not start; the reason is on stderr", NULL);
		send_report_emit(o);
	}
	return status;
}

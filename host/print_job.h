/*
 * print_job.h - what the stages of `stratum print` share (host/ only):
 * the options, the job, and the G-code's layer table.  host/cmd_print.c
 * runs the stages and reports; host/print_stream.c streams the job
 * through serial/printer.h with the journal kept (host/journal.h).
 */
#ifndef STRATUM_HOST_PRINT_JOB_H
#define STRATUM_HOST_PRINT_JOB_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "cfgopt.h"
#include "journal.h"
#include "profile.h"
#include "slicejob.h"

#define PRINT_CMD "stratum print"

struct print_args {
	const char *in;	/* the file printed, or the first of the models */
	const char *models[SLICEJOB_MODELS_MAX]; /* every model file given, models[0] = in */
	size_t nmodels;
	const char *printer, *port, *out, *resume, *sim_log;
	bool dry_run, json, yes, preview;
	bool force; /* --force: past the wrong-printer guard (guard.h) */
	double speedup;
	struct cfgopt cfg; /* --load, --set, --KEY-NAME ... (cfgopt.h) */
};

/* What the input file is, from its name. */
enum print_input { PRINT_MODEL, PRINT_GCODE, PRINT_X3G };

/* Where each layer of a G-code file starts, as the driver counts layers. */
struct print_layer {
	uint64_t line;	 /* file line of its layer comment */
	int64_t offset;	 /* byte offset of that line */
	double z;	 /* mm, NAN unknown */
	double est;	 /* estimated seconds of printing before it (print_estimate) */
};

struct print_layers {
	struct print_layer *v;
	size_t n, cap;
	uint64_t lines, commands; /* in the file */
	double est_total;	  /* estimated seconds of printing, 0 unknown */
};

/* Everything one print holds, for the stages and the summary. */
struct print_job {
	struct print_args *a;
	struct profile *prof;
	enum print_input input;
	const char *gcode;	   /* the G-code printed (or the X3G file) */
	char gcode_buf[JOURNAL_PATH_MAX];
	bool sliced;
	struct slicejob_result slice;
	struct print_layers layers;
	struct journal j;
	bool journal_on;	   /* G-code input: the journal is kept */
	bool journal_saved;	   /* it was written at least once (the summary names it) */
	bool simulated;
	const char *port;	   /* the port opened */
	char *port_auto;	   /* --port auto's choice (free) */
	char printer_desc[96];	   /* "Marlin 2.1.2 (simulated printer)" */
	/* the streaming stage */
	long start_layer;	   /* resume: the layer it starts at, else -1 */
	int64_t saved;		   /* resume: byte just past the journal's last confirmed
				    * line, where the nozzle stands (printer_job.saved) */
	uint64_t done, total;	   /* lines (Marlin) or commands (Sailfish) */
	uint64_t last_line;	   /* last file line the printer confirmed */
	long layer;		   /* its layer, -1 unknown */
	uint64_t resends;
	double stream_s;	   /* seconds of streaming */
	double machine_s;	   /* the simulator's clock over the stream, NAN real */
	const char *fail;	   /* why it stopped, NULL done */
	char fail_buf[300];
	int status;
};

/*
 * print_scan - read the G-code at path once: layer starts, line and
 * command counts into L (the printer's own check, printer_check, comes
 * before anything is sent).  Returns 0 or the exit status (message printed).
 */
int print_scan(const char *path, struct print_layers *L);

/*
 * print_estimate - fill L's estimate (est of each layer, est_total) from
 * the moves of the G-code at path, planned as the firmware plans them and
 * scaled to stated_s, the total the file states (0: none).  Leaves
 * est_total 0 when the file cannot be timed.  print_scan calls it.
 */
void print_estimate(const char *path, struct print_layers *L, double stated_s);

/* print_time_comment - seconds of a "; estimated printing time[ (normal
 * mode)] = 1d 2h 3m 4s" comment (c without the ';'), NAN for another. */
double print_time_comment(const char *c);

/* print_est_done - estimated seconds of printing done when the printer
 * has confirmed file line `line` of layer `layer` (0-based, -1 before the
 * first): the layers before it and its share of this one, by lines. */
double print_est_done(const struct print_layers *L, long layer, uint64_t line);

/*
 * print_byte_after - the byte offset just past file line `line` (1-based)
 * of the G-code at path, 0 for line 0, the file's size if it has fewer
 * lines.  Returns 0 or the exit status (message printed).
 */
int print_byte_after(const char *path, uint64_t line, int64_t *byte);

/*
 * print_stream - open the port the user asked for (or the simulator),
 * check, stream job->gcode with the journal kept, stop safely if need be.
 * Returns the exit status.
 */
int print_stream(struct print_job *job);

#endif /* STRATUM_HOST_PRINT_JOB_H */

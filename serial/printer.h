/*
 * printer.h - one connected printer, whatever its dialect
 * (docs/architecture.md "The printer interface").
 *
 * A table of operations per dialect (STYLE rule 13): printer_marlin.c
 * drives Marlin with the text protocol (marlin.h), printer_sailfish.c
 * drives Sailfish with S3G (s3g.h), G-code translated to X3G as it goes.
 * Each adapter opens a device path, a pty, tcp://HOST:PORT or, for port
 * "sim", its own simulated printer (serial/sim/) run in this process, sped
 * up.  A caller's test double implements the same table (the farm node's
 * `port = test-instant`).
 *
 * A print is: printer_check (the whole file, before anything is sent: a
 * bad file sends nothing), then printer_stream with hooks the adapter
 * calls as it goes: control (go, hold, cancel, stop), progress (line
 * or command, byte position, layer, Z, temperatures) and, where the
 * dialect can (takes_injected), an operator's lines and temperature
 * offsets.  A stream that ends
 * with the printer still answering but not done leaves it to the caller
 * to call printer_safe_stop (heaters and motors off).
 *
 * One thread drives a printer.  Library code: nothing is printed.
 */
#ifndef STRATUM_SERIAL_PRINTER_H
#define STRATUM_SERIAL_PRINTER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"
#include "x3g.h"

/* How a printer is reached; printer_options_init fills the defaults. */
struct printer_options {
	const char *name;	    /* for messages ("printer mk3s"); NULL: the port */
	const char *port;	    /* device, pty, tcp://HOST:PORT, or "sim" */
	long baud;		    /* bits/s; default 115200 */
	bool dtr_reset;		    /* opening a real serial port resets the board */
	unsigned rx_buffer;	    /* Marlin: firmware RX ring (bytes), 0 = unknown */
	unsigned bufsize;	    /* Marlin: firmware BUFSIZE (command slots), 0 = unknown */
	/* Marlin: the driver's time-outs (struct marlin_options); 0 = its default */
	int retry_ms, probe_ms, dead_ms;
	/* Optional traffic log: dir is "<" (from the printer) or ">" (to it). */
	void (*trace)(void *ctx, const char *dir, const char *line);
	void *trace_ctx;
	double sim_speedup;	    /* port "sim": time divisor; default 1000 */
	const char *sim_log;	    /* port "sim": execution log file, NULL none */
	struct x3g_machine machine; /* Sailfish: the machine G-code is translated for */
	struct x3g_options x3g;	    /* Sailfish: translator options (flavour) */
};

/* printer_options_init - defaults, no port. */
void printer_options_init(struct printer_options *o);

/* What control returns: the adapter's next step. */
enum printer_control {
	PRINTER_GO = 0,
	PRINTER_HOLD,	/* send nothing new until GO; the firmware runs out what it has */
	PRINTER_CANCEL, /* end the stream: PRINTER_END_CANCELLED */
	PRINTER_STOP,	/* end the stream: PRINTER_END_STOPPED (the job stays resumable) */
};

/* Where a stream stands; plain value. */
struct printer_progress {
	const char *unit;	 /* "line" (Marlin) or "command" (Sailfish) */
	uint64_t done, total;	 /* of unit, confirmed by the printer / in this run */
	uint64_t line;		 /* file line of the last confirmed command, 0 none */
	int64_t filepos;	 /* byte just past it; the job's offset before any */
	long layer;		 /* its layer (0-based, by layer comments), -1 unknown */
	double z;		 /* that layer's Z (mm), NAN unknown */
	bool tool, bed;		 /* the temperatures below were reported */
	double tool_actual, tool_target, bed_actual, bed_target; /* degC */
	bool tool1;		 /* a second extruder's were (Sailfish, two extruders) */
	double tool1_actual, tool1_target; /* degC */
	bool paused;		 /* holding, and the printer has run out what it had */
	uint64_t resends;	 /* lines or packets sent again */
	double seconds;		 /* since the stream started */
};

/* One stream: the file and the hooks. */
struct printer_job {
	const char *path;     /* G-code, or X3G (Sailfish, x3g set) */
	bool x3g;
	int64_t offset;	      /* byte the stream reads from */
	uint64_t first_line;  /* file lines before offset, so progress counts file lines */
	/* Continue an interrupted print at offset: the adapter first sends its
	 * resume preamble (resume.h) that restores heat and position as the
	 * file left them there.  saved: the byte just past the last command
	 * the printer executed, so where the nozzle stands (its Z is set
	 * there, resume_locate), and the position progress reports until a
	 * command of the file is confirmed (0 = offset). */
	bool resume;
	int64_t saved;
	uint64_t total;	      /* commands of the run (printer_check's), for progress */
	/* called about every 50 ms and before each command; NULL = always GO */
	enum printer_control (*control)(void *ctx);
	/* called about every 200 ms and at the end; may be NULL */
	void (*progress)(void *ctx, const struct printer_progress *p);
	/* called with control, going or holding, by adapters whose ops say
	 * takes_injected: a G-code line to send next, between two of the
	 * file's (an operator's command during a print), copied into line
	 * (cap bytes) and true; false when none.  A line that does not parse
	 * or fit the firmware is dropped.  NULL = none. */
	bool (*inject)(void *ctx, char *line, size_t cap);
	/* the operator's temperature offset (degC) for heater: a tool's
	 * number, or PRINTER_HEATER_BED; added to the S of the file's M104,
	 * M109, M140 and M190 above 0 (OctoPrint's offsets), by adapters whose
	 * ops say takes_injected.  Called at each such line.  NULL = none. */
	double (*temp_offset)(void *ctx, int heater);
	void *ctx;
};

#define PRINTER_HEATER_BED (-1) /* printer_job.temp_offset's heater for the bed */

/* What printer_check found. */
struct printer_file_info {
	uint64_t commands; /* commands to send from job.offset (preamble included) */
	uint64_t lines;	   /* G-code lines read */
	uint64_t warnings; /* translator warnings (Sailfish) */
};

/* Translator warnings found by printer_check, one call per line (Sailfish). */
typedef void (*printer_warn_fn)(void *ctx, const char *path, uint64_t line, const char *msg);

/* How a stream ended (printer_result.end). */
enum printer_end {
	PRINTER_END_DONE = 0,
	PRINTER_END_CANCELLED, /* control said CANCEL */
	PRINTER_END_STOPPED,   /* control said STOP */
	PRINTER_END_LINK_LOST, /* unplugged, reset, not answering: resumable */
	PRINTER_END_FAILED,    /* the firmware or its panel ended the job, or a bad line */
};

/* Counters of the link, for reports: name and value, adapter's own. */
struct printer_counter {
	const char *name; /* JSON key, e.g. "resend_requests" */
	double value;
	bool real;	  /* a rate or time, not a count */
};
#define PRINTER_COUNTERS_MAX 16

/* The end of a stream. */
struct printer_result {
	enum printer_end end;
	bool safe_stop;		/* the printer still answers: call printer_safe_stop */
	struct printer_progress last;
	uint64_t bytes_acked;	/* bytes of confirmed commands as sent */
	uint64_t bytes_written; /* every byte written */
	uint64_t errors, unknown_commands;
	struct printer_counter counters[PRINTER_COUNTERS_MAX];
	size_t ncounters;
	char detail[512];	/* the counters as text: lines, "\n  " between */
	/* port "sim": the time the simulated machine spent on the stream
	 * (its own clock: moves, waits, heating; not wall time x speed-up);
	 * NAN for a real printer */
	double machine_s;
};

/* The operations of one dialect (or a test double). */
struct printer_ops {
	const char *name;  /* "marlin", "sailfish" */
	bool can_resume;   /* a G-code print can continue from a layer (preamble) */
	bool takes_x3g;	   /* X3G files can be streamed (job.x3g) */
	/* a resume restarts at the start of the layer holding the saved
	 * position (resume_layer_start), not at the saved byte itself */
	bool resume_from_layer;
	/* the firmware answers in text lines (printer_command's reply, the
	 * trace); Sailfish answers in binary packets, so a host has nothing to
	 * print but what poll reads */
	bool text_replies;
	/* the stream sends job->inject's lines between the file's and applies
	 * job->temp_offset (Marlin: one more numbered line; Sailfish: the line
	 * translated by the stream's own translator, so with the file's
	 * position and modes, as S3G packets between the job's; G-code files
	 * only, not X3G).  Held, they go too, and going again the adapter
	 * first brings the head back where the file left it (resume_return). */
	bool takes_injected;
	int (*open)(const struct printer_options *o, void **state, struct st_error *err);
	void (*close)(void *state);
	int (*check)(const struct printer_options *o, const struct printer_job *job,
		     printer_warn_fn warn, void *warn_ctx, struct printer_file_info *info,
		     struct st_error *err);
	int (*stream)(void *state, const struct printer_job *job, struct printer_result *res,
		      struct st_error *err);
	int (*command)(void *state, const char *line, char *reply, size_t cap,
		       struct st_error *err);
	int (*poll)(void *state, struct printer_progress *temps, struct st_error *err);
	int (*safe_stop)(void *state, struct st_error *err);
	void (*describe)(void *state, char *out, size_t cap);
};

extern const struct printer_ops printer_marlin_ops;
extern const struct printer_ops printer_sailfish_ops;

/* Opaque: one open printer. */
struct printer;

struct marlin;
/* printer_marlin_driver - the Marlin driver under p (marlin.h: its status
 * and counters, for tests), NULL when p is not a Marlin printer. */
struct marlin *printer_marlin_driver(const struct printer *p);

/*
 * printer_open - open the printer o describes with ops (the options are
 * copied; the strings and machine must outlive the printer).  Connects:
 * the firmware has answered when this returns.  Returns 0, ST_ERR_IO (port,
 * no answer), ST_ERR_INTERNAL (a fatal firmware error), ST_ERR_ARG,
 * ST_ERR_NOMEM; *out NULL on error.
 */
int printer_open(const struct printer_ops *ops, const struct printer_options *o,
		 struct printer **out, struct st_error *err);

/* printer_close - disconnect (a simulator stops); NULL is fine. */
void printer_close(struct printer *p);

/* printer_ops_of - the table an open printer uses. */
const struct printer_ops *printer_ops_of(const struct printer *p);

/*
 * printer_check - read the whole file of job (from job->offset, preamble
 * first) as a printer of ops and o would be sent it, with no printer
 * needed: every line parses, fits the firmware, translates; warn (may be
 * NULL) sees the translator's warnings.  Returns 0, ST_ERR_PARSE (err
 * names file and line; "nothing was sent"), ST_ERR_IO (cannot read),
 * ST_ERR_UNSUPPORTED (a resume the dialect cannot do), ST_ERR_NOMEM.
 */
int printer_check(const struct printer_ops *ops, const struct printer_options *o,
		  const struct printer_job *job, printer_warn_fn warn, void *warn_ctx,
		  struct printer_file_info *info, struct st_error *err);

/*
 * printer_stream - send the file of job, blocking until it ends; res says
 * how (always filled).  Returns 0 when the stream ran (res->end says how it
 * ended: done, cancelled, stopped, link lost, failed; err says why when
 * not done), or a negative class when it could not start (ST_ERR_IO: the
 * file; ST_ERR_PARSE: a bad line found while streaming).
 */
int printer_stream(struct printer *p, const struct printer_job *job, struct printer_result *res,
		   struct st_error *err);

/*
 * printer_command - send one G-code line outside a print, checked first (a
 * bad line changes nothing), and wait until the firmware took it; its text
 * reply lines into reply ('\n' after each; may be NULL; Sailfish answers
 * in packets, so nothing).  Returns 0, ST_ERR_PARSE, ST_ERR_IO.
 */
int printer_command(struct printer *p, const char *line, char *reply, size_t cap,
		    struct st_error *err);

/* printer_poll - between jobs: read the temperatures (into t's fields).
 * Returns 0 or ST_ERR_IO when the link is gone. */
int printer_poll(struct printer *p, struct printer_progress *t, struct st_error *err);

/* printer_safe_stop - heaters and motors off, queued commands dropped; the
 * printer takes the next job after it.  Returns 0 or ST_ERR_IO. */
int printer_safe_stop(struct printer *p, struct st_error *err);

/* printer_describe - what is connected ("Marlin 2.1.2 (simulated printer)"). */
void printer_describe(struct printer *p, char *out, size_t cap);

/* printer_can_resume - whether ops can continue a G-code print from a layer. */
bool printer_can_resume(const struct printer_ops *ops);

/* ---- for adapters ---- */

struct gcode_line;

/*
 * printer_temp_offset - add job->temp_offset's offset to the S (above 0:
 * off stays off) of g when it sets a heater's target: M104 and M109 a
 * tool's (T, else tool 0), M140 and M190 the bed's; M109 is the bed's when
 * m109_bed (GPX's Makerbot flavour, x3g.h).  Both g's words and its cleaned
 * text change; nothing changes when the text would pass text_max bytes.
 */
void printer_temp_offset(const struct printer_job *job, struct gcode_line *g, bool m109_bed,
			 size_t text_max);

struct xport;

/*
 * printer_port_open - open path at o's baud rate (DTR reset only for a
 * real port when o asks and simulated is false).  Returns 0 or ST_ERR_IO,
 * err naming the printer.
 */
int printer_port_open(const struct printer_options *o, const char *path, bool simulated,
		      struct xport **x, struct st_error *err);

/* printer_state - the adapter state p's open returned. */
void *printer_state(const struct printer *p);

/* printer_port_close - drain (1 s at most) and close; NULL is fine. */
void printer_port_close(struct xport *x);

/* printer_sim_baud - the simulated link: o's baud sped up, within what a pty keeps up with. */
unsigned printer_sim_baud(const struct printer_options *o);

/* printer_name - o's name for messages (name, else port). */
const char *printer_name(const struct printer_options *o);

#endif /* STRATUM_SERIAL_PRINTER_H */

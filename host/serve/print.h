/*
 * print.h - the node's printer-worker interface: how a printer's worker
 * thread (worker.c) talks to the printer, over serial/printer.h.  print.c
 * picks the operations: for "test-instant" the test double
 * (print_double.c), which "prints" by reading the G-code file line by
 * line with our parser, reporting progress, honouring pause, cancel and
 * G4 dwells, with no printer involved (a testing aid, docs/serve.md);
 * otherwise the dialect's adapter the profile names (host/printer_profile.h),
 * to a device path, a pty, tcp://HOST:PORT or "sim", the adapter's own
 * simulated printer run inside the node, sped up.
 *
 * Threads: the worker thread alone calls the operations of one link; the
 * HTTP threads only write requests into struct node_print_ctl (under its
 * mutex) and read its status fields.
 */
#ifndef STRATUM_HOST_SERVE_PRINT_H
#define STRATUM_HOST_SERVE_PRINT_H

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>

#include "node.h"
#include "printer.h"
#include "profile.h"
#include "st_error.h"

/* Shared between a print and the API; every field under mu. */
#define NODE_PRINT_TOOLS 8 /* tools whose temperature offset is kept */

struct node_print_ctl {
	pthread_mutex_t mu;
	/* Requests, written by the API or node_stop. */
	bool pause;  /* hold at the next line boundary until cleared */
	bool cancel; /* stop this print: it ends as cancelled */
	bool stop;   /* the node shuts down: the print ends as interrupted */
	/* Status, written by the back end. */
	bool paused;		 /* the printer is holding (pause acknowledged) */
	int64_t filepos, size;	 /* bytes of the file sent, and its size */
	/* after a print: the file's commands written to the printer (a Marlin
	 * runs them all, confirmed or not), -1 unknown: then only the ones up
	 * to filepos, which the printer confirmed, are known to have gone */
	int64_t sent;
	long layer;		 /* layer of the last confirmed command (0-based), -1 unknown */
	double z;		 /* its Z (mm), NAN unknown */
	double tool_actual, tool_target, bed_actual, bed_target; /* degrees C */
	double tool1_actual, tool1_target; /* a second extruder's, NAN unknown */
	/* Operators' commands for between the file's lines (printer.h inject),
	 * set by the caller before node_print_file: next_command(commands, ...)
	 * copies the next one and returns true, false when none; NULL = none.
	 * Called without ctl->mu held. */
	bool (*next_command)(void *commands, char *line, size_t cap);
	void *commands;
	/* Operators' temperature offsets (OctoPrint's), degC, written by the
	 * API: added to the file's heater targets above 0 as they stream. */
	double tool_offset[NODE_PRINT_TOOLS], bed_offset;
};

/* node_print_file results besides negative errors. */
enum node_print_result {
	NODE_PRINT_DONE = 0,
	NODE_PRINT_CANCELLED = 1,
	NODE_PRINT_STOPPED = 2, /* ctl->stop: the job stays resumable */
	NODE_PRINT_LINK_LOST = 3, /* the printer went away: resumable, err says why */
};

struct node_link; /* one connected printer (opaque, per back end) */

/*
 * node_print_connect - open the printer of pc (profile prof stays the
 * caller's and outlives the link).  *out NULL on error.
 * Returns 0; ST_ERR_IO (port cannot be opened), ST_ERR_UNSUPPORTED (a back
 * end not wired yet), ST_ERR_NOMEM.
 */
int node_print_connect(const struct node_printer_config *pc, const struct profile *prof,
		       struct node_link **out, struct st_error *err);

/* node_print_disconnect - close the link; NULL is fine. */
void node_print_disconnect(struct node_link *l);

/*
 * node_print_file - print the G-code file path, blocking until it ends.
 * @start: byte offset to start from (0, or the saved position of an
 *         interrupted print); @resume: true when continuing an interrupted
 *         print, so the back end can restore heat and position first.
 * Progress and temperatures go into ctl; ctl->pause holds, ctl->cancel
 * ends as NODE_PRINT_CANCELLED, ctl->stop as NODE_PRINT_STOPPED.
 * Returns an enum node_print_result, or a negative class with err filled
 * (ST_ERR_IO: file or port; ST_ERR_PARSE: a line that is not G-code,
 * named "FILE: line N"); ctl->filepos then says how far it got.
 */
int node_print_file(struct node_link *l, const char *path, int64_t start, bool resume,
		    struct node_print_ctl *ctl, struct st_error *err);

/*
 * node_print_command - send one G-code line outside a print (POST
 * /api/printer/command).  The line is checked with the parser first; a bad
 * line changes nothing.  Returns 0, ST_ERR_PARSE, ST_ERR_IO.
 */
int node_print_command(struct node_link *l, const char *line, struct st_error *err);

/* node_print_takes_commands - whether the prints of the printer of pc
 * send ctl->next_command's lines between the file's and apply ctl's
 * temperature offsets (Marlin and Sailfish, not test-instant), paused or
 * not; on Sailfish for G-code files only (an X3G file is not G-code). */
bool node_print_takes_commands(const struct node_printer_config *pc, const struct profile *prof);

/*
 * node_print_poll - between jobs: read what the printer reported
 * (temperatures into ctl).  Returns 0, or ST_ERR_IO when the link is gone.
 */
int node_print_poll(struct node_link *l, struct node_print_ctl *ctl, struct st_error *err);

/* node_print_describe - what is connected ("Marlin 2.1.2 (simulated printer)"). */
void node_print_describe(struct node_link *l, char *out, size_t cap);

/*
 * node_print_resumable - whether the operations that drive pc with profile
 * prof can continue an interrupted print (all of them today; X3G jobs cannot).
 */
bool node_print_resumable(const struct node_printer_config *pc, const struct profile *prof);

/* node_port_simulated - true for a port value that is no real printer. */
bool node_port_simulated(const char *port);

/* The test double's operations (print_double.c). */
extern const struct printer_ops node_double_ops;

#endif /* STRATUM_HOST_SERVE_PRINT_H */

/*
 * marlintest.h - what the marlin suite's files share (check_marlin.c,
 * check_marlin_faults.c, check_marlin_parse.c): the simulated Marlin on a
 * pty with a printer (serial/printer.h) on it, generated files streamed
 * through it, and the simulator's log checked line by line against them.
 */
#ifndef STRATUM_TESTS_MARLINTEST_H
#define STRATUM_TESTS_MARLINTEST_H

#include <check.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "marlin.h"
#include "printer.h"
#include "sim/marlin_sim.h"
#include "testutil.h"

/* A simulator, a printer on its pty and the driver under it. */
struct rig {
	struct sim_marlin *sim;
	struct printer *p;
	struct marlin *m;
	FILE *log;
	long unnumbered;   /* log lines without a line number */
	long undetectable; /* lines changed in a way the XOR checksum misses */
	bool corrupting;   /* the simulator flips or drops bytes */
};

/* Lines per thousand that may differ in a way the XOR checksum misses
 * (check_log); a test of heavy faults raises it for its run. */
extern long undetectable_per_mille;

/* What a streamed run cost besides the driver's status. */
struct rig_result {
	uint64_t dropped; /* bytes the simulator lost (ring overflow, faults) */
	long unnumbered;  /* fragments without a line number it ran */
	double seconds;	  /* connecting and the stream */
	long answered;	  /* the last line it had answered when the job was done */
};


/*
 * The clean 100k-line run uses a 1 KiB receive ring (a 32-bit board's) so
 * the suite stays short on a loaded machine: with 128 bytes the window, not
 * the link, sets the pace over a pty.  Fault runs cost a round trip or more
 * per error (about one line in five at 1 % corrupted bytes), so they and
 * the small rings use shorter files.  The sanitizer pass streams 20 000
 * lines clean: the same code, a fifth of the time.
 */
#define BIG (TU_SANITIZED ? 20000 : 100000)
#define FAULTY 5000
#define SMALL 10000

/* A fast link and near-instant motion, so the suite stays short. */
void fast_sim(struct sim_marlin_options *o);
/* The driver's options for the fast simulator (MARLIN_TRACE=1 in the
 * environment shows the traffic). */
void fast_driver(struct printer_options *o);
/* Start the simulator thread and open a printer on its pty (connected). */
void rig_start(struct rig *r, struct sim_marlin_options *so, const struct printer_options *mo);
void rig_stop(struct rig *r);
/* Stream the file at path through the rig's printer: how it ended. */
enum printer_end rig_stream(struct rig *r, const char *path, struct st_error *err);
/* Stream text through a rig; how the stream ended. */
enum printer_end stream_text(struct rig *r, const char *text, struct st_error *err);

/* A file of n generated commands with a layer comment every 1000 lines,
 * written at GEN_PATH and open for reading. */
#define GEN_PATH tu_path("marlin-gen.gcode")
FILE *gen_file(long n);
/*
 * The log from the first job line on must be the file's commands, each
 * once, in order, with consecutive line numbers.  Returns the number of
 * log lines checked.
 */
long check_log(struct rig *r, FILE *file);
/* Stream n generated lines through the rig; check the log; return status
 * (and, if res is not NULL, the simulator's side). */
struct marlin_status stream_and_check_r(struct sim_marlin_options *so,
					const struct printer_options *mo, long n,
					struct rig_result *res);
struct marlin_status stream_and_check(struct sim_marlin_options *so,
				      const struct printer_options *mo, long n);
/* Stream 2000 generated lines with a reset or unplug fault: the job must
 * end with a link failure whose message has want1 and want2, before line
 * at_line was acknowledged, within limit_s. */
void fault_ends_job(struct sim_marlin_options *so, long at_line, const char *want1,
		    const char *want2, double limit_s);
/* A case of its own for test t, so CK_RUN_CASE can pick one. */
void marlin_add_case(Suite *s, const char *name, const TTest *t, int timeout);

#endif

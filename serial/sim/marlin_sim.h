/*
 * marlin_sim.h - a simulated Marlin 2.1 printer behind a pseudo-terminal
 * (docs/architecture.md item 7, docs/protocols.md section 1).
 *
 * The simulator opens a pty pair and answers on its master side the way
 * Marlin does: boot banner, RX ring of rx_buffer bytes (bytes arriving when
 * it is full are lost), a command queue of bufsize slots, line numbers and
 * checksums with Error/Resend/ok, "ok" once a command has been executed
 * (moves: once planned into the 16-block planner), temperature reports,
 * busy keep-alives, M115 capabilities and the emergency parser (M108, M112,
 * M410).  Like Marlin's main loop, the ring is read only between commands:
 * while a command blocks (a move waiting for a planner block, G4, G28,
 * M109...) lines stay in the ring.  Motion and heating run speedup times faster than real time; the
 * link itself is paced at baud/10 bytes/s in both directions and is never
 * sped up.  Faults: corrupted and dropped bytes, reset and unplug at a line, a hang
 * at a line (for ever or for a while), minutes of "busy", an M115 without FIRMWARE_NAME.
 *
 * Library code: nothing is printed; the execution log is the only output
 * besides the pty.  All state lives in struct sim_marlin, so several
 * simulators may run in one process.  One simulator must be driven by one
 * thread at a time (sim_marlin_run or the thread sim_marlin_start_thread
 * made).
 */
#ifndef STRATUM_SERIAL_SIM_MARLIN_SIM_H
#define STRATUM_SERIAL_SIM_MARLIN_SIM_H

#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "st_error.h"

#define SIM_MARLIN_CUTS 4 /* lose_newline_at entries */

/* Options; sim_marlin_options_init fills the defaults. */
struct sim_marlin_options {
	unsigned rx_buffer; /* RX ring size (bytes), Marlin RX_BUFFER_SIZE; default 128 */
	unsigned bufsize;   /* command queue slots, Marlin BUFSIZE; default 4 */
	bool advanced_ok;   /* "ok N<n> P<planner free> B<slots free>" */
	double speedup;	    /* motion/heating/boot time divisor (> 0); default 1 */
	unsigned baud;	    /* link speed (bits/s), baud/10 bytes/s; default 115200 */
	unsigned latency_ms; /* extra delay before each reply line (ms); default 0 */
	double corrupt_p;   /* probability of a bit flip in each received byte [0,1] */
	double drop_p;	    /* probability that a received byte is lost [0,1] */
	double reply_loss_p; /* probability that an "ok" reply is lost on the way
			      * back [0,1]: the host's count falls behind the firmware */
	long reset_at_line; /* simulate a board reset when this line runs; <= 0: never */
	long unplug_at_line; /* close the pty master when this line runs; <= 0: never */
	const char *log_path; /* execution log file, created/truncated; NULL: none */
	FILE *log_fp;	    /* or an open stream (stays the caller's); used if log_path is NULL */
	uint64_t seed;	    /* PRNG seed for faults; 0 picks a fixed default */
	double boot_s;	    /* boot time in simulated seconds (input ignored); default 1.5 */
	/* Firmware variants and hangs (docs/protocols.md section 1): */
	bool keep_rx_on_error; /* a line error leaves the bytes behind the bad line in
				* the RX ring, so each later line is answered in turn
				* (queue.cpp reads the ring empty); default false */
	bool no_firmware_name; /* M115 answers a bare "ok" (no FIRMWARE_NAME, no Cap:
				* lines), as some boards and serial bridges do */
	long freeze_at_line; /* when this line runs the board hangs: not one byte
			      * in or out any more (like kill -STOP); <= 0: never */
	double freeze_s;     /* with freeze_at_line: the hang ends after this many
			      * wall seconds and all goes on (a board, or the
			      * computer running the host, stalled); 0: for ever */
	long busy_at_line;   /* this line holds the queue for busy_s wall seconds,
			      * sending "echo:busy: processing" every 2 s; <= 0: never */
	double busy_s;
	long spoil_number_at; /* the first copy of this line arrives with its number
			       * spoilt into the one before (noise on a digit of N):
			       * dropped silently as a duplicate, as queue.cpp drops
			       * last_N - 1 and last_N; <= 0: never */
	long lose_newline_at[SIM_MARLIN_CUTS]; /* the first copy of each of these
			       * lines loses its newline: the firmware waits for the
			       * rest of it (0: unused) */
	long star_to_newline_at; /* the first copy of this line has its '*' turned
			       * into a newline (one bit flipped): the line errs for
			       * its missing checksum, and its checksum digits,
			       * arriving after the error emptied the ring, run as
			       * an unknown command; <= 0: never */
};

/* Opaque simulator. */
struct sim_marlin;

/* sim_marlin_options_init - fill opts with the defaults listed above. */
void sim_marlin_options_init(struct sim_marlin_options *opts);

/*
 * sim_marlin_new - create a simulator and its pty pair (slave in raw mode).
 * @opts: NULL for the defaults; copied (log_path is opened here).
 * @out:  set to the new simulator, or NULL on error.
 * @err:  may be NULL; filled on error.
 * Returns 0, ST_ERR_ARG (bad option), ST_ERR_IO (pty or log file) or
 * ST_ERR_NOMEM.  The boot banner is queued at once, so a host that opens
 * the slave later still reads "start".
 */
int sim_marlin_new(const struct sim_marlin_options *opts, struct sim_marlin **out,
		   struct st_error *err);

/* sim_marlin_slave_path - the pty slave's path (owned by sim), for the host
 * to open. */
const char *sim_marlin_slave_path(const struct sim_marlin *sim);

/*
 * sim_marlin_run - the event loop: runs until *stop becomes non-zero (a
 * signal handler or another thread sets it) or the link is unplugged
 * (unplug_at_line).  @stop may be NULL only with unplug_at_line > 0.
 * Returns 0, or ST_ERR_IO if the pty failed (err filled, may be NULL).
 */
int sim_marlin_run(struct sim_marlin *sim, volatile sig_atomic_t *stop, struct st_error *err);

/* sim_marlin_unplugged - true once the simulated cable was pulled. */
bool sim_marlin_unplugged(const struct sim_marlin *sim);

/* sim_marlin_halted - true once M112 killed the simulated board. */
bool sim_marlin_halted(const struct sim_marlin *sim);

/* sim_marlin_frozen - true once freeze_at_line hung the board. */
bool sim_marlin_frozen(const struct sim_marlin *sim);

/* sim_marlin_answered_line - the number of the last numbered line that ran
 * to its end and was answered (its ok, or an M105's report); 0: none yet.
 * Safe to call while the simulator thread runs. */
long sim_marlin_answered_line(const struct sim_marlin *sim);

/* sim_marlin_machine_s - the simulated machine's own clock: seconds of
 * motion (as planned), dwells, homing and heat waits it has run, in
 * simulated time, so unchanged by the host's pace or load.  Safe to call
 * while the simulator thread runs. */
double sim_marlin_machine_s(const struct sim_marlin *sim);

/* sim_marlin_dropped_bytes - bytes lost so far: RX ring overflow plus
 * injected drops. */
uint64_t sim_marlin_dropped_bytes(const struct sim_marlin *sim);

/*
 * sim_marlin_start_thread - run sim_marlin_run on a new thread, for tests.
 * Returns 0 or ST_ERR_IO (thread creation failed) / ST_ERR_ARG (already
 * running).
 */
int sim_marlin_start_thread(struct sim_marlin *sim, struct st_error *err);

/* sim_marlin_stop - stop and join the thread sim_marlin_start_thread made;
 * does nothing if none runs.  Returns that run's result. */
int sim_marlin_stop(struct sim_marlin *sim);

/* sim_marlin_free - stop a running thread, close the pty and the log file
 * it opened, free everything.  NULL is allowed. */
void sim_marlin_free(struct sim_marlin *sim);

#endif /* STRATUM_SERIAL_SIM_MARLIN_SIM_H */

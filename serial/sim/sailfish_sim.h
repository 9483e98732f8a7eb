/*
 * sailfish_sim.h - a simulated Sailfish (Makerbot-family) printer behind a
 * pseudo-terminal, as on a FlashForge Creator Pro (docs/architecture.md item 7,
 * docs/protocols.md section 2).
 *
 * The simulator answers S3G packets on the pty master the way Sailfish's
 * Host.cc and Packet.cc do: a byte-wise packet reader (noise bytes,
 * lengths over 32 and CRC mismatches each answered with the firmware's
 * code; a packet that stalls for 200 ms answered 0x8C), exactly one reply
 * per packet and no reading of new packets while a reply is still going
 * out, action commands pushed whole into a command buffer of buffer_size
 * bytes (512 in Sailfish) or refused with 0x82, queries answered at once.
 * The command processor takes commands out of the buffer by code and
 * length (s3g_action_length), runs moves through a 16-block planner timed
 * from their step counts and DDA rates (or duration for 142), waits for
 * heaters that take time (135, 141), and writes one log line per executed
 * command.  Motion and heating run speedup times faster than real time;
 * the link is paced at baud/10 bytes/s both ways and is not sped up, nor is
 * the firmware's 200 ms packet time-out.
 *
 * Faults: corrupted or dropped received bytes, corrupted reply bytes, a
 * board reset (the board then boots for boot_s and answers as freshly
 * booted) and an unplugged cable, both at an executed command number.
 *
 * Library code: nothing is printed.  All state lives in the struct; one
 * simulator is driven by one thread at a time.
 */
#ifndef STRATUM_SERIAL_SIM_SAILFISH_SIM_H
#define STRATUM_SERIAL_SIM_SAILFISH_SIM_H

#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "st_error.h"

/* Options; sim_sailfish_options_init fills the defaults. */
struct sim_sailfish_options {
	unsigned buffer_size; /* command buffer (bytes), Sailfish COMMAND_BUFFER_SIZE; default 512 */
	double speedup;	      /* motion/heating/boot time divisor (> 0); default 1 */
	unsigned baud;	      /* link speed (bits/s), baud/10 bytes/s; default 115200 */
	unsigned latency_ms;  /* extra delay before each reply (ms); default 0 */
	double corrupt_p;     /* probability of a bit flip in each received byte [0,1] */
	double drop_p;	      /* probability that a received byte is lost [0,1] */
	double reply_corrupt_p; /* probability of a bit flip in each reply byte [0,1] */
	long reset_at;	      /* reboot instead of executing command N (1-based); <= 0 never */
	long unplug_at;	      /* close the pty after executing command N; <= 0 never */
	const char *log_path; /* execution log, created/truncated; NULL: none */
	FILE *log_fp;	      /* or an open stream (stays the caller's) if log_path is NULL */
	uint64_t seed;	      /* PRNG seed for faults; 0 picks a fixed default */
	double boot_s;	      /* boot time after a reset (simulated s, input ignored); default 2 */
	long crc_escape_at;   /* the Nth action packet (1-based) received whole arrives
			       * with bit 7 of its command byte cleared and the CRC still
			       * matching, as two bit errors 127 bits apart do under
			       * CRC-8: the firmware answers it as a query; <= 0 never */
	uint8_t crc_escape_code; /* non-zero: that packet's command byte becomes this code
				  * instead (an action: the rest of its bytes are parsed
				  * as whatever commands they read as, so the build's
				  * line count drifts from what the host sent) */
	long query_escape_at; /* the Nth query packet (1-based) received whole runs as
			       * query query_escape_code, its CRC still matching (two
			       * bit errors CRC-8 cannot see): the host gets the other
			       * query's reply; <= 0 never */
	uint8_t query_escape_code;
};

/* Opaque simulator. */
struct sim_sailfish;

/* sim_sailfish_options_init - fill o with the defaults listed above. */
void sim_sailfish_options_init(struct sim_sailfish_options *o);

/*
 * sim_sailfish_new - create a simulator and its pty pair (slave raw).
 * opts: NULL for the defaults; copied (log_path is opened here).
 * Returns 0, ST_ERR_ARG (an option out of range), ST_ERR_IO (pty, log
 * file) or ST_ERR_NOMEM; *out NULL on error.
 */
int sim_sailfish_new(const struct sim_sailfish_options *opts, struct sim_sailfish **out,
		     struct st_error *err);

/* sim_sailfish_slave_path - the pty slave's path, for the host to open. */
const char *sim_sailfish_slave_path(const struct sim_sailfish *sim);

/*
 * sim_sailfish_run - the event loop, until *stop becomes non-zero or the
 * cable is unplugged (unplug_at).  stop may be NULL only with unplug_at > 0.
 * Returns 0, or ST_ERR_IO if the pty failed.
 */
int sim_sailfish_run(struct sim_sailfish *sim, volatile sig_atomic_t *stop, struct st_error *err);

/* sim_sailfish_unplugged - true once the simulated cable was pulled. */
bool sim_sailfish_unplugged(const struct sim_sailfish *sim);

/* sim_sailfish_executed - action commands executed so far (the log's last
 * sequence number). */
uint64_t sim_sailfish_executed(const struct sim_sailfish *sim);

/* sim_sailfish_machine_s - the simulated machine's own clock: seconds of
 * motion (as planned), delays, homing and heat waits it has run, in
 * simulated time, so unchanged by the host's pace or load.  Safe to call
 * while the simulator thread runs. */
double sim_sailfish_machine_s(const struct sim_sailfish *sim);

/* sim_sailfish_undetected - packets that lost or had a byte spoilt by the
 * drop_p/corrupt_p faults and still matched their CRC-8: damage no host
 * can see (about one in 1,300 at 2 % corruption). */
uint64_t sim_sailfish_undetected(const struct sim_sailfish *sim);

/* sim_sailfish_resets - board resets so far (reset_at). */
unsigned sim_sailfish_resets(const struct sim_sailfish *sim);

/* sim_sailfish_start_thread - run sim_sailfish_run on a new thread.
 * Returns 0, ST_ERR_ARG (already running) or ST_ERR_IO. */
int sim_sailfish_start_thread(struct sim_sailfish *sim, struct st_error *err);

/* sim_sailfish_stop - stop and join that thread (no-op without one);
 * returns the run's result. */
int sim_sailfish_stop(struct sim_sailfish *sim);

/* sim_sailfish_free - stop the thread, close the pty and the log it
 * opened, free everything.  NULL is allowed. */
void sim_sailfish_free(struct sim_sailfish *sim);

#endif /* STRATUM_SERIAL_SIM_SAILFISH_SIM_H */

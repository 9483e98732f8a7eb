/*
 * sim_util.h - what the simulated printers (marlin_sim.c, sailfish_sim.c)
 * share: the clock, the fault PRNG, the pty pair, the wait for the next
 * event and the test thread.  Private to serial/sim/.
 */
#ifndef STRATUM_SERIAL_SIM_SIM_UTIL_H
#define STRATUM_SERIAL_SIM_SIM_UTIL_H

#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

/* sim_clock - monotonic wall clock in seconds. */
double sim_clock(void);

/* sim_machine_add - advance a simulator's machine clock (microseconds, read
 * by other threads) by s simulated seconds of motion, waiting or heating:
 * what the printer spent, whatever the host's pace or load. */
static inline void sim_machine_add(_Atomic uint64_t *clock_us, double s)
{
	if (s > 0 && isfinite(s))
		atomic_fetch_add(clock_us, (uint64_t)llround(s * 1e6));
}

/* sim_heater_step - one heater's temperature after `scaled` simulated
 * seconds: toward max(target, ambient) at heat_rate or cool_rate (°C/s),
 * never past it. */
double sim_heater_step(double temp, double target, double ambient, double heat_rate,
		       double cool_rate, double scaled);

/* sim_rand01 - xorshift64* step on *state: uniform double in [0, 1). */
double sim_rand01(uint64_t *state);

/* sim_pty_open - open a pty pair: slave raw, master non-blocking, both
 * close-on-exec; path (cap >= 128) gets the slave's name.  Returns 0 or
 * -1 with errno set. */
int sim_pty_open(int *master, int *slave, char *path);

/* sim_pty_close - close whichever ends of a pty pair are open and mark
 * them closed (-1): the simulated cable pulled, or the simulator freed. */
void sim_pty_close(int *master, int *slave);

/*
 * sim_wait_input - sleep until wake (sim_clock seconds) or until fd is
 * readable (only if want_in), then read what came into buf[*len..cap),
 * setting *arrived to the clock when bytes came.  Returns 0, or -1 with
 * errno set when poll or read failed for a reason other than EINTR/EAGAIN.
 */
int sim_wait_input(int fd, bool want_in, double wake, uint8_t *buf, size_t *len, size_t cap,
		   double *arrived);

/* A simulator's event loop run on a thread, for tests. */
struct sim_thread {
	pthread_t thread;
	bool on;
	volatile sig_atomic_t stop;
	int rc;
	int (*run)(void *sim, volatile sig_atomic_t *stop); /* the event loop */
	void *sim;
};

/* sim_thread_start - run t->run(t->sim, &t->stop) on a new thread.
 * Returns 0, ST_ERR_ARG (already running) or ST_ERR_IO; who names the
 * simulator in the message. */
int sim_thread_start(struct sim_thread *t, const char *who, struct st_error *err);

/* sim_thread_stop - stop and join (no-op when not running); returns the
 * loop's result. */
int sim_thread_stop(struct sim_thread *t);

#endif /* STRATUM_SERIAL_SIM_SIM_UTIL_H */

/*
 * simtest.h - what the sim suite's files share (check_sim.c,
 * check_sim_faults.c): the host side of the simulated Marlin's pty, line
 * by line, and the simulator's execution log.
 */
#ifndef STRATUM_TESTS_SIMTEST_H
#define STRATUM_TESTS_SIMTEST_H

#include <stddef.h>
#include <stdio.h>

#include "sim/marlin_sim.h"

/* The host side of the link: the pty slave, with a line buffer. */
struct client {
	struct sim_marlin *sim;
	int fd;
	char buf[16384];
	size_t len;
	FILE *log;
};

/* Options for fast tests: high speedup, fast link. */
void fast_opts(struct sim_marlin_options *o);
/* Read one line (without "\n") within timeout seconds; -1 on time-out,
 * -2 on hang-up. */
int cl_line(struct client *c, char *out, size_t cap, double timeout);
/* Read lines until one starts with prefix; fails the test on time-out. */
void cl_expect(struct client *c, const char *prefix, char *out, size_t cap, double timeout);
/* The next line must be exactly want. */
void cl_next_is(struct client *c, const char *want);
/* Send text as it is. */
void cl_send(struct client *c, const char *text);
/* Send "N<n> <cmd>*<cs>\n". */
void cl_send_n(struct client *c, long n, const char *cmd);
/* Start a simulator with o on a thread and connect to it past its boot. */
void cl_start(struct client *c, struct sim_marlin_options *o);
/* Stop the simulator and close the link. */
void cl_stop(struct client *c);
/* Whole execution log as a string (static buffer). */
const char *cl_log(struct client *c);

#endif

/*
 * commands.h - one function per `stratum` subcommand, each in its own
 * host/cmd_<name>.c.  argv[0] is the subcommand name; the return value is the
 * process exit status (st_error.h enum st_exit).  Only host/ prints.
 */
#ifndef STRATUM_HOST_COMMANDS_H
#define STRATUM_HOST_COMMANDS_H

#include <stdbool.h>
#include <stddef.h>

#include "st_error.h"
#include "x3g.h"

int cmd_check(int argc, char **argv);	 /* host/cmd_check.c */
int cmd_repair(int argc, char **argv);	 /* host/cmd_repair.c */
int cmd_printers(int argc, char **argv); /* host/cmd_printers.c */
int cmd_ports(int argc, char **argv);	 /* host/cmd_ports.c */
int cmd_sim(int argc, char **argv);	 /* host/cmd_sim.c */
int cmd_slice(int argc, char **argv);	 /* host/cmd_slice.c */
int cmd_x3g(int argc, char **argv);	 /* host/cmd_x3g.c */
int cmd_send(int argc, char **argv);	 /* host/cmd_send.c */
int cmd_serve(int argc, char **argv);	 /* host/cmd_serve.c */
int cmd_preview(int argc, char **argv);	 /* host/cmd_preview.c */
int cmd_print(int argc, char **argv);	 /* host/cmd_print.c */

/*
 * cmd_parse_threads - the value of --threads N: N as an int, or -1 when it
 * is not a whole number in 1..256 (host/cmd_check.c).
 */
int cmd_parse_threads(const char *s);

/*
 * cmd_opt_value - the value of option argv[*i] given as "NAME VALUE" (then
 * *i moves past VALUE) or "NAME=VALUE"; NULL when the value is missing
 * (host/cmd_opts.c).
 */
const char *cmd_opt_value(int argc, char **argv, int *i, const char *name);

/*
 * cmd_number - true and *out set when v is a number (st_number.h rules);
 * else prints "CMD: OPT wants WHAT, not 'V'" on stderr and returns false.
 */
bool cmd_number(const char *cmd, const char *opt, const char *v, const char *what, double *out);

/* cmd_on_stop_signals - SIGINT and SIGTERM call handler, which sets the
 * command's stop flag (host/cmd_opts.c). */
void cmd_on_stop_signals(void (*handler)(int));

/* cmd_same_file - whether paths a and b name the same existing file (device
 * and inode, so through symlinks, hard links and any spelling of the path). */
bool cmd_same_file(const char *a, const char *b);

/*
 * cmd_output_check - before any work: refuse an output out that is the
 * input in (cmd_same_file; in may be NULL) or a directory (ST_EXIT_USAGE),
 * and one whose directory does not exist or cannot be written
 * (ST_EXIT_FAILURE), with a one-line reason in msg.  0 when out may be
 * written (host/cmd_output.c).
 */
int cmd_output_check(const char *in, const char *out, char *msg, size_t cap);

/* cmd_is_opt - true when a is NAME or NAME=...; the value may still be missing. */
bool cmd_is_opt(const char *a, const char *name);

struct json_t;
/*
 * cmd_json_out - write o to stdout with jansson's flags, then a newline;
 * o is freed.  0, or -1 when o is NULL (nothing written) or the write
 * failed (host/cmd_output.c).
 */
int cmd_json_out(struct json_t *o, size_t flags);

#endif

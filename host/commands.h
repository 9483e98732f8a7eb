/*
 * commands.h - one function per `stratum` subcommand, each in its own
 * host/cmd_<name>.c.  argv[0] is the subcommand name; the return value is the
 * process exit status (st_error.h enum st_exit).  Only host/ prints.
 */
#ifndef STRATUM_HOST_COMMANDS_H
#define STRATUM_HOST_COMMANDS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "meshio.h"
#include "st_error.h"
#include "x3g.h"

#define STRATUM_VERSION "0.1.0" /* --version and the man pages */

int cmd_check(int argc, char **argv);	 /* host/cmd_check.c */
int cmd_repair(int argc, char **argv);	 /* host/cmd_repair.c */
int cmd_printers(int argc, char **argv); /* host/cmd_printers.c */
int cmd_ports(int argc, char **argv);	 /* host/cmd_ports.c */
int cmd_sim(int argc, char **argv);	 /* host/cmd_sim.c */
int cmd_slice(int argc, char **argv);	 /* host/cmd_slice.c */
int cmd_x3g(int argc, char **argv);	 /* host/cmd_x3g.c */
int cmd_send(int argc, char **argv);	 /* host/cmd_send.c */
int cmd_serve(int argc, char **argv);	 /* host/cmd_serve.c */
int cmd_farm(int argc, char **argv);	 /* host/cmd_serve.c */
int cmd_preview(int argc, char **argv);	 /* host/cmd_preview.c */
int cmd_print(int argc, char **argv);	 /* host/cmd_print.c */
int cmd_jobs(int argc, char **argv);	 /* host/cmd_jobs.c */
int cmd_console(int argc, char **argv);	 /* host/cmd_console.c */
int cmd_analyze(int argc, char **argv);	 /* host/cmd_analyze.c */
int cmd_compare(int argc, char **argv);	 /* host/cmd_compare.c */
int cmd_refine(int argc, char **argv);	 /* host/cmd_refine.c */

/*
 * cmd_opt_value - the value of option argv[*i] given as "NAME VALUE" (then
 * *i moves past VALUE) or "NAME=VALUE"; NULL when the value is missing
 * (host/cmd_opts.c).
 */
const char *cmd_opt_value(int argc, char **argv, int *i, const char *name);

/* cmd_on_stop_signals - SIGINT and SIGTERM call handler, which sets the
 * command's stop flag (host/cmd_opts.c). */
void cmd_on_stop_signals(void (*handler)(int));

/* cmd_has_ext - true when path ends in ext (".x3g") after a name, any case. */
bool cmd_has_ext(const char *path, const char *ext);

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

/*
 * cmd_read_mesh - meshio_read of path (any format; fmt may be NULL): 0, or
 * the exit status (ST_EXIT_DATAERR, ST_EXIT_SOFTWARE out of memory) after
 * "CMD: MESSAGE" on stderr (host/cmd_output.c).
 */
int cmd_read_mesh(const char *cmd, const char *path, struct mesh **m, enum meshio_format *fmt);

/*
 * cmd_fail - print "CMD: MESSAGE" on stderr (fmt without its newline) and
 * return status: an error path is `return cmd_fail(CMD, STATUS, ...)`
 * (host/cmd_output.c).
 */
int cmd_fail(const char *cmd, int status, const char *fmt, ...)
	__attribute__((format(printf, 3, 4)));

/* cmd_is_opt - true when a is NAME or NAME=...; the value may still be missing. */
bool cmd_is_opt(const char *a, const char *name);

struct json_t;
/*
 * cmd_json_out - write o to stdout with jansson's flags, then a newline;
 * o is freed.  0, or -1 when o is NULL (nothing written) or the write
 * failed (host/cmd_output.c).
 */
int cmd_json_out(struct json_t *o, size_t flags);

/*
 * cmd_json_set - set keys of o in order from pairs of "K:key" and a value,
 * NULL after the last pair.  K is the value's C type: 'b' bool, 'i' int,
 * 'z' size_t, 'I' json_int_t, 'f' double, 's' string, 'o' json_t * (taken
 * over).  As json_object_set_new key by key, not json_pack: a value that
 * cannot be made (a NULL or non-UTF-8 string, a NaN) leaves only its own
 * key out, where json_pack would lose the whole object (host/cmd_output.c).
 */
void cmd_json_set(struct json_t *o, ...);

/*
 * cmd_report_end - after a command printed its report on stdout: json_failed
 * (the --json report could not be made) gives "CMD: cannot write the JSON
 * WHAT", a failed flush "CMD: cannot write the WHAT: REASON", both
 * ST_EXIT_SOFTWARE; else 0 (host/cmd_output.c).
 */
int cmd_report_end(const char *cmd, const char *what, bool json_failed);

/*
 * The option table of one subcommand: each option is declared once, with
 * its value's kind, range and help line, and both cmd_parse and the --help
 * text (cmd_usage) read it.
 */
enum cmd_kind {
	CMD_FLAG,     /* bool *: set true */
	CMD_STRING,   /* const char **: the value */
	CMD_DOUBLE,   /* double * */
	CMD_INT,      /* int *: a whole number */
	CMD_LONG,     /* long *: a whole number */
	CMD_UNSIGNED, /* unsigned *: a whole number */
	CMD_U64,      /* uint64_t *: a whole number */
	CMD_CUSTOM,   /* read by .read(value, dest); false: refused */
};

#define CMD_NONEMPTY 1u	 /* CMD_STRING: "" is refused as missing */
#define CMD_ABOVE_LO 2u	 /* numbers: lo itself is refused (lo < v <= hi) */
#define CMD_RANGE 4u	 /* numbers: refused outside lo..hi */
#define CMD_OPTIONAL 16u /* CMD_STRING: "NAME" alone when no value follows (the next
			  * argument is missing or an option): dest stays NULL */
#define CMD_TRUNCATE 8u /* whole-number kinds: a fraction is cut off, not refused */

struct cmd_opt {
	const char *name; /* "--output" */
	char letter;	  /* 'o' for -o, or 0 */
	enum cmd_kind kind;
	void *dest;
	unsigned flags;
	double lo, hi;
	/* The refusal: "CMD: NAME wants WANTS, not 'V'" for a value that does
	 * not read, "CMD: NAME needs WANTS" for a missing string (NULL: "a
	 * value"); a printf format given lo and hi. */
	const char *wants;
	const char *arg;  /* the value's name in the help ("OUT"), or NULL */
	const char *help; /* printf format given lo, hi and the default; '\n'
			   * continues the text under itself.  Every option has
			   * one: --help, the man page and the completion all list
			   * the whole table (tests/check_help.c) */
	bool (*read)(const char *v, void *dest); /* CMD_CUSTOM */
	const char **given; /* when not NULL, set to NAME when the option is given */
};

struct cfgopt;
struct cmd_spec {
	const char *cmd;   /* "stratum repair" */
	const char *head;  /* the help text before the options */
	const struct cmd_opt *opt;
	size_t nopt;
	int col;	   /* where the help lines start */
	const char *mid;   /* after the options, before the settings options */
	struct cfgopt *cfg; /* NULL, or takes the settings options (cfgopt.h) */
	const char *tail;  /* the help text after them */
	const char **pos;  /* slots for the arguments that are not options */
	size_t npos;
	size_t *ngot;	   /* NULL, or set to how many slots were filled */
	/* "CMD: EXTRA" when there are more than npos: a printf format given
	 * the first and the surplus argument (npos 1), or npos as an int and
	 * the surplus (npos > 1); NULL: "unexpected argument 'A'" and the usage. */
	const char *extra;
};

/*
 * cmd_parse - read argv[1..argc) by spec: "NAME VALUE", "NAME=VALUE" and
 * "-L VALUE" forms, the settings options, and arguments into spec->pos.
 * Returns 0; -1 after printing the usage on stdout for --help or -h; or
 * ST_EXIT_USAGE after printing "CMD: ..." naming the refused option (with
 * the usage on stderr for an unknown one).
 */
/* The spec's table: .opt and .nopt of an array. */
#define CMD_TABLE(t) .opt = (t), .nopt = sizeof(t) / sizeof((t)[0])

/* The common shapes of a table entry. */
#define CMD_OPT_FLAG(name, dest, help) \
	{name, 0, CMD_FLAG, dest, 0, 0, 0, NULL, NULL, help, NULL, NULL}
#define CMD_OPT_STRING(name, letter, dest, flags, wants, arg, help) \
	{name, letter, CMD_STRING, dest, flags, 0, 0, wants, arg, help, NULL, NULL}

/* --threads N of the commands with exact or parallel passes; help: what uses them. */
#define CMD_OPT_THREADS(dest, help)                                                      \
	{"--threads", 0, CMD_INT, dest, CMD_RANGE, 1, 256, "a number from %g to %g", "N", help, \
	 NULL, NULL}

/* The options of the commands that drive a printer (send, print, console). */
#define CMD_SIM_SPEEDUP 1000 /* --speedup's default: the built-in simulator's time divisor */
#define CMD_TEXT_OF_(x) #x
#define CMD_TEXT_OF(x) CMD_TEXT_OF_(x) /* a macro's value as a string, for help texts */
#define CMD_OPT_PRINTER_NAME(dest) \
	CMD_OPT_STRING("--printer", 0, dest, 0, NULL, "NAME", \
		       "the printer profile ('stratum printers'); required")
#define CMD_OPT_PORT_OR_SIM(dest)                                                    \
	CMD_OPT_STRING("--port", 0, dest, 0, NULL, "P",                              \
		       "a serial device, 'auto' (the port whose USB id the profile\n" \
		       "lists), tcp://HOST:PORT, or 'sim'.  Default: sim, the\n"      \
		       "built-in simulated printer of the profile's firmware")
#define CMD_OPT_BAUD(dest)                                                          \
	{"--baud", 0, CMD_LONG, dest, CMD_RANGE, 300, 10000000,                     \
	 "a whole number from %.0f to %.0f", "N",                                   \
	 "link speed, %.0f to %.0f (default: the profile's baudrate)", NULL, NULL}
#define CMD_OPT_SPEEDUP(dest)                                                       \
	{"--speedup", 0, CMD_DOUBLE, dest, CMD_RANGE, 1, 1e6, "a factor from %.0f to %.0f", \
	 "K", "the simulated printer runs K times faster (default " CMD_TEXT_OF(CMD_SIM_SPEEDUP) ")", \
	 NULL, NULL}
#define CMD_OPT_SIM_LOG(dest) \
	CMD_OPT_STRING("--sim-log", 0, dest, 0, NULL, "FILE", \
		       "testing aid: the simulated printer's execution log")

int cmd_parse(const struct cmd_spec *spec, int argc, char **argv);

/* cmd_usage - spec's help text: head, the option lines, mid, the settings
 * options when spec->cfg, tail. */
void cmd_usage(const struct cmd_spec *spec, FILE *f);

/* cmd_refuse - a command line refused: "CMD: MESSAGE" and the usage on
 * stderr; ST_EXIT_USAGE (host/cmd_opts.c). */
int cmd_refuse(const struct cmd_spec *spec, const char *fmt, ...)
	__attribute__((format(printf, 2, 3)));

#define CMD_HELP_MAX 600 /* bytes of one option's help text */

/* cmd_usage_opt - o's lines of --help: the label, then the text from column col. */
void cmd_usage_opt(const struct cmd_opt *o, int col, FILE *f);

/* cmd_opt_help - o's help text with its lo, hi and default filled in. */
void cmd_opt_help(const struct cmd_opt *o, char *buf, size_t cap);

/*
 * cmd_describe - spec in another form than --help (host/cmd_help.c), for
 * `stratum help` and the build (Makefile: man pages, completion): "man" the
 * stratum-CMD(1) page after its .TH and NAME (cmd_help adds those, which
 * need the command's summary), "bash" or "zsh" the command's branch of the
 * completion script, "options" one line per option (NAME, -L or -, the kind:
 * flag, value or optional, then the settings options when spec->cfg) for
 * tests/check_help.c.  cmd_parse calls it for a first argument
 * "--help=FORMAT".  0, or -1 after a message for an unknown format.
 */
int cmd_describe(const struct cmd_spec *spec, const char *format, FILE *f);

/* One subcommand of `stratum` (host/main.c's table). */
struct cmd_entry {
	const char *name;
	int (*run)(int argc, char **argv);
	const char *summary;
};

/*
 * cmd_help - `stratum help [CMD]`: the overview or CMD's --help; and for the
 * build `help --man [CMD]` (stratum(1) or stratum-CMD(1)), `help
 * --completion bash|zsh` and `help --commands` (the names, one a line).
 * argv[0] is "help"; the exit status (host/cmd_help.c).
 */
int cmd_help(const struct cmd_entry *cmds, size_t n, int argc, char **argv);

/* cmd_overview - the top-level usage: every command and its summary. */
void cmd_overview(const struct cmd_entry *cmds, size_t n, FILE *f);

#endif

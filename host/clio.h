/*
 * clio.h - command-line I/O shared by the subcommands (host/ only): "-" as
 * the input (stdin) or the output (stdout) of a command that reads or
 * writes files, and the last message a command printed on stderr, for the
 * --json answers that must name why a command stopped.
 *
 * "-" as input: stdin is read whole into a temporary file first (the
 * readers map, seek and sniff files).  "-" as output: the command writes a
 * temporary file and clio_finish copies it to stdout only when the command
 * succeeded, so a failing command never leaves half a stream; meanwhile the
 * reports the command prints on stdout go to stderr (fd 1 is fd 2 until
 * clio_finish).
 */
#ifndef STRATUM_HOST_CLIO_H
#define STRATUM_HOST_CLIO_H

#include <limits.h>
#include <stdbool.h>
#include <stddef.h>

struct clio {
	const char *cmd;	/* "stratum repair", the messages' prefix */
	char in_tmp[PATH_MAX];	/* stdin spooled here; "" none */
	char out_tmp[PATH_MAX]; /* the output written here first; "" none */
	int data_fd;		/* the real stdout while fd 1 is stderr; -1 none */
};

/* clio_is_std - whether path is "-" (stdin or stdout). */
bool clio_is_std(const char *path);

/* clio_init - no stdin taken, no stdout held; cmd prefixes the messages. */
void clio_init(struct clio *c, const char *cmd);

/*
 * clio_input - when *path is "-", copy stdin into a temporary file
 * $TMPDIR/stratum-XXXXXX/stdin<ext> (ext "" or ".gcode": for commands that
 * tell formats by name) and point *path at it.  Refuses a terminal on stdin.
 * 0, or the exit status after a message on stderr.
 */
int clio_input(struct clio *c, const char **path, const char *ext);

/*
 * clio_output - when *path is "-": refuse binary data for a terminal
 * (ST_EXIT_USAGE), else point *path at a temporary file stdout<ext> and
 * send whatever the command prints on stdout to stderr until clio_finish.
 * 0, or the exit status after a message.
 */
int clio_output(struct clio *c, const char **path, bool binary, const char *ext);

/*
 * clio_finish - the end of a command that called clio_input/clio_output:
 * when status is 0, the temporary output is copied to stdout; stdout is
 * given back; the temporary files are removed.  Returns status, or
 * ST_EXIT_FAILURE after a message when the copy failed.
 */
int clio_finish(struct clio *c, int status);

/*
 * clio_run - a whole command that may read or write "-": run(argc, argv,
 * io) between clio_init (cmd prefixes the messages) and clio_finish.
 */
int clio_run(const char *cmd, int (*run)(int argc, char **argv, struct clio *io), int argc,
	     char **argv);

/*
 * clio_capture_begin - from now on stderr also keeps, besides showing it,
 * the last line written that starts with "stratum " (the commands'
 * messages; usage text and progress bars do not).  clio_capture_end puts
 * stderr back and copies that line's text after its "CMD: " into msg
 * ("" when there was none).  glibc only (fopencookie); one capture at a
 * time.
 */
void clio_capture_begin(void);
void clio_capture_end(char *msg, size_t cap);

#endif /* STRATUM_HOST_CLIO_H */

/*
 * journal.h - the job journal of `stratum print` (docs/printing.md): where
 * a print got to, kept in the user's state directory so a print cut short
 * by a host crash, a power cut or a lost printer can be resumed.  One JSON
 * file per job, replaced whole (temp file, fsync, rename) so a crash never
 * leaves half a journal.  The G-code is identified by its SHA-256 (OpenSSL
 * libcrypto) so a resume refuses a file that changed.
 * Host code; nothing here prints.  Thread-safety: none shared.
 */
#ifndef STRATUM_HOST_JOURNAL_H
#define STRATUM_HOST_JOURNAL_H

#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

#define JOURNAL_ID_MAX 64
#define JOURNAL_PATH_MAX 4096
#define JOURNAL_ENV "STRATUM_STATE_DIR" /* overrides the state directory (tests) */

/* One job's record; the fields are what the file holds. */
struct journal {
	char id[JOURNAL_ID_MAX];	   /* "20261123-171800-4242" */
	char file[JOURNAL_PATH_MAX];	   /* journal file path (not stored in it) */
	char gcode[JOURNAL_PATH_MAX];	   /* absolute path of the G-code printed */
	char sha256[65];		   /* of the G-code, lower-case hex */
	char printer[128];		   /* profile id */
	char port[256];			   /* as given: sim, a device, tcp://... */
	char state[16];			   /* printing, done, cancelled, failed, link-lost */
	uint64_t lines;			   /* lines in the G-code file */
	uint64_t last_line;		   /* last line the printer acknowledged, 0 none */
	long layer;			   /* 0-based layer of that line, -1 unknown */
	double z;			   /* its height (mm), NAN unknown */
	double tool_actual, tool_target;   /* degC, last reported */
	double bed_actual, bed_target;	   /* degC */
	int64_t updated;		   /* Unix time of the last save */
};

/*
 * journal_dir - the jobs directory, created if missing: $STRATUM_STATE_DIR,
 * else $XDG_STATE_HOME/stratum, else $HOME/.local/state/stratum, with
 * "/jobs" appended.  Returns 0, ST_ERR_IO (cannot create; err names it)
 * or ST_ERR_RANGE (path too long).
 */
int journal_dir(char *out, size_t cap, struct st_error *err);

/*
 * journal_state_dir - the folder sub of the same state directory, created
 * if missing (journal_dir is its "jobs"); what names it in errors
 * ("console history").  Same returns as journal_dir.
 */
int journal_state_dir(char *out, size_t cap, const char *sub, const char *what,
		      struct st_error *err);

/*
 * journal_init - a new record for a job: a fresh id (time and process),
 * the file in journal_dir, state "printing", layer -1, z NAN.
 * Returns 0 or journal_dir's error.
 */
int journal_init(struct journal *j, struct st_error *err);

/*
 * journal_save - write j to j->file (temp file, fsync, rename), stamping
 * updated.  Returns 0 or ST_ERR_IO / ST_ERR_NOMEM.
 */
int journal_save(struct journal *j, struct st_error *err);

/*
 * journal_load - read the journal of job: an id (looked up in
 * journal_dir) or a path to a journal file.  Returns 0, ST_ERR_IO (no such
 * job: err says where it looked), ST_ERR_PARSE (not a journal).
 */
int journal_load(const char *job, struct journal *j, struct st_error *err);

/*
 * journal_sha256 - SHA-256 of the file at path as 64 hex digits in hex.
 * Returns 0, ST_ERR_IO (cannot read) or ST_ERR_INTERNAL (libcrypto).
 */
int journal_sha256(const char *path, char hex[65], struct st_error *err);

#endif /* STRATUM_HOST_JOURNAL_H */

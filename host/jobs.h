/*
 * jobs.h - the jobs directory of `stratum print` (journal_dir, journal.h):
 * each job is its journal ID.json and, for a sliced model, ID.gcode, both
 * kept so the job can be resumed.  Listed, and pruned by age and by a size
 * cap, oldest first; a running job is never pruned, a resumable one only
 * when asked.  A G-code file given on the command line lives elsewhere and
 * is never touched.  Host code; nothing here prints.
 */
#ifndef STRATUM_HOST_JOBS_H
#define STRATUM_HOST_JOBS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "journal.h"
#include "st_error.h"

#define JOBS_MAX_MB_DEFAULT 500		 /* the size cap, MB (10^6 bytes) */
#define JOBS_MAX_ENV "STRATUM_JOBS_MAX_MB" /* overrides it; 0: no cap */

enum jobs_kind {
	JOBS_RUNNING,	/* "printing" and its process is alive */
	JOBS_RESUMABLE, /* not done: `stratum print --resume ID` continues it */
	JOBS_DONE,	/* printed to the end */
	JOBS_LEFTOVER,	/* files without a readable journal (a print killed while
			 * slicing, a journal that does not read) */
};

/* One job: the files ID.* of the jobs directory. */
struct jobs_entry {
	char id[JOURNAL_ID_MAX];
	enum jobs_kind kind;
	char state[16];	     /* the journal's, or "leftover" */
	char printer[128];   /* the journal's profile, "" leftover */
	int64_t updated;     /* Unix time: the journal's, else the newest file's */
	uint64_t bytes;	     /* of its files here */
	bool pruned;	     /* chosen by jobs_prune */
};

struct jobs_list {
	char dir[JOURNAL_PATH_MAX - JOURNAL_ID_MAX - 8];
	struct jobs_entry *v; /* oldest first */
	size_t n;
	uint64_t bytes;	      /* all of them */
};

/*
 * jobs_scan - every job of journal_dir into l (free with jobs_free), oldest
 * first.  0, or ST_ERR_IO / ST_ERR_NOMEM with err set.
 */
int jobs_scan(struct jobs_list *l, struct st_error *err);
void jobs_free(struct jobs_list *l);

/* jobs_kind_name - "running", "resumable", "done", "leftover". */
const char *jobs_kind_name(enum jobs_kind k);

struct jobs_prune_opts {
	int64_t now;	    /* Unix time */
	int64_t older_than; /* seconds; < 0: no age limit */
	uint64_t max_bytes; /* the cap; 0: none */
	bool resumable;	    /* resumable jobs may go too */
};

/*
 * jobs_prune - mark (pruned) the jobs to remove: those older than
 * older_than, then the oldest until the rest fit in max_bytes; never a
 * running job, a resumable one only with o->resumable.  Returns how many,
 * and their bytes in *freed.  Nothing is removed (jobs_remove does).
 */
size_t jobs_prune(struct jobs_list *l, const struct jobs_prune_opts *o, uint64_t *freed);

/* jobs_remove - delete e's files from l->dir.  0 or ST_ERR_IO (err names the file). */
int jobs_remove(const struct jobs_list *l, const struct jobs_entry *e, struct st_error *err);

/*
 * jobs_parse_age - "30d", "12h", "45m", "90s" or "2w" into seconds; false
 * for anything else (a bare number is refused: its unit would be a guess).
 */
bool jobs_parse_age(const char *s, int64_t *seconds);

/*
 * jobs_cap - the size cap in bytes: $STRATUM_JOBS_MAX_MB when it is a
 * number of MB (0: none), else JOBS_MAX_MB_DEFAULT.
 */
uint64_t jobs_cap(void);

/*
 * jobs_trim - what `stratum print` does before a new job: prune to the cap
 * (jobs_cap), done and leftover jobs only.  Returns how many were removed,
 * their bytes in *freed; -1 with err set when the directory cannot be read.
 */
long jobs_trim(uint64_t *freed, struct st_error *err);

#endif /* STRATUM_HOST_JOBS_H */

/*
 * jobs.c - list and prune the jobs directory of `stratum print` (jobs.h).
 */
#include "jobs.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "st_grow.h"

const char *jobs_kind_name(enum jobs_kind k)
{
	static const char *const names[] = {"running", "resumable", "done", "leftover"};

	return (unsigned)k < sizeof(names) / sizeof(names[0]) ? names[k] : "?";
}

/* The process that made a job: the number after the id's last '-' (ids are
 * TIME-PID, leftovers print-PID and dry-run-PID); 0 when there is none. */
static long job_pid(const char *id)
{
	const char *dash = strrchr(id, '-');
	char *end;
	long pid;

	if (!dash || !dash[1])
		return 0;
	pid = strtol(dash + 1, &end, 10);
	return *end || pid <= 0 ? 0 : pid;
}

/* Whether process pid exists (one we may not signal exists too). */
static bool pid_alive(long pid)
{
	return pid > 0 && (kill((pid_t)pid, 0) == 0 || errno == EPERM);
}

/* The entry for id in l, added when new; NULL when out of memory. */
static struct jobs_entry *entry_for(struct jobs_list *l, const char *id, size_t *cap)
{
	for (size_t i = 0; i < l->n; i++)
		if (!strcmp(l->v[i].id, id))
			return &l->v[i];
	if (st_grow_at((void **)&l->v, cap, l->n + 1, sizeof(*l->v)))
		return NULL;
	memset(&l->v[l->n], 0, sizeof(l->v[0]));
	snprintf(l->v[l->n].id, sizeof(l->v[0].id), "%s", id);
	return &l->v[l->n++];
}

/* Read e's journal (if any) for its state, printer and time; its kind. */
static void classify(const struct jobs_list *l, struct jobs_entry *e, struct journal *j)
{
	char path[JOURNAL_PATH_MAX];
	struct st_error err = {0};

	snprintf(path, sizeof(path), "%s/%s.json", l->dir, e->id);
	if (access(path, F_OK) == 0 && journal_load(path, j, &err) == 0) {
		snprintf(e->state, sizeof(e->state), "%s", j->state);
		snprintf(e->printer, sizeof(e->printer), "%s", j->printer);
		if (j->updated > 0)
			e->updated = j->updated;
		if (!strcmp(j->state, "done"))
			e->kind = JOBS_DONE;
		else if (!strcmp(j->state, "printing") && pid_alive(job_pid(e->id)))
			e->kind = JOBS_RUNNING;
		else
			e->kind = JOBS_RESUMABLE;
		return;
	}
	snprintf(e->state, sizeof(e->state), "leftover");
	e->kind = pid_alive(job_pid(e->id)) ? JOBS_RUNNING : JOBS_LEFTOVER;
}

static int by_age(const void *a, const void *b)
{
	const struct jobs_entry *x = a, *y = b;

	if (x->updated != y->updated)
		return x->updated < y->updated ? -1 : 1;
	return strcmp(x->id, y->id);
}

int jobs_scan(struct jobs_list *l, struct st_error *err)
{
	struct journal j;
	struct dirent *d;
	size_t cap = 0;
	DIR *dir;
	int rc;

	memset(l, 0, sizeof(*l));
	if ((rc = journal_dir(l->dir, sizeof(l->dir), err)))
		return rc;
	if (!(dir = opendir(l->dir)))
		return st_error_set(err, ST_ERR_IO, "cannot read the jobs directory %s: %s", l->dir,
				    strerror(errno));
	while ((d = readdir(dir)) != NULL) {
		char path[JOURNAL_PATH_MAX + 256], id[JOURNAL_ID_MAX];
		const char *dot = strchr(d->d_name, '.');
		struct jobs_entry *e;
		struct stat st;

		if (d->d_name[0] == '.' || !dot || (size_t)(dot - d->d_name) >= sizeof(id))
			continue;
		snprintf(path, sizeof(path), "%s/%s", l->dir, d->d_name);
		if (lstat(path, &st) || !S_ISREG(st.st_mode))
			continue;
		snprintf(id, sizeof(id), "%.*s", (int)(dot - d->d_name), d->d_name);
		if (!(e = entry_for(l, id, &cap))) {
			closedir(dir);
			jobs_free(l);
			return st_error_set(err, ST_ERR_NOMEM, "out of memory listing the jobs");
		}
		e->bytes += (uint64_t)st.st_size;
		l->bytes += (uint64_t)st.st_size;
		if ((int64_t)st.st_mtime > e->updated)
			e->updated = (int64_t)st.st_mtime;
	}
	closedir(dir);
	for (size_t i = 0; i < l->n; i++)
		classify(l, &l->v[i], &j);
	if (l->n)
		qsort(l->v, l->n, sizeof(l->v[0]), by_age);
	return 0;
}

void jobs_free(struct jobs_list *l)
{
	free(l->v);
	l->v = NULL;
	l->n = 0;
}

/* Whether the user's options let e go. */
static bool may_prune(const struct jobs_entry *e, const struct jobs_prune_opts *o)
{
	return e->kind != JOBS_RUNNING && (e->kind != JOBS_RESUMABLE || o->resumable);
}

size_t jobs_prune(struct jobs_list *l, const struct jobs_prune_opts *o, uint64_t *freed)
{
	uint64_t left = l->bytes;
	size_t n = 0;

	*freed = 0;
	for (size_t i = 0; i < l->n; i++) {
		struct jobs_entry *e = &l->v[i];
		bool old = o->older_than >= 0 && o->now - e->updated > o->older_than;
		/* oldest first: while the rest is over the cap */
		bool over = o->max_bytes && left > o->max_bytes;

		e->pruned = may_prune(e, o) && (old || over);
		if (e->pruned) {
			left -= e->bytes;
			*freed += e->bytes;
			n++;
		}
	}
	return n;
}

int jobs_remove(const struct jobs_list *l, const struct jobs_entry *e, struct st_error *err)
{
	size_t len = strlen(e->id);
	struct dirent *d;
	DIR *dir = opendir(l->dir);
	int rc = 0;

	if (!dir)
		return st_error_set(err, ST_ERR_IO, "cannot read the jobs directory %s: %s", l->dir,
				    strerror(errno));
	while ((d = readdir(dir)) != NULL) {
		char path[JOURNAL_PATH_MAX + 256]; /* the directory and a d_name */

		if (strncmp(d->d_name, e->id, len) || d->d_name[len] != '.')
			continue;
		snprintf(path, sizeof(path), "%s/%s", l->dir, d->d_name);
		if (unlink(path) && errno != ENOENT && !rc)
			rc = st_error_set(err, ST_ERR_IO, "cannot remove %s: %s", path,
					  strerror(errno));
	}
	closedir(dir);
	return rc;
}

bool jobs_parse_age(const char *s, int64_t *seconds)
{
	static const struct { char unit; int64_t s; } units[] = {
	    {'s', 1}, {'m', 60}, {'h', 3600}, {'d', 86400}, {'w', 7 * 86400}};
	char *end;
	long long v;

	if (!s || *s < '0' || *s > '9')
		return false;
	errno = 0;
	v = strtoll(s, &end, 10);
	if (errno || end[0] == '\0' || end[1] != '\0' || v > 100LL * 365 * 86400)
		return false;
	for (size_t i = 0; i < sizeof(units) / sizeof(units[0]); i++)
		if (*end == units[i].unit) {
			*seconds = (int64_t)v * units[i].s;
			return true;
		}
	return false;
}

uint64_t jobs_cap(void)
{
	const char *env = getenv(JOBS_MAX_ENV);
	char *end;
	double mb;

	if (env && *env >= '0' && *env <= '9') {
		errno = 0;
		mb = strtod(env, &end);
		if (!errno && !*end && mb < 1e12)
			return (uint64_t)(mb * 1e6);
	}
	return (uint64_t)JOBS_MAX_MB_DEFAULT * 1000000u;
}

long jobs_trim(uint64_t *freed, struct st_error *err)
{
	struct jobs_prune_opts o = {.now = (int64_t)time(NULL), .older_than = -1,
				    .max_bytes = jobs_cap()};
	struct jobs_list l;
	long n = 0;

	*freed = 0;
	if (!o.max_bytes)
		return 0;
	if (jobs_scan(&l, err))
		return -1;
	if (jobs_prune(&l, &o, freed))
		for (size_t i = 0; i < l.n; i++)
			if (l.v[i].pruned && jobs_remove(&l, &l.v[i], err) == 0)
				n++;
	jobs_free(&l);
	return n;
}

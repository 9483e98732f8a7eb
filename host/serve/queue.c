/*
 * queue.c - the durable job queue (node_int.h): one SQLite database in the
 * data directory, WAL journal and synchronous=FULL so a job the API has
 * answered for survives kill -9 and a power cut.  One connection shared by
 * every thread behind one mutex: the node's writes are few and small.
 */
#include <pthread.h>
#include <sqlite3.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "node_int.h"

struct node_queue {
	sqlite3 *db;
	pthread_mutex_t mu;
};

static const char *const state_names[NODE_JOB_STATES] = {
	"queued", "slicing", "printing", "paused", "done", "failed", "cancelled"};

const char *node_job_state_name(enum node_job_state s)
{
	return (unsigned)s < NODE_JOB_STATES ? state_names[s] : "unknown";
}

static enum node_job_state state_from_name(const char *s)
{
	for (int i = 0; i < NODE_JOB_STATES; i++)
		if (s && !strcmp(s, state_names[i]))
			return (enum node_job_state)i;
	return NODE_JOB_FAILED; /* a row we do not understand is not printed */
}

static const char schema[] =
	"CREATE TABLE IF NOT EXISTS jobs ("
	" id INTEGER PRIMARY KEY AUTOINCREMENT,"
	" printer TEXT NOT NULL, name TEXT NOT NULL, file TEXT NOT NULL,"
	" gcode TEXT NOT NULL DEFAULT '', kind TEXT NOT NULL,"
	" state TEXT NOT NULL, interrupted INTEGER NOT NULL DEFAULT 0,"
	" resume INTEGER NOT NULL DEFAULT 0,"
	" filepos INTEGER NOT NULL DEFAULT 0, size INTEGER NOT NULL DEFAULT 0,"
	" error TEXT NOT NULL DEFAULT '',"
	" created INTEGER NOT NULL, started INTEGER NOT NULL DEFAULT 0,"
	" finished INTEGER NOT NULL DEFAULT 0, settings TEXT NOT NULL DEFAULT '',"
	" position INTEGER NOT NULL DEFAULT 0);"
	"CREATE INDEX IF NOT EXISTS jobs_printer_state ON jobs(printer, state);"
	"CREATE TABLE IF NOT EXISTS printers ("
	" name TEXT PRIMARY KEY, bed_clear INTEGER NOT NULL DEFAULT 1,"
	" selected TEXT NOT NULL DEFAULT '');"
	"CREATE TABLE IF NOT EXISTS commands ("
	" id TEXT PRIMARY KEY, printer TEXT NOT NULL, received INTEGER NOT NULL);";

#define JOB_COLUMNS                                                                       \
	"id, printer, name, file, gcode, kind, state, interrupted, resume, filepos, size, " \
	"error, created, started, finished, settings, position"

static int db_error(struct node_queue *q, struct st_error *err, const char *what)
{
	return st_error_set(err, ST_ERR_IO, "job queue: %s: %s", what, sqlite3_errmsg(q->db));
}

/* A queue written by an older node lacks the columns added since (per-job
 * settings, queue positions): add column name as decl (0, or -1 with *msg
 * from SQLite).  Old rows keep position 0 and so stay first, by id. */
static int add_column(struct node_queue *q, const char *name, const char *decl, char **msg)
{
	char sql[200];
	sqlite3_stmt *st;

	snprintf(sql, sizeof(sql), "SELECT %s FROM jobs LIMIT 0", name);
	if (sqlite3_prepare_v2(q->db, sql, -1, &st, NULL) == SQLITE_OK) {
		sqlite3_finalize(st);
		return 0;
	}
	snprintf(sql, sizeof(sql), "ALTER TABLE jobs ADD COLUMN %s %s", name, decl);
	return sqlite3_exec(q->db, sql, NULL, NULL, msg) == SQLITE_OK ? 0 : -1;
}

int node_queue_open(const char *path, struct node_queue **out, struct st_error *err)
{
	struct node_queue *q = calloc(1, sizeof(*q));
	char *msg = NULL;
	int rc;

	*out = NULL;
	if (!q)
		return st_error_set(err, ST_ERR_NOMEM, "job queue: out of memory");
	pthread_mutex_init(&q->mu, NULL);
	if (sqlite3_open_v2(path, &q->db,
			    SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX,
			    NULL) != SQLITE_OK) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot open the job queue: %s", path,
				  q->db ? sqlite3_errmsg(q->db) : "out of memory");
		goto out_close;
	}
	sqlite3_busy_timeout(q->db, 5000);
	if (sqlite3_exec(q->db, "PRAGMA journal_mode=WAL; PRAGMA synchronous=FULL;", NULL, NULL,
			 &msg) != SQLITE_OK ||
	    sqlite3_exec(q->db, schema, NULL, NULL, &msg) != SQLITE_OK ||
	    add_column(q, "settings", "TEXT NOT NULL DEFAULT ''", &msg) ||
	    add_column(q, "position", "INTEGER NOT NULL DEFAULT 0", &msg)) {
		rc = st_error_set(err, ST_ERR_IO, "%s: cannot set up the job queue: %s", path,
				  msg ? msg : sqlite3_errmsg(q->db));
		sqlite3_free(msg);
		goto out_close;
	}
	*out = q;
	return 0;

out_close:
	sqlite3_close(q->db);
	pthread_mutex_destroy(&q->mu);
	free(q);
	return rc;
}

void node_queue_close(struct node_queue *q)
{
	if (!q)
		return;
	sqlite3_close(q->db);
	pthread_mutex_destroy(&q->mu);
	free(q);
}

/* sql prepared with its text/integer parameters bound (fmt: 's' text,
 * 'i' int64), or NULL; q->mu held. */
static sqlite3_stmt *prepare(struct node_queue *q, const char *sql, const char *fmt, va_list ap)
{
	sqlite3_stmt *st;

	if (sqlite3_prepare_v2(q->db, sql, -1, &st, NULL) != SQLITE_OK)
		return NULL;
	for (int i = 0; fmt[i]; i++) {
		if (fmt[i] == 's')
			sqlite3_bind_text(st, i + 1, va_arg(ap, const char *), -1, SQLITE_TRANSIENT);
		else
			sqlite3_bind_int64(st, i + 1, va_arg(ap, int64_t));
	}
	return st;
}

/* prepare, with the parameters as arguments. */
static sqlite3_stmt *prepare_args(struct node_queue *q, const char *sql, const char *fmt, ...)
{
	sqlite3_stmt *st;
	va_list ap;

	va_start(ap, fmt);
	st = prepare(q, sql, fmt, ap);
	va_end(ap);
	return st;
}

/* Step st (NULL: not prepared) to its end and finalize it: 0, or -1. */
static int step_all(sqlite3_stmt *st)
{
	int rc = SQLITE_ERROR;

	while (st && (rc = sqlite3_step(st)) == SQLITE_ROW)
		;
	sqlite3_finalize(st);
	return rc == SQLITE_DONE ? 0 : -1;
}

/* Run sql with its parameters (fmt as prepare); q->mu held.  0, or -1. */
static int run(struct node_queue *q, const char *sql, const char *fmt, ...)
{
	va_list ap;
	sqlite3_stmt *st;

	va_start(ap, fmt);
	st = prepare(q, sql, fmt, ap);
	va_end(ap);
	return step_all(st);
}

/* run with q->mu taken: 0, or the error of doing what. */
static int run_locked(struct node_queue *q, struct st_error *err, const char *what,
		      const char *sql, const char *fmt, ...)
{
	va_list ap;
	int rc;

	pthread_mutex_lock(&q->mu);
	va_start(ap, fmt);
	rc = step_all(prepare(q, sql, fmt, ap)) ? db_error(q, err, what) : 0;
	va_end(ap);
	pthread_mutex_unlock(&q->mu);
	return rc;
}

static void copy_text(char *dst, size_t cap, const unsigned char *s)
{
	snprintf(dst, cap, "%s", s ? (const char *)s : "");
}

static void row_to_job(sqlite3_stmt *st, struct node_job *j)
{
	const unsigned char *kind;

	memset(j, 0, sizeof(*j));
	j->id = sqlite3_column_int64(st, 0);
	copy_text(j->printer, sizeof(j->printer), sqlite3_column_text(st, 1));
	copy_text(j->name, sizeof(j->name), sqlite3_column_text(st, 2));
	copy_text(j->file, sizeof(j->file), sqlite3_column_text(st, 3));
	copy_text(j->gcode, sizeof(j->gcode), sqlite3_column_text(st, 4));
	kind = sqlite3_column_text(st, 5);
	j->kind = kind && kind[0] == 'm' ? 'm' : 'g';
	j->state = state_from_name((const char *)sqlite3_column_text(st, 6));
	j->interrupted = sqlite3_column_int(st, 7) != 0;
	j->resume = sqlite3_column_int(st, 8) != 0;
	j->filepos = sqlite3_column_int64(st, 9);
	j->size = sqlite3_column_int64(st, 10);
	copy_text(j->error, sizeof(j->error), sqlite3_column_text(st, 11));
	j->created = sqlite3_column_int64(st, 12);
	j->started = sqlite3_column_int64(st, 13);
	j->finished = sqlite3_column_int64(st, 14);
	copy_text(j->settings, sizeof(j->settings), sqlite3_column_text(st, 15));
	j->position = sqlite3_column_int64(st, 16);
}

/* The first row of a one-job query with parameters (fmt as run); takes q->mu. */
static int one_job(struct node_queue *q, const char *sql, struct node_job *job,
		   struct st_error *err, const char *fmt, ...)
{
	sqlite3_stmt *st;
	va_list ap;
	int rc;

	pthread_mutex_lock(&q->mu);
	va_start(ap, fmt);
	st = prepare(q, sql, fmt, ap);
	va_end(ap);
	rc = st ? sqlite3_step(st) : SQLITE_ERROR;
	if (rc == SQLITE_ROW) {
		row_to_job(st, job);
		rc = 1;
	} else if (rc == SQLITE_DONE) {
		rc = 0;
	} else {
		rc = db_error(q, err, "query");
	}
	sqlite3_finalize(st);
	pthread_mutex_unlock(&q->mu);
	return rc;
}

int node_queue_recover(struct node_queue *q, int *interrupted, int *requeued,
		       struct st_error *err)
{
	int rc;

	pthread_mutex_lock(&q->mu);
	rc = run(q, "BEGIN IMMEDIATE", "") ||
	     run(q, "UPDATE jobs SET state='paused', interrupted=1, resume=0 "
		    "WHERE state IN ('printing','paused')", "");
	*interrupted = sqlite3_changes(q->db);
	rc = rc || run(q, "UPDATE jobs SET state='queued' WHERE state='slicing'", "");
	*requeued = sqlite3_changes(q->db);
	if (rc || run(q, "COMMIT", "")) {
		rc = db_error(q, err, "recovery");
		run(q, "ROLLBACK", "");
	}
	pthread_mutex_unlock(&q->mu);
	return rc;
}

/* Insert a queued job of printer, last in its queue or, with first, ahead
 * of every queued one; q->mu held.  0 with *id, or -1. */
static int insert_job(struct node_queue *q, const char *printer, const char *name,
		      const char *file, char kind, const char *settings, bool first, int64_t *id)
{
	const char *pos = first ? "(SELECT COALESCE(MIN(position), 1) - 1 FROM jobs WHERE "
				  "printer=? AND state='queued')"
				: "(SELECT COALESCE(MAX(position), 0) + 1 FROM jobs WHERE printer=?)";
	char sql[400];

	snprintf(sql, sizeof(sql), "INSERT INTO jobs(printer, name, file, gcode, kind, state, "
		 "created, settings, position) VALUES(?, ?, ?, ?, ?, 'queued', ?, ?, %s)", pos);
	if (run(q, sql, "sssssiss", printer, name, file, kind == 'm' ? "" : file,
		kind == 'm' ? "m" : "g", (int64_t)time(NULL), settings ? settings : "", printer))
		return -1;
	*id = sqlite3_last_insert_rowid(q->db);
	return 0;
}

int node_queue_add(struct node_queue *q, const char *printer, const char *name,
		   const char *file, char kind, const char *settings, int64_t *id,
		   struct st_error *err)
{
	int rc = 0;

	pthread_mutex_lock(&q->mu);
	if (insert_job(q, printer, name, file, kind, settings, false, id))
		rc = db_error(q, err, "adding a job");
	pthread_mutex_unlock(&q->mu);
	return rc;
}

int node_queue_copy(struct node_queue *q, const struct node_job *from, bool first, int64_t *id,
		    struct st_error *err)
{
	int rc = 0;

	pthread_mutex_lock(&q->mu);
	if (insert_job(q, from->printer, from->name, from->file, from->kind, from->settings, first,
		       id))
		rc = db_error(q, err, "queueing a job again");
	pthread_mutex_unlock(&q->mu);
	return rc;
}

int node_queue_next(struct node_queue *q, const char *printer, struct node_job *job,
		    struct st_error *err)
{
	return one_job(q, "SELECT " JOB_COLUMNS " FROM jobs WHERE printer=? AND "
			  "((state='paused' AND interrupted=1 AND resume=1) OR state='queued') "
			  "ORDER BY resume DESC, position, id LIMIT 1", job, err, "s", printer);
}

int node_queue_get(struct node_queue *q, int64_t id, struct node_job *job, struct st_error *err)
{
	return one_job(q, "SELECT " JOB_COLUMNS " FROM jobs WHERE id=?", job, err, "i", id);
}

int node_queue_active(struct node_queue *q, const char *printer, struct node_job *job,
		      struct st_error *err)
{
	return one_job(q, "SELECT " JOB_COLUMNS " FROM jobs WHERE printer=? AND state IN "
			  "('slicing','printing','paused') ORDER BY id DESC LIMIT 1", job, err,
		       "s", printer);
}

int node_queue_update(struct node_queue *q, const struct node_job *j, struct st_error *err)
{
	return run_locked(q, err, "updating a job",
			  "UPDATE jobs SET gcode=?, state=?, interrupted=?, resume=?, filepos=?, "
			  "size=?, error=?, started=?, finished=? WHERE id=?", "ssiiiisiii",
			  j->gcode, node_job_state_name(j->state), (int64_t)j->interrupted,
			  (int64_t)j->resume, j->filepos, j->size, j->error, j->started,
			  j->finished, j->id);
}

int node_queue_progress(struct node_queue *q, int64_t id, int64_t filepos, int64_t size)
{
	struct st_error ignored;

	return run_locked(q, &ignored, "progress", "UPDATE jobs SET filepos=?, size=? WHERE id=?",
			  "iii", filepos, size, id) ? -1 : 0;
}

int node_queue_file_busy(struct node_queue *q, const char *printer, const char *file)
{
	sqlite3_stmt *st;
	int busy = 1; /* when in doubt, do not overwrite */

	pthread_mutex_lock(&q->mu);
	st = prepare_args(q, "SELECT 1 FROM jobs WHERE printer=? AND file=? AND state "
			     "IN ('queued','slicing','printing','paused') LIMIT 1", "ss", printer,
			  file);
	if (st && sqlite3_step(st) == SQLITE_DONE)
		busy = 0;
	sqlite3_finalize(st);
	pthread_mutex_unlock(&q->mu);
	return busy;
}

/* The printers row of printer, created with its defaults when missing; q->mu held. */
static int printer_row(struct node_queue *q, const char *printer)
{
	return run(q, "INSERT OR IGNORE INTO printers(name) VALUES(?)", "s", printer);
}

/* Column 0 of sql (one parameter: the printer's name) for printer's row:
 * as text into text[cap], or as a flag into *flag.  0, or -1. */
static int printer_value(struct node_queue *q, const char *printer, const char *sql,
			 char *text, size_t cap, bool *flag)
{
	sqlite3_stmt *st;
	int rc = -1;

	pthread_mutex_lock(&q->mu);
	st = printer_row(q, printer) ? NULL : prepare_args(q, sql, "s", printer);
	if (st && sqlite3_step(st) == SQLITE_ROW) {
		if (text)
			copy_text(text, cap, sqlite3_column_text(st, 0));
		else
			*flag = sqlite3_column_int(st, 0) != 0;
		rc = 0;
	}
	sqlite3_finalize(st);
	pthread_mutex_unlock(&q->mu);
	return rc;
}

int node_queue_bed_clear(struct node_queue *q, const char *printer, bool *clear)
{
	return printer_value(q, printer, "SELECT bed_clear FROM printers WHERE name=?", NULL, 0,
			     clear);
}

int node_queue_set_bed_clear(struct node_queue *q, const char *printer, bool clear,
			     struct st_error *err)
{
	return run_locked(q, err, "bed state", "INSERT INTO printers(name, bed_clear) VALUES(?, ?) "
			  "ON CONFLICT(name) DO UPDATE SET bed_clear=excluded.bed_clear", "si",
			  printer, (int64_t)clear);
}

int node_queue_selected(struct node_queue *q, const char *printer, char *name, size_t cap)
{
	name[0] = '\0';
	return printer_value(q, printer, "SELECT selected FROM printers WHERE name=?", name, cap,
			     NULL);
}

int node_queue_set_selected(struct node_queue *q, const char *printer, const char *name,
			    struct st_error *err)
{
	return run_locked(q, err, "selecting a file", "INSERT INTO printers(name, selected) "
			  "VALUES(?, ?) ON CONFLICT(name) DO UPDATE SET selected=excluded.selected",
			  "ss", printer, name);
}

int node_queue_command_once(struct node_queue *q, const char *id, const char *printer,
			    struct st_error *err)
{
	int rc;

	pthread_mutex_lock(&q->mu);
	if (run(q, "INSERT OR IGNORE INTO commands(id, printer, received) VALUES(?, ?, ?)", "ssi",
		id, printer, (int64_t)time(NULL)))
		rc = db_error(q, err, "recording a command id");
	else
		rc = sqlite3_changes(q->db) == 1;
	pthread_mutex_unlock(&q->mu);
	return rc;
}

json_t *node_job_json(const struct node_job *j)
{
	json_t *o = json_object();

	if (!o)
		return NULL;
	json_object_set_new(o, "id", json_integer(j->id));
	json_object_set_new(o, "printer", json_string(j->printer));
	json_object_set_new(o, "name", json_string(j->name));
	json_object_set_new(o, "state", json_string(node_job_state_name(j->state)));
	json_object_set_new(o, "interrupted", json_boolean(j->interrupted));
	json_object_set_new(o, "sliced", json_boolean(j->kind == 'm' && j->gcode[0]));
	json_object_set_new(o, "filepos", json_integer(j->filepos));
	json_object_set_new(o, "size", json_integer(j->size));
	json_object_set_new(o, "error", j->error[0] ? json_string(j->error) : json_null());
	json_object_set_new(o, "created", json_integer(j->created));
	json_object_set_new(o, "started", j->started ? json_integer(j->started) : json_null());
	json_object_set_new(o, "finished", j->finished ? json_integer(j->finished) : json_null());
	json_object_set_new(o, "settings",
			    j->settings[0] ? json_loads(j->settings, 0, NULL) : json_array());
	return o;
}

/* The jobs of printer that sql (parameters: the printer, a limit) selects,
 * as JSON; with numbered, each with its "position" (1, 2, ...). */
static json_t *job_list(struct node_queue *q, const char *sql, const char *printer, int limit,
			bool numbered)
{
	json_t *arr = json_array();
	sqlite3_stmt *st;
	struct node_job j;

	if (!arr)
		return NULL;
	pthread_mutex_lock(&q->mu);
	st = prepare_args(q, sql, "si", printer, (int64_t)limit);
	while (st && sqlite3_step(st) == SQLITE_ROW) {
		json_t *o;

		row_to_job(st, &j);
		o = node_job_json(&j);
		if (numbered)
			json_object_set_new(o, "position", json_integer((json_int_t)json_array_size(arr) + 1));
		json_array_append_new(arr, o);
	}
	sqlite3_finalize(st);
	pthread_mutex_unlock(&q->mu);
	return arr;
}

json_t *node_queue_list(struct node_queue *q, const char *printer, int limit)
{
	return job_list(q, "SELECT " JOB_COLUMNS " FROM jobs WHERE printer=? ORDER BY id DESC "
			   "LIMIT ?", printer, limit, false);
}

/* The ids of printer's queued jobs in the order the worker takes them, into
 * ids (cap); their count, -2 when more than cap wait, or -1.  q->mu held. */
static int queued_ids(struct node_queue *q, const char *printer, int64_t *ids, int cap)
{
	sqlite3_stmt *st;
	int n = 0, rc;

	st = prepare_args(q, "SELECT id FROM jobs WHERE printer=? AND state='queued' "
			     "ORDER BY position, id", "s", printer);
	if (!st)
		return -1;
	while ((rc = sqlite3_step(st)) == SQLITE_ROW && n < cap)
		ids[n++] = sqlite3_column_int64(st, 0);
	sqlite3_finalize(st);
	return rc == SQLITE_ROW ? -2 : rc == SQLITE_DONE ? n : -1;
}

int node_queue_move(struct node_queue *q, const char *printer, int64_t id, int64_t to,
		    struct st_error *err)
{
	int64_t ids[NODE_QUEUE_MAX];
	int n, at = -1, rc = 1;

	pthread_mutex_lock(&q->mu);
	n = queued_ids(q, printer, ids, NODE_QUEUE_MAX);
	for (int i = 0; i < n; i++)
		if (ids[i] == id)
			at = i;
	if (n == -2) {
		rc = st_error_set(err, ST_ERR_RANGE, "more than %d jobs wait; a job can be moved "
				  "in a queue of at most %d", NODE_QUEUE_MAX, NODE_QUEUE_MAX);
		goto out;
	}
	if (n < 0) {
		rc = db_error(q, err, "reading the queue");
		goto out;
	}
	if (at < 0) {
		rc = 0;
		goto out;
	}
	/* to is 1-based; past the end is the end */
	to = to > n ? n : to;
	memmove(&ids[at], &ids[at + 1], sizeof(ids[0]) * (size_t)(n - at - 1));
	memmove(&ids[to], &ids[to - 1], sizeof(ids[0]) * (size_t)(n - to));
	ids[to - 1] = id;
	if (run(q, "BEGIN IMMEDIATE", "")) {
		rc = db_error(q, err, "reordering the queue");
		goto out;
	}
	for (int i = 0; i < n && rc == 1; i++)
		if (run(q, "UPDATE jobs SET position=? WHERE id=?", "ii", (int64_t)i + 1, ids[i]))
			rc = db_error(q, err, "reordering the queue");
	if (rc == 1 && run(q, "COMMIT", ""))
		rc = db_error(q, err, "reordering the queue");
	if (rc != 1)
		run(q, "ROLLBACK", "");
out:
	pthread_mutex_unlock(&q->mu);
	return rc;
}

json_t *node_queue_waiting(struct node_queue *q, const char *printer)
{
	return job_list(q, "SELECT " JOB_COLUMNS " FROM jobs WHERE printer=? AND state='queued' "
			   "ORDER BY position, id LIMIT ?", printer, NODE_QUEUE_MAX, true);
}

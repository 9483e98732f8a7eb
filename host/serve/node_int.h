/*
 * node_int.h - private to host/serve/: the node's parts (queue, workers,
 * HTTP) and how they share state.  Nothing outside host/serve/ includes it.
 *
 * Locks, taken in this order only: node_printer.mu, then the print ctl's
 * mu; the queue has its own mutex and is never called with ctl.mu held.
 */
#ifndef STRATUM_HOST_SERVE_NODE_INT_H
#define STRATUM_HOST_SERVE_NODE_INT_H

#include <jansson.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>
#include <time.h>

#include "node.h"
#include "print.h"
#include "profile.h"
#include "st_file.h"

/* Job states, as stored and as the API names them. */
enum node_job_state {
	NODE_JOB_QUEUED = 0,
	NODE_JOB_SLICING,
	NODE_JOB_PRINTING,
	NODE_JOB_PAUSED,
	NODE_JOB_DONE,
	NODE_JOB_FAILED,
	NODE_JOB_CANCELLED,
	NODE_JOB_STATES
};

const char *node_job_state_name(enum node_job_state s);

/* One row of the queue. */
#define NODE_SETTINGS_MAX 4096 /* a job's per-job settings as JSON, NUL included */

struct node_job {
	int64_t id;
	char printer[NODE_NAME_MAX];
	char name[NODE_FILE_NAME_MAX + 1]; /* the uploaded file's name */
	char file[NODE_PATH_MAX];	   /* the stored upload */
	char gcode[NODE_PATH_MAX];	   /* what is printed: file, or the sliced output ("" before) */
	char kind;			   /* 'g' G-code, 'm' model to slice, 'x' X3G */
	/* per-job settings of an uploaded model, a JSON array of [field, value]
	 * pairs as the upload's form gave them ("" for none; docs/serve.md) */
	char settings[NODE_SETTINGS_MAX];
	enum node_job_state state;
	bool interrupted; /* the node died or stopped while it printed */
	bool resume;	  /* an operator asked to resume the interrupted print */
	int64_t filepos, size; /* bytes printed, bytes of gcode */
	char error[256];
	int64_t created, started, finished; /* Unix time, s; 0 = not yet */
	int64_t position; /* order among the printer's queued jobs (lower first) */
};

#define NODE_QUEUE_MAX 1000 /* queued jobs listed, and a queue that can be reordered */

struct node_queue;

/* node_queue_open - open or create the database at path (WAL). */
int node_queue_open(const char *path, struct node_queue **out, struct st_error *err);
void node_queue_close(struct node_queue *q);

/*
 * node_queue_recover - after a start: printing/paused jobs become paused and
 * interrupted (never restarted on their own), slicing jobs queued again.
 * Counts in *interrupted and *requeued.
 */
int node_queue_recover(struct node_queue *q, int *interrupted, int *requeued,
		       struct st_error *err);

/* node_queue_add - a new queued job with its per-job settings (NULL or
 * "": none); *id its number. */
int node_queue_add(struct node_queue *q, const char *printer, const char *name,
		   const char *file, char kind, const char *settings, int64_t *id,
		   struct st_error *err);

/* node_queue_copy - a new queued job of from's printer, file, name, kind
 * and settings (requeue, restart): last in the queue, or ahead of every
 * queued job with first.  *id its number. */
int node_queue_copy(struct node_queue *q, const struct node_job *from, bool first, int64_t *id,
		    struct st_error *err);

/*
 * node_queue_move - move printer's queued job id to position to (1-based;
 * past the end is the end) of its queued jobs.  Returns 1, 0 when id is no
 * queued job of printer, ST_ERR_RANGE (more than NODE_QUEUE_MAX queued) or
 * ST_ERR_IO.
 */
int node_queue_move(struct node_queue *q, const char *printer, int64_t id, int64_t to,
		    struct st_error *err);

/* node_queue_waiting - printer's queued jobs in the order they will print
 * (at most NODE_QUEUE_MAX), each /api/stratum/queue entry with its
 * "position" (from 1), as JSON. */
json_t *node_queue_waiting(struct node_queue *q, const char *printer);

/*
 * node_queue_next - the job printer's worker should take: an interrupted job
 * an operator resumed, else the oldest queued one.  Returns 1 with *job, 0
 * when none, or a negative class.
 */
int node_queue_next(struct node_queue *q, const char *printer, struct node_job *job,
		    struct st_error *err);

/* node_queue_get - job number id; 1 found, 0 not, negative on error. */
int node_queue_get(struct node_queue *q, int64_t id, struct node_job *job, struct st_error *err);

/*
 * node_queue_active - printer's newest job in slicing, printing or paused
 * (an interrupted print counts); 1 found, 0 none, negative on error.
 */
int node_queue_active(struct node_queue *q, const char *printer, struct node_job *job,
		      struct st_error *err);

/* node_queue_update - write back the mutable fields of job. */
int node_queue_update(struct node_queue *q, const struct node_job *job, struct st_error *err);

/* node_queue_progress - store the print position of job id (cheap, often). */
int node_queue_progress(struct node_queue *q, int64_t id, int64_t filepos, int64_t size);

/* node_queue_file_busy - 1 when an unfinished job of printer uses file. */
int node_queue_file_busy(struct node_queue *q, const char *printer, const char *file);

/* Per printer: is the bed clear for the next job, and the selected file. */
int node_queue_bed_clear(struct node_queue *q, const char *printer, bool *clear);
int node_queue_set_bed_clear(struct node_queue *q, const char *printer, bool clear,
			     struct st_error *err);
int node_queue_selected(struct node_queue *q, const char *printer, char *name, size_t cap);
int node_queue_set_selected(struct node_queue *q, const char *printer, const char *name,
			    struct st_error *err);

/*
 * node_queue_command_once - record command id (MQTT) as received, durably.
 * Returns 1 the first time, 0 when id was seen before (a re-delivery: do
 * not run it again), or a negative class.
 */
int node_queue_command_once(struct node_queue *q, const char *id, const char *printer,
			    struct st_error *err);

/* node_queue_list - printer's jobs, newest first, at most limit, as JSON. */
json_t *node_queue_list(struct node_queue *q, const char *printer, int limit);

/* node_job_json - one job as the /api/stratum/queue entry. */
json_t *node_job_json(const struct node_job *job);

/* What a G-code file says of itself (gcinfo.c), kept per printer. */
struct node_gcode_mark {
	int64_t pos;   /* byte offset of an M73 line with R */
	double left_s; /* its R, in seconds */
};

struct node_gcode_info {
	char path[NODE_PATH_MAX]; /* the file read, "" none */
	int64_t mtime, size;	  /* its stat when read */
	double time_s;		  /* the slicer's print-time estimate, s; -1 unknown */
	double filament_mm, filament_cm3; /* filament of the print; -1 unknown */
	struct node_gcode_mark *marks;
	size_t nmarks;
};

struct node_gcode_estimate {
	double time_s, filament_mm, filament_cm3; /* as in node_gcode_info */
	double left_s; /* by the last M73 R before the byte asked for; -1 none */
};

/* One temperature sample of a printer's history (/api/printer?history). */
struct node_temp_sample {
	int64_t time;		/* Unix time, s */
	double tool[2], bed[2]; /* actual, target, degC */
	double tool1[2];	/* a second extruder's, NAN unknown */
};

#define NODE_TEMP_HISTORY 600 /* samples kept: 20 min at one per NODE_TEMP_EVERY ticks */
#define NODE_TEMP_EVERY 4     /* ticks (NODE_TICK_MS) between samples: 2 s, as OctoPrint polls */

#define NODE_CMD_QUEUE 16 /* printer commands waiting for an idle printer */
#define NODE_CMD_MAX 257 /* one command line with its NUL (serial/gcode.h GCODE_LINE_MAX) */

/*
 * The model a printer's worker slices, as the push API reports it
 * (slicingProgress and the Slicing* events, push.c).  The worker publishes
 * its progress at start, at most every NODE_SLICING_EVERY_MS, and at the
 * end; each client sends what it has not seen.  Under node_printer.slice_mu.
 */
#define NODE_SLICING_EVERY_MS 500

enum node_slicing_state {
	NODE_SLICING_NONE, /* nothing sliced since the node started */
	NODE_SLICING_RUNNING,
	NODE_SLICING_DONE,
	NODE_SLICING_FAILED,
};

struct node_slicing {
	unsigned gen;	/* bumped when a model starts being sliced */
	unsigned seq;	/* bumped each time percent or state is published */
	enum node_slicing_state state;
	char source[NODE_FILE_NAME_MAX + 1]; /* the model, as the printer's files name it */
	char dest[NODE_FILE_NAME_MAX + 1];   /* the G-code it becomes */
	double percent;			     /* published, 0..100 */
	double elapsed_s;		     /* DONE and FAILED: the time it took */
	char reason[256];		     /* FAILED: why */
	/* the worker's own: the whole job's fraction so far, and when it
	 * started and last published (monotonic ms) */
	double fraction;
	int64_t t0_ms, published_ms;
};

/* A printer and its worker. */
struct node_printer {
	struct node *node;
	const struct node_printer_config *cfg;
	struct profile *prof;
	char files_dir[NODE_PATH_MAX]; /* uploads of this printer */

	pthread_t thread;
	bool thread_started;
	pthread_mutex_t mu; /* the fields below */
	pthread_cond_t cv;  /* wakes the worker */
	bool stop;
	bool want_connect, want_disconnect;
	bool connected;
	char conn_error[256]; /* why the last connect failed, "" if it did not */
	char link_desc[128];  /* what is connected (firmware; simulated or not) */
	int64_t job_id;	      /* the job the worker is on, 0 when idle */
	bool job_printing;    /* job_id is at the print step */
	bool job_x3g;	      /* and prints an X3G file: no line goes in between */
	char cmds[NODE_CMD_QUEUE][NODE_CMD_MAX];
	int ncmds;

	struct node_link *link; /* the worker's alone */
	struct node_print_ctl ctl;

	atomic_uint files_version; /* bumped when its stored files change (push events) */

	/* temperature history, a ring written by the ticker, under ctl.mu */
	struct node_temp_sample temps[NODE_TEMP_HISTORY];
	size_t ntemps, temps_next; /* samples held; where the next goes */

	pthread_mutex_t gc_mu;	 /* gc, the last G-code file read (gcinfo.c) */
	struct node_gcode_info gc;

	pthread_mutex_t slice_mu; /* slicing (worker.c writes, push.c reads) */
	struct node_slicing slicing;
};

/*
 * node_gcode_estimate - what the G-code file path (NULL or "": none; not
 * G-code: nothing known) says of its print time and filament, and the time
 * left at byte filepos by its M73 R marks.  Reads the file the first time
 * it is asked for (or after it changed), under p->gc_mu; any thread.
 */
void node_gcode_estimate(struct node_printer *p, const char *path, int64_t filepos,
			 struct node_gcode_estimate *out);
/* node_gcode_summary - the estimate and filament of the G-code file path
 * (left_s -1), from its first 64 KiB and last 256 KiB only; no cache. */
void node_gcode_summary(const char *path, struct node_gcode_estimate *out);
/* node_gcode_moved - whether the G-code file path has a command that moves
 * the machine (motion, homing, probing, tool change, user wait) starting
 * before byte upto (what the printer confirmed of a job) or among its first
 * commands sent (lines with a command; what it may run besides).  True when
 * the file cannot be read as G-code (X3G, gone): when in doubt, it moved. */
bool node_gcode_moved(const char *path, int64_t upto, int64_t commands);
/* node_gcode_info_free - what node_gcode_estimate kept. */
void node_gcode_info_free(struct node_gcode_info *g);

struct MHD_Daemon;

struct node {
	struct node_config cfg;
	struct node_queue *q;
	char tmp_dir[NODE_PATH_MAX];	/* upload temp files, same file system */
	char sliced_dir[NODE_PATH_MAX]; /* G-code sliced from uploaded models */
	struct node_printer printers[NODE_MAX_PRINTERS];
	size_t nprinters;
	struct MHD_Daemon *httpd;
	uint16_t port;
	/* HTTP connections admitted and not yet closed (http.c). */
	atomic_uint http_connections;
	/* The header and body bounds' watchdog (http_deadline.c). */
	struct http_deadlines *deadlines;
	bool started, stopped;
	/* The ticker stores each print's position every NODE_TICK_MS. */
	pthread_t ticker;
	bool ticker_started, ticker_stop;
	pthread_mutex_t tick_mu;
	pthread_cond_t tick_cv;
	struct node_mqtt *mqtt; /* NULL without [mqtt] */
	/* push API clients (push.c), each on its own detached thread */
	pthread_mutex_t push_mu;
	pthread_cond_t push_cv; /* npush went down */
	int npush;
	bool push_stop;
};

#define NODE_TICK_MS 500

/* node_log - one record to the sink (log.c); printer NULL and job 0 omit. */
void node_log(const char *level, const char *printer, int64_t job, const char *fmt, ...)
	__attribute__((format(printf, 4, 5)));

/* worker.c: the printer's thread, and waking it after a change. */
void *node_worker_main(void *printer);
void node_printer_wake(struct node_printer *p);

/*
 * control.c: shared by the HTTP API and MQTT.  node_control_job - cmd
 * "cancel" or "pause" (action pause, resume or toggle; NULL = toggle) on
 * p's active job.  Returns 0, ST_ERR_RANGE (no job, or not in a state for
 * it: HTTP 409), ST_ERR_ARG (bad command or action: 400), ST_ERR_IO.
 */
int node_control_job(struct node *n, struct node_printer *p, const char *cmd,
		     const char *action, struct st_error *err);

/*
 * node_control_restart - OctoPrint's "restart": p's paused job (paused by
 * an operator, or interrupted) is cancelled and its file queued again ahead
 * of every queued job, *id the new job.  It prints from the start once the
 * bed is confirmed clear, as every job after a print does.  Returns 0,
 * ST_ERR_RANGE (no paused job, printer offline, file gone: HTTP 409),
 * ST_ERR_IO.
 */
int node_control_restart(struct node *n, struct node_printer *p, int64_t *id,
			 struct st_error *err);

/*
 * node_control_cancel - cancel p's job id: a queued one ends at once (it
 * never started), an active one as node_control_job's cancel.  Returns 0,
 * ST_ERR_RANGE (no such job, or finished: HTTP 409), ST_ERR_IO.
 */
int node_control_cancel(struct node *n, struct node_printer *p, int64_t id, struct st_error *err);

/*
 * node_control_move - move p's queued job id to position to (1: the next to
 * print; past the end is the end).  Returns 0, ST_ERR_ARG (to below 1:
 * HTTP 400), ST_ERR_RANGE (no queued job id of p, or a queue too long to
 * reorder: HTTP 409), ST_ERR_IO.
 */
int node_control_move(struct node *n, struct node_printer *p, int64_t id, int64_t to,
		      struct st_error *err);

/*
 * node_control_requeue - queue p's finished job id (done, failed or
 * cancelled) again, last in the queue, as a new job *out with the same file
 * (as it is now) and settings.  Returns 0, ST_ERR_RANGE (not finished, no
 * such job, file gone: HTTP 409), ST_ERR_IO.
 */
int node_control_requeue(struct node *n, struct node_printer *p, int64_t id, int64_t *out,
			 struct st_error *err);

/*
 * node_store_file - publish the finished temporary file tmp (st_file_finish
 * done; same file system) as p's file rel (checked by the caller), select
 * it and, with print, queue it (*id the job, else 0).  tmp is consumed when
 * the file is stored; on an error before that it stays the caller's.  G-code
 * sliced for another printer or leaving its bed (host/guard.h) is refused
 * unless force.  settings (NULL or "": none) go with the queued job
 * (node_job.settings, checked by the caller with node_settings_profile).
 * Returns 0, ST_ERR_RANGE (a queued or running job uses that file, or the
 * guard refused it: 409), ST_ERR_ARG, ST_ERR_IO.
 */
int node_store_file(struct node *n, struct node_printer *p, struct st_file_out *tmp, const char *rel,
		    bool select, bool print, bool force, const char *settings, int64_t *id,
		    struct st_error *err);

/*
 * node_settings_profile - p's profile under a job's per-job settings (the
 * JSON of node_job.settings), read by the same options parser as `stratum
 * slice --set` (host/cfgopt.h).  *out is new (profile_free).  Returns 0, or
 * ST_ERR_ARG/ST_ERR_RANGE/ST_ERR_PARSE with err naming the field.
 */
int node_settings_profile(const struct node_printer *p, const char *settings,
			  struct profile **out, struct st_error *err);

/*
 * node_check_kind - whether p takes a file called name: G-code and models
 * always, X3G only with a `protocol = sailfish` profile.  Returns 0 or
 * ST_ERR_UNSUPPORTED with the reason (HTTP 415).
 */
int node_check_kind(const struct node_printer *p, const char *name, struct st_error *err);

/*
 * auth.c.  node_key_roles - the roles of the config's key whose secret is
 * key (0 for none; *who its [key NAME], else NULL), compared in constant time.
 */
unsigned node_key_roles(const struct node_config *cfg, const char *key, const char **who);

/* A signed MQTT command's "time" is taken this many seconds either way. */
#define NODE_MQTT_SIGNED_WINDOW_S 300

/*
 * node_mqtt_authorize - whether the command payload that came on topic may
 * run: a JSON object with "key" (a key with the control role), or the signed
 * form {"signed": TEXT, "by": KEY_NAME, "hmac": HEX}, HEX the HMAC-SHA256 of
 * topic "\n" TEXT with that key, TEXT the command with "time" (Unix seconds,
 * within NODE_MQTT_SIGNED_WINDOW_S of now).  *cmd is the command object (new
 * reference; NULL when it is not JSON) even when refused, for the id of the
 * answer; *who the key's name.  Returns 0, or ST_ERR_PARSE, ST_ERR_ARG,
 * ST_ERR_RANGE (no key, a wrong one, no control role, stale) with err,
 * which never holds the key.
 */
int node_mqtt_authorize(const struct node *n, const char *topic, const char *payload, time_t now,
			json_t **cmd, const char **who, struct st_error *err);

/*
 * node_mqtt_url_allowed - whether an MQTT enqueue may download url: http or
 * https from a host of c->download_hosts ("host" for the scheme's port,
 * "host:port").  Returns 0, ST_ERR_ARG (not an http(s) URL) or ST_ERR_RANGE
 * (downloads off, or the host not listed) with err.
 */
int node_mqtt_url_allowed(const struct node_mqtt_config *c, const char *url,
			  struct st_error *err);

/* mqtt.c: started and stopped with the node; does nothing without [mqtt]. */
struct node_mqtt;
int node_mqtt_start(struct node *n, struct st_error *err);
void node_mqtt_stop(struct node *n);
/* node_mqtt_listening - the HTTP server listens on port: announce the
 * node's info (its URL, printers and profiles) on the broker. */
void node_mqtt_listening(struct node *n, uint16_t port);

/* http.c; node_printer_json - p's state, temperatures, progress, job and
 * its newest queue_limit jobs (0: no queue), for /api/stratum/node and MQTT. */
json_t *node_printer_json(struct node *n, struct node_printer *p, int queue_limit);

/* The script both pages begin with (page.c, farm_page.c): the API key from
 * the address (#key= or ?key=), a new element with its text, and a result
 * said to the operator in the page's #msg. */
#define PAGE_SCRIPT_BASICS \
	"function fromAddress() {\n" \
	"  var m = /[#&?]key=([^&]*)/.exec(location.hash + '&' + location.search);\n" \
	"  return m ? decodeURIComponent(m[1]) : '';\n" \
	"}\n" \
	"function el(tag, text, cls) {\n" \
	"  var e = document.createElement(tag);\n" \
	"  if (text) e.textContent = text;\n" \
	"  if (cls) e.className = cls;\n" \
	"  return e;\n" \
	"}\n" \
	"function say(text, ok) {\n" \
	"  var m = document.getElementById('msg');\n" \
	"  m.textContent = text;\n" \
	"  m.className = ok ? 'ok' : '';\n" \
	"}\n"

/* page.c: the status page served at GET / (HTML with its script). */
extern const char node_status_page[];

/* http.c */
int node_http_start(struct node *n, struct st_error *err);
void node_http_stop(struct node *n);

#endif /* STRATUM_HOST_SERVE_NODE_INT_H */

/*
 * mqtt.c - the node on an MQTT broker (libmosquitto; docs/serve.md "MQTT"),
 * when the config has an [mqtt] section.  Under ROOT/NODE/ (ROOT = the
 * `topic` key, default "stratum"):
 *   status                      "online", or "offline" (the last will)
 *   info                        {"url", "printers": [{"name", "profile", "prefix"}]}
 *   PRINTER/status              OctoPrint's state text
 *   PRINTER/temperatures        as /api/printer's temperature: {"tool0":{"actual",
 *                               "target","offset"},"tool1" (second extruder),"bed"}
 *   PRINTER/progress            {"completion","filepos","size"}
 *   PRINTER/job                 the active job as /api/stratum/queue has it, or null
 *   PRINTER/queue               the queued jobs in order, with their positions
 *   PRINTER/bed_clear           true, or false while the bed waits for an operator
 * all retained and published when they change.  Commands arrive on
 * PRINTER/cmd as JSON {"id", "command": enqueue|cancel|pause|resume, "url",
 * "name"}, or the queue's list|move|cancel|requeue {"job", "position"} as
 * /api/stratum/queue has them, with a key with the control role, or signed
 * with one (auth.c);
 * each id is recorded in the queue database before the command runs, so a
 * re-delivered command (QoS 1, a client that sends twice) runs once.  The
 * answer goes to PRINTER/result.  G-code never travels over MQTT: enqueue
 * downloads the file from url (libcurl: http and https, from the hosts of
 * download_hosts only, each redirect checked); "force": true takes G-code
 * sliced for another printer (host/guard.h).  The node's name on the broker
 * (one node per name; ping and pong) is mqtt_name.c's.
 *
 * Threads: libmosquitto's network thread only queues commands; the node's
 * MQTT thread runs them (a download may take a while) and publishes state.
 */
#include <curl/curl.h>
#include <errno.h>
#include <fcntl.h>
#include <mosquitto.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "mqtt_int.h"

#define MQTT_TICK_MS 500	  /* state publishing period */
#define MQTT_PENDING 32		  /* commands waiting to run */
#define MQTT_PAYLOAD_MAX 4096	  /* largest command accepted, bytes */
#define MQTT_ID_MAX 128		  /* longest command id, bytes */
#define MQTT_DOWNLOAD_S 600	  /* longest download */
#define MQTT_REDIRECTS 5	  /* redirects an enqueue download follows */
#define MQTT_RETRY_MAX_S 30	  /* longest wait between two tries to reach the broker */
#define MQTT_COMMANDS "enqueue, cancel, pause, resume, list, move or requeue"

const char *const node_mqtt_state_topics[MQTT_TOPICS] = {
	"status", "temperatures", "progress", "job", "queue", "bed_clear"};

struct node_mqtt {
	struct node *n;
	struct mosquitto *mosq;
	char base[256]; /* ROOT/NODE */
	pthread_t thread;
	bool thread_started, loop_started;
	time_t since;	   /* when the node started, for its answer to a ping */
	atomic_bool stopping; /* node_mqtt_stop began: cuts a name check short */
	pthread_mutex_t mu; /* the fields below */
	pthread_cond_t cv;
	bool stop, connected, republish;
	bool off; /* another node took the name: no more connecting */
	uint16_t http_port; /* the node's HTTP port once it listens (for info), else 0 */
	struct {
		size_t printer;
		char *payload;
	} pending[MQTT_PENDING];
	int npending;
	char *last[NODE_MAX_PRINTERS][MQTT_TOPICS]; /* last published; the MQTT thread's */
};

static void on_connect(struct mosquitto *mosq, void *ctx, int rc)
{
	struct node_mqtt *m = ctx;
	char topic[300];

	if (rc) {
		node_log("error", NULL, 0, "mqtt: the broker refused the connection: %s",
			 mosquitto_connack_string(rc));
		return;
	}
	snprintf(topic, sizeof(topic), "%s/+/cmd", m->base);
	mosquitto_subscribe(mosq, NULL, topic, 1);
	snprintf(topic, sizeof(topic), "%s/ping", m->base);
	mosquitto_subscribe(mosq, NULL, topic, 0); /* answered only while connected */
	snprintf(topic, sizeof(topic), "%s/status", m->base);
	mosquitto_publish(mosq, NULL, topic, 6, "online", 1, true);
	pthread_mutex_lock(&m->mu);
	m->connected = m->republish = true;
	pthread_cond_signal(&m->cv);
	pthread_mutex_unlock(&m->mu);
	node_log("info", NULL, 0, "mqtt: connected to %s:%u as %s, topics under %s/",
		 m->n->cfg.mqtt.host, m->n->cfg.mqtt.port, m->n->cfg.mqtt.client_id, m->base);
}

/* A lost connection: before libmosquitto reconnects with the node's client
 * id, check that no other node took the name meanwhile (two nodes of one
 * name started together, or one started while this one was away). */
static void on_disconnect(struct mosquitto *mosq, void *ctx, int rc)
{
	struct node_mqtt *m = ctx;
	struct st_error err = {0};
	int cancel_state;
	bool held;

	pthread_mutex_lock(&m->mu);
	m->connected = false;
	pthread_mutex_unlock(&m->mu);
	if (!rc || atomic_load(&m->stopping))
		return;
	node_log("warning", NULL, 0, "mqtt: connection lost (%s); reconnecting",
		 mosquitto_strerror(rc));
	/* node_mqtt_stop cancels this thread: not in the middle of the check
	 * (which sees stopping and ends within 0.1 s). */
	pthread_setcancelstate(PTHREAD_CANCEL_DISABLE, &cancel_state);
	node_mqtt_claim(&m->n->cfg, &m->stopping, &held, &err);
	pthread_setcancelstate(cancel_state, NULL);
	if (held) {
		node_log("error", NULL, 0, "%s; MQTT is off until the node restarts", err.msg);
		pthread_mutex_lock(&m->mu);
		m->off = true;
		pthread_mutex_unlock(&m->mu);
		mosquitto_disconnect(mosq); /* ends libmosquitto's reconnecting */
	}
}

/* Queue a command for the MQTT thread (the network thread must not block). */
static void on_message(struct mosquitto *mosq, void *ctx, const struct mosquitto_message *msg)
{
	struct node_mqtt *m = ctx;
	size_t blen = strlen(m->base), i;
	const char *rest;
	char *copy;

	if (strncmp(msg->topic, m->base, blen) || msg->topic[blen] != '/')
		return;
	rest = msg->topic + blen + 1;
	if (!strcmp(rest, "ping")) {
		node_log("warning", NULL, 0, "mqtt: a node asked whether the name %s is held on "
					     "the broker (one starting with this node's name?); "
					     "answered", m->n->cfg.name);
		node_mqtt_pong(mosq, m->base, msg, m->since);
		return;
	}
	for (i = 0; i < m->n->nprinters; i++) {
		size_t pl = strlen(m->n->printers[i].cfg->name);

		if (!strncmp(rest, m->n->printers[i].cfg->name, pl) && !strcmp(rest + pl, "/cmd"))
			break;
	}
	if (i == m->n->nprinters) {
		node_log("warning", NULL, 0, "mqtt: %.200s: no such printer on this node",
			 msg->topic);
		return;
	}
	if (msg->payloadlen <= 0 || msg->payloadlen > MQTT_PAYLOAD_MAX) {
		node_log("warning", m->n->printers[i].cfg->name, 0, "mqtt: a command of %d bytes "
			 "was dropped (1 to %d)", msg->payloadlen, MQTT_PAYLOAD_MAX);
		return;
	}
	copy = malloc((size_t)msg->payloadlen + 1);
	if (!copy)
		return;
	memcpy(copy, msg->payload, (size_t)msg->payloadlen);
	copy[msg->payloadlen] = '\0';
	pthread_mutex_lock(&m->mu);
	if (m->npending == MQTT_PENDING) {
		free(copy);
		node_log("warning", m->n->printers[i].cfg->name, 0, "mqtt: too many commands "
			 "waiting; one was dropped");
	} else {
		m->pending[m->npending].printer = i;
		m->pending[m->npending++].payload = copy;
		pthread_cond_signal(&m->cv);
	}
	pthread_mutex_unlock(&m->mu);
}

/* Publish text (retained) under base/printer/what. */
static void publish(struct node_mqtt *m, const char *printer, const char *what, const char *text,
		    bool retain)
{
	char topic[400];

	snprintf(topic, sizeof(topic), "%s/%s/%s", m->base, printer, what);
	mosquitto_publish(m->mosq, NULL, topic, (int)strlen(text), text, 1, retain);
}

/* What a download writes to, with the size limit. */
struct download {
	FILE *f;
	uint64_t bytes, max;
	bool too_big, write_failed;
};

static size_t download_write(char *data, size_t size, size_t nmemb, void *ctx)
{
	struct download *d = ctx;
	size_t n = size * nmemb;

	if (d->bytes + n > d->max) {
		d->too_big = true;
		return 0;
	}
	if (n && fwrite(data, 1, n, d->f) != n) {
		d->write_failed = true;
		return 0;
	}
	d->bytes += n;
	return n;
}

/* The file name a URL ends in ("http://h/a/b.gcode?x" -> "b.gcode"). */
static void name_of_url(const char *url, char *out, size_t cap)
{
	const char *end = url + strcspn(url, "?#"), *s = end;

	while (s > url && s[-1] != '/')
		s--;
	snprintf(out, cap, "%.*s", (int)(end - s), s);
}

/* One request of a download, redirects not followed: 0 with *status, or
 * ST_ERR_* with err.  A redirect's target goes to *next (free it). */
static int fetch_once(CURL *c, const char *url, struct download *d, long *status, char **next,
		      struct st_error *err)
{
	char curl_err[CURL_ERROR_SIZE] = "";
	char *location = NULL;
	CURLcode cc;

	curl_easy_setopt(c, CURLOPT_URL, url);
	curl_easy_setopt(c, CURLOPT_ERRORBUFFER, curl_err);
	cc = curl_easy_perform(c);
	*status = 0;
	*next = NULL;
	curl_easy_getinfo(c, CURLINFO_RESPONSE_CODE, status);
	if (cc == CURLE_OK && *status / 100 == 3 &&
	    curl_easy_getinfo(c, CURLINFO_REDIRECT_URL, &location) == CURLE_OK && location)
		*next = strdup(location);
	if (cc == CURLE_OK)
		return 0;
	if (d->too_big || cc == CURLE_FILESIZE_EXCEEDED)
		return st_error_set(err, ST_ERR_RANGE, "the file is larger than the node's limit "
						       "of %llu bytes", (unsigned long long)d->max);
	if (d->write_failed)
		return st_error_set(err, ST_ERR_IO, "cannot store the download: %s",
				    strerror(errno));
	return st_error_set(err, ST_ERR_IO, "download failed: %s",
			    curl_err[0] ? curl_err : curl_easy_strerror(cc));
}

/* Download url into a finished temporary file out (st_file.h): only from
 * the hosts of download_hosts, each redirect's target checked before it is
 * followed (libcurl would follow it anywhere). */
static int download(struct node *n, const char *url, struct st_file_out *out,
		    struct st_error *err)
{
	struct download d = {.max = n->cfg.max_upload};
	char *at = strdup(url), *next = NULL;
	CURL *c;
	long status = 0;
	int rc = 0, hops;

	if (!at)
		return st_error_set(err, ST_ERR_NOMEM, "out of memory");
	if ((rc = node_mqtt_url_allowed(&n->cfg.mqtt, url, err))) {
		free(at);
		return rc;
	}
	if (st_file_begin_temp(out, n->tmp_dir, "mqtt", NULL)) {
		free(at);
		return st_error_set(err, ST_ERR_IO, "%s/mqtt-XXXXXX: %s", n->tmp_dir,
				    strerror(errno));
	}
	d.f = out->f;
	c = curl_easy_init();
	if (!c) {
		free(at);
		st_file_abort(out);
		return st_error_set(err, ST_ERR_NOMEM, "cannot start a download");
	}
	curl_easy_setopt(c, CURLOPT_PROTOCOLS_STR, "http,https");
	curl_easy_setopt(c, CURLOPT_FOLLOWLOCATION, 0L);
	curl_easy_setopt(c, CURLOPT_TIMEOUT, (long)MQTT_DOWNLOAD_S);
	curl_easy_setopt(c, CURLOPT_NOSIGNAL, 1L);
	curl_easy_setopt(c, CURLOPT_MAXFILESIZE_LARGE, (curl_off_t)d.max);
	curl_easy_setopt(c, CURLOPT_WRITEFUNCTION, download_write);
	curl_easy_setopt(c, CURLOPT_WRITEDATA, &d);
	curl_easy_setopt(c, CURLOPT_USERAGENT, "stratum-node");
	for (hops = 0; !rc; hops++) {
		/* a redirect's own body is not the file */
		fflush(d.f);
		if (ftruncate(fileno(d.f), 0) || fseek(d.f, 0, SEEK_SET))
			rc = st_error_set(err, ST_ERR_IO, "cannot store the download: %s",
					  strerror(errno));
		d.bytes = 0;
		if (rc || (rc = fetch_once(c, at, &d, &status, &next, err)) || !next)
			break;
		free(at);
		at = next;
		if (hops == MQTT_REDIRECTS)
			rc = st_error_set(err, ST_ERR_IO, "download failed: more than %d redirects",
					  MQTT_REDIRECTS);
		else if ((rc = node_mqtt_url_allowed(&n->cfg.mqtt, at, err)))
			st_error_set(err, rc, "redirected to %.200s: %s", at, err->msg);
	}
	curl_easy_cleanup(c);
	free(at);
	if (!rc && status != 200)
		rc = st_error_set(err, ST_ERR_IO, "the server answered HTTP %ld", status);
	if (!rc && st_file_finish(out, NULL))
		rc = st_error_set(err, ST_ERR_IO, "cannot store the download: %s", strerror(errno));
	if (rc)
		st_file_abort(out);
	return rc;
}

/* enqueue: fetch url and queue it like an upload with print=true. */
static int cmd_enqueue(struct node *n, struct node_printer *p, json_t *o, int64_t *job,
		       struct st_error *err)
{
	const char *url = json_string_value(json_object_get(o, "url"));
	const char *name = json_string_value(json_object_get(o, "name"));
	char fname[NODE_FILE_NAME_MAX + 1];
	struct st_file_out tmp;
	struct st_error e = {0};
	int rc;

	if (!url)
		return st_error_set(err, ST_ERR_ARG, "enqueue needs url");
	/* Before the name: a refused host is the first thing to say. */
	if ((rc = node_mqtt_url_allowed(&n->cfg.mqtt, url, err)))
		return rc;
	if (name)
		snprintf(fname, sizeof(fname), "%s", name);
	else
		name_of_url(url, fname, sizeof(fname));
	if ((name && strlen(name) > NODE_FILE_NAME_MAX) ||
	    node_check_file_name(fname, strlen(fname), err))
		return st_error_set(err, ST_ERR_ARG, "bad file name '%.100s': %s", fname,
				    name && strlen(name) > NODE_FILE_NAME_MAX ? "too long" : err->msg);
	if (node_check_kind(p, fname, &e))
		return st_error_set(err, ST_ERR_ARG, "'%.100s': %s", fname, e.msg);
	if ((rc = download(n, url, &tmp, err)))
		return rc;
	if ((rc = node_store_file(n, p, &tmp, fname, true, true,
				   json_is_true(json_object_get(o, "force")), NULL, job, err))) {
		st_file_abort(&tmp);
		return rc;
	}
	node_log("info", p->cfg->name, *job, "mqtt: downloaded %s from %.200s, queued", fname,
		 url);
	return 0;
}

/* The job number a queue command names ("job"), or 0. */
static int64_t job_named(const json_t *o)
{
	json_t *v = json_object_get(o, "job");

	return json_is_integer(v) && json_integer_value(v) > 0 ? json_integer_value(v) : 0;
}

/*
 * The queue commands, as /api/stratum/queue has them: list (the jobs and
 * the ones waiting, in order, into *out), move {"job", "position"},
 * cancel {"job"} (without job: the active one, below) and requeue {"job"}
 * (the new job in *job).  Returns 0, a negative class, or 1 when cmd is
 * none of them.
 */
static int cmd_queue(struct node *n, struct node_printer *p, const char *cmd, json_t *o,
		     json_t **out, int64_t *job, struct st_error *err)
{
	int64_t id = job_named(o);
	json_t *pos = json_object_get(o, "position");

	if (!strcmp(cmd, "list")) {
		*out = json_pack("{s:o,s:o}", "waiting", node_queue_waiting(n->q, p->cfg->name),
				 "jobs", node_queue_list(n->q, p->cfg->name, 200));
		return 0;
	}
	if (strcmp(cmd, "move") && strcmp(cmd, "requeue") &&
	    (strcmp(cmd, "cancel") || !json_object_get(o, "job")))
		return 1;
	if (!id)
		return st_error_set(err, ST_ERR_ARG, "%s needs job, a job number", cmd);
	if (!strcmp(cmd, "move"))
		return node_control_move(n, p, id, json_is_integer(pos) ? json_integer_value(pos) : 0,
					 err);
	if (!strcmp(cmd, "cancel"))
		return node_control_cancel(n, p, id, err);
	return node_control_requeue(n, p, id, job, err);
}

/* Run one command and publish its result (never with its key). */
static void run_command(struct node_mqtt *m, struct node_printer *p, const char *payload)
{
	struct st_error err = {0};
	char topic[400];
	json_t *o, *res, *out = NULL;
	const char *id, *cmd, *who;
	int64_t job = 0;
	bool duplicate = false;
	char *text;
	int rc;

	snprintf(topic, sizeof(topic), "%s/%s/cmd", m->base, p->cfg->name);
	rc = node_mqtt_authorize(m->n, topic, payload, time(NULL), &o, &who, &err);
	id = json_string_value(json_object_get(o, "id"));
	cmd = json_string_value(json_object_get(o, "command"));
	if (rc) {
		/* refused before its id is recorded: a forged command cannot use up an id */
	} else if (!id || !*id || strlen(id) > MQTT_ID_MAX) {
		rc = st_error_set(&err, ST_ERR_ARG, "id is required (a string of 1 to %d bytes) so "
				  "that a re-delivered command runs once", MQTT_ID_MAX);
	} else if (!cmd) {
		rc = st_error_set(&err, ST_ERR_ARG, "command is " MQTT_COMMANDS);
	} else if ((rc = node_queue_command_once(m->n->q, id, p->cfg->name, &err)) <= 0) {
		duplicate = rc == 0; /* seen before: it ran (or was refused) then */
	} else if ((rc = cmd_queue(m->n, p, cmd, o, &out, &job, &err)) != 1) {
		/* a queue command: ran */
	} else if (!strcmp(cmd, "enqueue")) {
		rc = cmd_enqueue(m->n, p, o, &job, &err);
	} else if (!strcmp(cmd, "cancel")) {
		rc = node_control_job(m->n, p, "cancel", NULL, &err);
	} else if (!strcmp(cmd, "pause") || !strcmp(cmd, "resume")) {
		rc = node_control_job(m->n, p, "pause", cmd, &err);
	} else {
		rc = st_error_set(&err, ST_ERR_ARG, "command is " MQTT_COMMANDS ", not '%.40s'",
				  cmd);
	}
	if (rc < 0)
		node_log("warning", p->cfg->name, 0, "mqtt: command %.40s (id %.60s) refused: %s",
			 cmd ? cmd : "?", id ? id : "?", err.msg);
	else if (!duplicate)
		node_log("info", p->cfg->name, job, "mqtt: command %.40s (id %.60s) by key %s", cmd,
			 id, who);
	else
		node_log("info", p->cfg->name, 0, "mqtt: command id %.60s was received before; not "
			 "run again", id);
	res = json_pack("{s:s?,s:s?,s:b,s:b}", "id", id, "command", cmd, "ok", rc >= 0,
			"duplicate", duplicate);
	if (rc < 0)
		json_object_set_new(res, "error", json_string(err.msg));
	if (job)
		json_object_set_new(res, "job", json_integer(job));
	if (out)
		json_object_update_new(res, out);
	text = json_dumps(res, JSON_COMPACT);
	if (text)
		publish(m, p->cfg->name, "result", text, false);
	free(text);
	json_decref(res);
	json_decref(o);
}

/* Publish printer i's state topics that changed (all with force). */
static void publish_state(struct node_mqtt *m, size_t i, bool force)
{
	struct node_printer *p = &m->n->printers[i];
	json_t *o = node_printer_json(m->n, p, 0);
	char *text[MQTT_TOPICS];

	if (!o)
		return;
	text[0] = strdup(json_string_value(json_object_get(o, "state")));
	text[1] = json_dumps(json_object_get(o, "temperature"), JSON_COMPACT);
	text[2] = json_dumps(json_object_get(o, "progress"), JSON_COMPACT);
	text[3] = json_dumps(json_object_get(o, "job"), JSON_COMPACT | JSON_ENCODE_ANY);
	text[4] = json_dumps(json_object_get(o, "waiting"), JSON_COMPACT);
	text[5] = json_dumps(json_object_get(o, "bedClear"), JSON_COMPACT | JSON_ENCODE_ANY);
	json_decref(o);
	for (int t = 0; t < MQTT_TOPICS; t++) {
		if (!text[t])
			continue;
		if (force || !m->last[i][t] || strcmp(m->last[i][t], text[t])) {
			publish(m, p->cfg->name, node_mqtt_state_topics[t], text[t], true);
			free(m->last[i][t]);
			m->last[i][t] = text[t];
		} else {
			free(text[t]);
		}
	}
}

/* The node's retained info: where it is reached and its printers with
 * their profiles, for the farm view (docs/serve.md "The farm view"). */
static void publish_info(struct node_mqtt *m, uint16_t port)
{
	struct node *n = m->n;
	char url[NODE_URL_MAX + 64], host[128] = "localhost", topic[300];
	json_t *o, *printers = json_array();
	char *text;

	if (n->cfg.url[0]) {
		snprintf(url, sizeof(url), "%s", n->cfg.url);
	} else {
		/* every address: the host's name is what another machine can reach */
		if (strcmp(n->cfg.listen_addr, "0.0.0.0"))
			snprintf(host, sizeof(host), "%s", n->cfg.listen_addr);
		else
			gethostname(host, sizeof(host) - 1);
		snprintf(url, sizeof(url), "http://%s:%u", host, port);
	}
	for (size_t i = 0; i < n->nprinters; i++)
		json_array_append_new(printers, json_pack("{s:s,s:s,s:s,s:s}", "name",
							  n->printers[i].cfg->name, "profile",
							  n->printers[i].prof->id, "profileName",
							  n->printers[i].prof->name, "prefix",
							  n->printers[i].cfg->prefix));
	o = json_pack("{s:s,s:o}", "url", url, "printers", printers);
	text = o ? json_dumps(o, JSON_COMPACT) : NULL;
	json_decref(o);
	if (!text)
		return;
	snprintf(topic, sizeof(topic), "%s/info", m->base);
	mosquitto_publish(m->mosq, NULL, topic, (int)strlen(text), text, 1, true);
	free(text);
}

/* Connect with the node's client id once its name is free: libmosquitto's
 * network thread keeps the connection from then on. */
static void link_up(struct node_mqtt *m)
{
	const struct node_mqtt_config *c = &m->n->cfg.mqtt;
	int rc = mosquitto_connect_async(m->mosq, c->host, c->port, c->keepalive);

	if (rc != MOSQ_ERR_SUCCESS)
		node_log("warning", NULL, 0, "mqtt: cannot reach %s:%u yet (%s); retrying",
			 c->host, c->port, rc == MOSQ_ERR_ERRNO ? strerror(errno)
								 : mosquitto_strerror(rc));
	if (mosquitto_loop_start(m->mosq) == MOSQ_ERR_SUCCESS)
		m->loop_started = true;
	else
		node_log("error", NULL, 0, "mqtt: cannot start the network thread");
}

/* Not linked yet (the broker was down at start): check the name again and
 * connect, trying every 1, 2, 4 ... MQTT_RETRY_MAX_S seconds. */
static void retry_link(struct node_mqtt *m, time_t *next_try, int *wait_s)
{
	struct st_error err = {0};
	bool held = false;
	int rc;

	if (time(NULL) < *next_try)
		return;
	rc = node_mqtt_claim(&m->n->cfg, &m->stopping, &held, &err);
	if (!rc) {
		link_up(m);
	} else if (held) {
		node_log("error", NULL, 0, "%s; MQTT is off until the node restarts", err.msg);
		pthread_mutex_lock(&m->mu);
		m->off = true;
		pthread_mutex_unlock(&m->mu);
	} else if (rc == ST_ERR_RANGE) {
		node_log("error", NULL, 0, "%s; retrying", err.msg); /* credentials */
	}
	*wait_s = *wait_s * 2 > MQTT_RETRY_MAX_S ? MQTT_RETRY_MAX_S : *wait_s * 2;
	*next_try = time(NULL) + *wait_s;
}

static void *mqtt_main(void *arg)
{
	struct node_mqtt *m = arg;
	struct timespec t;
	time_t next_try = time(NULL) + 1; /* node_mqtt_start made the first try */
	int wait_s = 1;

	pthread_mutex_lock(&m->mu);
	while (!m->stop) {
		if (!m->loop_started && !m->off) {
			pthread_mutex_unlock(&m->mu);
			retry_link(m, &next_try, &wait_s);
			pthread_mutex_lock(&m->mu);
			continue;
		}
		if (m->npending) {
			size_t i = m->pending[0].printer;
			char *payload = m->pending[0].payload;

			memmove(&m->pending[0], &m->pending[1],
				sizeof(m->pending[0]) * (size_t)--m->npending);
			pthread_mutex_unlock(&m->mu);
			run_command(m, &m->n->printers[i], payload);
			free(payload);
			pthread_mutex_lock(&m->mu);
			continue;
		}
		if (m->connected) {
			bool force = m->republish;
			uint16_t port = m->http_port;

			m->republish = false;
			pthread_mutex_unlock(&m->mu);
			if (force && port)
				publish_info(m, port);
			for (size_t i = 0; i < m->n->nprinters; i++)
				publish_state(m, i, force);
			pthread_mutex_lock(&m->mu);
		}
		clock_gettime(CLOCK_REALTIME, &t);
		t.tv_nsec += MQTT_TICK_MS * 1000000L;
		t.tv_sec += t.tv_nsec / 1000000000L;
		t.tv_nsec %= 1000000000L;
		if (!m->stop && !m->npending)
			pthread_cond_timedwait(&m->cv, &m->mu, &t);
	}
	pthread_mutex_unlock(&m->mu);
	return NULL;
}

int node_mqtt_start(struct node *n, struct st_error *err)
{
	const struct node_mqtt_config *c = &n->cfg.mqtt;
	struct node_mqtt *m;
	char topic[300];
	bool held;
	int rc;

	if (!c->host[0])
		return 0;
	m = calloc(1, sizeof(*m));
	if (!m)
		return st_error_set(err, ST_ERR_NOMEM, "mqtt: out of memory");
	m->n = n;
	pthread_mutex_init(&m->mu, NULL);
	pthread_cond_init(&m->cv, NULL);
	n->mqtt = m;
	snprintf(m->base, sizeof(m->base), "%s/%s", c->topic, n->cfg.name);
	mosquitto_lib_init();
	curl_global_init(CURL_GLOBAL_DEFAULT);
	m->since = time(NULL);
	/* A kept session: commands sent while the node was away still arrive. */
	if ((rc = node_mqtt_client(c, c->client_id, false, m, &m->mosq, err)))
		return rc;
	snprintf(topic, sizeof(topic), "%s/status", m->base);
	mosquitto_will_set(m->mosq, topic, 7, "offline", 1, true);
	mosquitto_connect_callback_set(m->mosq, on_connect);
	mosquitto_disconnect_callback_set(m->mosq, on_disconnect);
	mosquitto_message_callback_set(m->mosq, on_message);
	mosquitto_reconnect_delay_set(m->mosq, 1, MQTT_RETRY_MAX_S, true);
	/* The name first: a node that holds it is not knocked off (mqtt_name.c).
	 * A broker that is down now is retried by the MQTT thread; the node
	 * runs meanwhile. */
	rc = node_mqtt_claim(&n->cfg, &m->stopping, &held, err);
	if (rc == ST_ERR_RANGE)
		return rc;
	if (rc)
		node_log("warning", NULL, 0, "%s; retrying", err->msg);
	else
		link_up(m);
	if (pthread_create(&m->thread, NULL, mqtt_main, m))
		return st_error_set(err, ST_ERR_INTERNAL, "mqtt: cannot start its thread");
	m->thread_started = true;
	return 0;
}

void node_mqtt_listening(struct node *n, uint16_t port)
{
	struct node_mqtt *m = n->mqtt;

	if (!m)
		return;
	pthread_mutex_lock(&m->mu);
	m->http_port = port;
	m->republish = true;
	pthread_cond_signal(&m->cv);
	pthread_mutex_unlock(&m->mu);
}

void node_mqtt_stop(struct node *n)
{
	struct node_mqtt *m = n->mqtt;
	char topic[300];

	if (!m)
		return;
	atomic_store(&m->stopping, true);
	if (m->thread_started) {
		pthread_mutex_lock(&m->mu);
		m->stop = true;
		pthread_cond_signal(&m->cv);
		pthread_mutex_unlock(&m->mu);
		pthread_join(m->thread, NULL);
	}
	if (m->mosq) {
		/* A clean stop says offline itself: the broker sends no will then. */
		snprintf(topic, sizeof(topic), "%s/status", m->base);
		mosquitto_publish(m->mosq, NULL, topic, 7, "offline", 1, true);
		mosquitto_disconnect(m->mosq);
		if (m->loop_started)
			mosquitto_loop_stop(m->mosq, true);
		mosquitto_destroy(m->mosq);
	}
	for (int i = 0; i < m->npending; i++)
		free(m->pending[i].payload);
	for (size_t i = 0; i < NODE_MAX_PRINTERS; i++)
		for (int t = 0; t < MQTT_TOPICS; t++)
			free(m->last[i][t]);
	pthread_mutex_destroy(&m->mu);
	pthread_cond_destroy(&m->cv);
	free(m);
	n->mqtt = NULL;
	curl_global_cleanup();
	mosquitto_lib_cleanup();
}

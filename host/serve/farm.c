/*
 * farm.c - the farm view (`stratum farm`, docs/serve.md "The farm view"):
 * one MQTT client reads every node's retained state topics under the topic
 * root (mqtt.c publishes them), keeps them as the broker sends them, and
 * answers for the whole farm: its JSON, and which printer takes a job.
 * It subscribes to the state and info topics only, never to cmd (whose
 * plain form carries a key), so the broker may let it read just those.
 *
 * A printer is idle when its node is online and it says Operational with no
 * job, nothing queued and its bed confirmed clear, and no job was handed to
 * it in the last FARM_RESERVE_MS that its state does not show yet.
 */
#include <curl/curl.h>
#include <errno.h>
#include <openssl/rand.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "farm_int.h"
#include "mqtt_int.h"
#include "st_clock.h"

#define FARM_RETRY_MAX_S 30 /* longest wait between two tries to reach the broker */

static void on_connect(struct mosquitto *mosq, void *ctx, int rc)
{
	struct farm *f = ctx;
	const char *root = f->cfg.base.mqtt.topic;
	char topics[MQTT_TOPICS + 2][300], *subs[MQTT_TOPICS + 2];

	if (rc) {
		node_log("error", NULL, 0, "farm: the broker refused the connection: %s",
			 mosquitto_connack_string(rc));
		return;
	}
	snprintf(topics[0], sizeof(topics[0]), "%s/+/status", root);
	snprintf(topics[1], sizeof(topics[1]), "%s/+/info", root);
	for (size_t i = 0; i < MQTT_TOPICS; i++)
		snprintf(topics[i + 2], sizeof(topics[0]), "%s/+/+/%s", root, node_mqtt_state_topics[i]);
	for (size_t i = 0; i < MQTT_TOPICS + 2; i++)
		subs[i] = topics[i];
	pthread_mutex_lock(&f->mu);
	/* the broker sends every retained topic again: start from them */
	json_object_clear(f->nodes);
	f->connected = true;
	pthread_mutex_unlock(&f->mu);
	mosquitto_subscribe_multiple(mosq, NULL, (int)(MQTT_TOPICS + 2), subs, 0, 0, NULL);
	node_log("info", NULL, 0, "farm: connected to %s:%u, reading %s/", f->cfg.base.mqtt.host,
		 f->cfg.base.mqtt.port, root);
}

static void on_disconnect(struct mosquitto *mosq, void *ctx, int rc)
{
	struct farm *f = ctx;

	(void)mosq;
	pthread_mutex_lock(&f->mu);
	f->connected = false;
	pthread_mutex_unlock(&f->mu);
	if (rc)
		node_log("warning", NULL, 0, "farm: connection to the broker lost (%s); reconnecting",
			 mosquitto_strerror(rc));
}

/* The object at key of o, made when missing. */
static json_t *child(json_t *o, const char *key)
{
	json_t *c = json_object_get(o, key);

	if (!c) {
		c = json_object();
		json_object_set_new(o, key, c);
	}
	return c;
}

/* Whether printer pr (its topics) may take a job now, reservations aside. */
static bool state_idle(json_t *pr)
{
	json_t *queue = json_object_get(pr, "queue");

	return json_is_string(json_object_get(pr, "status")) &&
	       !strcmp(json_string_value(json_object_get(pr, "status")), "Operational") &&
	       json_is_null(json_object_get(pr, "job")) &&
	       (!queue || (json_is_array(queue) && !json_array_size(queue))) &&
	       json_is_true(json_object_get(pr, "bed_clear"));
}

/* ROOT/NODE/status, ROOT/NODE/info or ROOT/NODE/PRINTER/TOPIC: kept under
 * f->nodes; an empty payload (a retained topic cleared) drops it. */
static void on_message(struct mosquitto *mosq, void *ctx, const struct mosquitto_message *m)
{
	struct farm *f = ctx;
	size_t rl = strlen(f->cfg.base.mqtt.topic);
	char node[NODE_NAME_MAX], printer[NODE_NAME_MAX], topic[NODE_NAME_MAX];
	json_t *value = NULL, *where;
	const char *rest;
	int parts;

	(void)mosq;
	if (strncmp(m->topic, f->cfg.base.mqtt.topic, rl) || m->topic[rl] != '/')
		return;
	rest = m->topic + rl + 1;
	/* NODE/TOPIC or NODE/PRINTER/TOPIC (the subscriptions allow no other) */
	parts = sscanf(rest, "%63[^/]/%63[^/]/%63[^/]", node, printer, topic);
	if (parts == 2) {
		memcpy(topic, printer, sizeof(topic));
		printer[0] = '\0';
	} else if (parts != 3) {
		return;
	}
	if (m->payloadlen > 0 && strcmp(topic, "status"))
		value = json_loadb(m->payload, (size_t)m->payloadlen, JSON_DECODE_ANY, NULL);
	else if (m->payloadlen > 0)
		value = json_stringn(m->payload, (size_t)m->payloadlen);
	if (m->payloadlen > 0 && !value) {
		node_log("warning", NULL, 0, "farm: %.200s: not what a node publishes; ignored",
			 m->topic);
		return;
	}
	pthread_mutex_lock(&f->mu);
	where = child(f->nodes, node);
	if (printer[0])
		where = child(child(where, "printers"), printer);
	if (value)
		json_object_set_new(where, topic, value);
	else
		json_object_del(where, topic);
	/* the state shows the job handed to it (or another): no reservation needed */
	if (printer[0] && !state_idle(where))
		json_object_del(where, "reservedUntil");
	pthread_mutex_unlock(&f->mu);
}

/* The names of object o's keys, sorted (new array). */
static json_t *sorted_keys(json_t *o)
{
	json_t *names = json_array(), *v;
	const char *k;
	size_t n;

	json_object_foreach(o, k, v)
		json_array_append_new(names, json_string(k));
	n = json_array_size(names);
	for (size_t i = 1; i < n; i++) /* insertion sort: a farm has tens of nodes */
		for (size_t j = i; j > 0 && strcmp(json_string_value(json_array_get(names, j - 1)),
						   json_string_value(json_array_get(names, j))) > 0;
		     j--) {
			json_t *a = json_incref(json_array_get(names, j - 1));

			json_array_set(names, j - 1, json_array_get(names, j));
			json_array_set_new(names, j, a);
		}
	return names;
}

/* The node's printers in the order its info lists them, then any other
 * that has topics (info not received yet): new array of names. */
static json_t *printer_names(json_t *node)
{
	json_t *names = json_array(), *listed = json_object_get(json_object_get(node, "info"),
								 "printers"), *p;
	json_t *rest = sorted_keys(json_object_get(node, "printers"));
	size_t i;

	json_array_foreach(listed, i, p)
		if (json_is_string(json_object_get(p, "name")))
			json_array_append(names, json_object_get(p, "name"));
	json_array_foreach(rest, i, p) {
		bool seen = false;

		for (size_t j = 0; j < json_array_size(names); j++)
			seen |= json_equal(json_array_get(names, j), p);
		if (!seen)
			json_array_append(names, p);
	}
	json_decref(rest);
	return names;
}

/* The entry of printer name in node's info, or NULL. */
static json_t *printer_info(json_t *node, const char *name)
{
	json_t *listed = json_object_get(json_object_get(node, "info"), "printers"), *p;
	size_t i;

	json_array_foreach(listed, i, p)
		if (json_is_string(json_object_get(p, "name")) &&
		    !strcmp(json_string_value(json_object_get(p, "name")), name))
			return p;
	return NULL;
}

/* The [remote] section of node name, or NULL. */
static const struct farm_remote *remote_of(const struct farm_config *c, const char *name)
{
	for (size_t i = 0; i < c->nremotes; i++)
		if (!strcmp(c->remotes[i].name, name))
			return &c->remotes[i];
	return NULL;
}

/* Where node name is reached: its [remote] url, else the URL it announces
 * in its info (NULL before that). */
static const char *node_url(const struct farm *f, const char *name, json_t *node)
{
	const struct farm_remote *r = remote_of(&f->cfg, name);

	if (r && r->url[0])
		return r->url;
	return json_string_value(json_object_get(json_object_get(node, "info"), "url"));
}

static bool node_online(json_t *node)
{
	json_t *s = json_object_get(node, "status");

	return json_is_string(s) && !strcmp(json_string_value(s), "online");
}

/* Whether printer pr of a node (online or not) may take a job at now. */
static bool printer_idle(bool online, json_t *pr, int64_t now)
{
	json_t *until = json_object_get(pr, "reservedUntil");

	return online && state_idle(pr) && !(until && json_integer_value(until) > now);
}

/* A value of pr for the JSON (null when the node has not sent it; pr may be NULL). */
static json_t *topic_or_null(json_t *pr, const char *topic)
{
	json_t *v = json_object_get(pr, topic);

	return v ? json_incref(v) : json_null();
}

/* One printer as GET /api/farm lists it. */
static json_t *printer_json(json_t *node, const char *name, const char *node_url, int64_t now)
{
	json_t *pr = json_object_get(json_object_get(node, "printers"), name);
	json_t *info = printer_info(node, name), *queue = json_object_get(pr, "queue");
	const char *prefix = json_string_value(json_object_get(info, "prefix"));
	bool online = node_online(node);
	char url[NODE_URL_MAX + NODE_PREFIX_MAX];
	json_t *o = json_object();

	json_object_set_new(o, "name", json_string(name));
	json_object_set_new(o, "profile", topic_or_null(info, "profile"));
	json_object_set_new(o, "profileName", topic_or_null(info, "profileName"));
	snprintf(url, sizeof(url), "%s%s", node_url ? node_url : "", prefix ? prefix : "");
	json_object_set_new(o, "url", node_url && prefix ? json_string(url) : json_null());
	/* the last state of a node that went away is not its state now */
	json_object_set_new(o, "state", online ? topic_or_null(pr, "status") : json_string("Offline"));
	json_object_set_new(o, "job", topic_or_null(pr, "job"));
	json_object_set_new(o, "progress", topic_or_null(pr, "progress"));
	json_object_set_new(o, "temperature", topic_or_null(pr, "temperatures"));
	json_object_set_new(o, "bedClear", topic_or_null(pr, "bed_clear"));
	json_object_set_new(o, "queued", json_integer(json_is_array(queue)
						      ? (json_int_t)json_array_size(queue) : 0));
	/* without its node's info the farm cannot reach it */
	json_object_set_new(o, "idle", json_boolean(info && node_url && prefix &&
						    printer_idle(online, pr, now)));
	return o;
}

json_t *farm_json(struct farm *f)
{
	json_t *out = json_object(), *nodes = json_array(), *names, *nm;
	int64_t now = st_mono_ms();
	size_t i, nprinters = 0, nidle = 0;

	pthread_mutex_lock(&f->mu);
	names = sorted_keys(f->nodes);
	json_array_foreach(names, i, nm) {
		json_t *node = json_object_get(f->nodes, json_string_value(nm));
		const char *url = node_url(f, json_string_value(nm), node);
		json_t *pnames, *printers, *pn;
		size_t j;

		/* a node taken out of the farm: its status and info were cleared */
		if (!json_object_get(node, "status") && !json_object_get(node, "info"))
			continue;
		pnames = printer_names(node);
		printers = json_array();

		json_array_foreach(pnames, j, pn) {
			json_t *p = printer_json(node, json_string_value(pn), url, now);

			nprinters++;
			nidle += json_is_true(json_object_get(p, "idle"));
			json_array_append_new(printers, p);
		}
		json_decref(pnames);
		json_array_append_new(nodes, json_pack("{s:O,s:b,s:s?,s:o}", "name", nm, "online",
						       node_online(node), "url", url, "printers",
						       printers));
	}
	json_object_set_new(out, "brokerConnected", json_boolean(f->connected));
	pthread_mutex_unlock(&f->mu);
	json_decref(names);
	json_object_set_new(out, "nodes", nodes);
	json_object_set_new(out, "printers", json_integer((json_int_t)nprinters));
	json_object_set_new(out, "idle", json_integer((json_int_t)nidle));
	return out;
}

/* The farm's key on node: its [remote] key, else node_key ("" none). */
static const char *key_for(const struct farm_config *c, const char *node)
{
	const struct farm_remote *r = remote_of(c, node);

	return r ? r->key : c->node_key;
}

static bool was_tried(json_t *tried, const char *node, const char *printer)
{
	char id[2 * NODE_NAME_MAX];
	json_t *t;
	size_t i;

	snprintf(id, sizeof(id), "%s/%s", node, printer);
	json_array_foreach(tried, i, t)
		if (!strcmp(json_string_value(t), id))
			return true;
	return false;
}

int farm_pick(struct farm *f, const char *profile, json_t *tried, struct farm_pick *out,
	      struct st_error *err)
{
	json_t *names, *nm;
	int64_t now = st_mono_ms();
	size_t i, have = 0, busy = 0, keyless = 0;
	int rc = ST_ERR_ARG;

	pthread_mutex_lock(&f->mu);
	names = sorted_keys(f->nodes);
	json_array_foreach(names, i, nm) {
		json_t *node = json_object_get(f->nodes, json_string_value(nm));
		const char *url = node_url(f, json_string_value(nm), node);
		const char *key = key_for(&f->cfg, json_string_value(nm));
		json_t *pnames = printer_names(node), *pn;
		size_t j;

		json_array_foreach(pnames, j, pn) {
			const char *name = json_string_value(pn);
			json_t *info = printer_info(node, name);
			json_t *pr = json_object_get(json_object_get(node, "printers"), name);
			const char *prof = json_string_value(json_object_get(info, "profile"));
			const char *prefix = json_string_value(json_object_get(info, "prefix"));

			if (!prof || strcmp(prof, profile))
				continue;
			have++;
			if (!key[0]) {
				keyless++;
				continue;
			}
			if (!url || !prefix || !printer_idle(node_online(node), pr, now) ||
			    was_tried(tried, json_string_value(nm), name)) {
				busy++;
				continue;
			}
			snprintf(out->node, sizeof(out->node), "%s", json_string_value(nm));
			snprintf(out->printer, sizeof(out->printer), "%s", name);
			snprintf(out->url, sizeof(out->url), "%s%s", url, prefix);
			snprintf(out->key, sizeof(out->key), "%s", key);
			json_object_set_new(pr, "reservedUntil", json_integer(now + FARM_RESERVE_MS));
			rc = 0;
			break;
		}
		json_decref(pnames);
		if (!rc)
			break;
	}
	pthread_mutex_unlock(&f->mu);
	json_decref(names);
	if (rc && !have)
		return st_error_set(err, ST_ERR_ARG, "no printer of any node has the profile '%.100s'",
				    profile);
	if (rc)
		return st_error_set(err, ST_ERR_RANGE, "no printer with the profile '%.100s' is idle "
						       "(%zu of them: %zu busy, offline or refused, "
						       "%zu on nodes the farm has no key for)",
				    profile, have, busy, keyless);
	return 0;
}

void farm_release(struct farm *f, const struct farm_pick *pick)
{
	json_t *pr;

	pthread_mutex_lock(&f->mu);
	pr = json_object_get(json_object_get(json_object_get(f->nodes, pick->node), "printers"),
			     pick->printer);
	json_object_del(pr, "reservedUntil");
	pthread_mutex_unlock(&f->mu);
}

int farm_new(const struct farm_config *cfg, struct farm **out, struct st_error *err)
{
	struct farm *f = calloc(1, sizeof(*f));

	*out = NULL;
	if (!f || !(f->nodes = json_object())) {
		free(f);
		return st_error_set(err, ST_ERR_NOMEM, "farm: out of memory");
	}
	f->cfg = *cfg;
	pthread_mutex_init(&f->mu, NULL);
	pthread_cond_init(&f->cv, NULL);
	*out = f;
	return 0;
}

/* Connect, trying every 1, 2, 4 ... FARM_RETRY_MAX_S seconds while the
 * broker does not answer; once it has, libmosquitto's loop keeps the link
 * (and reconnects itself), but it does not retry a first connection. */
static void *link_main(void *arg)
{
	struct farm *f = arg;
	const struct node_mqtt_config *c = &f->cfg.base.mqtt;
	int wait_s = 1, rc;
	struct timespec t;

	pthread_mutex_lock(&f->mu);
	while (!f->stop) {
		pthread_mutex_unlock(&f->mu);
		rc = mosquitto_connect_async(f->mosq, c->host, c->port, c->keepalive);
		pthread_mutex_lock(&f->mu);
		if (rc == MOSQ_ERR_SUCCESS) {
			if (mosquitto_loop_start(f->mosq) == MOSQ_ERR_SUCCESS)
				f->loop_started = true;
			else
				node_log("error", NULL, 0, "farm: cannot start the MQTT loop");
			break;
		}
		node_log("warning", NULL, 0, "farm: cannot reach the broker %s:%u (%s); retrying "
					     "in %d s", c->host, c->port,
			 rc == MOSQ_ERR_ERRNO ? strerror(errno) : mosquitto_strerror(rc), wait_s);
		clock_gettime(CLOCK_REALTIME, &t);
		t.tv_sec += wait_s;
		pthread_cond_timedwait(&f->cv, &f->mu, &t);
		wait_s = wait_s * 2 > FARM_RETRY_MAX_S ? FARM_RETRY_MAX_S : wait_s * 2;
	}
	pthread_mutex_unlock(&f->mu);
	return NULL;
}

int farm_start(struct farm *f, struct st_error *err)
{
	const struct node_mqtt_config *c = &f->cfg.base.mqtt;
	unsigned char rnd[4];
	char id[sizeof(c->client_id) + 16];
	int rc;

	if (!c->host[0])
		return st_error_set(err, ST_ERR_ARG, "farm: no broker: give [mqtt] host = or "
						     "--broker HOST");
	mosquitto_lib_init();
	curl_global_init(CURL_GLOBAL_DEFAULT);
	/* A random tail: farm views only read, so several may run under one name. */
	if (RAND_bytes(rnd, sizeof(rnd)) != 1)
		return st_error_set(err, ST_ERR_INTERNAL, "farm: no random bytes");
	snprintf(id, sizeof(id), "%s-%02x%02x%02x%02x", c->client_id, rnd[0], rnd[1], rnd[2],
		 rnd[3]);
	if ((rc = node_mqtt_client(c, id, true, f, &f->mosq, err)))
		return rc;
	mosquitto_connect_callback_set(f->mosq, on_connect);
	mosquitto_disconnect_callback_set(f->mosq, on_disconnect);
	mosquitto_message_callback_set(f->mosq, on_message);
	mosquitto_reconnect_delay_set(f->mosq, 1, FARM_RETRY_MAX_S, true);
	if (pthread_create(&f->linker, NULL, link_main, f))
		return st_error_set(err, ST_ERR_INTERNAL, "farm: cannot start the MQTT thread");
	f->linker_started = true;
	if ((rc = farm_http_start(f, err)))
		return rc;
	node_log("info", NULL, 0, "farm %s listening on %s:%u, broker %s:%u", f->cfg.base.name,
		 f->cfg.base.listen_addr, f->port, c->host, c->port);
	return 0;
}

void farm_free(struct farm *f)
{
	if (!f)
		return;
	farm_http_stop(f);
	if (f->linker_started) {
		pthread_mutex_lock(&f->mu);
		f->stop = true;
		pthread_cond_signal(&f->cv);
		pthread_mutex_unlock(&f->mu);
		pthread_join(f->linker, NULL);
	}
	if (f->mosq) {
		mosquitto_disconnect(f->mosq);
		if (f->loop_started)
			mosquitto_loop_stop(f->mosq, true);
		mosquitto_destroy(f->mosq);
		curl_global_cleanup();
		mosquitto_lib_cleanup();
	}
	json_decref(f->nodes);
	pthread_mutex_destroy(&f->mu);
	pthread_cond_destroy(&f->cv);
	free(f);
}

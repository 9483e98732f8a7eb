/*
 * mqtt_name.c - the node's connection settings (credentials, TLS) and its
 * name on the broker (docs/serve.md "MQTT"): one client id per node name,
 * and a node that finds its name held by a live node refuses it instead of
 * connecting with that id, which would knock the holder off the broker.
 *
 * The holder is told by ROOT/NODE/status, retained "online" while it is
 * connected ("offline" on a clean stop and as its last will).  "online" may
 * be stale (the broker notices a dead client only after 1.5 keepalives),
 * so the starting node pings ROOT/NODE/ping and a live holder answers on
 * ROOT/NODE/pong; silence means the name is free.  The check runs on a
 * connection of its own (a random client id, a clean session) and subscribes
 * to ping too: its own ping coming back tells that the retained status, sent
 * before it, has arrived.
 */
#include <errno.h>
#include <openssl/rand.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "mqtt_int.h"
#include "st_clock.h"

#define CLAIM_CONNECT_MS 5000 /* to connect and subscribe */

int node_mqtt_client(const struct node_mqtt_config *c, const char *id, bool clean, void *ctx,
		     struct mosquitto **out, struct st_error *err)
{
	const char *files[3][2] = {{"ca_file", c->ca_file}, {"cert_file", c->cert_file},
				   {"key_file", c->key_file}};
	struct mosquitto *mosq;
	int rc = MOSQ_ERR_SUCCESS;

	*out = NULL;
	if (c->tls)
		for (int i = 0; i < 3; i++)
			if (files[i][1][0] && access(files[i][1], R_OK))
				return st_error_set(err, ST_ERR_RANGE, "mqtt: %s %s: %s", files[i][0],
						    files[i][1], strerror(errno));
	mosq = mosquitto_new(id, clean, ctx);
	if (!mosq)
		return st_error_set(err, ST_ERR_NOMEM, "mqtt: cannot create the client");
	if (c->username[0])
		rc = mosquitto_username_pw_set(mosq, c->username, c->password[0] ? c->password : NULL);
	if (!rc && c->tls) {
		/* No CA given: the system's, as for a broker with a public certificate. */
		if (!c->ca_file[0] && !c->ca_dir[0])
			rc = mosquitto_int_option(mosq, MOSQ_OPT_TLS_USE_OS_CERTS, 1);
		else
			rc = mosquitto_tls_set(mosq, c->ca_file[0] ? c->ca_file : NULL,
					       c->ca_dir[0] ? c->ca_dir : NULL,
					       c->cert_file[0] ? c->cert_file : NULL,
					       c->key_file[0] ? c->key_file : NULL, NULL);
		if (!rc)
			rc = mosquitto_tls_opts_set(mosq, 1 /* SSL_VERIFY_PEER */,
						    c->tls_version[0] ? c->tls_version : NULL, NULL);
		if (!rc)
			rc = mosquitto_tls_insecure_set(mosq, c->tls_insecure != 0);
	}
	if (rc) {
		mosquitto_destroy(mosq);
		return st_error_set(err, ST_ERR_RANGE, "mqtt: the TLS settings were refused: %s",
				    mosquitto_strerror(rc));
	}
	*out = mosq;
	return 0;
}

/* What the check has seen (libmosquitto's callbacks run in its caller). */
struct claim {
	char status[300], ping[300], pong[300]; /* the topics */
	char nonce[33];
	int connack;	   /* -1 until CONNACK */
	bool subscribed, online, ping_back, answered;
	char holder[400];  /* the holder's answer */
};

static void claim_connect(struct mosquitto *mosq, void *ctx, int rc)
{
	struct claim *cl = ctx;
	char *subs[3] = {cl->status, cl->ping, cl->pong};

	cl->connack = rc;
	if (!rc)
		mosquitto_subscribe_multiple(mosq, NULL, 3, subs, 1, 0, NULL);
}

static void claim_subscribe(struct mosquitto *mosq, void *ctx, int mid, int n, const int *qos)
{
	struct claim *cl = ctx;

	(void)mid, (void)n, (void)qos;
	cl->subscribed = true;
	/* QoS 0: a kept session of a node that is away holds no stale pings */
	mosquitto_publish(mosq, NULL, cl->ping, (int)strlen(cl->nonce), cl->nonce, 0, false);
}

static void claim_message(struct mosquitto *mosq, void *ctx, const struct mosquitto_message *m)
{
	struct claim *cl = ctx;
	const char *p = m->payload;
	size_t nl = strlen(cl->nonce);

	(void)mosq;
	if (!strcmp(m->topic, cl->status))
		cl->online = m->payloadlen == 6 && !memcmp(p, "online", 6);
	else if (!strcmp(m->topic, cl->ping))
		cl->ping_back |= (size_t)m->payloadlen == nl && !memcmp(p, cl->nonce, nl);
	else if (!strcmp(m->topic, cl->pong) && m->payloadlen > 0 && strstr(p ? p : "", cl->nonce)) {
		cl->answered = true;
		/* the answer without the nonce: "host H, pid P, online since T" */
		snprintf(cl->holder, sizeof(cl->holder), "%.*s", m->payloadlen, p);
		if (!strncmp(cl->holder, cl->nonce, nl) && !strncmp(cl->holder + nl, ": ", 2))
			memmove(cl->holder, cl->holder + nl + 2, strlen(cl->holder + nl + 2) + 1);
	}
}

/* Run the check's connection until it can tell; see node_mqtt_claim. */
static int claim_run(const struct node_config *cfg, struct mosquitto *mosq, struct claim *cl,
		     const atomic_bool *stop, struct st_error *err)
{
	const struct node_mqtt_config *c = &cfg->mqtt;
	int64_t deadline = st_mono_ms() + CLAIM_CONNECT_MS, ping_until = 0;
	int rc = mosquitto_connect_async(mosq, c->host, c->port, c->keepalive);

	while (rc == MOSQ_ERR_SUCCESS && !*stop && cl->connack <= 0) {
		if (cl->answered)
			return st_error_set(err, ST_ERR_RANGE, "mqtt: another node named %s is "
							       "connected to the broker %s:%u (it "
							       "answered %s); give this node another "
							       "name in [node]",
					    cfg->name, c->host, c->port, cl->holder);
		if (cl->ping_back && !cl->online)
			return 0;
		if (cl->ping_back && !ping_until)
			ping_until = st_mono_ms() + MQTT_PING_WAIT_MS;
		if (ping_until && st_mono_ms() > ping_until) {
			node_log("warning", NULL, 0, "mqtt: %s/status says online but no node "
						     "answered; taking the name (its holder is gone)",
				 c->topic);
			return 0;
		}
		if (!ping_until && st_mono_ms() > deadline)
			return st_error_set(err, ST_ERR_IO, "mqtt: cannot reach %s:%u: no answer "
							    "within %d s", c->host, c->port,
					    CLAIM_CONNECT_MS / 1000);
		rc = mosquitto_loop(mosq, 100, 1);
	}
	if (cl->connack > 0) /* 4, 5: the credentials, which the config must change */
		return st_error_set(err, cl->connack == 4 || cl->connack == 5 ? ST_ERR_RANGE
									      : ST_ERR_IO,
				    "mqtt: the broker %s:%u refused the connection: %s", c->host,
				    c->port, mosquitto_connack_string(cl->connack));
	if (*stop)
		return st_error_set(err, ST_ERR_IO, "mqtt: stopped");
	return st_error_set(err, ST_ERR_IO, "mqtt: cannot reach %s:%u (%s)", c->host, c->port,
			    rc == MOSQ_ERR_ERRNO ? strerror(errno) : mosquitto_strerror(rc));
}

int node_mqtt_claim(const struct node_config *cfg, const atomic_bool *stop, bool *held,
		    struct st_error *err)
{
	const struct node_mqtt_config *c = &cfg->mqtt;
	struct claim cl = {.connack = -1};
	struct mosquitto *mosq;
	unsigned char rnd[8];
	char id[sizeof(cfg->mqtt.client_id) + 48];
	int rc;

	*held = false;
	if (RAND_bytes(rnd, sizeof(rnd)) != 1)
		return st_error_set(err, ST_ERR_INTERNAL, "mqtt: no random bytes for a nonce");
	for (size_t i = 0; i < sizeof(rnd); i++)
		snprintf(cl.nonce + 2 * i, 3, "%02x", rnd[i]);
	snprintf(cl.status, sizeof(cl.status), "%s/%s/status", c->topic, cfg->name);
	snprintf(cl.ping, sizeof(cl.ping), "%s/%s/ping", c->topic, cfg->name);
	snprintf(cl.pong, sizeof(cl.pong), "%s/%s/pong", c->topic, cfg->name);
	snprintf(id, sizeof(id), "%s-check-%s", c->client_id, cl.nonce);
	if ((rc = node_mqtt_client(c, id, true, &cl, &mosq, err)))
		return rc;
	mosquitto_connect_callback_set(mosq, claim_connect);
	mosquitto_subscribe_callback_set(mosq, claim_subscribe);
	mosquitto_message_callback_set(mosq, claim_message);
	rc = claim_run(cfg, mosq, &cl, stop, err);
	*held = cl.answered;
	mosquitto_disconnect(mosq);
	mosquitto_loop(mosq, 10, 1); /* sends the DISCONNECT */
	mosquitto_destroy(mosq);
	return rc;
}

void node_mqtt_pong(struct mosquitto *mosq, const char *base, const struct mosquitto_message *ping,
		    time_t since)
{
	char topic[300], host[128] = "?", when[32], text[600];
	struct tm tm;

	gethostname(host, sizeof(host) - 1);
	gmtime_r(&since, &tm);
	strftime(when, sizeof(when), "%Y-%m-%dT%H:%M:%SZ", &tm);
	snprintf(topic, sizeof(topic), "%s/pong", base);
	snprintf(text, sizeof(text), "%.*s: host %s, pid %ld, online since %s",
		 ping->payloadlen > 64 ? 64 : ping->payloadlen, (const char *)ping->payload, host,
		 (long)getpid(), when);
	mosquitto_publish(mosq, NULL, topic, (int)strlen(text), text, 1, false);
}

/*
 * mqtttest.h - what the serve suite's MQTT tests share (check_servesim.c,
 * check_servemqtt.c, check_servemqtt_name.c, check_farm.c): a mosquitto
 * broker on a loopback port, a client that keeps the last message of each
 * topic, a node on a broker, and a small HTTP file server for the node's
 * downloads.
 */
#ifndef STRATUM_TESTS_MQTTTEST_H
#define STRATUM_TESTS_MQTTTEST_H

#include <mosquitto.h>
#include <pthread.h>
#include <stddef.h>
#include <sys/types.h>

#include <stdbool.h>

#define MOSQUITTO_BIN "/usr/sbin/mosquitto"
/* One test-instant printer, mk3s, for a node's config. */
#define ONE_PRINTER "[printer mk3s]\nprofile = prusa-i3-mk3s\nport = test-instant\n"
/* The command and result topics of printer mk3s of the test node. */
#define CMD_TOPIC "stratum/test-node/mk3s/cmd"
#define RESULT_TOPIC "stratum/test-node/mk3s/result"

/* have_broker - whether mosquitto is here (make deps installs it); prints
 * that test is skipped when not. */
bool have_broker(const char *test);

/* free_port - a free loopback TCP port (bound once, then released). */
int free_port(void);

/* A one-file HTTP server: answers every request with body, or with a 302
 * to redirect when that is set; served counts the requests. */
struct file_server {
	int fd, port;
	const char *body, *redirect;
	pthread_t thread;
	int served;
};
void file_server_start(struct file_server *fs, const char *body);
void file_server_stop(struct file_server *fs);

/* What a test's MQTT client saw: the last payload of each topic. */
#define SEEN_MAX 64
struct mqtt_seen {
	pthread_mutex_t mu;
	int n;
	char topic[SEEN_MAX][128];
	char payload[SEEN_MAX][2048];
	int results; /* messages on .../result */
};
/* seen_message - the message callback that fills a struct mqtt_seen (ctx). */
void seen_message(struct mosquitto *mosq, void *ctx, const struct mosquitto_message *m);
/* wait_topic - wait up to secs for topic's last payload to contain want;
 * a copy in out (cap bytes) when out is not NULL.  Fails the test otherwise. */
void wait_topic(struct mqtt_seen *s, const char *topic, const char *want, int secs, char *out,
		size_t cap);

/* broker_start - mosquitto with the config text conf (written to a file
 * named after port), listening on port; waits until it accepts. */
pid_t broker_start(int port, const char *conf);
void broker_stop(pid_t broker);
/* anon_broker_start - broker_start with anonymous clients allowed and
 * nothing kept across restarts. */
pid_t anon_broker_start(int port);

/* watch_start - a client (user NULL: anonymous) that subscribes to filter
 * and fills seen; watch_stop ends it.  watch_start_tls: over TLS, the
 * broker's certificate checked with cafile. */
struct mosquitto *watch_start(struct mqtt_seen *seen, int port, const char *user,
			      const char *pass, const char *filter);
struct mosquitto *watch_start_tls(struct mqtt_seen *seen, int port, const char *user,
				  const char *pass, const char *filter, const char *cafile);
void watch_stop(struct mosquitto *mq, struct mqtt_seen *seen);
/* watch_send - publish payload on topic (QoS 1). */
void watch_send(struct mosquitto *mq, const char *topic, const char *payload);
/* mqtt_command - send payload on CMD_TOPIC and wait up to 10 s for its
 * answer on RESULT_TOPIC, which must contain want; the answer in out (cap
 * bytes) when out is not NULL. */
void mqtt_command(struct mosquitto *mq, struct mqtt_seen *seen, const char *payload,
		  const char *want, char *out, size_t cap);

struct node_proc;
/* write_mqtt_config - np's config: one test-instant printer and [mqtt] on
 * the broker at port with the lines extra. */
void write_mqtt_config(struct node_proc *np, int port, const char *extra);
/* node_on_broker - a broker (its port in *port, its pid returned), the node
 * np on it with the [mqtt] lines extra, and a client *mq watching the
 * node's topics into seen, once the node says it is online. */
pid_t node_on_broker(struct node_proc *np, int *port, const char *extra,
		     struct mqtt_seen *seen, struct mosquitto **mq);

#endif /* STRATUM_TESTS_MQTTTEST_H */

/*
 * mqtt_int.h - what the node's MQTT files share (mqtt.c: topics, commands,
 * downloads; mqtt_name.c: the connection's settings and the node's name on
 * the broker).  docs/serve.md "MQTT" describes both.
 */
#ifndef STRATUM_HOST_SERVE_MQTT_INT_H
#define STRATUM_HOST_SERVE_MQTT_INT_H

#include <mosquitto.h>
#include <stdbool.h>

#include "node_int.h"

/* Under ROOT/NODE/: "status" (retained online/offline: who holds the name),
 * "ping" (a starting node asks whether the holder lives), "pong" (its answer). */
#define MQTT_PING_WAIT_MS 2000 /* how long a starting node waits for the holder */

/* A printer's retained state topics under ROOT/NODE/PRINTER/, in the order
 * mqtt.c publishes them; the farm view (farm.c) subscribes to each. */
#define MQTT_TOPICS 6
extern const char *const node_mqtt_state_topics[MQTT_TOPICS];

/*
 * node_mqtt_client - a new libmosquitto client for c with client id id,
 * a clean session or a kept one, credentials and TLS as c says.  Returns 0,
 * ST_ERR_RANGE (a TLS file cannot be read: err names it) or ST_ERR_NOMEM.
 */
int node_mqtt_client(const struct node_mqtt_config *c, const char *id, bool clean, void *ctx,
		     struct mosquitto **out, struct st_error *err);

/*
 * node_mqtt_claim - whether this node may take its name (ROOT/NODE) on the
 * broker, asked before it connects with its client id (which would knock a
 * holder off): a short connection of its own reads the retained status and,
 * when it says online, pings the holder.  An answer within MQTT_PING_WAIT_MS
 * means another node holds the name (*held true).  *stop cuts the wait
 * short.  Returns 0 (free, or held by a node that no longer answers),
 * ST_ERR_RANGE (held by a live node, or the broker refused the credentials:
 * err says which), ST_ERR_IO (broker unreachable).
 */
int node_mqtt_claim(const struct node_config *cfg, const atomic_bool *stop, bool *held,
		    struct st_error *err);

/* node_mqtt_pong - the holder's answer to a ping message (its payload, a
 * nonce) on base/pong: the nonce, host, process and start time. */
void node_mqtt_pong(struct mosquitto *mosq, const char *base, const struct mosquitto_message *ping,
		    time_t since);

#endif /* STRATUM_HOST_SERVE_MQTT_INT_H */

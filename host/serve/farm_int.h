/*
 * farm_int.h - what the farm view's files share (docs/serve.md "The farm
 * view"): farm.c keeps every node's retained state as the broker sends it
 * and picks printers for jobs; farm_http.c serves the page and the API and
 * hands jobs to the nodes; farm_page.c is the page.  host/serve/ only.
 */
#ifndef STRATUM_HOST_SERVE_FARM_INT_H
#define STRATUM_HOST_SERVE_FARM_INT_H

#include <jansson.h>
#include <mosquitto.h>
#include <pthread.h>
#include <stdbool.h>

#include "node_int.h"

/* After a job is handed to a printer, how long it is not offered again
 * unless its state shows the job before then (the node publishes within
 * NODE_TICK_MS; a node that lost the job frees it after this). */
#define FARM_RESERVE_MS 15000

struct farm {
	struct farm_config cfg;
	struct mosquitto *mosq;
	pthread_t linker; /* connects until the broker answers, then starts the loop */
	bool linker_started;
	bool loop_started; /* the linker's until it ends */
	struct MHD_Daemon *httpd;
	uint16_t port;
	struct http_deadlines *deadlines; /* the header and body bounds (http_deadline.c) */
	pthread_mutex_t mu; /* the fields below; libmosquitto's thread writes them */
	pthread_cond_t cv;  /* wakes the linker to stop */
	bool stop;	    /* farm_free began */
	bool connected;	    /* to the broker */
	/* {NODE: {"status": TEXT, "info": {...}, "printers": {PRINTER: {TOPIC:
	 * value, ..., "reservedUntil": ms}}}} as the topics say */
	json_t *nodes;
};

/* A printer picked for a job: where to send it and with which key. */
struct farm_pick {
	char node[NODE_NAME_MAX], printer[NODE_NAME_MAX];
	char url[NODE_URL_MAX + NODE_PREFIX_MAX]; /* the node's URL and the printer's prefix */
	char key[NODE_KEY_MAX + 1];
};

/* farm_json - the farm as GET /api/farm answers it (new reference). */
json_t *farm_json(struct farm *f);

/*
 * farm_pick - the first idle printer of profile (nodes, then their
 * printers, by name) that is not in tried (an array of "NODE/PRINTER"),
 * reserved for FARM_RESERVE_MS.  Returns 0 with *out, ST_ERR_ARG when no
 * printer of any node has that profile, ST_ERR_RANGE when none of them is
 * idle (err says what they are doing).
 */
int farm_pick(struct farm *f, const char *profile, json_t *tried, struct farm_pick *out,
	      struct st_error *err);

/* farm_release - free a reservation that farm_pick made (the node refused). */
void farm_release(struct farm *f, const struct farm_pick *pick);

/* farm_http.c */
int farm_http_start(struct farm *f, struct st_error *err);
void farm_http_stop(struct farm *f);

/* farm_page.c: the page served at GET / (HTML with its script). */
extern const char farm_page[];

#endif /* STRATUM_HOST_SERVE_FARM_INT_H */

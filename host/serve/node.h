/*
 * node.h - the farm node behind `stratum serve` (docs/architecture.md item 8): one
 * process that drives every printer of its config, each with its own
 * durable job queue (SQLite, WAL) and worker thread, behind an HTTP API
 * that speaks the OctoPrint subset slicers upload to (libmicrohttpd,
 * jansson).  docs/serve.md describes the config, the API and the queue.
 *
 * Life cycle: node_config_load, node_new (opens the queue, recovers it after
 * a crash, loads the profiles), node_start (workers and HTTP), node_stop
 * (from any thread but the node's own), node_free.  Errors fill a struct
 * st_error; the node itself logs one-line records through node_set_log.
 */
#ifndef STRATUM_HOST_SERVE_NODE_H
#define STRATUM_HOST_SERVE_NODE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "st_error.h"

#define NODE_MAX_PRINTERS 16
#define NODE_MAX_KEYS 32
#define NODE_NAME_MAX 64	/* node, printer and key names, bytes with the NUL */
#define NODE_KEY_MIN 16		/* shortest API key accepted, bytes */
#define NODE_KEY_MAX 128	/* longest API key, bytes */
#define NODE_PATH_MAX 1024	/* data directory, profile and port paths */
#define NODE_PREFIX_MAX 128	/* a printer's URL path prefix */
#define NODE_URL_MAX 256	/* a node's URL, bytes with the NUL */
#define NODE_FILE_NAME_MAX 255	/* an uploaded file's name, bytes (NAME_MAX) */
#define NODE_UPLOAD_DEFAULT (256ull << 20) /* max_upload_mb default: 256 MiB */
/* HTTP connection bounds (docs/serve.md, "Limits"): the total stays under the
 * usual 1024 open files so the node keeps descriptors for its own files;
 * libmicrohttpd divides it among the HTTP threads (4), so at least 2 each. */
#define NODE_CONN_DEFAULT 512	       /* max_connections */
#define NODE_CONN_MIN 8
#define NODE_CONN_MAX 65536
#define NODE_CONN_PER_IP_DEFAULT 32    /* max_connections_per_ip */
#define NODE_IDLE_TIMEOUT_DEFAULT 30   /* idle_timeout_s: no byte in either direction */
#define NODE_HEADER_TIMEOUT_DEFAULT 30 /* header_timeout_s: a whole request header */
#define NODE_MIN_BODY_RATE_DEFAULT 1024 /* min_body_rate: bytes/s over each header_timeout_s */

/* Roles of an API key (bit set). */
enum node_role {
	NODE_ROLE_READ = 1u << 0,    /* every GET */
	NODE_ROLE_UPLOAD = 1u << 1,  /* POST /api/files/local */
	NODE_ROLE_CONTROL = 1u << 2, /* job, printer command, connection, bed clear */
};

struct node_key {
	char name[NODE_NAME_MAX];  /* the [key NAME] section, for the log */
	char secret[NODE_KEY_MAX + 1];
	unsigned roles; /* enum node_role bits */
};

struct node_printer_config {
	char name[NODE_NAME_MAX];	/* [printer NAME] */
	char profile[NODE_PATH_MAX];	/* profile name or .ini path (profile_find) */
	char port[NODE_PATH_MAX];	/* device path, tcp://, "sim" or "test-instant" */
	char prefix[NODE_PREFIX_MAX];	/* URL prefix; default "/p/NAME" */
	double sim_speedup;		/* port = sim: time divisor; default 100 */
	char sim_log[NODE_PATH_MAX];	/* port = sim: execution log (set by node_new) */
};

/* [mqtt]: optional; host empty = no MQTT (docs/serve.md "MQTT"). */
#define NODE_MQTT_HOSTS_MAX 16		/* download_hosts entries */
#define NODE_MQTT_PORT 1883		/* port default */
#define NODE_MQTT_TLS_PORT 8883		/* port default with tls = 1 */
struct node_mqtt_config {
	char host[256];
	uint16_t port;			/* NODE_MQTT_PORT, or NODE_MQTT_TLS_PORT with tls */
	char username[128], password[128]; /* "" = none */
	char client_id[NODE_NAME_MAX + 16]; /* "stratum-NODE": one per node name */
	char topic[128];		/* topic root; default "stratum" */
	int keepalive;			/* seconds; default 30 */
	int tls;			/* 1: TLS, the broker's certificate checked */
	char ca_file[NODE_PATH_MAX], ca_dir[NODE_PATH_MAX]; /* "" both: the system's CAs */
	char cert_file[NODE_PATH_MAX], key_file[NODE_PATH_MAX]; /* client certificate */
	char tls_version[16];		/* lowest accepted: "" (tlsv1.2), tlsv1.2, tlsv1.3 */
	int tls_insecure;		/* 1: the broker's host name is not checked */
	/* "host" or "host:port" (lower case) that enqueue may download from */
	char download_hosts[NODE_MQTT_HOSTS_MAX][264];
	size_t ndownload_hosts;
};

struct node_config {
	char path[NODE_PATH_MAX];	/* the file it was read from */
	char name[NODE_NAME_MAX];	/* [node] name; default "stratum" */
	char listen_addr[64];		/* IPv4 address; default 127.0.0.1 */
	/* where clients reach the node ("http://farm-1.lan:5000"), announced on
	 * MQTT for the farm view; "" = from listen (the host name for 0.0.0.0) */
	char url[NODE_URL_MAX];
	uint16_t listen_port;		/* default 5000 (OctoPrint's); 0 = any free port */
	char data_dir[NODE_PATH_MAX];	/* relative paths are from the config's folder */
	uint64_t max_upload;		/* bytes; max_upload_mb in the file */
	int slice_threads;		/* cores per slicing job, 0 = all; default 1 */
	unsigned max_connections;	/* HTTP connections in all; NODE_CONN_DEFAULT */
	unsigned max_connections_per_ip; /* from one client address */
	unsigned idle_timeout_s;	/* close a connection silent this long */
	unsigned header_timeout_s;	/* a request's header must be whole within this */
	unsigned min_body_rate;		/* bytes/s a body brings over each header_timeout_s; 0 = any */
	struct node_key keys[NODE_MAX_KEYS];
	size_t nkeys;
	struct node_printer_config printers[NODE_MAX_PRINTERS];
	size_t nprinters;
	struct node_mqtt_config mqtt;
};

/*
 * node_config_load - read and check a node config (docs/serve.md): the
 * syntax of host/ini.h, with a ' #' or ' ;' after a value starting a comment.
 * The whole file is checked before *cfg is used: any bad line rejects it.
 * Returns 0, or ST_ERR_IO (cannot read), ST_ERR_PARSE (syntax, unknown
 * section or key, duplicate), ST_ERR_RANGE (a value out of range, no key,
 * no printer, two printers with one name or prefix) with "FILE: line N:
 * ..." in err.
 */
int node_config_load(const char *path, struct node_config *cfg, struct st_error *err);

/* node_config_read - node_config_load, and with keys_required false a file
 * without any [key NAME] section is accepted too (to add the first key). */
int node_config_read(const char *path, struct node_config *cfg, bool keys_required,
		     struct st_error *err);

/* node_good_name - whether s may name a node, printer or key: letters,
 * digits, '-', '_' and '.', not starting with '.', at most 63 bytes. */
bool node_good_name(const char *s);

/* node_parse_roles - "read, upload, control" (any of them, comma separated)
 * into enum node_role bits; v is cut up.  ST_ERR_PARSE for an unknown role,
 * ST_ERR_RANGE for none, with "roles: ..." in err. */
int node_parse_roles(char *v, unsigned *roles, struct st_error *err);

/* An API key made by the node: OctoPrint's form, 16 random bytes as 32
 * upper-case hexadecimal digits (0-9, A-F). */
#define NODE_NEW_KEY_LEN 32

/*
 * node_config_new_key - add [key name] with roles (node_parse_roles' form)
 * and a new random key to the config at path, written whole (st_file.h),
 * mode 0600, checked by node_config_load before it replaces the file; the
 * key into key.  Returns 0; ST_ERR_ARG for a bad name or roles; ST_ERR_RANGE
 * when the file has a key of that name; the reader's error when the config
 * is bad; ST_ERR_IO when it cannot be written (then it is left as it was).
 */
int node_config_new_key(const char *path, const char *name, const char *roles,
			char key[NODE_NEW_KEY_LEN + 1], struct st_error *err);

/*
 * The farm view's config (`stratum farm`, docs/serve.md "The farm view"):
 * [farm] with the [node] keys that apply (name, listen, max_upload_mb and
 * the connection limits) and node_key, [key NAME] (its own API's keys),
 * [mqtt] (the broker, as a node's) and [remote NODE] (key: the farm's key
 * on that node, instead of node_key; url: its address, instead of the one
 * it announces).  No printers.
 */
#define FARM_MAX_REMOTES 256
struct farm_remote {
	char name[NODE_NAME_MAX];	/* the node's [node] name */
	char key[NODE_KEY_MAX + 1];	/* a key of that node with the upload role */
	char url[NODE_URL_MAX];		/* where it is reached; "" = what it announces */
};
struct farm_config {
	struct node_config base; /* name, listen, limits, keys, mqtt; no printers */
	char node_key[NODE_KEY_MAX + 1]; /* the farm's key on nodes without a [remote] */
	struct farm_remote remotes[FARM_MAX_REMOTES];
	size_t nremotes;
};

/*
 * farm_config_load - read and check a farm view's config, as
 * node_config_load does a node's (same syntax, same errors and codes).
 * The MQTT client id is "stratum-farm-NAME".
 */
int farm_config_load(const char *path, struct farm_config *cfg, struct st_error *err);

/*
 * node_config_exposed - whether the config at path, loaded as cfg, holds
 * secrets (API keys, an MQTT password) and can be read by its group or by
 * others (mode & 077; *mode is set to the permission bits).  The caller
 * warns: the keys give upload and control of the printers, the password
 * the node's place on the broker.  false when the file cannot be examined.
 */
bool node_config_exposed(const char *path, const struct node_config *cfg, unsigned *mode);

/*
 * node_parse_listen - "ADDR:PORT" (IPv4 dotted quad, port 0-65535) into
 * addr (cap bytes) and *port.  Returns 0, ST_ERR_PARSE, or ST_ERR_RANGE for
 * a port number beyond 0-65535.
 */
int node_parse_listen(const char *s, char *addr, size_t cap, uint16_t *port,
		      struct st_error *err);

/*
 * node_check_file_name - whether name (len bytes, may hold NUL bytes) may be
 * stored as an uploaded file: 1-255 bytes, no '/', '\\', NUL or control
 * byte, not starting with '.', no leading or trailing blank.  Returns 0 or
 * ST_ERR_PARSE with the reason (the API answers 400 with it).
 */
int node_check_file_name(const char *name, size_t len, struct st_error *err);

/*
 * node_file_kind - 'g' for G-code (.gcode .gco .g), 'm' for a model the
 * node slices (.stl .obj .off .3mf: every format meshio.h reads; a 3MF
 * with several objects is sliced with its build placement), 'x' for X3G (.x3g, Sailfish printers only: see
 * node_check_kind), 0 for anything else (the API answers 415).
 * Case-insensitive on the extension.
 */
char node_file_kind(const char *name);

/*
 * The log sink: every record is one line without the newline ("level=info
 * printer=mk3s job=3 msg=..."), passed to fn.  One sink per process (the
 * style's one allowed global); set it before node_new.  NULL drops records.
 */
typedef void (*node_log_fn)(const char *line, void *ctx);
void node_set_log(node_log_fn fn, void *ctx);

struct node;

/*
 * node_new - open the data directory (created when missing) and its queue
 * database, recover the queue after a crash (a printing job becomes paused
 * and marked interrupted; a slicing one is queued again), load every
 * printer's profile.  Nothing is started.  *out NULL on error.
 * Returns 0, ST_ERR_IO (data directory, database), ST_ERR_PARSE /
 * ST_ERR_RANGE / ST_ERR_ARG (a printer's profile), ST_ERR_NOMEM.
 */
int node_new(const struct node_config *cfg, struct node **out, struct st_error *err);

/*
 * node_start - start one worker thread per printer and the HTTP server.
 * Returns 0 or ST_ERR_IO (cannot listen: the message names the address).
 */
int node_start(struct node *n, struct st_error *err);

/* node_port - the TCP port the node listens on (after node_start). */
uint16_t node_port(const struct node *n);

/*
 * node_stop - stop the HTTP server and the workers; a print in progress is
 * left as an interrupted job (as after a crash) to be resumed by an
 * operator.  Safe to call twice.
 */
void node_stop(struct node *n);

/* node_free - stop if needed and free; NULL is fine. */
void node_free(struct node *n);

/*
 * The farm view (host/serve/farm*.c): every node's printers on one page and
 * one JSON API, read from the broker, and jobs handed to idle printers.
 * farm_new copies cfg; farm_start connects to the broker (retried while it
 * is down) and listens: 0, ST_ERR_ARG (no broker host), ST_ERR_RANGE (TLS
 * files), ST_ERR_IO (cannot listen).  farm_free stops and frees (NULL ok).
 */
struct farm;
int farm_new(const struct farm_config *cfg, struct farm **out, struct st_error *err);
int farm_start(struct farm *f, struct st_error *err);
void farm_free(struct farm *f);

#endif /* STRATUM_HOST_SERVE_NODE_H */

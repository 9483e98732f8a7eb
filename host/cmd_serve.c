/*
 * cmd_serve.c - `stratum serve --config node.ini [--listen ADDR:PORT]`: run
 * the farm node (host/serve/node.h) until SIGTERM or SIGINT (with --new-key
 * NAME --roles ROLES: add a new API key to the config and print it); and
 * `stratum farm --config farm.ini [--broker HOST[:PORT]] [--listen ADDR:PORT]`:
 * the farm view over every node on the broker, the same way.  Log records go
 * to stderr, one line each, with a UTC time stamp (journald adds its own,
 * but a plain terminal needs one).
 * Exit 0 after a signal, 2 usage, 65 bad config or printer profile,
 * 69 cannot listen, 70 internal error.
 */
#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "commands.h"
#include "serve/node.h"
#include "st_error.h"

#define SERVE_CMD "stratum serve"
#define FARM_CMD "stratum farm"

/* The help text around the option lines. */
static const char serve_head[] =
    "usage: stratum serve --config NODE.ini [--listen ADDR:PORT]\n"
    "       stratum serve --config NODE.ini --new-key NAME --roles ROLE,...\n"
    "\n"
    "Runs the farm node: every printer of the config with its own job queue,\n"
    "behind an OctoPrint-compatible HTTP API that PrusaSlicer and Cura upload to.\n"
    "Uploaded STL/OBJ models are repaired and sliced with the printer's profile.\n"
    "The queue lives in DATA_DIR/queue.db and survives a crash; a print that was\n"
    "running is marked interrupted and waits for an operator.  See docs/serve.md.\n"
    "\n";
static const char serve_tail[] =
    "\n"
    "Stops cleanly on SIGTERM or SIGINT.  Exit status: 0 stopped by a signal,\n"
    "2 usage, 65 bad config or printer profile, 69 cannot listen, 70 internal\n"
    "error.\n";

/* Log sink: a UTC time stamp, then the record. */
static void log_stderr(const char *line, void *ctx)
{
	char ts[32];
	time_t now = time(NULL);
	struct tm tm;

	(void)ctx;
	gmtime_r(&now, &tm);
	strftime(ts, sizeof(ts), "%Y-%m-%dT%H:%M:%SZ", &tm);
	fprintf(stderr, "%s %s\n", ts, line);
	fflush(stderr);
}

/* --new-key NAME --roles ROLES: the key on stdout, nothing else. */
static int new_key_command(const struct cmd_spec *spec, const char *config, const char *name,
			   const char *roles)
{
	char key[NODE_NEW_KEY_LEN + 1];
	struct st_error err = {0};
	int rc;

	if (!name || !roles)
		return cmd_refuse(spec, "%s", name ? "--new-key needs --roles (read, upload, control)"
						   : "--roles goes with --new-key NAME");
	rc = node_config_new_key(config, name, roles, key, &err);
	if (rc)
		return cmd_fail(SERVE_CMD, st_exit_for(rc), "%s", err.msg);
	printf("%s\n", key);
	fprintf(stderr, SERVE_CMD ": added [key %s] to %s (mode 0600); restart the node to use "
			"it\n", name, config);
	return ST_EXIT_OK;
}

/* Warn when the config at path, holding secrets, is readable by others. */
static void warn_exposed(const char *cmd, const char *who, const char *path,
			 const struct node_config *cfg)
{
	unsigned mode;

	if (node_config_exposed(path, cfg, &mode))
		fprintf(stderr, "%s: warning: %s holds API keys%s and can be read by other users "
				"(mode %04o); make it readable by the %s's user only: chmod 600 %s\n",
			cmd, path, cfg->mqtt.password[0] ? " and the MQTT password" : "", mode, who,
			path);
}

/* SIGTERM and SIGINT are taken by sigwait in set only (every thread
 * inherits the mask); the log goes to stderr. */
static void block_signals(sigset_t *set)
{
	sigemptyset(set);
	sigaddset(set, SIGTERM);
	sigaddset(set, SIGINT);
	pthread_sigmask(SIG_BLOCK, set, NULL);
	signal(SIGPIPE, SIG_IGN);
	node_set_log(log_stderr, NULL);
}

int cmd_serve(int argc, char **argv)
{
	const char *config = NULL, *listen = NULL, *new_key = NULL, *roles = NULL;
	struct node_config *cfg;
	struct node *n = NULL;
	struct st_error err = {0};
	sigset_t set;
	int sig = 0, rc;
	static struct node_config cfg_store; /* large: kept off the stack */

	const struct cmd_opt opts[] = {
	    CMD_OPT_STRING("--config", 0, &config, CMD_NONEMPTY, "the node's config file", "FILE",
	     "the node's config (docs/serve.md)"),
	    CMD_OPT_STRING("--listen", 0, &listen, 0, "ADDR:PORT", "ADDR:PORT",
	     "listen there instead of the config's listen = (port 0:\n"
	     "any free port, logged at start)"),
	    CMD_OPT_STRING("--new-key", 0, &new_key, CMD_NONEMPTY, "a key name", "NAME",
	     "add [key NAME] with a new random key (OctoPrint's form:\n"
	     "32 hex digits) to the config, print the key and exit;\n"
	     "restart the node to use it"),
	    CMD_OPT_STRING("--roles", 0, &roles, CMD_NONEMPTY, "roles such as read,upload",
	     "ROLE,...", "the new key's roles: read, upload, control"),
	};
	const struct cmd_spec spec = {.cmd = SERVE_CMD, .head = serve_head, CMD_TABLE(opts), .col = 21,
				      .tail = serve_tail};

	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (!config)
		return cmd_refuse(&spec, "no config given; add --config NODE.ini");
	if (new_key || roles)
		return new_key_command(&spec, config, new_key, roles);
	cfg = &cfg_store;
	rc = node_config_load(config, cfg, &err);
	if (rc)
		return cmd_fail(SERVE_CMD, rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR,
				"%s", err.msg);
	warn_exposed(SERVE_CMD, "node", config, cfg);
	if (listen && node_parse_listen(listen, cfg->listen_addr, sizeof(cfg->listen_addr),
					&cfg->listen_port, &err))
		return cmd_fail(SERVE_CMD, ST_EXIT_USAGE, "--listen: %s", err.msg);

	block_signals(&set);

	rc = node_new(cfg, &n, &err);
	if (rc) {
		fprintf(stderr, SERVE_CMD ": %s\n", err.msg);
		return rc == ST_ERR_IO ? ST_EXIT_DATAERR
		       : rc == ST_ERR_NOMEM || rc == ST_ERR_INTERNAL ? ST_EXIT_SOFTWARE
								       : ST_EXIT_DATAERR;
	}
	rc = node_start(n, &err);
	if (rc) {
		fprintf(stderr, SERVE_CMD ": %s\n", err.msg);
		node_free(n);
		/* RANGE: the node's name is held on the MQTT broker, or a TLS
		 * file cannot be read: the config must change, as for 65 above. */
		return rc == ST_ERR_IO ? ST_EXIT_UNAVAILABLE
		       : rc == ST_ERR_RANGE ? ST_EXIT_DATAERR
					    : ST_EXIT_SOFTWARE;
	}
	sigwait(&set, &sig);
	fprintf(stderr, SERVE_CMD ": %s received, stopping\n", sig == SIGTERM ? "SIGTERM" : "SIGINT");
	node_free(n);
	return ST_EXIT_OK;
}

static const char farm_head[] =
    "usage: stratum farm --config FARM.ini [--broker HOST[:PORT]] [--listen ADDR:PORT]\n"
    "\n"
    "Runs the farm view: reads every node's state on the MQTT broker and serves\n"
    "one page and one JSON API (GET /api/farm) with all printers of all nodes;\n"
    "POST /api/farm/jobs hands a job to the first idle printer of a profile,\n"
    "through its node's upload API.  See docs/serve.md, \"The farm view\".\n"
    "\n";
static const char farm_tail[] =
    "\n"
    "Stops cleanly on SIGTERM or SIGINT.  Exit status: 0 stopped by a signal,\n"
    "2 usage, 65 bad config, 69 cannot listen, 70 internal error.\n";

int cmd_farm(int argc, char **argv)
{
	const char *config = NULL, *listen = NULL, *broker = NULL;
	static struct farm_config cfg; /* large: kept off the stack */
	struct node_mqtt_config *m = &cfg.base.mqtt;
	struct farm *f = NULL;
	struct st_error err = {0};
	sigset_t set;
	int sig = 0, rc;

	const struct cmd_opt opts[] = {
	    CMD_OPT_STRING("--config", 0, &config, CMD_NONEMPTY, "the farm's config file", "FILE",
	     "the farm view's config: its keys, the broker, the keys it\n"
	     "sends jobs to nodes with (docs/serve.md)"),
	    CMD_OPT_STRING("--broker", 0, &broker, CMD_NONEMPTY, "HOST or HOST:PORT",
	     "HOST[:PORT]", "the MQTT broker instead of the config's [mqtt] host\n"
	     "(and port)"),
	    CMD_OPT_STRING("--listen", 0, &listen, 0, "ADDR:PORT", "ADDR:PORT",
	     "listen there instead of the config's listen = (port 0:\n"
	     "any free port, logged at start)"),
	};
	const struct cmd_spec spec = {.cmd = FARM_CMD, .head = farm_head, CMD_TABLE(opts), .col = 23,
				      .tail = farm_tail};

	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (!config)
		return cmd_refuse(&spec, "no config given; add --config FARM.ini");
	if ((rc = farm_config_load(config, &cfg, &err)))
		return cmd_fail(FARM_CMD, rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR,
				"%s", err.msg);
	warn_exposed(FARM_CMD, "farm view", config, &cfg.base);
	if (listen && node_parse_listen(listen, cfg.base.listen_addr, sizeof(cfg.base.listen_addr),
					&cfg.base.listen_port, &err))
		return cmd_fail(FARM_CMD, ST_EXIT_USAGE, "--listen: %s", err.msg);
	if (broker) {
		const char *colon = strrchr(broker, ':');
		char *end = NULL;
		long port = colon ? strtol(colon + 1, &end, 10) : 0;
		size_t host_len = colon ? (size_t)(colon - broker) : strlen(broker);

		if ((colon && (*end || end == colon + 1 || port < 1 || port > 65535)) ||
		    !host_len || host_len >= sizeof(m->host))
			return cmd_fail(FARM_CMD, ST_EXIT_USAGE,
					"--broker: '%s' is not HOST or HOST:PORT (port 1 to 65535)",
					broker);
		snprintf(m->host, sizeof(m->host), "%.*s", (int)host_len, broker);
		if (colon)
			m->port = (uint16_t)port;
	}
	if (!m->host[0])
		return cmd_fail(FARM_CMD, ST_EXIT_USAGE,
				"no broker: give --broker HOST or [mqtt] host = in %s", config);
	block_signals(&set);
	rc = farm_new(&cfg, &f, &err);
	if (!rc)
		rc = farm_start(f, &err);
	if (rc) {
		fprintf(stderr, FARM_CMD ": %s\n", err.msg);
		farm_free(f);
		return rc == ST_ERR_IO ? ST_EXIT_UNAVAILABLE
		       : rc == ST_ERR_RANGE ? ST_EXIT_DATAERR
					    : ST_EXIT_SOFTWARE;
	}
	sigwait(&set, &sig);
	fprintf(stderr, FARM_CMD ": %s received, stopping\n", sig == SIGTERM ? "SIGTERM" : "SIGINT");
	farm_free(f);
	return ST_EXIT_OK;
}

/*
 * cmd_serve.c - `stratum serve --config node.ini [--listen ADDR:PORT]`: run
 * the farm node (host/serve/node.h) until SIGTERM or SIGINT; with --new-key
 * NAME --roles ROLES, add a new API key to the config and print it.  Log records go
 * to stderr, one line each, with a UTC time stamp (journald adds its own,
 * but a plain terminal needs one).
 * Exit 0 after a signal, 2 usage, 65 bad config or printer profile,
 * 69 cannot listen, 70 internal error.
 */
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "commands.h"
#include "serve/node.h"
#include "st_error.h"

#define SERVE_CMD "stratum serve"

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

	if (!name || !roles) {
		fprintf(stderr, SERVE_CMD ": %s\n", name ? "--new-key needs --roles (read, upload, "
							  "control)"
							: "--roles goes with --new-key NAME");
		cmd_usage(spec, stderr);
		return ST_EXIT_USAGE;
	}
	rc = node_config_new_key(config, name, roles, key, &err);
	if (rc) {
		fprintf(stderr, SERVE_CMD ": %s\n", err.msg);
		return st_exit_for(rc);
	}
	printf("%s\n", key);
	fprintf(stderr, SERVE_CMD ": added [key %s] to %s (mode 0600); restart the node to use "
			"it\n", name, config);
	return ST_EXIT_OK;
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
	if (!config) {
		fprintf(stderr, SERVE_CMD ": no config given; add --config NODE.ini\n");
		cmd_usage(&spec, stderr);
		return ST_EXIT_USAGE;
	}
	if (new_key || roles)
		return new_key_command(&spec, config, new_key, roles);
	cfg = &cfg_store;
	rc = node_config_load(config, cfg, &err);
	if (rc) {
		fprintf(stderr, SERVE_CMD ": %s\n", err.msg);
		return rc == ST_ERR_NOMEM ? ST_EXIT_SOFTWARE : ST_EXIT_DATAERR;
	}
	{
		unsigned mode;

		if (node_config_exposed(config, cfg, &mode))
			fprintf(stderr,
				SERVE_CMD ": warning: %s holds API keys%s and can be read by other "
					  "users (mode %04o); make it readable by the node's user "
					  "only: chmod 600 %s\n",
				config, cfg->mqtt.password[0] ? " and the MQTT password" : "", mode,
				config);
	}
	if (listen && node_parse_listen(listen, cfg->listen_addr, sizeof(cfg->listen_addr),
					&cfg->listen_port, &err)) {
		fprintf(stderr, SERVE_CMD ": --listen: %s\n", err.msg);
		return ST_EXIT_USAGE;
	}

	/* Signals are taken by sigwait here only; every thread inherits the mask. */
	sigemptyset(&set);
	sigaddset(&set, SIGTERM);
	sigaddset(&set, SIGINT);
	pthread_sigmask(SIG_BLOCK, &set, NULL);
	signal(SIGPIPE, SIG_IGN);
	node_set_log(log_stderr, NULL);

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

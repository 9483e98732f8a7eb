/*
 * cmd_opts.c - option parsing helpers shared by the subcommands (commands.h).
 */
#include <signal.h>
#include <stdio.h>
#include <string.h>

#include "commands.h"
#include "st_number.h"

void cmd_on_stop_signals(void (*handler)(int))
{
	struct sigaction sa;

	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = handler;
	sigemptyset(&sa.sa_mask);
	sigaction(SIGINT, &sa, NULL);
	sigaction(SIGTERM, &sa, NULL);
}

const char *cmd_opt_value(int argc, char **argv, int *i, const char *name)
{
	size_t len = strlen(name);
	const char *a = argv[*i];

	if (!strcmp(a, name))
		return *i + 1 < argc ? argv[++*i] : NULL;
	if (!strncmp(a, name, len) && a[len] == '=')
		return a + len + 1;
	return NULL;
}

bool cmd_is_opt(const char *a, const char *name)
{
	size_t len = strlen(name);

	return !strncmp(a, name, len) && (a[len] == '\0' || a[len] == '=');
}

bool cmd_number(const char *cmd, const char *opt, const char *v, const char *what, double *out)
{
	if (v && st_parse_double(v, strlen(v), 0, out) == ST_NUMBER_OK)
		return true;
	fprintf(stderr, "%s: %s wants %s, not '%s'\n", cmd, opt, what, v ? v : "");
	return false;
}

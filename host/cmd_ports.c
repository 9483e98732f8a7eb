/*
 * cmd_ports.c - `stratum ports [--printer NAME] [--json]`: the serial ports
 * the OS knows, with their USB identity, which printer profiles claim them
 * through their usb_ids, and what `--port auto` would choose (portpick.h).  Ptys and tcp:// bridges are not enumerable and are not
 * listed.
 */
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "portpick.h"
#include "profile.h"
#include "st_error.h"
#include "xport.h"

/* The profiles that load, for matching; bad ones are counted and skipped. */
struct profile_set {
	struct profile **items;
	size_t count;
};

static void load_profiles(struct profile_set *set)
{
	struct st_error err = {0};
	size_t skipped = 0;

	if (portpick_profiles(&set->items, &set->count, &skipped, &err))
		fprintf(stderr, "stratum ports: %s\n", err.msg);
	else if (skipped)
		fprintf(stderr,
			"stratum ports: %zu printer profile%s could not be loaded and %s skipped "
			"('stratum printers' says why)\n",
			skipped, skipped == 1 ? "" : "s", skipped == 1 ? "is" : "are");
}

static const char *or_dash(const char *s)
{
	return s && *s ? s : "-";
}

static void print_text(const struct xport_port_info *ports, size_t n,
		       const struct profile_set *set, const struct portpick_result *pick,
		       const struct profile *want)
{
	if (n == 0) {
		printf("No serial ports found. Is the printer plugged in and switched on?\n"
		       "(Pseudo-terminals and tcp:// bridges are not listed; give them with "
		       "--port.)\n");
		return;
	}
	for (size_t i = 0; i < n; i++) {
		const struct xport_port_info *p = &ports[i];
		bool any = false;

		printf("%s\n", p->by_id ? p->by_id : p->name);
		if (p->by_id)
			printf("  device        %s\n", p->name);
		printf("  transport     %s\n", xport_transport_name(p->transport));
		if (p->usb_vid >= 0)
			printf("  usb id        %04x:%04x\n", p->usb_vid, p->usb_pid);
		printf("  manufacturer  %s\n  product       %s\n  serial number %s\n",
		       or_dash(p->manufacturer), or_dash(p->product), or_dash(p->serial));
		printf("  printers      ");
		for (size_t k = 0; k < set->count; k++) {
			if (!portpick_claims(set->items[k], p))
				continue;
			printf("%s%s", any ? ", " : "", set->items[k]->id);
			any = true;
		}
		if (!any)
			printf(p->usb_vid < 0 ? "(not a USB device)" : "(no profile lists this USB id)");
		printf("\n");
	}
	printf("\n--port auto%s%s: %s%s\n", want ? " for " : "", want ? want->id : "",
	       pick->index >= 0 ? "" : "nothing chosen: ", pick->why);
}

static json_t *optional_string(const char *s)
{
	return s ? json_string(s) : json_null();
}

static int print_json(const struct xport_port_info *ports, size_t n,
		      const struct profile_set *set, const struct portpick_result *pick)
{
	json_t *arr = json_array();

	for (size_t i = 0; i < n; i++) {
		const struct xport_port_info *p = &ports[i];
		json_t *o = json_object(), *matches = json_array();
		char usb[16];

		for (size_t k = 0; k < set->count; k++)
			if (portpick_claims(set->items[k], p))
				json_array_append_new(matches, json_string(set->items[k]->id));
		snprintf(usb, sizeof(usb), "%04x:%04x", p->usb_vid & 0xffff, p->usb_pid & 0xffff);
		cmd_json_set(o, "s:name", p->name, "o:by_id", optional_string(p->by_id),
			     "s:transport", xport_transport_name(p->transport),
			     "o:usb_id", p->usb_vid >= 0 ? json_string(usb) : json_null(),
			     "o:manufacturer", optional_string(p->manufacturer),
			     "o:product", optional_string(p->product),
			     "o:serial_number", optional_string(p->serial),
			     "o:description", optional_string(p->description), "o:printers", matches,
			     "b:auto", pick->index == (long)i, NULL);
		json_array_append_new(arr, o);
	}
	return cmd_json_out(arr, JSON_INDENT(2) | JSON_PRESERVE_ORDER);
}

int cmd_ports(int argc, char **argv)
{
	struct xport_port_info *ports = NULL;
	struct profile_set set;
	struct portpick_result pick;
	struct profile *want = NULL;
	struct st_error err = {0};
	const char *printer = NULL;
	bool json = false;
	size_t n = 0;
	int rc = ST_EXIT_OK;

	const struct cmd_opt opts[] = {
	    CMD_OPT_FLAG("--json", &json, "one JSON object on stdout instead of the table"),
	    CMD_OPT_STRING("--printer", 0, &printer, CMD_NONEMPTY,
	     "a printer name or file (see 'stratum printers')", "NAME",
	     "say which port '--port auto' picks for this printer"),
	};
	const struct cmd_spec spec = {
	    .cmd = "stratum ports", CMD_TABLE(opts),
	    .head = "usage: stratum ports [--printer NAME] [--json]\n\n"
		    "Lists the serial ports (name, stable /dev/serial/by-id name, USB\n"
		    "VID:PID, manufacturer, product, serial number) and the printer\n"
		    "profiles whose usb_ids match each one, then which port '--port auto'\n"
		    "would choose (for the printer NAME when given) and why.\n"};

	rc = cmd_parse(&spec, argc, argv);
	if (rc)
		return rc < 0 ? ST_EXIT_OK : rc;
	if (printer && profile_find(printer, &want, &err))
		return cmd_fail("stratum ports", profile_exit_status(err.code), "%s", err.msg);
	if (xport_list(&ports, &n, &err)) {
		profile_free(want);
		return cmd_fail("stratum ports", ST_EXIT_UNAVAILABLE, "%s", err.msg);
	}
	load_profiles(&set);
	/* Only the explanation is wanted here; "nothing fits" is not an error. */
	portpick_choose(want, (const struct profile *const *)set.items, set.count, ports, n, &pick,
			NULL);
	if (json) {
		if (print_json(ports, n, &set, &pick)) {
			fprintf(stderr, "stratum ports: cannot write the JSON list\n");
			rc = ST_EXIT_SOFTWARE;
		}
	} else {
		print_text(ports, n, &set, &pick, want);
	}
	portpick_profiles_free(set.items, set.count);
	profile_free(want);
	xport_list_free(ports, n);
	if (fflush(stdout) == EOF)
		rc = ST_EXIT_SOFTWARE;
	return rc;
}

/*
 * portpick.c - choose the port for `--port auto` (portpick.h).
 */
#include "portpick.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "st_append.h"

bool portpick_claims(const struct profile *p, const struct xport_port_info *port)
{
	if (!p || port->usb_vid < 0 || port->usb_pid < 0)
		return false;
	for (size_t i = 0; i < p->usb_id_count; i++)
		if (p->usb_ids[i].vid == port->usb_vid && p->usb_ids[i].pid == port->usb_pid)
			return true;
	return false;
}

static const char *port_path(const struct xport_port_info *p)
{
	return p->by_id ? p->by_id : p->name;
}

/* "PATH (vvvv:pppp PRODUCT, serial S)" for lists. */
static void add_port(char *buf, size_t cap, const struct xport_port_info *p)
{
	st_appendf(buf, cap, "%s", port_path(p));
	if (p->usb_vid < 0) {
		st_appendf(buf, cap, " (%s, no USB id)", xport_transport_name(p->transport));
		return;
	}
	st_appendf(buf, cap, " (%04x:%04x", p->usb_vid, p->usb_pid);
	if (p->product)
		st_appendf(buf, cap, " %s", p->product);
	if (p->serial)
		st_appendf(buf, cap, ", serial %s", p->serial);
	st_appendf(buf, cap, ")");
}

/* The first profile of all that claims port, or NULL. */
static const struct profile *claimant(const struct profile *const *all, size_t nall,
				      const struct xport_port_info *port)
{
	for (size_t k = 0; k < nall; k++)
		if (portpick_claims(all[k], port))
			return all[k];
	return NULL;
}

static void add_ids(char *buf, size_t cap, const struct profile *p)
{
	for (size_t i = 0; i < p->usb_id_count; i++)
		st_appendf(buf, cap, "%s%04x:%04x", i ? ", " : "", p->usb_ids[i].vid, p->usb_ids[i].pid);
}

/* Why nothing was chosen, into out->why. */
static void explain_none(const struct profile *want, bool by_profile,
			 const struct xport_port_info *ports, size_t n, size_t usb,
			 struct portpick_result *out)
{
	char *w = out->why;
	size_t cap = sizeof(out->why);

	if (n == 0) {
		st_appendf(w, cap, "no serial ports found; is the printer plugged in and switched on?");
		return;
	}
	if (by_profile) {
		st_appendf(w, cap, "no port has a USB id that printer %s lists (", want->id);
		add_ids(w, cap, want);
		st_appendf(w, cap, ")");
	} else if (usb) {
		st_appendf(w, cap, "no printer profile lists the USB id of any of the %zu USB serial ports",
		    usb);
	} else {
		st_appendf(w, cap, "no USB serial port found");
	}
	st_appendf(w, cap, "; found: ");
	for (size_t i = 0; i < n; i++) {
		st_appendf(w, cap, "%s", i ? "; " : "");
		add_port(w, cap, &ports[i]);
	}
	if (by_profile)
		st_appendf(w, cap, ". Give --port PATH, or add the id to usb_ids in %s", want->path);
	else
		st_appendf(w, cap, ". Give --port PATH");
}

int portpick_choose(const struct profile *want, const struct profile *const *all, size_t nall,
		    const struct xport_port_info *ports, size_t n, struct portpick_result *out,
		    struct st_error *err)
{
	bool by_profile = want && want->usb_id_count > 0;
	size_t matches = 0, usb = 0, first = 0, first_usb = 0;

	if (!out)
		return st_error_set(err, ST_ERR_ARG, "portpick: no result to fill");
	memset(out, 0, sizeof(*out));
	out->index = -1;
	for (size_t i = 0; i < n; i++) {
		const struct xport_port_info *p = &ports[i];
		bool m = by_profile ? portpick_claims(want, p) : claimant(all, nall, p) != NULL;
		if (m && matches++ == 0)
			first = i;
		if (p->transport == XPORT_TRANSPORT_USB && p->usb_vid >= 0 && usb++ == 0)
			first_usb = i;
	}
	if (matches == 1 || (!matches && !by_profile && usb == 1)) {
		const struct xport_port_info *p = &ports[matches ? first : first_usb];
		out->index = (long)(matches ? first : first_usb);
		out->path = port_path(p);
		out->profile = by_profile ? want : claimant(all, nall, p);
		st_appendf(out->why, sizeof(out->why), "%s", out->path);
		if (out->profile)
			st_appendf(out->why, sizeof(out->why), ": its USB id %04x:%04x is in %s's usb_ids",
			    p->usb_vid, p->usb_pid, out->profile->id);
		else
			st_appendf(out->why, sizeof(out->why),
			    ": the only USB serial port (%04x:%04x; no printer profile lists it)",
			    p->usb_vid, p->usb_pid);
		if (!p->by_id)
			st_appendf(out->why, sizeof(out->why), " (no /dev/serial/by-id/ name for it)");
		return 0;
	}
	if (matches > 1) {
		st_appendf(out->why, sizeof(out->why), "%zu ports match %s: ", matches,
		    by_profile ? want->id : "the printer profiles");
		for (size_t i = 0, k = 0; i < n; i++) {
			if (by_profile ? !portpick_claims(want, &ports[i])
				       : !claimant(all, nall, &ports[i]))
				continue;
			st_appendf(out->why, sizeof(out->why), "%s", k++ ? "; " : "");
			add_port(out->why, sizeof(out->why), &ports[i]);
		}
		st_appendf(out->why, sizeof(out->why), ". Give --port with the one to use");
	} else {
		explain_none(want, by_profile, ports, n, usb, out);
	}
	return st_error_set(err, ST_ERR_IO, "--port auto: %s", out->why);
}

int portpick_profiles(struct profile ***out, size_t *n, size_t *skipped, struct st_error *err)
{
	struct profile_entry *list = NULL;
	struct profile **items;
	size_t count = 0, bad = 0;
	int rc = profile_list(&list, &count, err);

	*out = NULL;
	*n = 0;
	if (rc)
		return rc;
	items = calloc(count ? count : 1, sizeof(*items));
	if (!items) {
		profile_list_free(list, count);
		return st_error_set(err, ST_ERR_NOMEM, "out of memory loading printer profiles");
	}
	for (size_t i = 0; i < count; i++) {
		if (profile_load_file(list[i].path, &items[*n], NULL))
			bad++;
		else
			(*n)++;
	}
	profile_list_free(list, count);
	if (skipped)
		*skipped = bad;
	*out = items;
	return 0;
}

void portpick_profiles_free(struct profile **list, size_t n)
{
	for (size_t i = 0; list && i < n; i++)
		profile_free(list[i]);
	free(list);
}

int portpick_auto(const struct profile *want, char **path, char *why, size_t whylen,
		  struct st_error *err)
{
	struct xport_port_info *ports = NULL;
	struct profile **all = NULL;
	struct portpick_result r;
	size_t n = 0, nall = 0;
	int rc;

	*path = NULL;
	if ((rc = xport_list(&ports, &n, err)))
		return rc;
	/* Profiles are only needed when the printer's own ids do not decide. */
	if (!(want && want->usb_id_count) && (rc = portpick_profiles(&all, &nall, NULL, err)))
		goto out;
	rc = portpick_choose(want, (const struct profile *const *)all, nall, ports, n, &r, err);
	if (why && whylen)
		snprintf(why, whylen, "%s", r.why);
	if (rc == 0 && !(*path = strdup(r.path)))
		rc = st_error_set(err, ST_ERR_NOMEM, "out of memory");
out:
	portpick_profiles_free(all, nall);
	xport_list_free(ports, n);
	return rc;
}

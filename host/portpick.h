/*
 * portpick.h - `--port auto`: choose the serial port of a printer from the
 * ports the OS lists (xport_list) and the printer profiles' usb_ids.
 *
 * Rules, in order:
 *  1. With a profile that lists usb_ids: the ports whose USB VID:PID it
 *     lists.  One: chosen.  Several: refused as ambiguous, with the list.
 *     None: refused, saying what was found and why it does not fit.
 *  2. Without a profile (or one listing no usb_ids): the ports some loaded
 *     profile claims.  One: chosen.  Several: ambiguous.  None: the one
 *     USB serial port when there is exactly one (a board whose adapter no
 *     profile lists yet), else refused.
 * On-board UARTs (/dev/ttyS*) and Bluetooth ports are never chosen by the
 * last rule: every PC lists dozens of the first.  A chosen port is named by
 * its /dev/serial/by-id/ link when it has one: that name survives replugging
 * and reboots, /dev/ttyUSB0 does not.
 *
 * No I/O except in portpick_auto; thread-safety: none shared.
 */
#ifndef STRATUM_HOST_PORTPICK_H
#define STRATUM_HOST_PORTPICK_H

#include <stdbool.h>
#include <stddef.h>

#include "profile.h"
#include "st_error.h"
#include "xport.h"

/* The choice. */
struct portpick_result {
	long index;	  /* into the port list, -1 when nothing was chosen */
	const char *path; /* the chosen port's by_id or name (points into the list), or NULL */
	const struct profile *profile; /* the profile that claims it, or NULL */
	char why[512];	  /* one sentence: what was chosen and why */
};

/* portpick_claims - true when profile p lists port's USB VID:PID in usb_ids. */
bool portpick_claims(const struct profile *p, const struct xport_port_info *port);

/*
 * portpick_choose - apply the rules above.
 * @want:      the printer's profile, or NULL.
 * @all, nall: every loaded profile, for rule 2 (may be NULL, 0).
 * @ports, n:  the enumeration.
 * Returns 0 with out filled, or ST_ERR_IO when nothing fits or several
 * ports fit (the printer is unavailable until the user says which: err
 * and out->why hold the explanation and the list).  ST_ERR_ARG for a NULL
 * out.
 */
int portpick_choose(const struct profile *want, const struct profile *const *all, size_t nall,
		    const struct xport_port_info *ports, size_t n, struct portpick_result *out,
		    struct st_error *err);

/*
 * portpick_profiles - load every profile profile_list finds, skipping
 * those that fail to load (*skipped counts them, may be NULL).  *out is an
 * array of *n (portpick_profiles_free).  Returns 0, or the error of
 * profile_list, or ST_ERR_NOMEM.
 */
int portpick_profiles(struct profile ***out, size_t *n, size_t *skipped, struct st_error *err);

/* portpick_profiles_free - NULL is safe. */
void portpick_profiles_free(struct profile **list, size_t n);

/*
 * portpick_auto - what `stratum send/print --port auto` call: enumerate
 * the ports, load the profiles and choose.  *path is a new string (free)
 * naming the port; why (may be NULL, whylen bytes) gets the explanation.
 * Returns 0, ST_ERR_IO (enumeration failed, nothing fits, ambiguous),
 * ST_ERR_NOMEM; err explains.
 */
int portpick_auto(const struct profile *want, char **path, char *why, size_t whylen,
		  struct st_error *err);

#endif /* STRATUM_HOST_PORTPICK_H */
